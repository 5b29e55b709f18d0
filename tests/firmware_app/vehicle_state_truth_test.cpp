// firmware_app/vehicle_state against the simulator's ground truth: the app replays a simulated
// sequence through the real path (shipped detector and crop network, lifting, tracker,
// toVehicleState, validation and the DDS writer on a loopback domain) and every confirmed state
// it publishes is matched to the true vehicle of its frame. Checked: the UTM fields are the UTM
// of the published position and agree with the UTM of the true centre within the position error;
// the rear axle lies near the true one (the middle of the true rear wheel centres on the road);
// the published keypoints lie near the true ones (E_D2D: RMS plan distance over the seed's 24
// evaluation keypoints, as docs/model_card.md defines it, here in the world frame, so the pose
// and size errors count too; and with the pose removed by a best rigid plan fit); large vehicles
// publish no keypoints.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SVD>

#include "app.hpp"
#include "app_test_support.hpp"
#include "dds_test_support.hpp"
#include "geodesy/geodesy.hpp"
#include "output_files/trajectory_file.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::app {
namespace {

// Every published state with the frame it was published in (the loop runs every frame in order).
class FrameLog final : public LoopObserver {
 public:
  FrameLog() { states.reserve(4096); }
  void onPublished(const messages::VehicleState& state) override {
    states.push_back({frames, state});
  }
  void onFrameDone(std::uint64_t processed) override { frames = processed; }
  struct Entry {
    std::uint64_t frameIndex = 0;  // 0-based index into the sequence's frames
    messages::VehicleState state;
  };
  std::vector<Entry> states;
  std::uint64_t frames = 0;
};

double rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (const double v : values) {
    sum += v * v;
  }
  return values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

double median(std::vector<double> values) {
  if (values.empty()) {
    return 0.0;
  }
  std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2),
                   values.end());
  return values[values.size() / 2];
}

// Plan distances of the evaluation keypoints after the best rigid 2D fit (rotation and
// translation, no scale) of the published onto the true keypoints: what is left is the shape and
// size error, the pose error removed.
constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::vector<double> alignedDistances(const std::vector<Eigen::Vector2d>& published,
                                     const std::vector<Eigen::Vector2d>& truth) {
  Eigen::Vector2d mp = Eigen::Vector2d::Zero();
  Eigen::Vector2d mt = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < published.size(); ++k) {
    mp += published[k];
    mt += truth[k];
  }
  mp /= static_cast<double>(published.size());
  mt /= static_cast<double>(truth.size());
  Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
  for (std::size_t k = 0; k < published.size(); ++k) {
    h += (published[k] - mp) * (truth[k] - mt).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix2d r = svd.matrixV() * svd.matrixU().transpose();
  if (r.determinant() < 0.0) {
    Eigen::Matrix2d v = svd.matrixV();
    v.col(1) *= -1.0;
    r = v * svd.matrixU().transpose();
  }
  std::vector<double> distances;
  for (std::size_t k = 0; k < published.size(); ++k) {
    distances.push_back((r * (published[k] - mp) + mt - truth[k]).norm());
  }
  return distances;
}

TEST(VehicleStateTruth, UtmRearAxleAndKeypointsAgreeWithTheSimulatorsTruth) {
  test::useLoopbackDds();
  // The loop sequence's scene at 960 x 768: a GSD of 0.10 m at the image centre, which the
  // default working_gsd_m brings to the detector's 0.12 m, as in flight (the loop tests' 320 x
  // 256 frames have 0.31 m: too coarse for centimetre keypoints).
  const std::string dir = test::simulatedSequence("truth_960", 16, 960, 768, 7);
  ASSERT_FALSE(dir.empty());
  std::string why;
  sequence::SequenceReader reader;
  ASSERT_TRUE(reader.open(dir, &why)) << why;
  ASSERT_TRUE(reader.hasGroundTruth());
  const geodesy::LocalFrame world(reader.rig().origin);

  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.domainId = static_cast<std::uint32_t>(1 + (getpid() * 7 + 5) % 200);
  config.dds.partition = "truth_test_" + std::to_string(getpid());
  config.source.paced = false;
  config.app.statsPeriod_s = 3600.0;
  config.app.trajectoryCsv = test::scratchDir("vehicle_state_truth") + "/tracks.csv";
  RunSettings run;
  run.everyFrame = true;
  run.quiet = true;
  FrameLog log;
  {
    App app;
    AppSeams seams;  // the real perception: shipped detector and crop network
    seams.observer = &log;
    ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    EXPECT_EQ(app.counters().framesDropped, 0U);
    EXPECT_EQ(app.counters().publishErrors, 0U);
  }
  ASSERT_EQ(log.frames, reader.frames().size());

  // The trajectory file carries the published UTM and rear axle: one row per published state,
  // the same values at the file's precision (mm, 1e-8 deg).
  output_files::TrajectoryFile file;
  ASSERT_TRUE(output_files::readTrajectoryFile(config.app.trajectoryCsv, &file, &why)) << why;
  ASSERT_EQ(file.rows.size(), log.states.size());
  for (std::size_t i = 0; i < file.rows.size(); ++i) {
    const tracking::TrajectoryPlace& place = file.rows[i].place;
    const messages::VehicleState& s = log.states[i].state;
    EXPECT_EQ(file.rows[i].trackId, s.trackId);
    EXPECT_EQ(place.utmZone, s.utmZone);
    EXPECT_NEAR(place.utmEasting_m, s.utmEasting_m, 0.0005 + 1e-9);
    EXPECT_NEAR(place.utmNorthing_m, s.utmNorthing_m, 0.0005 + 1e-9);
    ASSERT_TRUE(place.hasRearAxle);
    EXPECT_NEAR(place.rearAxle.latitude_deg, s.rearAxlePosition.latitude_deg, 5e-9 + 1e-12);
    EXPECT_NEAR(place.rearAxle.longitude_deg, s.rearAxlePosition.longitude_deg, 5e-9 + 1e-12);
    EXPECT_NEAR(file.rows[i].lengthVariance_m2, s.lengthVariance_m2,
                5e-7 + 1e-6 * static_cast<double>(s.lengthVariance_m2));
  }

  const auto& wheels = shape::wheelCentreKeypoints();
  const auto& evaluation = shape::evaluationKeypoints();
  std::vector<double> centreErrors;
  std::vector<double> utmErrors;
  std::vector<double> rearAxleErrors;
  std::vector<double> keypointErrors;         // world plan distances, every evaluation keypoint
  std::vector<double> alignedKeypointErrors;  // the same after the rigid fit
  std::vector<double> perVehicleMean;         // mean world plan distance per matched state
  int matched = 0;
  int matchedCars = 0;
  int flipped = 0;
  for (const FrameLog::Entry& entry : log.states) {
    const messages::VehicleState& s = entry.state;
    if (s.status != messages::TrackStatus::Confirmed) {
      continue;  // a lost track is a prediction
    }
    // The UTM fields are the UTM of the published position, to the millimetre.
    const geodesy::UtmPoint own = geodesy::toUtm(s.position);
    ASSERT_EQ(s.utmZone, own.zone);
    EXPECT_EQ(s.utmNorthernHemisphere, own.northp);
    EXPECT_NEAR(s.utmEasting_m, own.easting_m, 1e-3);
    EXPECT_NEAR(s.utmNorthing_m, own.northing_m, 1e-3);
    // The rear axle's WGS84 is its ENU point's.
    const Eigen::Vector3d axle(s.rearAxleEnu_m[0], s.rearAxleEnu_m[1], s.rearAxleEnu_m[2]);
    EXPECT_LT((world.toEnu(s.rearAxlePosition) - axle).norm(), 1e-6);
    if (s.type == shape::VehicleType::Large) {
      EXPECT_EQ(s.keypointCount, 0);
    }

    // The true vehicle: nearest true centre in plan, whole in the image.
    const std::int64_t frameId = reader.frames()[entry.frameIndex].frameId;
    const Eigen::Vector2d centre(s.enu_m[0], s.enu_m[1]);
    const sequence::ObjectTruth* truth = nullptr;
    double best = 1.5;  // m: farther is another vehicle (or a false track)
    for (const sequence::ObjectTruth& object : reader.objects(frameId)) {
      const double d = (object.positionEnu.head<2>() - centre).norm();
      if (object.truncation == 0.0 && d < best) {
        best = d;
        truth = &object;
      }
    }
    if (truth == nullptr) {
      continue;
    }
    double headingError = std::fmod(std::abs(s.headingEnu_rad - truth->headingEnu_rad), kTwoPi);
    headingError = std::min(headingError, kTwoPi - headingError);
    flipped += headingError > 0.5 * std::numbers::pi ? 1 : 0;
    ++matched;
    centreErrors.push_back(best);
    const geodesy::UtmPoint trueUtm =
        geodesy::toUtm(world.toGeodetic(truth->positionEnu), own.zone);
    utmErrors.push_back(
        std::hypot(s.utmEasting_m - trueUtm.easting_m, s.utmNorthing_m - trueUtm.northing_m));

    // True keypoints of this vehicle in this frame.
    std::vector<Eigen::Vector3d> trueKeypoints(shape::kKeypointCount);
    int found = 0;
    for (const sequence::KeypointTruth& k : reader.keypoints(frameId)) {
      if (k.trackId == truth->trackId && k.keypoint >= 0 && k.keypoint < shape::kKeypointCount) {
        trueKeypoints[static_cast<std::size_t>(k.keypoint)] = k.worldEnu;
        ++found;
      }
    }
    if (found != shape::kKeypointCount) {
      continue;  // a large vehicle: no true keypoints
    }
    const Eigen::Vector2d trueAxle =
        0.5 * (trueKeypoints[static_cast<std::size_t>(wheels[2])].head<2>() +
               trueKeypoints[static_cast<std::size_t>(wheels[3])].head<2>());
    rearAxleErrors.push_back((axle.head<2>() - trueAxle).norm());
    if (s.keypointCount != shape::kKeypointCount) {
      continue;  // published as a large vehicle (a type error)
    }
    ++matchedCars;
    std::vector<Eigen::Vector2d> published;
    std::vector<Eigen::Vector2d> trueOnes;
    double sum = 0.0;
    for (const int k : evaluation) {
      const auto& p = s.keypointsEnu_m[static_cast<std::size_t>(k)];
      published.emplace_back(p[0], p[1]);
      trueOnes.push_back(trueKeypoints[static_cast<std::size_t>(k)].head<2>());
      const double d = (published.back() - trueOnes.back()).norm();
      keypointErrors.push_back(d);
      sum += d;
    }
    perVehicleMean.push_back(sum / static_cast<double>(evaluation.size()));
    for (const double d : alignedDistances(published, trueOnes)) {
      alignedKeypointErrors.push_back(d);
    }
  }

  const double meanPerVehicle =
      perVehicleMean.empty() ? 0.0
                             : std::accumulate(perVehicleMean.begin(), perVehicleMean.end(), 0.0) /
                                   static_cast<double>(perVehicleMean.size());
  std::printf(
      "published confirmed states matched to the truth: %d (%d cars with keypoints, %d turned "
      "by more than 90 degrees)\n"
      "  centre error median %.3f m; UTM vs the true centre's UTM median %.3f m\n"
      "  rear axle plan error median %.3f m, RMS %.3f m\n"
      "  keypoints (24 evaluation keypoints, plan): E_D2D world %.3f m (RMS), mean per vehicle "
      "%.3f m; pose removed (rigid fit) %.3f m (RMS)\n",
      matched, matchedCars, flipped, median(centreErrors), median(utmErrors),
      median(rearAxleErrors), rms(rearAxleErrors), rms(keypointErrors), meanPerVehicle,
      rms(alignedKeypointErrors));

  ASSERT_GE(matchedCars, 10);
  // UTM of the published centre vs UTM of the true centre: the same plan error as in ENU (the
  // UTM scale differs from 1 by < 0.1 %), so the UTM conversion adds nothing.
  for (std::size_t i = 0; i < utmErrors.size(); ++i) {
    EXPECT_NEAR(utmErrors[i], centreErrors[i], 1e-3 + 1e-3 * centreErrors[i]);
  }
  // The criteria (measured at this commit: rear axle median 0.054 m; E_D2D 0.068 m with the pose
  // removed, 0.114 m in the world, 0.088 m mean per vehicle; 305 matched states):
  //  - with the pose removed the keypoints meet the model card's shape figure, E_D2D (RMS over
  //    vehicles and the 24 evaluation keypoints of the plan distance) <= 0.081 m;
  //  - in the world frame the position and heading errors add to that; the world E_D2D does NOT
  //    meet 0.081 m, it is bounded at 0.13 m here (the detector's position error, median 0.05 m
  //    at this GSD, is most of the difference);
  //  - the rear axle: median plan error <= 0.08 m (a point of the same placed shape).
  EXPECT_LE(rms(alignedKeypointErrors), 0.081);
  EXPECT_LE(rms(keypointErrors), 0.13);
  EXPECT_LE(median(rearAxleErrors), 0.08);
}

}  // namespace
}  // namespace vp::app
