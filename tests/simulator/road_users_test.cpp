// Tests of the simulator's road users that are not vehicles (vp_simulate --road-users: rows of
// parked motorbikes, bicycle racks, groups of pedestrians): they are added after the seed's
// scene and change nothing else in it; they stand off the drivable area, clear of buildings,
// with the sizes of real machines and people; no vehicle ever overlaps one; rendered, they are
// in the furniture list (background), never in the vehicle ground truth.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "furniture_checks.hpp"
#include "scene.hpp"
#include "sim_render.hpp"
#include "simulator.hpp"
#include "traffic_walk.hpp"

namespace {

namespace fs = std::filesystem;
using vp::sim::FurnitureKind;
using vp::sim::SceneKind;
using vp::sim::SceneSpec;

constexpr auto& kKinds = vp::sim::testing::kSceneKinds;

SceneSpec sceneFor(SceneKind kind, std::uint64_t seed, bool roadUsers) {
  vp::sim::Rng rng(seed);
  SceneSpec scene = vp::sim::generateScene(kind, rng);
  if (roadUsers) {
    vp::sim::addRoadUsers(scene);
  }
  return scene;
}

bool isRoadUser(FurnitureKind k) {
  return k == FurnitureKind::Motorbikes || k == FurnitureKind::Bicycles ||
         k == FurnitureKind::Pedestrians;
}

TEST(RoadUsers, AddedAfterTheSceneAndChangeNothingElse) {
  std::size_t added = 0;
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      const SceneSpec plain = sceneFor(kind, seed, false);
      const SceneSpec with = sceneFor(kind, seed, true);
      ASSERT_GE(with.furniture.size(), plain.furniture.size()) << toString(kind) << " " << seed;
      for (std::size_t i = 0; i < plain.furniture.size(); ++i) {
        EXPECT_TRUE(vp::sim::testing::sameItem(plain.furniture[i], with.furniture[i]))
            << toString(kind) << " seed " << seed << " item " << i;
      }
      for (std::size_t i = plain.furniture.size(); i < with.furniture.size(); ++i) {
        EXPECT_TRUE(isRoadUser(with.furniture[i].kind)) << toString(with.furniture[i].kind);
      }
      added += with.furniture.size() - plain.furniture.size();
      EXPECT_EQ(plain.buildings.size(), with.buildings.size());
      EXPECT_EQ(plain.trees.size(), with.trees.size());
      EXPECT_EQ(plain.light.sunAzimuth_deg, with.light.sunAzimuth_deg);
      // Deterministic: the same seed draws the same road users.
      const SceneSpec again = sceneFor(kind, seed, true);
      ASSERT_EQ(again.furniture.size(), with.furniture.size());
      for (std::size_t i = 0; i < with.furniture.size(); ++i) {
        EXPECT_TRUE(vp::sim::testing::sameItem(again.furniture[i], with.furniture[i]));
      }
    }
  }
  EXPECT_GT(added, 18U * 8U) << "fewer than eight rows or groups per scene";
}

TEST(RoadUsers, OffTheLanesClearOfBuildingsWithRealSizes) {
  std::map<FurnitureKind, int> counts;
  std::map<FurnitureKind, int> members;
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 30; ++seed) {
      const SceneSpec scene = sceneFor(kind, seed, true);
      for (const auto& item : scene.furniture) {
        if (!isRoadUser(item.kind)) {
          continue;
        }
        ++counts[item.kind];
        members[item.kind] += item.count;
        vp::sim::testing::expectOffTheRoadsAndBuildings(
            scene, item, std::string(toString(kind)) + " seed " + std::to_string(seed));
        switch (item.kind) {
          case FurnitureKind::Motorbikes:  // width: one machine's length (scooters from 1.6 m)
            EXPECT_TRUE(item.count >= 1 && item.count <= 5) << item.count;
            EXPECT_TRUE(item.width_m >= 1.6 && item.width_m <= 2.3) << item.width_m;
            EXPECT_TRUE(item.height_m >= 1.05 && item.height_m <= 1.35) << item.height_m;
            break;
          case FurnitureKind::Bicycles:
            EXPECT_TRUE(item.count >= 2 && item.count <= 8) << item.count;
            EXPECT_TRUE(item.width_m >= 1.65 && item.width_m <= 1.85) << item.width_m;
            EXPECT_TRUE(item.height_m >= 0.95 && item.height_m <= 1.1) << item.height_m;
            break;
          default:  // pedestrians: the tallest member
            EXPECT_TRUE(item.count >= 1 && item.count <= 5) << item.count;
            EXPECT_TRUE(item.height_m >= 1.5 && item.height_m <= 1.95) << item.height_m;
            EXPECT_LE(item.length_m, 0.6 + 0.7 * 4 * 1.2 + 1e-9);
            break;
        }
      }
    }
  }
  // Every kind is placed, several per scene (90 scenes).
  EXPECT_GT(counts[FurnitureKind::Motorbikes], 90);
  EXPECT_GT(counts[FurnitureKind::Bicycles], 90);
  EXPECT_GT(counts[FurnitureKind::Pedestrians], 180);
  EXPECT_GT(members[FurnitureKind::Bicycles], 3 * counts[FurnitureKind::Bicycles]);
}

TEST(RoadUsers, NoVehicleEverOverlapsOne) {
  long checked = 0;
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      vp::sim::Rng rng(seed);
      SceneSpec scene = vp::sim::generateScene(kind, rng);
      vp::sim::addRoadUsers(scene);
      vp::sim::testing::walkTraffic(scene, rng, [&](const auto& v, const auto& fv, int step) {
        for (const auto& item : scene.furniture) {
          if (!isRoadUser(item.kind)) {
            continue;
          }
          ++checked;
          EXPECT_FALSE(vp::sim::footprintsOverlap(fv, vp::sim::footprintOf(item), 0.0))
              << "vehicle " << v.trackId << (v.parked ? " (parked)" : "") << " overlaps "
              << toString(item.kind) << ", " << toString(kind) << " seed " << seed << " step "
              << step;
        }
      });
    }
  }
  EXPECT_GT(checked, 10000);
}

// Rendered with the option, road users are drawn (their object ids in the id image) and listed
// as furniture; the vehicles' ground truth is the seed's without them.
TEST(RoadUsers, RenderedAsListedBackground) {
  const auto render = [](bool roadUsers, const std::string& name) {
    const fs::path dir = vp::sim::testing::freshDir("road_users_" + name);
    vp::sim::SimOptions o = vp::sim::testing::smallOptions(SceneKind::Straight, 11, dir, 480, 380);
    o.frames = 1;
    o.roadUsers = roadUsers;
    vp::sim::Simulator sim;
    std::string why;
    EXPECT_TRUE(sim.init(o, &why)) << why;
    std::vector<vp::sim::FrameOutput> frames;
    EXPECT_TRUE(sim.write(&why, [&](const vp::sim::FrameOutput& f) {
      vp::sim::FrameOutput copy = f;
      copy.ids = f.ids.clone();
      frames.push_back(std::move(copy));
    })) << why;
    fs::remove_all(dir);
    return frames;
  };
  const auto plain = render(false, "plain");
  const auto with = render(true, "with");
  ASSERT_EQ(plain.size(), 1U);
  ASSERT_EQ(with.size(), 1U);
  std::set<std::string> kinds;
  for (const auto& t : with[0].furniture) {
    kinds.insert(t.kind);
    EXPECT_GT(t.visiblePixels, 0);
  }
  EXPECT_TRUE(kinds.count("pedestrians") + kinds.count("motorbikes") + kinds.count("bicycles") > 0)
      << "no road user in view of straight seed 11";
  EXPECT_GT(with[0].furniture.size(), plain[0].furniture.size());
  ASSERT_EQ(with[0].objects.size(), plain[0].objects.size()) << "road users became vehicles";
  for (std::size_t i = 0; i < plain[0].objects.size(); ++i) {
    EXPECT_EQ(with[0].objects[i].trackId, plain[0].objects[i].trackId);
  }
}

}  // namespace
