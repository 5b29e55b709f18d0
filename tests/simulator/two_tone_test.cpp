// Tests of the simulator's two-tone cars (--two-tone-share): the contrasting colour covers the
// roof panel between the four roof corners and nothing else, contrasts with the body both ways
// (white on dark, black on light), and repaints roofs without changing the scene a seed gives.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <utility>

#include "default_asm.hpp"
#include "shape/vehicle_model.hpp"
#include "sim_render.hpp"
#include "simulator.hpp"
#include "twin_cars.hpp"
#include "vehicles.hpp"

namespace {

float luminance(const Eigen::Vector3f& c) {
  return 0.2126F * c.x() + 0.7152F * c.y() + 0.0722F * c.z();
}

int roofTriangles(const vp::sim::VehicleModel& m) {
  int n = 0;
  for (const auto& t : m.triangles) {
    n += t.material == vp::sim::Material::RoofPaint ? 1 : 0;
  }
  return n;
}

TEST(TwoTone, TheRoofPanelAloneTakesAContrastingColour) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory plain(asmModel);
  const vp::sim::VehicleFactory twoTone(asmModel, 1.0);
  int dark = 0;
  int light = 0;
  vp::sim::test::forEachTwinCar(plain, twoTone, 11, 60, [&](auto, const auto& a, const auto& b) {
    // The same car ...
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    EXPECT_TRUE(a.vertices.front().isApprox(b.vertices.front()));
    EXPECT_FALSE(a.look.twoTone);
    EXPECT_EQ(roofTriangles(a), 0);
    // ... with its roof panel, two or more triangles between the roof corners, repainted.
    ASSERT_TRUE(b.look.twoTone);
    EXPECT_GE(roofTriangles(b), 2);
    const double roofTop = b.dimensions_m.z();
    for (std::size_t t = 0; t < b.triangles.size(); ++t) {
      if (b.triangles[t].material != vp::sim::Material::RoofPaint) {
        EXPECT_EQ(b.triangles[t].material, a.triangles[t].material) << "triangle " << t;
        continue;
      }
      for (const auto v : b.triangles[t].v) {
        EXPECT_LT(v, vp::shape::kKeypointCount);
        EXPECT_GT(b.vertices[v].z(), 0.7 * roofTop) << "a roof vertex low on the car";
      }
    }
    const float body = luminance(b.look.paint);
    const float roof = luminance(b.look.roofPaint);
    EXPECT_GT(std::abs(body - roof), 0.2F) << "body " << body << " roof " << roof;
    (body < roof ? dark : light) += 1;
  });
  EXPECT_GT(dark, 5);  // white roofs on dark cars and black roofs on light ones both occur
  EXPECT_GT(light, 5);
}

TEST(TwoTone, AShareOfCarsAndTheSameScene) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory half(asmModel, 0.5);
  vp::sim::Rng rng(3);
  int twoTone = 0;
  for (int i = 0; i < 400; ++i) {
    twoTone += half.makeCar(rng, half.drawCarType(rng))->look.twoTone ? 1 : 0;
  }
  EXPECT_GT(twoTone, 150);
  EXPECT_LT(twoTone, 250);

  // A whole sequence: the ground truth (cars, boxes, keypoints) is the seed's; frames differ.
  const auto run = [](double share, const std::string& name) {
    vp::sim::SimOptions o = vp::sim::testing::smallOptions(
        vp::sim::SceneKind::Straight, 5, vp::sim::testing::freshDir("two_tone_" + name), 320, 256);
    o.frames = 1;
    o.twoToneShare = share;
    const auto files = vp::sim::testing::renderedFiles(o);
    const auto out =
        std::make_pair(files.at("ground_truth/objects.csv"), files.at("frames/000000.png"));
    // The sequence says how it was made (its notes), and only when the option is on.
    EXPECT_EQ(files.at("sequence.yaml").find("two-tone share") != std::string::npos, share > 0.0);
    return out;
  };
  const auto plain = run(0.0, "plain");
  const auto painted = run(1.0, "painted");
  ASSERT_FALSE(plain.first.empty());
  ASSERT_FALSE(plain.second.empty());
  EXPECT_EQ(plain.first, painted.first);
  EXPECT_NE(plain.second, painted.second);
}

}  // namespace
