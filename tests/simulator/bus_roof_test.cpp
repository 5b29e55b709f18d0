// Tests of the simulator's bus roof details (--bus-roof-share): closed boxes standing on the
// roof inside its outline, dark paint (hatches, fans, digits) seen from above, the bus's
// dimensions and wheels unchanged, and the scene's stream untouched by the option.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <utility>

#include <Eigen/Geometry>

#include "car_generator.hpp"
#include "default_asm.hpp"
#include "vehicles.hpp"

namespace {

using vp::shape::LargeVehicleKind;
using vp::shape::LargeVehicleMesh;
using vp::shape::SurfacePart;
using vp::shape::Triangle;

// Area seen from straight above of the upward-facing triangles of a part above height z.
double topArea(const LargeVehicleMesh& m, SurfacePart part, double aboveZ) {
  double area = 0.0;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const Triangle& t = m.triangles[i];
    const Eigen::Vector3d& a = m.vertices[t.v[0]];
    const Eigen::Vector3d n = (m.vertices[t.v[1]] - a).cross(m.vertices[t.v[2]] - a);
    if (t.part == part && n.z() > 0.0 && a.z() > aboveZ) {
      area += 0.5 * n.z();
    }
  }
  return area;
}

TEST(BusRoof, ClosedBoxesOnTheRoofWithDarkPaintAndTheBusUnchanged) {
  std::mt19937_64 rng(31);
  int withNumber = 0;
  for (const LargeVehicleKind kind :
       {LargeVehicleKind::CityBus, LargeVehicleKind::ArticulatedBus, LargeVehicleKind::Coach}) {
    for (int i = 0; i < 15; ++i) {
      const LargeVehicleMesh plain = vp::shape::generateLargeVehicle(kind, rng);
      LargeVehicleMesh detailed = plain;
      vp::shape::addBusRoofDetails(&detailed, rng);
      EXPECT_EQ(detailed.length_m, plain.length_m);
      EXPECT_EQ(detailed.width_m, plain.width_m);
      EXPECT_EQ(detailed.height_m, plain.height_m);
      EXPECT_EQ(detailed.wheelCentres, plain.wheelCentres);
      ASSERT_GT(detailed.triangles.size(), plain.triangles.size());
      // Every added vertex stands on the roof (at most 0.35 m above it) inside its outline.
      for (std::size_t v = plain.vertices.size(); v < detailed.vertices.size(); ++v) {
        const Eigen::Vector3d& p = detailed.vertices[v];
        EXPECT_GE(p.z(), plain.height_m - 1e-9);
        EXPECT_LE(p.z(), plain.height_m + 0.35);
        EXPECT_LE(std::abs(p.x()), 0.5 * plain.length_m - 0.1);
        EXPECT_LE(std::abs(p.y()), 0.5 * plain.width_m + 1e-9);
      }
      // The whole mesh stays closed and consistently wound: each detail is a closed box.
      std::map<std::pair<int, int>, int> directed;
      for (const Triangle& t : detailed.triangles) {
        for (int j = 0; j < 3; ++j) {
          ++directed[{t.v[static_cast<std::size_t>(j)],
                      t.v[static_cast<std::size_t>((j + 1) % 3)]}];
        }
      }
      for (const auto& [edge, count] : directed) {
        ASSERT_EQ(count, 1);
        ASSERT_EQ(directed.count({edge.second, edge.first}), 1u);
      }
      // Hatches and fans at least: over half a square metre of dark paint above the roof.
      const double dark = topArea(detailed, SurfacePart::Underbody, plain.height_m - 1e-6);
      EXPECT_GT(dark, 0.5);
      // A fleet number adds more dark strokes than hatches and fans alone (< 2.6 m^2).
      withNumber += dark > 2.6 ? 1 : 0;
    }
  }
  EXPECT_GT(withNumber, 20);  // 75 % of 45 carry a number
  EXPECT_LT(withNumber, 45);
}

TEST(BusRoof, OnlyBusesChangeAndTheStreamIsUntouched) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory plain(asmModel);
  const vp::sim::VehicleFactory roofs(asmModel, 0.0, 0.0, 0.0, 1.0);
  vp::sim::Rng rngPlain(17);
  vp::sim::Rng rngRoofs(17);
  int changed = 0;
  int unchanged = 0;
  for (int i = 0; i < 60; ++i) {
    const auto a = plain.makeLarge(rngPlain);
    const auto b = roofs.makeLarge(rngRoofs);
    // Same draw from the scene's stream: the same dimensions and paint.
    ASSERT_TRUE(a->dimensions_m.isApprox(b->dimensions_m)) << "vehicle " << i;
    ASSERT_TRUE(a->look.paint.isApprox(b->look.paint)) << "vehicle " << i;
    EXPECT_EQ(a->wheelbase_m, b->wheelbase_m);
    // Buses gain roof triangles; trucks are drawn as before.
    if (b->triangles.size() > a->triangles.size()) {
      ++changed;
    } else {
      EXPECT_EQ(b->triangles.size(), a->triangles.size());
      ++unchanged;
    }
  }
  EXPECT_GT(changed, 20);    // 60 % of the large vehicles are buses or coaches
  EXPECT_GT(unchanged, 10);  // ... and the trucks stay plain
  // The next draw after them is the same too.
  EXPECT_EQ(rngPlain.next(), rngRoofs.next());
}

}  // namespace
