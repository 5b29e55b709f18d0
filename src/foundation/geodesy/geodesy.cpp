#include "geodesy/geodesy.hpp"

#include <cmath>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/UTMUPS.hpp>

namespace vp::geodesy {

bool isValid(const GeodeticPoint& point) {
  return std::isfinite(point.latitude_deg) && std::isfinite(point.longitude_deg) &&
         std::isfinite(point.height_m) && std::abs(point.latitude_deg) <= 90.0 &&
         std::abs(point.longitude_deg) <= 180.0;
}

LocalFrame::LocalFrame(const GeodeticPoint& origin)
    : origin_(origin),
      cartesian_(origin.latitude_deg, origin.longitude_deg, origin.height_m,
                 GeographicLib::Geocentric::WGS84()) {}

Eigen::Vector3d LocalFrame::toEnu(const GeodeticPoint& point) const {
  Eigen::Vector3d enu;
  cartesian_.Forward(point.latitude_deg, point.longitude_deg, point.height_m, enu.x(), enu.y(),
                     enu.z());
  return enu;
}

Eigen::Vector3d LocalFrame::toEnu(const GeodeticPoint& point, Eigen::Matrix3d* localToWorld) const {
  if (localToWorld != nullptr) {
    // GeographicLib's rotation output goes through a std::vector; this path must not
    // allocate, so compose the two ENU bases here: M = R_ecef_enu0^T * R_ecef_enu(point).
    *localToWorld = enuToEcef(origin_).transpose() * enuToEcef(point);
  }
  return toEnu(point);
}

Eigen::Matrix3d enuToEcef(const GeodeticPoint& point) {
  constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
  const double sinLat = std::sin(point.latitude_deg * kDegToRad);
  const double cosLat = std::cos(point.latitude_deg * kDegToRad);
  const double sinLon = std::sin(point.longitude_deg * kDegToRad);
  const double cosLon = std::cos(point.longitude_deg * kDegToRad);
  Eigen::Matrix3d r;
  // Columns: east, north, up unit vectors in ECEF.
  r << -sinLon, -sinLat * cosLon, cosLat * cosLon,  //
      cosLon, -sinLat * sinLon, cosLat * sinLon,    //
      0.0, cosLat, sinLat;
  return r;
}

GeodeticPoint LocalFrame::toGeodetic(const Eigen::Vector3d& enu) const {
  GeodeticPoint p;
  cartesian_.Reverse(enu.x(), enu.y(), enu.z(), p.latitude_deg, p.longitude_deg, p.height_m);
  return p;
}

UtmPoint toUtm(const GeodeticPoint& point, std::optional<int> forcedZone) {
  UtmPoint utm;
  double gamma = 0.0;
  double k = 0.0;
  const int setZone = forcedZone ? *forcedZone : GeographicLib::UTMUPS::STANDARD;
  GeographicLib::UTMUPS::Forward(point.latitude_deg, point.longitude_deg, utm.zone, utm.northp,
                                 utm.easting_m, utm.northing_m, gamma, k, setZone);
  utm.height_m = point.height_m;
  return utm;
}

std::optional<UtmPoint> tryUtm(const GeodeticPoint& point) {
  // UTM's band; UTMUPS::STANDARD would give UPS (zone 0) beyond it.
  constexpr double kSouthLimit_deg = -80.0;
  constexpr double kNorthLimit_deg = 84.0;
  if (!isValid(point) || point.latitude_deg < kSouthLimit_deg ||
      point.latitude_deg >= kNorthLimit_deg) {
    return std::nullopt;
  }
  UtmPoint utm;
  double gamma = 0.0;
  double k = 0.0;
  // A valid latitude in the band: GeographicLib's only throw (|latitude| > 90) cannot happen.
  GeographicLib::UTMUPS::Forward(point.latitude_deg, point.longitude_deg, utm.zone, utm.northp,
                                 utm.easting_m, utm.northing_m, gamma, k);
  if (utm.zone < GeographicLib::UTMUPS::MINUTMZONE ||
      utm.zone > GeographicLib::UTMUPS::MAXUTMZONE || !std::isfinite(utm.easting_m) ||
      !std::isfinite(utm.northing_m)) {
    return std::nullopt;
  }
  utm.height_m = point.height_m;
  return utm;
}

GeodeticPoint fromUtm(const UtmPoint& point) {
  GeodeticPoint p;
  GeographicLib::UTMUPS::Reverse(point.zone, point.northp, point.easting_m, point.northing_m,
                                 p.latitude_deg, p.longitude_deg);
  p.height_m = point.height_m;
  return p;
}

double azimuth_deg(const GeodeticPoint& a, const GeodeticPoint& b) {
  double azi1 = 0.0;
  double azi2 = 0.0;
  GeographicLib::Geodesic::WGS84().Inverse(a.latitude_deg, a.longitude_deg, b.latitude_deg,
                                           b.longitude_deg, azi1, azi2);
  double azimuth = std::fmod(azi1, 360.0);
  if (azimuth < 0.0) {
    azimuth += 360.0;
  }
  return azimuth >= 360.0 ? 0.0 : azimuth;
}

}  // namespace vp::geodesy
