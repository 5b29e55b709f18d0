#include "terrain/terrain_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <utility>

namespace vp::terrain {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
// WGS84, for the metres-per-degree estimate of geographic cells (only used to size steps).
constexpr double kWgs84A = 6378137.0;
constexpr double kWgs84E2 = 6.69437999014e-3;
constexpr double kEarthRadius_m = 6371000.0;
// UTM false northing of the southern hemisphere: converts northings between hemispheres.
constexpr double kSouthFalseNorthing_m = 10000000.0;
// Tolerance (in cells) at the grid edges, so points computed on the border (e.g. the
// corners of the grid fed back through the geodetic round trip) still count as inside.
constexpr double kEdgeEpsilonCells = 1e-6;
// Bisection stops once the bracketing interval is shorter than this along the ray.
constexpr double kBisectionTolerance_m = 1e-5;
// Upper bound on ray-march steps: a huge grid gets longer steps instead of a longer loop.
constexpr int kMaxMarchSteps = 200000;
// Lattice used at init to bound the grid's footprint (ENU and geographic).
constexpr int kLatticeIntervals = 32;

double wrap_deg(double deg) {
  // Into [-180, 180).
  double wrapped = std::fmod(deg + 180.0, 360.0);
  if (wrapped < 0.0) {
    wrapped += 360.0;
  }
  return wrapped - 180.0;
}

bool isFinite(const GeoTransform& t) {
  return std::isfinite(t.x0) && std::isfinite(t.dxCol) && std::isfinite(t.dxRow) &&
         std::isfinite(t.y0) && std::isfinite(t.dyCol) && std::isfinite(t.dyRow);
}

void setWhy(std::string* why, std::string text) {
  if (why != nullptr) {
    *why = std::move(text);
  }
}

}  // namespace

std::optional<CrsSpec> crsFromString(const std::string& text) {
  std::string lower;
  lower.reserve(text.size());
  for (const char c : text) {
    lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  if (lower == "wgs84") {
    return CrsSpec{HorizontalCrs::Wgs84Geographic, 0, true};
  }
  const std::string prefix = "utm:";
  if (lower.rfind(prefix, 0) != 0) {
    return std::nullopt;
  }
  const std::string rest = lower.substr(prefix.size());
  // One or two digits, then the hemisphere letter.
  if (rest.size() < 2 || rest.size() > 3) {
    return std::nullopt;
  }
  const char hemisphere = rest.back();
  if (hemisphere != 'n' && hemisphere != 's') {
    return std::nullopt;
  }
  int zone = 0;
  for (std::size_t i = 0; i + 1 < rest.size(); ++i) {
    if (std::isdigit(static_cast<unsigned char>(rest[i])) == 0) {
      return std::nullopt;
    }
    zone = zone * 10 + (rest[i] - '0');
  }
  if (zone < 1 || zone > 60) {
    return std::nullopt;
  }
  return CrsSpec{HorizontalCrs::Utm, zone, hemisphere == 'n'};
}

std::string toString(const CrsSpec& crs) {
  if (crs.kind == HorizontalCrs::Wgs84Geographic) {
    return "wgs84";
  }
  return "utm:" + std::to_string(crs.utmZone) + (crs.utmNorth ? "N" : "S");
}

const char* toString(TerrainError error) {
  switch (error) {
    case TerrainError::OutsideDtm:
      return "outside the DTM";
    case TerrainError::NoData:
      return "DTM has no data there";
    case TerrainError::NoIntersection:
      return "ray does not meet the terrain";
  }
  return "unknown terrain error";
}

namespace {

// Where a query point falls relative to the grid; also the result of evaluating the ray.
enum class SampleKind { Valid, Outside, NoData };

struct GridSample {
  SampleKind kind = SampleKind::Outside;
  double height_m = 0.0;
};

}  // namespace

bool TerrainModel::init(TerrainGrid grid, const geodesy::LocalFrame& frame, std::string* why) {
  if (grid.cols < 2 || grid.rows < 2) {
    setWhy(why, "terrain grid must be at least 2x2 samples (got " + std::to_string(grid.cols) +
                    "x" + std::to_string(grid.rows) + ")");
    return false;
  }
  const auto expected = static_cast<std::size_t>(grid.cols) * static_cast<std::size_t>(grid.rows);
  if (grid.heights_m.size() != expected) {
    setWhy(why, "terrain grid has " + std::to_string(grid.heights_m.size()) +
                    " heights, expected " + std::to_string(expected));
    return false;
  }
  if (grid.crs.kind == HorizontalCrs::Utm && (grid.crs.utmZone < 1 || grid.crs.utmZone > 60)) {
    setWhy(why, "terrain grid has invalid UTM zone " + std::to_string(grid.crs.utmZone));
    return false;
  }
  const GeoTransform& t = grid.transform;
  const double det = t.dxCol * t.dyRow - t.dxRow * t.dyCol;
  // Relative test: the two axes must not be (nearly) parallel whatever the units.
  const double scale = std::hypot(t.dxCol, t.dyCol) * std::hypot(t.dxRow, t.dyRow);
  if (!isFinite(t) || !std::isfinite(det) || scale == 0.0 || std::abs(det) <= 1e-12 * scale) {
    setWhy(why, "terrain grid geotransform is singular or not finite");
    return false;
  }
  GeoTransform inv;
  inv.dxCol = t.dyRow / det;   // col from X
  inv.dxRow = -t.dxRow / det;  // col from Y
  inv.dyCol = -t.dyCol / det;  // row from X
  inv.dyRow = t.dxCol / det;   // row from Y
  inv.x0 = -(inv.dxCol * t.x0 + inv.dxRow * t.y0);
  inv.y0 = -(inv.dyCol * t.x0 + inv.dyRow * t.y0);

  bool any = false;
  float lo = std::numeric_limits<float>::max();
  float hi = std::numeric_limits<float>::lowest();
  for (const float h : grid.heights_m) {
    if (std::isnan(h) || !std::isfinite(h) || (grid.noData && h == *grid.noData)) {
      continue;
    }
    any = true;
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  if (!any) {
    setWhy(why, "terrain grid has no valid height");
    return false;
  }

  // Geographic footprint (lat, and lon relative to a reference meridian so that grids
  // across the antimeridian work) from a lattice over the grid, plus a margin for the
  // curvature of the edges between lattice points. heightAt() uses it to reject far points
  // cheaply and, for UTM, before asking for a projection into a zone far from the point.
  const bool utm = grid.crs.kind == HorizontalCrs::Utm;
  const double centreX = t.x0 + 0.5 * (grid.cols - 1) * t.dxCol + 0.5 * (grid.rows - 1) * t.dxRow;
  const double centreY = t.y0 + 0.5 * (grid.cols - 1) * t.dyCol + 0.5 * (grid.rows - 1) * t.dyRow;
  const double lonRef = utm ? 6.0 * grid.crs.utmZone - 183.0 : wrap_deg(centreX);
  double latMin = std::numeric_limits<double>::max();
  double latMax = std::numeric_limits<double>::lowest();
  double dLonMin = latMin;
  double dLonMax = latMax;
  std::vector<geodesy::GeodeticPoint> lattice;
  lattice.reserve((kLatticeIntervals + 1) * (kLatticeIntervals + 1));
  for (int i = 0; i <= kLatticeIntervals; ++i) {
    for (int j = 0; j <= kLatticeIntervals; ++j) {
      const double col = (grid.cols - 1) * static_cast<double>(i) / kLatticeIntervals;
      const double row = (grid.rows - 1) * static_cast<double>(j) / kLatticeIntervals;
      const double x = t.x0 + col * t.dxCol + row * t.dxRow;
      const double y = t.y0 + col * t.dyCol + row * t.dyRow;
      geodesy::GeodeticPoint p;
      if (utm) {
        geodesy::UtmPoint u;
        u.zone = grid.crs.utmZone;
        u.northp = grid.crs.utmNorth;
        u.easting_m = x;
        u.northing_m = y;
        try {
          p = geodesy::fromUtm(u);
        } catch (const std::exception& e) {
          setWhy(why, std::string("terrain grid extends outside its UTM zone: ") + e.what());
          return false;
        }
      } else {
        p.latitude_deg = y;
        p.longitude_deg = x;
      }
      if (!std::isfinite(p.latitude_deg) || !std::isfinite(p.longitude_deg) ||
          std::abs(p.latitude_deg) > 90.0) {
        setWhy(why, "terrain grid lies outside valid latitudes/longitudes");
        return false;
      }
      const double dLon = wrap_deg(p.longitude_deg - lonRef);
      latMin = std::min(latMin, p.latitude_deg);
      latMax = std::max(latMax, p.latitude_deg);
      dLonMin = std::min(dLonMin, dLon);
      dLonMax = std::max(dLonMax, dLon);
      lattice.push_back(p);
    }
  }
  const double latMargin = 0.01 * (latMax - latMin) + 1e-4;
  const double lonMargin = 0.01 * (dLonMax - dLonMin) + 1e-4;
  latMinDeg_ = std::max(-90.0, latMin - latMargin);
  latMaxDeg_ = std::min(90.0, latMax + latMargin);
  dLonMinDeg_ = dLonMin - lonMargin;
  dLonMaxDeg_ = dLonMax + lonMargin;
  lonRefDeg_ = lonRef;

  // Approximate ground size of one cell: the shorter of the two axis steps, in metres.
  double colStep_m = std::hypot(t.dxCol, t.dyCol);
  double rowStep_m = std::hypot(t.dxRow, t.dyRow);
  if (!utm) {
    const double lat = std::clamp(centreY, -89.0, 89.0) * kDegToRad;
    const double s = std::sin(lat);
    const double w = std::sqrt(1.0 - kWgs84E2 * s * s);
    const double mPerDegLat = kDegToRad * kWgs84A * (1.0 - kWgs84E2) / (w * w * w);
    const double mPerDegLon = kDegToRad * kWgs84A * std::cos(lat) / w;
    colStep_m = std::hypot(t.dxCol * mPerDegLon, t.dyCol * mPerDegLat);
    rowStep_m = std::hypot(t.dxRow * mPerDegLon, t.dyRow * mPerDegLat);
  }
  const double cellSize = std::min(colStep_m, rowStep_m);
  if (!(cellSize > 0.0) || !std::isfinite(cellSize)) {
    setWhy(why, "terrain grid cell size is not positive");
    return false;
  }

  // ENU box holding the grid's volume between its lowest and highest heights: the ray is
  // clipped to it before marching. ENU z of a fixed geodetic height drops with the square of
  // the distance from the frame origin, so the lattice samples both heights everywhere and
  // the margins cover what the curvature can add between lattice points (s^2 / 8R, taken
  // generously) and the projection's bending of the edges (a cell is far more).
  Eigen::Vector3d boxMin = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector3d boxMax = Eigen::Vector3d::Constant(std::numeric_limits<double>::lowest());
  double extent_m = 0.0;
  for (geodesy::GeodeticPoint p : lattice) {
    for (const float h : {lo, hi}) {
      p.height_m = static_cast<double>(h);
      const Eigen::Vector3d enu = frame.toEnu(p);
      boxMin = boxMin.cwiseMin(enu);
      boxMax = boxMax.cwiseMax(enu);
    }
  }
  extent_m = (boxMax.head<2>() - boxMin.head<2>()).norm();
  if (!boxMin.allFinite() || !boxMax.allFinite()) {
    setWhy(why, "terrain grid cannot be placed in the local frame");
    return false;
  }
  const double latticeStep_m = extent_m / kLatticeIntervals;
  const double marginXy_m = cellSize + 1e-3 * extent_m + 1.0;
  const double marginZM = 1.0 + latticeStep_m * latticeStep_m / kEarthRadius_m;
  boxMin_ = boxMin - Eigen::Vector3d(marginXy_m, marginXy_m, marginZM);
  boxMax_ = boxMax + Eigen::Vector3d(marginXy_m, marginXy_m, marginZM);

  grid_ = std::move(grid);
  frame_ = frame;
  inverse_ = inv;
  minHeightM_ = lo;
  maxHeightM_ = hi;
  cellSizeM_ = cellSize;
  return true;
}

Expected<double, TerrainError> TerrainModel::heightAt(double latitude_deg,
                                                      double longitude_deg) const {
  if (grid_.heights_m.empty()) {
    return unexpected(TerrainError::OutsideDtm);
  }
  if (!std::isfinite(latitude_deg) || !std::isfinite(longitude_deg)) {
    return unexpected(TerrainError::OutsideDtm);
  }
  const double dLon = wrap_deg(longitude_deg - lonRefDeg_);
  if (latitude_deg < latMinDeg_ || latitude_deg > latMaxDeg_ || dLon < dLonMinDeg_ ||
      dLon > dLonMaxDeg_) {
    return unexpected(TerrainError::OutsideDtm);
  }
  double x = 0.0;
  double y = 0.0;
  if (grid_.crs.kind == HorizontalCrs::Utm) {
    geodesy::UtmPoint u;
    try {
      u = geodesy::toUtm(geodesy::GeodeticPoint{latitude_deg, longitude_deg, 0.0},
                         grid_.crs.utmZone);
    } catch (const std::exception&) {
      // Defensive only: the footprint test above keeps points near the grid's zone.
      return unexpected(TerrainError::OutsideDtm);
    }
    if (u.zone != grid_.crs.utmZone) {
      return unexpected(TerrainError::OutsideDtm);
    }
    x = u.easting_m;
    y = u.northing_m;
    // A grid in one hemisphere may hold points of the other (near the equator): same
    // projection, northings differ only by the southern false northing.
    if (u.northp && !grid_.crs.utmNorth) {
      y += kSouthFalseNorthing_m;
    } else if (!u.northp && grid_.crs.utmNorth) {
      y -= kSouthFalseNorthing_m;
    }
  } else {
    x = lonRefDeg_ + dLon;
    y = latitude_deg;
  }
  double col = inverse_.x0 + inverse_.dxCol * x + inverse_.dxRow * y;
  double row = inverse_.y0 + inverse_.dyCol * x + inverse_.dyRow * y;
  const double maxCol = grid_.cols - 1;
  const double maxRow = grid_.rows - 1;
  if (!(col >= -kEdgeEpsilonCells && col <= maxCol + kEdgeEpsilonCells &&
        row >= -kEdgeEpsilonCells && row <= maxRow + kEdgeEpsilonCells)) {
    return unexpected(TerrainError::OutsideDtm);
  }
  col = std::clamp(col, 0.0, maxCol);
  row = std::clamp(row, 0.0, maxRow);
  const int c0 = std::min(static_cast<int>(col), grid_.cols - 2);
  const int r0 = std::min(static_cast<int>(row), grid_.rows - 2);
  const double fc = col - c0;
  const double fr = row - r0;
  const std::size_t i00 = static_cast<std::size_t>(r0) * grid_.cols + c0;
  const std::size_t i10 = i00 + static_cast<std::size_t>(grid_.cols);
  const float h00 = grid_.heights_m[i00];
  const float h01 = grid_.heights_m[i00 + 1];
  const float h10 = grid_.heights_m[i10];
  const float h11 = grid_.heights_m[i10 + 1];
  for (const float h : {h00, h01, h10, h11}) {
    if (!std::isfinite(h) || (grid_.noData && h == *grid_.noData)) {
      return unexpected(TerrainError::NoData);
    }
  }
  const double top = (1.0 - fc) * static_cast<double>(h00) + fc * static_cast<double>(h01);
  const double bottom = (1.0 - fc) * static_cast<double>(h10) + fc * static_cast<double>(h11);
  return (1.0 - fr) * top + fr * bottom;
}

Expected<double, TerrainError> TerrainModel::heightAtEnu(const Eigen::Vector3d& enu) const {
  const geodesy::GeodeticPoint p = frame_.toGeodetic(enu);
  return heightAt(p.latitude_deg, p.longitude_deg);
}

Expected<Eigen::Vector3d, TerrainError> TerrainModel::groundPointEnu(double xEast_m,
                                                                     double yNorth_m) const {
  // Moving along ENU z shifts the geodetic position by only z * d / R (d: distance from
  // the frame origin), so the fixed-point iteration z += H - h converges in 2-3 steps.
  Eigen::Vector3d enu(xEast_m, yNorth_m, 0.0);
  for (int iteration = 0; iteration < 20; ++iteration) {
    const geodesy::GeodeticPoint p = frame_.toGeodetic(enu);
    const Expected<double, TerrainError> h = heightAt(p.latitude_deg, p.longitude_deg);
    if (!h) {
      return unexpected(h.error());
    }
    const double dz = *h - p.height_m;
    enu.z() += dz;
    if (std::abs(dz) < 1e-7) {
      break;
    }
  }
  return enu;
}

Expected<Eigen::Vector3d, TerrainError> TerrainModel::intersectRay(
    const Eigen::Vector3d& originEnu, const Eigen::Vector3d& directionEnu) const {
  if (grid_.heights_m.empty()) {
    return unexpected(TerrainError::OutsideDtm);
  }
  const double dirNorm = directionEnu.norm();
  if (!originEnu.allFinite() || !directionEnu.allFinite() || !(dirNorm > 0.0)) {
    return unexpected(TerrainError::NoIntersection);
  }

  // A descending ray that leaves the grid still above the ground would meet it outside
  // the DTM: OutsideDtm. A level or rising one never meets it (over these distances the
  // Earth's curvature does not change that): NoIntersection.
  const TerrainError leftTheGrid =
      directionEnu.z() < 0.0 ? TerrainError::OutsideDtm : TerrainError::NoIntersection;

  // 1. Clip to the grid's ENU box (slab method). The box spans the footprint and the
  // heights [minH, maxH] with curvature margins (see init), so every crossing lies inside.
  // Missing the footprint horizontally means the ray never enters the grid: OutsideDtm.
  // Meeting the footprint but not the height slab: passing over it descending, see
  // leftTheGrid; pointing up, level above it, or starting below it: NoIntersection.
  double tEnter = 0.0;
  double tExit = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    const double o = originEnu[axis];
    const double d = directionEnu[axis];
    if (d == 0.0) {
      if (o < boxMin_[axis] || o > boxMax_[axis]) {
        return unexpected(axis < 2 ? TerrainError::OutsideDtm : TerrainError::NoIntersection);
      }
      continue;
    }
    double t0 = (boxMin_[axis] - o) / d;
    double t1 = (boxMax_[axis] - o) / d;
    if (t0 > t1) {
      std::swap(t0, t1);
    }
    tEnter = std::max(tEnter, t0);
    tExit = std::min(tExit, t1);
    if (tEnter > tExit) {
      if (axis < 2) {
        return unexpected(TerrainError::OutsideDtm);
      }
      return unexpected(o >= boxMin_.z() ? leftTheGrid : TerrainError::NoIntersection);
    }
  }

  // g(t) = geodetic height of the ray point minus the DTM height below it: the exact
  // surface condition, curvature included.
  const auto evaluate = [this, &originEnu, &directionEnu](double t, double* g) -> SampleKind {
    const geodesy::GeodeticPoint p = frame_.toGeodetic(originEnu + t * directionEnu);
    const Expected<double, TerrainError> h = heightAt(p.latitude_deg, p.longitude_deg);
    if (!h) {
      return h.error() == TerrainError::NoData ? SampleKind::NoData : SampleKind::Outside;
    }
    *g = p.height_m - *h;
    return SampleKind::Valid;
  };

  // 2. March with horizontal steps of at most half a cell, so a crossing of a bilinear
  // surface is missed only where the ray enters and leaves the ground within half a cell
  // (a sliver at a grazing angle); the first sign change is the nearest crossing. A
  // (near-)vertical ray has no horizontal motion: the slab clip alone bounds it, and g is
  // monotonic along it, so a few steps suffice.
  const double horizontal = directionEnu.head<2>().norm();
  const double span = tExit - tEnter;
  double step = span;
  if (horizontal > 0.0) {
    step = std::min(step, 0.5 * cellSizeM_ / horizontal);
  }
  step = std::max(step, span / kMaxMarchSteps);
  const int steps = step > 0.0 ? std::max(1, static_cast<int>(std::ceil(span / step))) : 1;
  step = span / steps;

  // State of the previous sample. A sign change is only trusted between two valid samples
  // (above ground, then below); below-ground samples after other states are classified:
  //  - first sample of the ray (origin inside the grid below the terrain, or the ray came
  //    up through the slab bottom): NoIntersection, the camera is under the DTM;
  //  - after samples outside the grid: the ray entered through the grid's side wall below
  //    the surface, so the real crossing lies outside the DTM: OutsideDtm;
  //  - after NoData samples: the crossing is in the hole: NoData.
  // Leaving the grid ends the march (its footprint is convex): see leftTheGrid, or NoData
  // if the ray crossed NoData since the last valid sample.
  enum class Previous { Start, Outside, NoData, Above };
  Previous previous = Previous::Start;
  bool everInside = false;
  double tAbove = 0.0;
  double gAbove = 0.0;
  for (int i = 0; i <= steps; ++i) {
    const double t = (i == steps) ? tExit : tEnter + i * step;
    double g = 0.0;
    const SampleKind kind = evaluate(t, &g);
    if (kind == SampleKind::Outside) {
      if (everInside) {
        return unexpected(previous == Previous::NoData ? TerrainError::NoData : leftTheGrid);
      }
      previous = Previous::Outside;
      continue;
    }
    everInside = true;
    if (kind == SampleKind::NoData) {
      previous = Previous::NoData;
      continue;
    }
    if (g > 0.0) {
      previous = Previous::Above;
      tAbove = t;
      gAbove = g;
      continue;
    }
    switch (previous) {
      case Previous::Start:
        if (g == 0.0) {
          return Eigen::Vector3d(originEnu + t * directionEnu);
        }
        return unexpected(TerrainError::NoIntersection);
      case Previous::Outside:
        return unexpected(TerrainError::OutsideDtm);
      case Previous::NoData:
        return unexpected(TerrainError::NoData);
      case Previous::Above:
        break;
    }
    // 3. Bisection on [tAbove, t] down to kBisectionTolerance_m along the ray, then one
    // secant step inside the final bracket (g is almost linear there) for the point.
    double tLo = tAbove;
    double gLo = gAbove;
    double tHi = t;
    double gHi = g;
    // The iteration cap only matters for absurd direction scales, where the tolerance in t
    // would fall below the spacing of doubles.
    for (int iteration = 0; iteration < 200 && (tHi - tLo) * dirNorm > kBisectionTolerance_m;
         ++iteration) {
      const double tMid = 0.5 * (tLo + tHi);
      double gMid = 0.0;
      const SampleKind midKind = evaluate(tMid, &gMid);
      if (midKind != SampleKind::Valid) {
        // The bracket touches a cell with a NoData corner that neither end touched.
        return unexpected(midKind == SampleKind::NoData ? TerrainError::NoData
                                                        : TerrainError::OutsideDtm);
      }
      if (gMid > 0.0) {
        tLo = tMid;
        gLo = gMid;
      } else {
        tHi = tMid;
        gHi = gMid;
      }
    }
    const double denom = gLo - gHi;
    const double tHit = denom > 0.0 ? tLo + (tHi - tLo) * gLo / denom : 0.5 * (tLo + tHi);
    return Eigen::Vector3d(originEnu + tHit * directionEnu);
  }
  if (!everInside) {
    return unexpected(TerrainError::OutsideDtm);
  }
  return unexpected(previous == Previous::NoData ? TerrainError::NoData : leftTheGrid);
}

Expected<geodesy::GeodeticPoint, TerrainError> TerrainModel::samplePosition(int col,
                                                                            int row) const {
  if (col < 0 || row < 0 || col >= grid_.cols || row >= grid_.rows) {
    return unexpected(TerrainError::OutsideDtm);
  }
  const GeoTransform& t = grid_.transform;
  const double x = t.x0 + col * t.dxCol + row * t.dxRow;
  const double y = t.y0 + col * t.dyCol + row * t.dyRow;
  geodesy::GeodeticPoint p;
  if (grid_.crs.kind == HorizontalCrs::Utm) {
    geodesy::UtmPoint u;
    u.zone = grid_.crs.utmZone;
    u.northp = grid_.crs.utmNorth;
    u.easting_m = x;
    u.northing_m = y;
    try {
      p = geodesy::fromUtm(u);
    } catch (const std::exception&) {
      return unexpected(TerrainError::OutsideDtm);  // init() refused grids beyond their zone
    }
  } else {
    p.latitude_deg = y;
    p.longitude_deg = x;
  }
  p.height_m = static_cast<double>(
      grid_.heights_m[static_cast<std::size_t>(row) * static_cast<std::size_t>(grid_.cols) +
                      static_cast<std::size_t>(col)]);
  return p;
}

namespace {

constexpr int kCoverageLattice = 256;  // samples per axis looked at, at most

void extend(const Eigen::Vector2d& point, std::size_t count, Eigen::Vector2d& lo,
            Eigen::Vector2d& hi) {
  if (count == 1) {
    lo = hi = point;
    return;
  }
  lo = lo.cwiseMin(point);
  hi = hi.cwiseMax(point);
}

}  // namespace

Coverage coverage(const TerrainModel& covered, const TerrainModel& cover) {
  Coverage out;
  const TerrainGrid& grid = covered.grid();
  if (grid.cols < 2 || grid.rows < 2) {
    return out;
  }
  const int colSteps = std::min(grid.cols, kCoverageLattice);
  const int rowSteps = std::min(grid.rows, kCoverageLattice);
  for (int j = 0; j < rowSteps; ++j) {
    const int row = static_cast<int>(
        std::lround(static_cast<double>(j) * (grid.rows - 1) / std::max(1, rowSteps - 1)));
    for (int i = 0; i < colSteps; ++i) {
      const int col = static_cast<int>(
          std::lround(static_cast<double>(i) * (grid.cols - 1) / std::max(1, colSteps - 1)));
      const auto p = covered.samplePosition(col, row);
      if (!p) {
        continue;
      }
      const float h = static_cast<float>(p->height_m);
      if (!std::isfinite(h) || (grid.noData && h == *grid.noData)) {
        continue;  // the covered model has no height there: nothing to compare
      }
      ++out.checked;
      const auto other = cover.heightAt(p->latitude_deg, p->longitude_deg);
      if (other) {
        continue;
      }
      const Eigen::Vector2d enu = covered.frame().toEnu(*p).head<2>();
      if (other.error() == TerrainError::NoData) {
        extend(enu, ++out.noData, out.noDataMin_m, out.noDataMax_m);
      } else {
        extend(enu, ++out.outside, out.outsideMin_m, out.outsideMax_m);
      }
    }
  }
  return out;
}

}  // namespace vp::terrain
