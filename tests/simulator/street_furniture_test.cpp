// Tests of the simulator's street furniture (benches, shelters, kiosks, stair entrances, and
// the opt-in sign posts and street lamps): the same seed gives the same furniture, different
// seeds different furniture; every item stands off the drivable area with its kerb clearance
// and clear of buildings; no vehicle, parked or moving, ever overlaps one; sizes stay within
// the real objects' ranges; the poles leave the rest of a seed's scene as it was.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <string>

#include "furniture_checks.hpp"
#include "scene.hpp"
#include "traffic_walk.hpp"

namespace {

using vp::sim::FurnitureKind;
using vp::sim::SceneKind;
using vp::sim::SceneSpec;

constexpr auto& kKinds = vp::sim::testing::kSceneKinds;

SceneSpec sceneFor(SceneKind kind, std::uint64_t seed, bool poles = false) {
  vp::sim::Rng rng(seed);
  SceneSpec scene = vp::sim::generateScene(kind, rng);
  if (poles) {
    vp::sim::addPoles(scene);
  }
  return scene;
}

bool sameFurniture(const SceneSpec& a, const SceneSpec& b) {
  if (a.furniture.size() != b.furniture.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.furniture.size(); ++i) {
    if (!vp::sim::testing::sameItem(a.furniture[i], b.furniture[i])) {
      return false;
    }
  }
  return true;
}

TEST(StreetFurniture, SameSeedSameSceneDifferentSeedDifferentScene) {
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
      const SceneSpec a = sceneFor(kind, seed);
      const SceneSpec b = sceneFor(kind, seed);
      EXPECT_TRUE(sameFurniture(a, b)) << toString(kind) << " seed " << seed;
      const SceneSpec c = sceneFor(kind, seed + 1000);
      EXPECT_FALSE(sameFurniture(a, c))
          << toString(kind) << " seeds " << seed << ", " << seed + 1000;
    }
  }
}

TEST(StreetFurniture, OffTheLanesClearOfBuildingsWithRealSizes) {
  std::map<FurnitureKind, int> counts;
  int facingTraffic = 0;
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 30; ++seed) {
      const SceneSpec scene = sceneFor(kind, seed, /*poles=*/true);
      for (const auto& item : scene.furniture) {
        ++counts[item.kind];
        if (item.kind == FurnitureKind::SignPost) {
          // Facing the traffic: the plate's axis across the nearest road.
          double best = 1e9;
          double across = 0.0;
          for (const auto& road : scene.roads) {
            const double d = std::fabs(road.lateral(item.centre));
            if (d < best) {
              best = d;
              across = std::fabs(item.axis().dot(road.leftNormal()));
            }
          }
          facingTraffic += across > 0.7 ? 1 : 0;
        }
        vp::sim::testing::expectOffTheRoadsAndBuildings(
            scene, item, std::string(toString(kind)) + " seed " + std::to_string(seed));
        switch (item.kind) {
          case FurnitureKind::Bench:
            EXPECT_TRUE(item.length_m >= 1.5 && item.length_m <= 2.2) << item.length_m;
            EXPECT_TRUE(item.width_m >= 0.5 && item.width_m <= 0.7) << item.width_m;
            break;
          case FurnitureKind::Shelter:
            EXPECT_TRUE(item.length_m >= 3.0 && item.length_m <= 6.0) << item.length_m;
            EXPECT_TRUE(item.width_m >= 1.5 && item.width_m <= 2.0) << item.width_m;
            break;
          case FurnitureKind::SignPost:  // the plate's width; its top 2.6-3.6 m up
            EXPECT_TRUE(item.length_m >= 0.6 && item.length_m <= 0.9) << item.length_m;
            EXPECT_TRUE(item.height_m >= 2.6 && item.height_m <= 3.6) << item.height_m;
            break;
          case FurnitureKind::StreetLamp:
            EXPECT_TRUE(item.height_m >= 6.0 && item.height_m <= 10.0) << item.height_m;
            EXPECT_TRUE(item.reach_m >= 0.8 && item.reach_m <= 2.5) << item.reach_m;
            break;
          default:
            EXPECT_TRUE(item.length_m >= 1.5 && item.length_m <= 8.0) << item.length_m;
            break;
        }
      }
    }
  }
  // Every kind is placed (the density is documented per pavement and per scene).
  for (const FurnitureKind k :
       {FurnitureKind::Bench, FurnitureKind::Shelter, FurnitureKind::Kiosk,
        FurnitureKind::StairEntrance, FurnitureKind::SignPost, FurnitureKind::StreetLamp}) {
    EXPECT_GT(counts[k], 0) << toString(k) << " never placed in 90 scenes";
  }
  EXPECT_GT(counts[FurnitureKind::Bench], 90) << "fewer than one bench per scene";
  EXPECT_GT(counts[FurnitureKind::SignPost], 180) << "fewer than two sign posts per scene";
  EXPECT_GT(facingTraffic, counts[FurnitureKind::SignPost] / 3)
      << "sign plates facing the traffic are mostly dropped by the site check";
  EXPECT_GT(counts[FurnitureKind::StreetLamp], 180) << "fewer than two street lamps per scene";
}

TEST(StreetFurniture, NoVehicleEverOverlapsFurniture) {
  long checked = 0;
  long near = 0;  // vehicle-furniture pairs within 3 m: the test sees close calls
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      vp::sim::Rng rng(seed);
      SceneSpec scene = vp::sim::generateScene(kind, rng);
      vp::sim::addPoles(scene);
      vp::sim::testing::walkTraffic(scene, rng, [&](const auto& v, const auto& fv, int step) {
        for (const auto& item : scene.furniture) {
          const vp::sim::Footprint fi = vp::sim::footprintOf(item);
          ++checked;
          EXPECT_FALSE(vp::sim::footprintsOverlap(fv, fi, 0.0))
              << "vehicle " << v.trackId << (v.parked ? " (parked)" : "") << " overlaps a "
              << toString(item.kind) << ", " << toString(kind) << " seed " << seed << " step "
              << step;
          near += vp::sim::footprintsOverlap(fv, fi, 1.5) ? 1 : 0;
        }
      });
    }
  }
  EXPECT_GT(checked, 100000);
  EXPECT_GT(near, 0) << "no vehicle ever came within 3 m of furniture: the test proves little";
}

TEST(StreetFurniture, PolesAreAddedAfterTheSceneAndChangeNothingElse) {
  std::size_t added = 0;
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const SceneSpec plain = sceneFor(kind, seed);
      const SceneSpec poles = sceneFor(kind, seed, /*poles=*/true);
      ASSERT_GE(poles.furniture.size(), plain.furniture.size()) << toString(kind) << " " << seed;
      added += poles.furniture.size() - plain.furniture.size();
      SceneSpec firstPart = poles;
      firstPart.furniture.resize(plain.furniture.size());
      EXPECT_TRUE(sameFurniture(plain, firstPart)) << toString(kind) << " seed " << seed;
      for (std::size_t i = plain.furniture.size(); i < poles.furniture.size(); ++i) {
        const FurnitureKind k = poles.furniture[i].kind;
        EXPECT_TRUE(k == FurnitureKind::SignPost || k == FurnitureKind::StreetLamp) << toString(k);
      }
      EXPECT_EQ(plain.buildings.size(), poles.buildings.size());
      EXPECT_EQ(plain.trees.size(), poles.trees.size());
      EXPECT_EQ(plain.light.sunAzimuth_deg, poles.light.sunAzimuth_deg);
      EXPECT_TRUE(sameFurniture(poles, sceneFor(kind, seed, /*poles=*/true)));
    }
  }
  EXPECT_GT(added, 18U * 4U) << "fewer than four poles per scene";
}

TEST(StreetFurniture, FootprintOverlapIsASeparatingAxisTest) {
  const vp::sim::Footprint a{{0.0, 0.0}, {1.0, 0.0}, 2.0, 1.0};
  // Rotated by 45 degrees, corner pointing at a: separate at 3.5 m, overlapping at 2.9 m.
  const Eigen::Vector2d diag(std::sqrt(0.5), std::sqrt(0.5));
  EXPECT_FALSE(
      vp::sim::footprintsOverlap(a, {{2.0 + std::sqrt(2.0) + 0.1, 0.0}, diag, 1.0, 1.0}, 0.0));
  EXPECT_TRUE(
      vp::sim::footprintsOverlap(a, {{2.0 + std::sqrt(2.0) - 0.1, 0.0}, diag, 1.0, 1.0}, 0.0));
  // The margin grows both: 0.2 m apart touches with a 0.1 m margin each.
  EXPECT_FALSE(vp::sim::footprintsOverlap(a, {{0.0, 2.2}, {1.0, 0.0}, 2.0, 1.0}, 0.09));
  EXPECT_TRUE(vp::sim::footprintsOverlap(a, {{0.0, 2.2}, {1.0, 0.0}, 2.0, 1.0}, 0.11));
}

}  // namespace
