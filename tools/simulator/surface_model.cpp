// tools/simulator/surface_model: buildings rasterised onto the DTM's samples.
#include "surface_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace vp::sim {

namespace {

constexpr double kNone = -1e9;
constexpr double kGableOverhang_m = 0.35;  // the renderer's eaves overhang of gabled roofs

// Lowest and highest ground (ENU z) under the footprint, as the renderer places the walls.
void groundRange(const Building& b, const World& world, double* lo, double* hi) {
  const Eigen::Vector2d f(std::cos(b.heading_rad), std::sin(b.heading_rad));
  const Eigen::Vector2d n(-f.y(), f.x());
  *lo = 1e9;
  *hi = -1e9;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      const Eigen::Vector2d p = b.centre + 0.5 * i * b.length_m * f + 0.5 * j * b.width_m * n;
      const double z = world.groundZ(p.x(), p.y());
      *lo = std::min(*lo, z);
      *hi = std::max(*hi, z);
    }
  }
}

}  // namespace

double roofZ(const Building& b, const World& world, const Eigen::Vector2d& p) {
  const Eigen::Vector2d f(std::cos(b.heading_rad), std::sin(b.heading_rad));
  const Eigen::Vector2d n(-f.y(), f.x());
  const Eigen::Vector2d d = p - b.centre;
  const double along = d.dot(f);
  const double across = d.dot(n);
  const double hl = 0.5 * b.length_m;
  const double hw = 0.5 * b.width_m;
  const bool gabled = b.roof == RoofKind::Gabled;
  const double overhang = gabled ? kGableOverhang_m : 0.0;
  if (std::abs(along) > hl + overhang || std::abs(across) > hw + overhang) {
    return kNone;
  }
  double lo = 0.0;
  double hi = 0.0;
  groundRange(b, world, &lo, &hi);
  const double eaves = hi + b.height_m;
  double z = gabled ? eaves + b.ridgeHeight_m * (1.0 - std::abs(across) / hw) : eaves;
  for (const RoofFixture& fixture : b.fixtures) {
    if (fixture.height_m <= 0.0 || std::abs(along - fixture.along_m) > 0.5 * fixture.length_m ||
        std::abs(across - fixture.across_m) > 0.5 * fixture.width_m) {
      continue;
    }
    const double base =
        gabled ? eaves + b.ridgeHeight_m * (1.0 - std::abs(fixture.across_m) / hw) : eaves;
    z = std::max(z, base + fixture.height_m);
  }
  return z;
}

terrain::TerrainGrid surfaceGrid(const SceneSpec& scene, const World& world) {
  const terrain::TerrainModel& dtm = world.terrain();
  terrain::TerrainGrid grid = dtm.grid();
  // Each building's east/north box first, so a sample looks only at the buildings near it.
  struct Box {
    Eigen::Vector2d lo;
    Eigen::Vector2d hi;
  };
  std::vector<Box> boxes;
  boxes.reserve(scene.buildings.size());
  for (const Building& b : scene.buildings) {
    const double r = 0.5 * std::hypot(b.length_m, b.width_m) + kGableOverhang_m + 0.1;
    boxes.push_back({b.centre - Eigen::Vector2d(r, r), b.centre + Eigen::Vector2d(r, r)});
  }
  for (int row = 0; row < grid.rows; ++row) {
    for (int col = 0; col < grid.cols; ++col) {
      const auto sample = dtm.samplePosition(col, row);
      if (!sample) {
        continue;
      }
      const float h = static_cast<float>(sample->height_m);
      if (!std::isfinite(h) || (grid.noData && h == *grid.noData)) {
        continue;
      }
      const Eigen::Vector3d enu = world.frame().toEnu(*sample);
      const Eigen::Vector2d p = enu.head<2>();
      double top = kNone;
      for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
        if ((p.array() < boxes[i].lo.array()).any() || (p.array() > boxes[i].hi.array()).any()) {
          continue;
        }
        top = std::max(top, roofZ(scene.buildings[i], world, p));
      }
      if (top > enu.z()) {
        // ENU z and ellipsoidal height rise alike over a building's height.
        grid.heights_m[static_cast<std::size_t>(row) * static_cast<std::size_t>(grid.cols) +
                       static_cast<std::size_t>(col)] =
            static_cast<float>(sample->height_m + (top - enu.z()));
      }
    }
  }
  return grid;
}

}  // namespace vp::sim
