// geodesy/geodesy: WGS84 geodetic coordinates, the local ENU world frame, UTM.
//
// Contract: heights are WGS84 ellipsoidal heights in metres everywhere (telemetry, DTM,
// output); a deployment whose DTM is referred to a geoid converts it once, offline.
// The world frame is a local East-North-Up tangent frame at a configured origin
// (GeographicLib::LocalCartesian): x east, y north, z up, metres. LocalFrame is cheap to
// copy, never allocates, and is safe to share read-only between threads.
#pragma once

#include <optional>

#include <Eigen/Core>
#include <GeographicLib/LocalCartesian.hpp>

namespace vp::geodesy {

struct GeodeticPoint {
  double latitude_deg = 0.0;   // WGS84, positive north
  double longitude_deg = 0.0;  // WGS84, positive east
  double height_m = 0.0;       // ellipsoidal height
};

struct UtmPoint {
  int zone = 0;        // 1..60 (0 = UPS, polar)
  bool northp = true;  // northern hemisphere
  double easting_m = 0.0;
  double northing_m = 0.0;
  double height_m = 0.0;  // ellipsoidal height, carried along
};

// Returns true when the point is a finite, valid WGS84 position.
bool isValid(const GeodeticPoint& point);

class LocalFrame {
 public:
  LocalFrame() = default;
  explicit LocalFrame(const GeodeticPoint& origin);

  const GeodeticPoint& origin() const { return origin_; }

  Eigen::Vector3d toEnu(const GeodeticPoint& point) const;
  GeodeticPoint toGeodetic(const Eigen::Vector3d& enu) const;

  // toEnu plus the rotation that maps vectors expressed in the ENU frame *at the point*
  // into the world (origin) ENU frame. Identity at the origin; differs by the meridian
  // convergence and the Earth's curvature away from it (about 0.009 deg per km).
  Eigen::Vector3d toEnu(const GeodeticPoint& point, Eigen::Matrix3d* localToWorld) const;

 private:
  GeodeticPoint origin_{};
  GeographicLib::LocalCartesian cartesian_{};
};

// Rotation whose columns are the east, north and up unit vectors at the point in ECEF.
Eigen::Matrix3d enuToEcef(const GeodeticPoint& point);

// UTM (Transverse Mercator on WGS84, k0 0.9996, false easting 500 km, false northing 10 000 km
// south of the equator), by GeographicLib's Krueger series to sixth order (accurate to a few
// nanometres within a zone). toUtm() takes the standard zone of the point, the zone of its
// longitude with the Norway (zone 32 extended to 3 deg E between 56 and 64 deg N) and Svalbard
// (zones 31, 33, 35, 37 between 72 and 84 deg N) exceptions applied, and UPS (zone 0) beyond
// UTM's latitude band; or a forced zone (e.g. the DTM's). It throws on a latitude outside
// [-90, 90] (start-up callers only).
UtmPoint toUtm(const GeodeticPoint& point, std::optional<int> forcedZone = std::nullopt);
// The same standard-zone UTM for the real-time path: never throws, no allocation; empty for a
// point that is not valid (isValid()) or lies outside UTM's band, latitude [-80, 84) (UPS).
std::optional<UtmPoint> tryUtm(const GeodeticPoint& point);
GeodeticPoint fromUtm(const UtmPoint& point);

// Azimuth (deg, clockwise from true north, [0, 360)) of the geodesic from a to b.
double azimuth_deg(const GeodeticPoint& a, const GeodeticPoint& b);

}  // namespace vp::geodesy
