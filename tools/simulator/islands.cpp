// Raised traffic islands in road medians (vp_simulate --islands): dividers on a junction's
// approaches, pedestrian refuges at crossings and at mid-block. Real drone footage shows the
// detector boxing a planted island of a car's size (grass, weeds, a bush and the shadow of its
// sign post); the simulator draws such islands so that training sees them as background. Sizes
// follow common practice: 1.2-3 m wide, 6-30 m long, pointed noses of 1-4 m, a keep-right sign
// at the nose that faces the traffic.
#include <algorithm>
#include <array>
#include <cmath>

#include "scene.hpp"

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Share of roads whose median gets islands, per scene kind (an intersection's two roads are
// drawn one by one).
constexpr double kIslandRoadShare = 0.6;

// A bush (or a small tree) on a planted island: a low canopy on a thin stem.
Tree makeBush(const SceneSpec& scene, Rng& rng, const Eigen::Vector2d& position, double radius,
              bool smallTree) {
  Tree t;
  t.position = position;
  t.canopyRadius_m = radius;
  if (smallTree) {
    t.canopyVerticalRadius_m = radius * rng.uniform(0.6, 0.9);
    t.canopyCentreHeight_m = t.canopyVerticalRadius_m + rng.uniform(1.5, 3.0);
    t.trunkRadius_m = rng.uniform(0.06, 0.12);
  } else {
    t.canopyVerticalRadius_m = radius * rng.uniform(0.45, 0.8);
    t.canopyCentreHeight_m = t.canopyVerticalRadius_m + rng.uniform(0.05, 0.3);
    t.trunkRadius_m = 0.03;
  }
  if (scene.season == "winter") {
    t.leafAlbedo = toneColour(rng, Eigen::Vector3f(0.13F, 0.11F, 0.08F), 0.15);
    t.gapFraction = static_cast<float>(rng.uniform(0.4, 0.7));
  } else if (scene.season == "autumn") {
    t.leafAlbedo = toneColour(rng, Eigen::Vector3f(0.25F, 0.18F, 0.05F), 0.25);
    t.gapFraction = static_cast<float>(rng.uniform(0.05, 0.3));
  } else {
    t.leafAlbedo = toneColour(rng, Eigen::Vector3f(0.07F, 0.14F, 0.04F), 0.25);
    t.gapFraction = static_cast<float>(rng.uniform(0.0, 0.15));
  }
  t.seed = rng.nextU32();
  return t;
}

// A sign post standing on the island near the nose at along offset noseAlong_m from the
// island's centre, its plate facing the traffic that drives towards that nose.
StreetFurniture keepRightSign(Rng& rng, const Island& island, double noseAlong_m) {
  StreetFurniture sign;
  sign.kind = FurnitureKind::SignPost;
  sign.centre = island.centre + noseAlong_m * island.dir;
  sign.length_m = rng.uniform(0.45, 0.7);  // plate width
  sign.width_m = 0.12;
  sign.height_m = rng.uniform(1.8, 2.8);
  static const std::array<Eigen::Vector3f, 3> kPlates = {Eigen::Vector3f(0.05F, 0.15F, 0.5F),
                                                         Eigen::Vector3f(0.75F, 0.75F, 0.72F),
                                                         Eigen::Vector3f(0.6F, 0.1F, 0.08F)};
  sign.roofAlbedo = toneColour(rng, kPlates[static_cast<std::size_t>(rng.uniformInt(0, 2))], 0.1);
  sign.albedo = toneColour(rng, Eigen::Vector3f(0.45F, 0.46F, 0.47F), 0.15);  // the pole
  // The plate's front faces +left normal of its length axis; traffic driving along +dir meets
  // the nose at the island's low-along end, so that plate faces -dir.
  const double roadHeading = std::atan2(island.dir.y(), island.dir.x());
  sign.heading_rad = roadHeading + (noseAlong_m < 0.0 ? 0.5 * kPi : -0.5 * kPi);
  sign.seed = rng.nextU32();
  return sign;
}

void plant(SceneSpec& scene, Rng& rng, const Island& island) {
  const Eigen::Vector2d across(-island.dir.y(), island.dir.x());
  // Half length of the part at full width (bushes stand there).
  const double body = island.halfLength_m - 0.5 * (island.noseLength_m + island.noseHighLength_m);
  if (island.planted && rng.chance(0.55)) {
    const bool smallTree = island.halfWidth_m > 0.9 && rng.chance(0.25);
    const int count = smallTree ? 1 : rng.uniformInt(1, 4);
    for (int i = 0; i < count; ++i) {
      const double radius = smallTree ? rng.uniform(1.2, 2.2)
                                      : rng.uniform(0.35, std::max(0.4, island.halfWidth_m - 0.1));
      const double along = 0.5 * (island.noseLength_m - island.noseHighLength_m) +
                           rng.uniform(-std::max(0.0, body - 0.3), std::max(0.0, body - 0.3));
      const double lateral = rng.uniform(-0.3, 0.3) * island.halfWidth_m;
      scene.trees.push_back(makeBush(
          scene, rng, island.centre + along * island.dir + lateral * across, radius, smallTree));
    }
  }
  // Keep-right signs at the noses (each nose faces the traffic of one direction).
  const auto inset = [&](double nose) {
    return island.halfLength_m - std::min(1.0, 0.6 * nose) - 0.3 - (nose > 0.0 ? 0.0 : 0.2);
  };
  if (rng.chance(0.8)) {
    scene.furniture.push_back(keepRightSign(rng, island, -inset(island.noseLength_m)));
  }
  if (rng.chance(0.5)) {
    scene.furniture.push_back(keepRightSign(rng, island, inset(island.noseHighLength_m)));
  }
}

Island makeIsland(Rng& rng, const Road& road, double centreAlong_m, double length_m) {
  Island island;
  island.dir = road.dir;
  island.centre = road.centre + centreAlong_m * road.dir;
  island.halfLength_m = 0.5 * length_m;
  island.halfWidth_m = road.islandHalfWidth_m;
  island.noseLength_m = std::min(rng.uniform(1.0, 4.0), 0.35 * length_m);
  island.noseHighLength_m = island.noseLength_m;
  if (rng.chance(0.3)) {
    // A wedge: blunt at one end, tapering over most of its length to the other.
    const double longNose = rng.uniform(0.4, 0.8) * length_m;
    island.noseLength_m = rng.chance(0.5) ? 0.0 : longNose;
    island.noseHighLength_m = island.noseLength_m > 0.0 ? 0.0 : longNose;
  }
  island.planted = rng.chance(0.7);
  return island;
}

}  // namespace

double Island::distance(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d q = p - centre;
  const double a = q.dot(dir);
  const double u = std::fabs(a);
  const double v = std::fabs(q.x() * -dir.y() + q.y() * dir.x());
  const double nose = a < 0.0 ? noseLength_m : noseHighLength_m;
  // The taper: the line from (halfLength - nose, halfWidth) to the tip (halfLength, 0).
  const double taper = ((u - (halfLength_m - nose)) * halfWidth_m + v * nose - halfWidth_m * nose) /
                       std::hypot(nose, halfWidth_m);
  return std::max({v - halfWidth_m, u - halfLength_m, taper});
}

void widenMedians(SceneSpec& scene, Rng& rng) {
  for (Road& road : scene.roads) {
    if (!rng.chance(kIslandRoadShare)) {
      continue;
    }
    road.islandHalfWidth_m = rng.uniform(0.6, 2.0);
    // Room between the island's kerb and the innermost lanes, whose vehicles run at the lane
    // centres: the lane lines sit just outside the kerb.
    road.medianHalf_m = road.islandHalfWidth_m + rng.uniform(0.25, 0.6);
    road.centreLine = CentreLine::DoubleYellow;
    road.medianHatch = rng.chance(0.5);
  }
}

void addIslands(SceneSpec& scene, Rng& rng) {
  for (const Road& road : scene.roads) {
    if (road.islandHalfWidth_m <= 0.0) {
      continue;
    }
    if (scene.kind == SceneKind::Intersection) {
      // Dividers on the approaches, from just behind the stop line outwards.
      const bool lowSide = rng.chance(0.75);
      const bool highSide = !lowSide || rng.chance(0.75);
      for (const int side : {-1, 1}) {
        if ((side < 0 && !lowSide) || (side > 0 && !highSide)) {
          continue;
        }
        const double start = road.stopDistance_m + rng.uniform(0.5, 3.0);
        const double length = rng.uniform(6.0, 25.0);
        scene.islands.push_back(makeIsland(rng, road, side * (start + 0.5 * length), length));
      }
    } else if (road.crosswalkCentre_m < 1e8) {
      // A refuge for the pedestrians of the mid-block crossing.
      const double length = road.crosswalkWidth_m + rng.uniform(4.0, 14.0);
      scene.islands.push_back(makeIsland(rng, road, road.crosswalkCentre_m, length));
    } else {
      const int count = rng.uniformInt(1, 2);
      const double first = road.along(scene.viewCentre) + rng.uniform(-30.0, 10.0);
      double along = first;
      for (int i = 0; i < count; ++i) {
        const double length = rng.uniform(8.0, 30.0);
        scene.islands.push_back(makeIsland(rng, road, along + 0.5 * length, length));
        along += length + rng.uniform(10.0, 30.0);
      }
    }
  }
  for (const Island& island : scene.islands) {
    plant(scene, rng, island);
  }
}

}  // namespace vp::sim
