// Tests of the simulator's roof fixtures (HVAC units, skylights, dormers, solar panels): the
// same building seed gives the same fixtures; each fixture lies on its roof, clear of the
// edges, the ridge and the other fixtures, with the documented sizes; every kind occurs; and
// they depend on the building's seed alone.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "scene.hpp"

namespace {

using vp::sim::RoofFixtureKind;

TEST(RoofFixtures, OnTheRoofClearOfEachOtherWithRealSizes) {
  std::map<RoofFixtureKind, int> onFlat;
  std::map<RoofFixtureKind, int> onGabled;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    vp::sim::Rng rng(seed);
    const vp::sim::SceneSpec scene = vp::sim::generateScene(vp::sim::SceneKind::Straight, rng);
    for (const vp::sim::Building& b : scene.buildings) {
      const bool gabled = b.roof == vp::sim::RoofKind::Gabled;
      int hvac = 0;
      for (std::size_t i = 0; i < b.fixtures.size(); ++i) {
        const vp::sim::RoofFixture& x = b.fixtures[i];
        ++(gabled ? onGabled : onFlat)[x.kind];
        hvac += x.kind == RoofFixtureKind::Hvac ? 1 : 0;
        EXPECT_LE(std::fabs(x.along_m) + 0.5 * x.length_m, 0.5 * b.length_m - 0.5 + 1e-9);
        EXPECT_LE(std::fabs(x.across_m) + 0.5 * x.width_m, 0.5 * b.width_m - 0.5 + 1e-9);
        if (gabled) {
          EXPECT_NE(x.kind, RoofFixtureKind::Hvac);
          EXPECT_GE(std::fabs(x.across_m) - 0.5 * x.width_m, 0.4 - 1e-9) << "across the ridge";
        } else {
          EXPECT_NE(x.kind, RoofFixtureKind::Dormer);
        }
        if (x.kind == RoofFixtureKind::Hvac) {
          EXPECT_TRUE(x.length_m >= 1.0 && x.length_m <= 3.0) << x.length_m;
          EXPECT_TRUE(x.width_m >= 1.0 && x.width_m <= 3.0) << x.width_m;
          EXPECT_TRUE(x.height_m >= 0.8 && x.height_m <= 2.0) << x.height_m;
        }
        for (std::size_t j = 0; j < i; ++j) {
          const vp::sim::RoofFixture& o = b.fixtures[j];
          EXPECT_FALSE(vp::sim::footprintsOverlap(
              {{x.along_m, x.across_m}, {1.0, 0.0}, 0.5 * x.length_m, 0.5 * x.width_m},
              {{o.along_m, o.across_m}, {1.0, 0.0}, 0.5 * o.length_m, 0.5 * o.width_m}, 0.0))
              << "fixtures " << i << " and " << j << " overlap, seed " << seed;
        }
      }
      // The drawn rooftop units are all placed unless the roof is too small for them.
      if (!gabled && b.length_m >= 20.0 && b.width_m >= 12.0) {
        EXPECT_GE(hvac, b.rooftopUnits) << "seed " << seed;
      }
      // Same building seed, same fixtures.
      vp::sim::Building again = b;
      vp::sim::addRoofFixtures(again);
      ASSERT_EQ(again.fixtures.size(), b.fixtures.size());
      for (std::size_t i = 0; i < b.fixtures.size(); ++i) {
        EXPECT_EQ(again.fixtures[i].along_m, b.fixtures[i].along_m);
        EXPECT_EQ(again.fixtures[i].across_m, b.fixtures[i].across_m);
        EXPECT_EQ(again.fixtures[i].kind, b.fixtures[i].kind);
      }
    }
  }
  EXPECT_GT(onFlat[RoofFixtureKind::Hvac], 0);
  EXPECT_GT(onFlat[RoofFixtureKind::Skylight], 0);
  EXPECT_GT(onGabled[RoofFixtureKind::Skylight], 0);
  EXPECT_GT(onGabled[RoofFixtureKind::Dormer], 0);
  EXPECT_GT(onGabled[RoofFixtureKind::SolarPanel], 0);
}

TEST(RoofFixtures, DependOnTheBuildingSeedAlone) {
  // Two scenes from one seed leave the sequence's Rng in the same state, and the fixtures of a
  // building depend on its seed alone: the same building with another seed gets others.
  vp::sim::Rng a(77);
  vp::sim::Rng b(77);
  const vp::sim::SceneSpec sa = vp::sim::generateScene(vp::sim::SceneKind::Parking, a);
  vp::sim::SceneSpec sb = vp::sim::generateScene(vp::sim::SceneKind::Parking, b);
  EXPECT_EQ(a.next(), b.next());
  int differing = 0;
  for (vp::sim::Building& building : sb.buildings) {
    const auto before = building.fixtures;
    building.seed += 1U;
    vp::sim::addRoofFixtures(building);
    differing += before.size() != building.fixtures.size() ||
                         (!before.empty() && before[0].along_m != building.fixtures[0].along_m)
                     ? 1
                     : 0;
  }
  EXPECT_GT(differing, 0);
  EXPECT_EQ(sa.buildings.size(), sb.buildings.size());
}

}  // namespace
