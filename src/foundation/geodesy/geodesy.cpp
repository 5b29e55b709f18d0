#include "geodesy/geodesy.hpp"

#include <cmath>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/UTMUPS.hpp>

namespace vp::geodesy {

bool isValid(const GeodeticPoint& point) {
  return std::isfinite(point.latitudeDeg) && std::isfinite(point.longitudeDeg) &&
         std::isfinite(point.heightM) && std::abs(point.latitudeDeg) <= 90.0 &&
         std::abs(point.longitudeDeg) <= 180.0;
}

LocalFrame::LocalFrame(const GeodeticPoint& origin)
    : origin_(origin),
      cartesian_(origin.latitudeDeg, origin.longitudeDeg, origin.heightM,
                 GeographicLib::Geocentric::WGS84()) {}

Eigen::Vector3d LocalFrame::toEnu(const GeodeticPoint& point) const {
  Eigen::Vector3d enu;
  cartesian_.Forward(point.latitudeDeg, point.longitudeDeg, point.heightM, enu.x(), enu.y(),
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
  const double sinLat = std::sin(point.latitudeDeg * kDegToRad);
  const double cosLat = std::cos(point.latitudeDeg * kDegToRad);
  const double sinLon = std::sin(point.longitudeDeg * kDegToRad);
  const double cosLon = std::cos(point.longitudeDeg * kDegToRad);
  Eigen::Matrix3d r;
  // Columns: east, north, up unit vectors in ECEF.
  r << -sinLon, -sinLat * cosLon, cosLat * cosLon,  //
      cosLon, -sinLat * sinLon, cosLat * sinLon,    //
      0.0, cosLat, sinLat;
  return r;
}

GeodeticPoint LocalFrame::toGeodetic(const Eigen::Vector3d& enu) const {
  GeodeticPoint p;
  cartesian_.Reverse(enu.x(), enu.y(), enu.z(), p.latitudeDeg, p.longitudeDeg, p.heightM);
  return p;
}

UtmPoint toUtm(const GeodeticPoint& point, std::optional<int> forcedZone) {
  UtmPoint utm;
  double gamma = 0.0;
  double k = 0.0;
  const int setZone = forcedZone ? *forcedZone : GeographicLib::UTMUPS::STANDARD;
  GeographicLib::UTMUPS::Forward(point.latitudeDeg, point.longitudeDeg, utm.zone, utm.northp,
                                 utm.eastingM, utm.northingM, gamma, k, setZone);
  utm.heightM = point.heightM;
  return utm;
}

GeodeticPoint fromUtm(const UtmPoint& point) {
  GeodeticPoint p;
  GeographicLib::UTMUPS::Reverse(point.zone, point.northp, point.eastingM, point.northingM,
                                 p.latitudeDeg, p.longitudeDeg);
  p.heightM = point.heightM;
  return p;
}

double azimuthDeg(const GeodeticPoint& a, const GeodeticPoint& b) {
  double azi1 = 0.0;
  double azi2 = 0.0;
  GeographicLib::Geodesic::WGS84().Inverse(a.latitudeDeg, a.longitudeDeg, b.latitudeDeg,
                                           b.longitudeDeg, azi1, azi2);
  double azimuth = std::fmod(azi1, 360.0);
  if (azimuth < 0.0) {
    azimuth += 360.0;
  }
  return azimuth >= 360.0 ? 0.0 : azimuth;
}

}  // namespace vp::geodesy
