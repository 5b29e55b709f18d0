// tests/perception/footprint_type: the lifted footprint's size as evidence on a car's type.
// Perfect detections of vehicles on a grid, lifted: each car type's probability moves as the
// contract's formula says (computed here independently), the cars' total and Large's probability
// stay, a short car unsure between compact and estate becomes a compact and is lifted again as
// one (equal to lifting it so directly), and observations not lifted, cut by the frame's border,
// most likely Large, or with the evidence off are left as they were; no allocation.
#include "perception/footprint_type.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "test_scene.hpp"

namespace vp::perception {
namespace {

using shape::VehicleType;
using testworld::Scene;
using testworld::TruthVehicle;

constexpr int kCompact = static_cast<int>(VehicleType::Compact);
constexpr int kEstate = static_cast<int>(VehicleType::Estate);
constexpr int kLarge = static_cast<int>(VehicleType::Large);

struct TypeWorld {
  Scene scene{testworld::plane(0.03, 0.01), camera::LensModel::BrownConrady};
  lifting::DronePose pose = testworld::hoveringPose(20.0, -85.0);
  lifting::CameraPoseWorld cameraPose{};
  std::vector<VehicleObservation> lifted;

  // Vehicles of the grid, each given the probabilities probabilities(i) and lifted.
  template <typename Probabilities>
  explicit TypeWorld(Probabilities probabilities) {
    const auto camera = scene.lifter.cameraPose(pose);
    EXPECT_TRUE(camera);
    cameraPose = *camera;
    std::vector<detection::Detection> detections;
    for (TruthVehicle t : testworld::truthVehicles(scene.terrain, 50.0, 10.0)) {
      detection::Detection d;
      if (!testworld::perfectDetection(scene, cameraPose, t, &d)) {
        continue;
      }
      d.typeProbabilities = probabilities(detections.size());
      detections.push_back(d);
    }
    lifted.resize(detections.size());
    const FrameLiftSummary summary = scene.detectionLifter.liftFrame(
        scene.lifter, 55, telemetry::PoseStatus::Ok, pose, detections, lifted);
    EXPECT_EQ(summary.lifted, detections.size());
  }
};

std::array<float, shape::kVehicleTypeCount> spread(std::size_t i) {
  std::array<float, shape::kVehicleTypeCount> p{};
  float sum = 0.0F;
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    p[t] = 0.05F + 0.1F * static_cast<float>((i + 3 * t) % 7);
    sum += p[t];
  }
  for (float& v : p) {
    v /= sum;
  }
  p[kLarge] *= 0.2F;  // cars: Large the least likely
  sum = 0.0F;
  for (const float v : p) {
    sum += v;
  }
  for (float& v : p) {
    v /= sum;
  }
  return p;
}

TEST(FootprintType, MovesEachCarTypeAsTheFormulaSays) {
  TypeWorld w(spread);
  ASSERT_GT(w.lifted.size(), 30U);
  const FootprintTypeOptions options;
  FootprintType evidence;
  std::string why;
  ASSERT_TRUE(evidence.init(options, &w.scene.detectionLifter, &why)) << why;
  ASSERT_TRUE(evidence.active());
  std::vector<VehicleObservation> observations = w.lifted;

  vp::test::AllocationCounter counter;
  const FootprintTypeScreening result = evidence.apply(observations, w.scene.lifter, w.cameraPose);
  counter.stop();
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(result.weighed, observations.size());

  std::size_t retyped = 0;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const VehicleObservation& before = w.lifted[i];
    const double length = before.ground.length_m;
    const double width = before.ground.width_m;
    std::array<double, shape::kCarTypeCount> expected{};
    double carTotal = 0.0;
    double sum = 0.0;
    for (int t = 0; t < shape::kCarTypeCount; ++t) {
      const double p = before.detection.typeProbabilities[t];
      carTotal += p;
      const double lengthTerm = std::clamp((length - 4.6) / 0.4, -2.5, 2.5);
      const double aspectTerm = std::clamp(std::log(length / width / 2.35) / 0.1, -2.5, 2.5);
      expected[t] =
          p * std::exp(options.lengthWeight[t] * lengthTerm + options.aspectWeight[t] * aspectTerm);
      sum += expected[t];
    }
    const auto& got = observations[i].detection.typeProbabilities;
    double gotCars = 0.0;
    for (int t = 0; t < shape::kCarTypeCount; ++t) {
      EXPECT_NEAR(got[t], carTotal * expected[t] / sum, 2e-6) << i << " type " << t;
      gotCars += static_cast<double>(got[t]);
    }
    EXPECT_NEAR(gotCars, carTotal, 2e-6) << i;
    EXPECT_EQ(got[kLarge], before.detection.typeProbabilities[kLarge]) << i;
    EXPECT_EQ(observations[i].type, mostLikelyType(observations[i].detection, nullptr)) << i;
    retyped += observations[i].type != before.type ? 1 : 0;
  }
  EXPECT_EQ(result.retyped, retyped);
}

TEST(FootprintType, AShortCarUnsureOfCompactOrEstateBecomesACompactAndIsLiftedAsOne) {
  // Estate 0.47 against compact 0.45: the shipped weights favour the compact by about 0.2 in
  // log-odds for a 3.9 m x 1.8 m footprint.
  const auto unsure = [](std::size_t) {
    std::array<float, shape::kVehicleTypeCount> p{};
    p.fill(0.02F);
    p[kEstate] = 0.47F;
    p[kCompact] = 0.45F;
    return p;
  };
  TypeWorld w(unsure);
  ASSERT_FALSE(w.lifted.empty());
  // A 3.9 m x 1.8 m footprint of the first grid vehicle: its perfect box again, lifted.
  TruthVehicle shortCar;
  shortCar.footprint.centreEnu = w.lifted[0].ground.centreEnu;
  shortCar.footprint.headingEnu_rad = w.lifted[0].ground.headingEnu_rad;
  shortCar.footprint.length_m = 3.9;
  shortCar.footprint.width_m = 1.8;
  detection::Detection d;
  ASSERT_TRUE(testworld::perfectDetection(w.scene, w.cameraPose, shortCar, &d));
  d.typeProbabilities = unsure(0);
  std::vector<VehicleObservation> observations(1);
  const std::vector<detection::Detection> one{d};
  w.scene.detectionLifter.liftFrame(w.scene.lifter, 55, telemetry::PoseStatus::Ok, w.pose, one,
                                    observations);
  ASSERT_EQ(observations[0].liftStatus, LiftStatus::Ok);
  ASSERT_EQ(observations[0].type, VehicleType::Estate);
  ASSERT_NEAR(observations[0].ground.length_m, 3.9, 0.01);

  FootprintType evidence;
  ASSERT_TRUE(evidence.init(FootprintTypeOptions{}, &w.scene.detectionLifter));
  const FootprintTypeScreening result = evidence.apply(observations, w.scene.lifter, w.cameraPose);
  EXPECT_EQ(result.weighed, 1U);
  EXPECT_EQ(result.retyped, 1U);
  const VehicleObservation& o = observations[0];
  EXPECT_EQ(o.type, VehicleType::Compact);
  EXPECT_GT(o.detection.typeProbabilities[kCompact], o.detection.typeProbabilities[kEstate]);

  // Equal to lifting the weighed detection directly: the compact's shape stands on the ground.
  std::vector<VehicleObservation> direct(1);
  const std::vector<detection::Detection> weighed{o.detection};
  w.scene.detectionLifter.liftFrame(w.scene.lifter, 55, telemetry::PoseStatus::Ok, w.pose, weighed,
                                    direct);
  EXPECT_EQ(direct[0].type, VehicleType::Compact);
  EXPECT_EQ(o.timestamp_ns, 55);
  EXPECT_NEAR(o.height_m, direct[0].height_m, 1e-12);
  EXPECT_NEAR((o.keypointsEnu - direct[0].keypointsEnu).norm(), 0.0, 1e-9);
  EXPECT_NEAR((o.rearAxleEnu - direct[0].rearAxleEnu).norm(), 0.0, 1e-9);
  EXPECT_NEAR((o.ground.centreEnu - direct[0].ground.centreEnu).norm(), 0.0, 1e-9);
}

TEST(FootprintType, LeavesWhatItCannotWeigh) {
  TypeWorld w(spread);
  ASSERT_GT(w.lifted.size(), 4U);
  std::vector<VehicleObservation> observations = w.lifted;
  observations[0].liftStatus = LiftStatus::OutsideDtm;  // no footprint
  observations[1].detection.atFrameEdge = true;         // footprint cut short
  observations[2].detection.typeProbabilities.fill(0.05F);
  observations[2].detection.typeProbabilities[kLarge] = 0.7F;  // a bus or a truck
  const std::vector<VehicleObservation> before = observations;
  FootprintType evidence;
  ASSERT_TRUE(evidence.init(FootprintTypeOptions{}, &w.scene.detectionLifter));
  const FootprintTypeScreening result = evidence.apply(observations, w.scene.lifter, w.cameraPose);
  EXPECT_EQ(result.weighed, observations.size() - 3);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(observations[i].detection.typeProbabilities, before[i].detection.typeProbabilities)
        << i;
  }
  // Off (perception.footprint_type: false), or without a lifter: nothing moves.
  FootprintTypeOptions off;
  off.enabled = false;
  for (const auto& [options, lifter] :
       {std::pair<FootprintTypeOptions, const DetectionLifter*>{off, &w.scene.detectionLifter},
        std::pair<FootprintTypeOptions, const DetectionLifter*>{FootprintTypeOptions{}, nullptr}}) {
    ASSERT_TRUE(evidence.init(options, lifter));
    EXPECT_FALSE(evidence.active());
    std::vector<VehicleObservation> copy = w.lifted;
    EXPECT_EQ(evidence.apply(copy, w.scene.lifter, w.cameraPose).weighed, 0U);
    for (std::size_t i = 0; i < copy.size(); ++i) {
      EXPECT_EQ(copy[i].detection.typeProbabilities, w.lifted[i].detection.typeProbabilities);
    }
  }
}

TEST(FootprintType, RefusesScalesAndWeightsThatCannotBeUsed) {
  FootprintType evidence;
  std::string why;
  FootprintTypeOptions bad;
  bad.lengthScale_m = 0.0;
  EXPECT_FALSE(evidence.init(bad, nullptr, &why));
  EXPECT_NE(why.find("must be positive and finite"), std::string::npos) << why;
  bad = FootprintTypeOptions{};
  bad.maxTerm = 0.0;
  EXPECT_FALSE(evidence.init(bad, nullptr, &why));
  bad = FootprintTypeOptions{};
  bad.referenceAspect = std::nan("");
  EXPECT_FALSE(evidence.init(bad, nullptr, &why));
  bad = FootprintTypeOptions{};
  bad.aspectWeight[3] = INFINITY;
  EXPECT_FALSE(evidence.init(bad, nullptr, &why));
  EXPECT_NE(why.find("weight must be finite"), std::string::npos) << why;
  EXPECT_FALSE(evidence.active());
}

}  // namespace
}  // namespace vp::perception
