// Test helpers of the scene tests: the three scene kinds, the equality of two furniture items,
// and the site checks every kind of street furniture and road user must pass.
#pragma once

#include <array>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scene.hpp"

namespace vp::sim::testing {

inline constexpr std::array<SceneKind, 3> kSceneKinds = {SceneKind::Intersection,
                                                         SceneKind::Straight, SceneKind::Parking};

// The same item, drawn alike: kind, site, size, row or group count, colour and seed.
inline bool sameItem(const StreetFurniture& x, const StreetFurniture& y) {
  return x.kind == y.kind && x.centre == y.centre && x.heading_rad == y.heading_rad &&
         x.length_m == y.length_m && x.width_m == y.width_m && x.height_m == y.height_m &&
         x.count == y.count && x.albedo == y.albedo && x.seed == y.seed;
}

// Every point of the item's footprint (a 5 x 5 grid over it) lies behind the kerb with the
// documented 0.6 m clearance (on no lane, parking lane, lot or driveway), and the footprint
// overlaps no building; `where` names the scene in the failure messages.
inline void expectOffTheRoadsAndBuildings(const SceneSpec& scene, const StreetFurniture& item,
                                          const std::string& where) {
  const Footprint f = footprintOf(item);
  const Eigen::Vector2d n(-f.axis.y(), f.axis.x());
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      const Eigen::Vector2d p =
          f.centre + (0.5 * i) * f.halfLength_m * f.axis + (0.5 * j) * f.halfWidth_m * n;
      EXPECT_GE(scene.roadDistance(p), scene.kerbWidth_m + 0.59)
          << toString(item.kind) << " on the drivable area, " << where;
    }
  }
  for (const Building& b : scene.buildings) {
    const Footprint fb{b.centre,
                       {std::cos(b.heading_rad), std::sin(b.heading_rad)},
                       0.5 * b.length_m,
                       0.5 * b.width_m};
    EXPECT_FALSE(footprintsOverlap(f, fb, 0.0))
        << toString(item.kind) << " inside a building, " << where;
  }
}

}  // namespace vp::sim::testing
