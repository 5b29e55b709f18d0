#include "world.hpp"

#include <cmath>
#include <vector>

namespace vp::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

const char* toString(ReliefKind kind) {
  switch (kind) {
    case ReliefKind::Flat:
      return "flat";
    case ReliefKind::Slope:
      return "slope";
    case ReliefKind::Undulating:
      return "undulating";
  }
  return "unknown";
}

TerrainSpec drawTerrain(Rng& rng) {
  TerrainSpec spec;
  const double draw = rng.uniform();
  spec.kind =
      draw < 0.3 ? ReliefKind::Flat : (draw < 0.65 ? ReliefKind::Slope : ReliefKind::Undulating);
  spec.cell_m = rng.chance(0.5) ? 0.5 : 1.0;
  if (spec.kind != ReliefKind::Flat) {
    const double grade = rng.uniform(0.0, spec.kind == ReliefKind::Slope ? 0.045 : 0.02);
    const double a = rng.uniform(0.0, 2.0 * kPi);
    spec.gradient = grade * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  if (spec.kind == ReliefKind::Undulating) {
    for (std::size_t i = 0; i < spec.waves.size(); ++i) {
      const double lambda = rng.uniform(40.0, 200.0);
      const double a = rng.uniform(0.0, 2.0 * kPi);
      const double k = 2.0 * kPi / lambda;
      // Amplitude bounded so the slope stays below ~5 %.
      const double amplitude = std::min(rng.uniform(0.1, 1.2), 0.015 / k);
      spec.waves[i] = Eigen::Vector3d(k * std::cos(a), k * std::sin(a), amplitude);
      spec.phases[i] = rng.uniform(0.0, 2.0 * kPi);
    }
  }
  return spec;
}

geodesy::GeodeticPoint drawOrigin(Rng& rng) {
  geodesy::GeodeticPoint origin;
  origin.latitude_deg = 43.0731 + rng.uniform(-0.01, 0.01);
  origin.longitude_deg = -89.4012 + rng.uniform(-0.013, 0.013);
  origin.height_m = 230.0 + rng.uniform(0.0, 40.0);  // ellipsoidal (geoid ~ -33 m there)
  return origin;
}

double World::relief(double x, double y) const {
  double h = spec_.gradient.x() * x + spec_.gradient.y() * y;
  for (std::size_t i = 0; i < spec_.waves.size(); ++i) {
    const Eigen::Vector3d& w = spec_.waves[i];
    if (w.z() != 0.0) {
      h += w.z() * std::sin(w.x() * x + w.y() * y + spec_.phases[i]);
    }
  }
  return h;
}

bool World::build(const geodesy::GeodeticPoint& origin, const TerrainSpec& spec,
                  const Eigen::Vector2d& centre, double halfSize_m, std::string* why) {
  spec_ = spec;
  frame_ = geodesy::LocalFrame(origin);
  terrain::TerrainGrid grid;
  const geodesy::UtmPoint centreUtm =
      geodesy::toUtm(frame_.toGeodetic({centre.x(), centre.y(), 0.0}));
  grid.crs.kind = terrain::HorizontalCrs::Utm;
  grid.crs.utmZone = centreUtm.zone;
  grid.crs.utmNorth = centreUtm.northp;
  // UTM grid north differs from true north by the meridian convergence (< 2 deg here):
  // 6 % extra covers the ENU square.
  const double half = halfSize_m * 1.06;
  const double cell = spec.cell_m;
  grid.cols = static_cast<int>(std::ceil(2.0 * half / cell)) + 1;
  grid.rows = grid.cols;
  grid.transform.x0 = std::floor((centreUtm.easting_m - half) / cell) * cell + 0.5 * cell;
  grid.transform.dxCol = cell;
  grid.transform.dxRow = 0.0;
  grid.transform.y0 = std::floor((centreUtm.northing_m + half) / cell) * cell + 0.5 * cell;
  grid.transform.dyCol = 0.0;
  grid.transform.dyRow = -cell;
  grid.heights_m.resize(static_cast<std::size_t>(grid.cols) * static_cast<std::size_t>(grid.rows));
  // ENU position of each sample centre: exact (GeographicLib) on a lattice every kStep
  // samples, bilinear in between; the UTM -> ENU map is affine to well below a millimetre
  // over a few metres, and this is ~100 times faster than converting every sample.
  constexpr int kStep = 16;
  const int lc = (grid.cols + kStep - 1) / kStep + 1;
  const int lr = (grid.rows + kStep - 1) / kStep + 1;
  std::vector<Eigen::Vector2d> lattice(static_cast<std::size_t>(lc) * static_cast<std::size_t>(lr));
  for (int j = 0; j < lr; ++j) {
    for (int i = 0; i < lc; ++i) {
      geodesy::UtmPoint u = centreUtm;
      u.easting_m = grid.transform.x0 + i * kStep * cell;
      u.northing_m = grid.transform.y0 - j * kStep * cell;
      const geodesy::GeodeticPoint g = geodesy::fromUtm(u);
      lattice[static_cast<std::size_t>(j) * static_cast<std::size_t>(lc) +
              static_cast<std::size_t>(i)] =
          frame_.toEnu({g.latitude_deg, g.longitude_deg, origin.height_m}).head<2>();
    }
  }
  const auto at = [&](int i, int j) -> const Eigen::Vector2d& {
    return lattice[static_cast<std::size_t>(j) * static_cast<std::size_t>(lc) +
                   static_cast<std::size_t>(i)];
  };
  for (int r = 0; r < grid.rows; ++r) {
    const int j = r / kStep;
    const double tr = static_cast<double>(r - j * kStep) / kStep;
    for (int c = 0; c < grid.cols; ++c) {
      const int i = c / kStep;
      const double tc = static_cast<double>(c - i * kStep) / kStep;
      const Eigen::Vector2d enu = (1 - tr) * ((1 - tc) * at(i, j) + tc * at(i + 1, j)) +
                                  tr * ((1 - tc) * at(i, j + 1) + tc * at(i + 1, j + 1));
      grid.heights_m[static_cast<std::size_t>(r) * static_cast<std::size_t>(grid.cols) +
                     static_cast<std::size_t>(c)] =
          static_cast<float>(origin.height_m + relief(enu.x(), enu.y()));
    }
  }
  return terrain_.init(std::move(grid), frame_, why);
}

double World::groundZ(double x, double y) const {
  const auto p = terrain_.groundPointEnu(x, y);
  if (p) {
    return p->z();
  }
  // Off the DTM (far traffic only): the analytic relief with the curvature drop.
  return relief(x, y) - (x * x + y * y) / (2.0 * 6378137.0);
}

}  // namespace vp::sim
