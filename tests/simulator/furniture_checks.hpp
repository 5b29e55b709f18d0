// Test helper: the site checks every kind of street furniture and road user must pass.
#pragma once

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scene.hpp"

namespace vp::sim::testing {

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
