// Tests for tracking/track_manager: lifecycle, re-acquisition keeping the id, heading flip
// correction, type fusion, bad input as values, the CSV line, and zero heap allocations per
// step with 200 tracks.
#include "tracking/track_manager.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "alloc_counter.hpp"
#include "geometry/rotated_box.hpp"
#include "seed_one_options.hpp"
#include "synthetic_scene.hpp"
#include "tracking/trajectory_csv.hpp"

namespace vp::tracking {
namespace {

constexpr std::int64_t kFrame_ns = 100'000'000;  // 10 Hz

WorldDetection car(double x, double y, double heading, std::int64_t t, float score = 0.9f) {
  WorldDetection d;
  d.timestamp_ns = t;
  d.centreEnu = {x, y};
  d.headingEnu_rad = heading;
  d.length_m = 4.5;
  d.width_m = 1.8;
  d.score = score;
  d.typeProbabilities.fill(1.0f / 7.0f);
  return d;
}

TrackerConfig smallConfig() {
  TrackerConfig c = test::seedOneTracker();
  c.maxTracks = 8;
  c.maxDetections = 8;
  return c;
}

// Why init() refuses the configuration ("" when it accepts it).
std::string initProblem(const TrackerConfig& config) {
  TrackManager m;
  std::string why;
  return m.init(config, &why) ? std::string() : why;
}

TEST(TrackManager, InitRejectsBadConfigAndStepBeforeInitIsAnError) {
  TrackManager m;
  EXPECT_EQ(m.step(0, {}).error(), TrackError::NotInitialised);
  TrackerConfig c = smallConfig();
  c.maxTracks = 0;
  std::string why;
  EXPECT_FALSE(m.init(c, &why));
  EXPECT_NE(why.find("maxTracks"), std::string::npos);
  c = smallConfig();
  c.association.lowScore = 0.8f;
  EXPECT_FALSE(m.init(c, &why));
}

TEST(TrackManager, LifecycleTentativeConfirmedLostReacquiredDeleted) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::int64_t t = 0;
  auto stepAt = [&](double x, bool detected) {
    std::vector<WorldDetection> d;
    if (detected) {
      d.push_back(car(x, 0.0, 0.0, t));
    }
    auto r = m.step(t, d);
    EXPECT_TRUE(r.hasValue());
    t += kFrame_ns;
    return r;
  };
  double x = 0.0;
  stepAt(x, true);
  ASSERT_EQ(m.tracks().size(), 1u);
  const std::uint32_t id = m.tracks()[0].id;
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Tentative);
  stepAt(x += 1.0, true);
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Tentative);
  stepAt(x += 1.0, true);
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Confirmed);
  for (int k = 0; k < 20; ++k) {
    stepAt(x += 1.0, true);
  }
  EXPECT_NEAR(m.tracks()[0].speed_mps, 10.0, 0.3);
  // Occluded for 1 s: lost but predicted on.
  for (int k = 0; k < 10; ++k) {
    stepAt(x += 1.0, false);
    ASSERT_EQ(m.tracks().size(), 1u);
    EXPECT_EQ(m.tracks()[0].status, TrackStatus::Lost);
  }
  auto r = stepAt(x += 1.0, true);
  ASSERT_EQ(m.tracks().size(), 1u);
  EXPECT_EQ(m.tracks()[0].id, id);
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Confirmed);
  EXPECT_EQ(r->reacquisitions, 1);
  // Gone for good: deleted after maxLost_s.
  for (int k = 0; k < 40; ++k) {
    stepAt(x += 1.0, false);
  }
  EXPECT_TRUE(m.tracks().empty());
  // A single false positive dies tentative.
  stepAt(-50.0, true);
  EXPECT_EQ(m.tracks().size(), 1u);
  stepAt(0.0, false);
  stepAt(0.0, false);
  stepAt(0.0, false);
  EXPECT_TRUE(m.tracks().empty());
}

// A partial detection (a vehicle driving into the frame: the detector places it too far
// inside) tells where the vehicle is across its axis, hardly where along it.
TEST(TrackManager, PartialDetectionsMoveTheTrackAcrossNotAlong) {
  const auto run = [](double insideShare) {
    TrackerConfig config = smallConfig();
    config.noise.measurementPosition_m = 0.3;  // the app's (docs/tracking.md)
    TrackManager m;
    EXPECT_TRUE(m.init(config));
    std::int64_t t = 0;
    for (int k = 0; k < 10; ++k, t += kFrame_ns) {
      EXPECT_TRUE(m.step(t, std::vector<WorldDetection>{car(0.0, 0.0, 0.0, t)}).hasValue());
    }
    WorldDetection cut = car(-0.5, 0.2, 0.0, t);  // 0.5 m behind along the axis, 0.2 m aside
    cut.length_m = 3.5;
    cut.atFrameEdge = true;
    cut.insideShare = insideShare;
    EXPECT_TRUE(m.step(t, std::vector<WorldDetection>{cut}).hasValue());
    EXPECT_EQ(m.tracks().size(), 1u);
    return m.tracks()[0];
  };
  const TrackState nearEdge = run(0.99);  // at the edge but whole: a full update
  const TrackState partial = run(0.6);
  EXPECT_LT(std::abs(partial.centreEnu.x()), 0.05 * std::abs(nearEdge.centreEnu.x()));
  EXPECT_GT(std::abs(nearEdge.centreEnu.x()), 0.05);
  EXPECT_NEAR(partial.centreEnu.y(), nearEdge.centreEnu.y(), 0.02);
  EXPECT_GT(partial.centreEnu.y(), 0.01);
  // Both touch the border: their short length hardly changes the fused one.
  EXPECT_LT(std::abs(partial.length_m - 4.5), 0.1);
  EXPECT_LT(std::abs(nearEdge.length_m - 4.5), 0.1);

  for (const auto& [field, value] : {std::pair<const char*, double>{"partialAlongNoiseFactor", 0.5},
                                     {"partialInsideShare", 1.5}}) {
    TrackerConfig bad = smallConfig();
    (std::string(field) == "partialInsideShare" ? bad.partialInsideShare
                                                : bad.partialAlongNoiseFactor) = value;
    TrackManager m;
    std::string why;
    EXPECT_FALSE(m.init(bad, &why)) << field;
    EXPECT_NE(why.find(field), std::string::npos) << why;
  }
}

// One bus (11.5 x 2.7 m, score 0.6) boxed at boxCentre(frame) for 40 frames at 10 Hz: how many
// track ids it got and the step reports' overlap counters summed.
struct BusRun {
  std::size_t ids = 0;
  int suppressedBirths = 0;
  int overlapMatches = 0;
};
template <typename BoxCentre>
BusRun runBus(const TrackerConfig& config, double heading, BoxCentre boxCentre) {
  TrackManager m;
  EXPECT_TRUE(m.init(config));
  std::vector<std::uint32_t> ids;
  BusRun run;
  for (int f = 0; f < 40; ++f) {
    const std::int64_t t = f * kFrame_ns;
    const Eigen::Vector2d c = boxCentre(f);
    WorldDetection bus = car(c.x(), c.y(), heading, t, 0.6f);
    bus.length_m = 11.5;
    bus.width_m = 2.7;
    auto r = m.step(t, std::vector<WorldDetection>{bus});
    EXPECT_TRUE(r.hasValue());
    run.suppressedBirths += r->suppressedBirths;
    run.overlapMatches += r->overlapMatches;
    for (const TrackState& s : m.tracks()) {
      if (std::find(ids.begin(), ids.end(), s.id) == ids.end()) {
        ids.push_back(s.id);
      }
    }
  }
  run.ids = ids.size();
  return run;
}

// A standing bus whose box jumps along its axis frame to frame (the first stage places a long
// vehicle's ends less surely: +-1.2 m here) is one track. With the long-vehicle noise and the
// overlap rules off, the jumps fail the gate and start further tracks of the same bus.
TEST(TrackManager, StandingBusWithJumpingBoxIsOneTrack) {
  const double heading = 2.46;  // rad, any direction
  const Eigen::Vector2d axis(std::cos(heading), std::sin(heading));
  auto jumping = [&axis](int f) {
    const double jumps_m[] = {0.0, 1.2, -1.0, 0.4, -1.2, 1.1, 0.2, -0.8, 1.2, -1.1};
    return Eigen::Vector2d(Eigen::Vector2d(40.0, 4.0) + jumps_m[f % 10] * axis);
  };
  TrackerConfig config = smallConfig();
  config.noise.measurementPosition_m = 0.3;
  EXPECT_EQ(runBus(config, heading, jumping).ids, 1u);
  TrackerConfig off = config;
  off.longVehicleLength_m = 0.0;
  off.maxOverlap = 1.0;
  const BusRun without = runBus(off, heading, jumping);
  EXPECT_GT(without.ids, 1u);
  EXPECT_EQ(without.suppressedBirths + without.overlapMatches, 0);
}

// Two boxes of one vehicle in one frame (a bus boxed whole and again in part) start one track,
// the second counted as a suppressed birth; two cars queued a metre apart start two.
TEST(TrackManager, SecondBoxOfAVehicleStartsNoTrackButQueuedCarsDo) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  WorldDetection whole = car(0.0, 0.0, 0.0, 0);
  whole.length_m = 11.0;
  whole.width_m = 2.6;
  const WorldDetection part = car(2.0, 0.1, 0.05, 0, 0.7f);
  auto r = m.step(0, std::vector<WorldDetection>{whole, part});
  ASSERT_TRUE(r.hasValue());
  EXPECT_EQ(r->births, 1);
  EXPECT_EQ(r->suppressedBirths, 1);
  EXPECT_EQ(m.tracks().size(), 1u);

  TrackManager queue;
  ASSERT_TRUE(queue.init(smallConfig()));
  r = queue.step(0, std::vector<WorldDetection>{car(0.0, 0.0, 0.0, 0), car(5.5, 0.0, 0.0, 0)});
  ASSERT_TRUE(r.hasValue());
  EXPECT_EQ(r->births, 2);
  EXPECT_EQ(r->suppressedBirths, 0);

  for (const auto& [field, value] :
       {std::pair<const char*, double>{"longVehicleLength_m", -1.0}, {"maxOverlap", 1.5}}) {
    TrackerConfig bad = smallConfig();
    (std::string(field) == "maxOverlap" ? bad.maxOverlap : bad.longVehicleLength_m) = value;
    EXPECT_NE(initProblem(bad).find(field), std::string::npos) << field;
  }
}

// A track whose prediction comes to overlap a track fed by a detection, along one axis, is a
// duplicate of that vehicle (a bus's jumping box followed twice: the twins take every other
// detection): the younger is deleted, the older keeps its id. With the rule off both stay.
TEST(TrackManager, OfTwoOverlappingTracksTheYoungerIsDeleted) {
  auto run = [](double maxOverlap, int* merged) {
    TrackerConfig config = smallConfig();
    config.maxOverlap = maxOverlap;
    config.maxCoast_s = 0.3;
    TrackManager m;
    EXPECT_TRUE(m.init(config));
    *merged = 0;
    std::uint32_t firstId = 0;
    for (int f = 0; f < 12; ++f) {
      const std::int64_t t = f * kFrame_ns;
      std::vector<WorldDetection> dets{car(0.0, 0.0, 0.0, t)};
      if (f < 8) {  // the second box closes in at 10 m/s, then is seen no more
        dets.push_back(car(16.0 - 1.0 * f, 0.0, 0.0, t));
      }
      for (WorldDetection& d : dets) {
        d.length_m = 11.0;
        d.width_m = 2.6;
      }
      auto r = m.step(t, dets);
      EXPECT_TRUE(r.hasValue());
      *merged += r->mergedTracks;
      if (f == 0) {
        firstId = m.tracks()[0].id;
      }
    }
    std::vector<std::uint32_t> ids;
    for (const TrackState& s : m.tracks()) {
      ids.push_back(s.id);
    }
    EXPECT_NE(std::find(ids.begin(), ids.end(), firstId), ids.end());
    return ids.size();
  };
  int merged = 0;
  EXPECT_EQ(run(0.3, &merged), 1u);
  EXPECT_EQ(merged, 1);
  EXPECT_EQ(run(1.0, &merged), 2u);
  EXPECT_EQ(merged, 0);
}

// A bus driving at 10 m/s whose box stands still for four frames and then jumps 4 m (how the
// first stage boxes long vehicles): the jump fails the gates, the box overlaps the bus's track
// and is fused into it; the bus stays one track. With the overlap rule off, the jumps start
// new tracks.
TEST(TrackManager, ABusBoxThatStandsThenJumpsStaysOneTrack) {
  // The bus at 1 m per frame, its box in 4 m steps.
  auto steps = [](int f) { return Eigen::Vector2d(4.0 * (f / 4), 0.0); };
  TrackerConfig config = smallConfig();
  config.maxCoast_s = 0.3;
  const BusRun with = runBus(config, 0.0, steps);
  EXPECT_EQ(with.ids, 1u);
  EXPECT_GT(with.overlapMatches, 0);
  config.maxOverlap = 1.0;
  const BusRun without = runBus(config, 0.0, steps);
  EXPECT_GT(without.ids, 1u);
  EXPECT_EQ(without.overlapMatches, 0);
}

// A car driving into view at 10 m/s whose partial boxes lag (their centre moves at half its
// speed, then catches up): its track is confirmed only after two whole detections, and then with
// the car's speed, not the half speed of the partial boxes.
TEST(TrackManager, VehicleDrivingIntoViewIsConfirmedWithItsSpeed) {
  TrackerConfig config = smallConfig();
  config.noise.measurementPosition_m = 0.3;
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  constexpr double kSpeed = 10.0;
  std::int64_t t = 0;
  for (int k = 0; k < 12; ++k, t += kFrame_ns) {
    const double x = kSpeed * 0.1 * k;  // true centre
    WorldDetection d = car(x, 0.0, 0.0, t);
    if (k < 2) {  // entering: 40 and 70 % of the box inside, centre 1.5 and 1.0 m inside
      d.insideShare = 0.4 + 0.3 * k;
      d.atFrameEdge = true;
      d.centreEnu.x() = x + 1.5 - 0.5 * k;
    }
    ASSERT_TRUE(m.step(t, std::vector<WorldDetection>{d}).hasValue());
    ASSERT_EQ(m.tracks().size(), 1u);
    const TrackState& track = m.tracks()[0];
    if (k < 3) {  // three matches, but only one whole
      EXPECT_EQ(track.status, TrackStatus::Tentative) << "frame " << k;
    } else {
      EXPECT_EQ(track.status, TrackStatus::Confirmed) << "frame " << k;
      EXPECT_NEAR(track.speed_mps, kSpeed, 2.0) << "frame " << k;
    }
  }
}

// A parked car seen whole twice is confirmed on the second match (its speed is observed as
// about 0); one driving at 10 m/s still waits for confirmHits (lifecycle test above); a zero
// confirmHitsStanding is a configuration error.
TEST(TrackManager, StandingVehicleIsConfirmedAfterConfirmHitsStandingWholeMatches) {
  TrackerConfig config = smallConfig();
  ASSERT_EQ(config.confirmHitsStanding, 2);
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  std::int64_t t = 0;
  for (int k = 0; k < 3; ++k, t += kFrame_ns) {
    const double jitter_m = k == 1 ? 0.05 : 0.0;
    ASSERT_TRUE(
        m.step(t, std::vector<WorldDetection>{car(5.0 + jitter_m, 3.0, 1.0, t)}).hasValue());
    ASSERT_EQ(m.tracks().size(), 1u);
    EXPECT_EQ(m.tracks()[0].status, k == 0 ? TrackStatus::Tentative : TrackStatus::Confirmed)
        << "match " << k + 1;
  }
  EXPECT_LT(std::abs(m.tracks()[0].speed_mps), config.movingSpeed_mps);
  config.confirmHitsStanding = 0;
  EXPECT_NE(initProblem(config).find("confirmHitsStanding"), std::string::npos);
}

// With confirmMinScore 0.5, weak boxes (score 0.46: enough for a birth at highScore 0.45) keep a
// track tentative however long they last: its mean score stays below it; the same place seen
// with confident boxes confirms as usual. An out-of-range threshold is a configuration error.
TEST(TrackManager, TrackConfirmsOnlyWithAMeanScoreOfConfirmMinScore) {
  TrackerConfig config = smallConfig();
  config.association.highScore = 0.45f;
  EXPECT_DOUBLE_EQ(config.confirmMinScore, 0.0);  // off by default
  config.confirmMinScore = 0.5;
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  std::int64_t t = 0;
  for (int k = 0; k < 20; ++k, t += kFrame_ns) {
    ASSERT_TRUE(m.step(t, std::vector<WorldDetection>{car(5.0, 3.0, 1.0, t, 0.46f)}).hasValue());
    ASSERT_EQ(m.tracks().size(), 1u);
    EXPECT_EQ(m.tracks()[0].status, TrackStatus::Tentative) << "frame " << k;
  }
  EXPECT_NEAR(m.tracks()[0].score, 0.46, 1e-6);
  TrackManager strong;
  ASSERT_TRUE(strong.init(config));
  for (int k = 0; k < 2; ++k, t += kFrame_ns) {
    ASSERT_TRUE(
        strong.step(t, std::vector<WorldDetection>{car(5.0, 3.0, 1.0, t, 0.6f)}).hasValue());
  }
  EXPECT_EQ(strong.tracks()[0].status, TrackStatus::Confirmed);
  config.confirmMinScore = 1.5;
  EXPECT_NE(initProblem(config).find("confirmMinScore"), std::string::npos);
}

// A car that drives out of the frame (its last boxes touch the border) is deleted
// maxLostAtFrameEdge_s after its last detection, so a car driving in at the same place later
// gets a new id; one that disappears inside the frame (under a tree) is kept for maxLost_s.
TEST(TrackManager, TrackLastSeenAtTheFrameBorderIsDeletedSooner) {
  const TrackerConfig config = smallConfig();
  ASSERT_LT(config.maxLostAtFrameEdge_s + 0.5, config.maxLost_s);
  for (const bool atEdge : {true, false}) {
    TrackManager m;
    ASSERT_TRUE(m.init(config));
    std::int64_t t = 0;
    double x = 0.0;
    for (int k = 0; k < 10; ++k, t += kFrame_ns, x += 1.0) {
      WorldDetection d = car(x, 0.0, 0.0, t);
      d.atFrameEdge = atEdge && k == 9;  // the last box touches the border
      ASSERT_TRUE(m.step(t, std::vector<WorldDetection>{d}).hasValue());
    }
    ASSERT_EQ(m.tracks().size(), 1u);
    ASSERT_EQ(m.tracks()[0].status, TrackStatus::Confirmed);
    const std::int64_t lastSeen = t - kFrame_ns;
    auto aliveAfter = [&](double seconds) {
      while (t <= lastSeen + static_cast<std::int64_t>(seconds * 1e9)) {
        EXPECT_TRUE(m.step(t, {}).hasValue());
        t += kFrame_ns;
      }
      return !m.tracks().empty();
    };
    EXPECT_TRUE(aliveAfter(config.maxLostAtFrameEdge_s - 0.05)) << "at edge " << atEdge;
    EXPECT_EQ(aliveAfter(config.maxLostAtFrameEdge_s + 0.15), !atEdge) << "at edge " << atEdge;
    EXPECT_FALSE(aliveAfter(config.maxLost_s + 0.15)) << "at edge " << atEdge;
  }
  TrackerConfig bad = smallConfig();
  bad.maxLostAtFrameEdge_s = -1.0;
  EXPECT_NE(initProblem(bad), "");
}

// A car parked at the frame's border is only ever seen in part: it is confirmed after
// confirmHitsAnyway matches, standing still.
TEST(TrackManager, VehicleSeenOnlyInPartIsConfirmedAfterMoreMatches) {
  TrackerConfig config = smallConfig();
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  std::int64_t t = 0;
  for (int k = 0; k < config.confirmHitsAnyway; ++k, t += kFrame_ns) {
    WorldDetection d = car(5.0, 3.0, 1.0, t);
    d.insideShare = 0.5;
    d.atFrameEdge = true;
    ASSERT_TRUE(m.step(t, std::vector<WorldDetection>{d}).hasValue());
    ASSERT_EQ(m.tracks().size(), 1u);
    EXPECT_EQ(m.tracks()[0].status,
              k + 1 < config.confirmHitsAnyway ? TrackStatus::Tentative : TrackStatus::Confirmed)
        << "match " << k + 1;
  }
  EXPECT_LT(std::abs(m.tracks()[0].speed_mps), 0.5);
}

TEST(TrackManager, ConfirmedTrackCoastsThroughShortMissesThenTurnsLost) {
  TrackerConfig config = smallConfig();
  config.maxCoast_s = 0.25;  // 2 missed frames at 10 Hz stay confirmed, the 3rd does not
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  std::int64_t t = 0;
  double x = 0.0;
  auto stepAt = [&](bool detected) {
    std::vector<WorldDetection> d;
    if (detected) {
      d.push_back(car(x, 0.0, 0.0, t));
    }
    auto r = m.step(t, d);
    EXPECT_TRUE(r.hasValue());
    t += kFrame_ns;
    x += 1.0;
    return r;
  };
  for (int k = 0; k < 10; ++k) {
    stepAt(true);
  }
  ASSERT_EQ(m.tracks().size(), 1u);
  ASSERT_EQ(m.tracks()[0].status, TrackStatus::Confirmed);
  for (int k = 0; k < 2; ++k) {
    stepAt(false);
    EXPECT_EQ(m.tracks()[0].status, TrackStatus::Confirmed) << "miss " << k + 1;
    EXPECT_FALSE(m.tracks()[0].updated);
  }
  // Back within the coast window: confirmed, not a re-acquisition.
  auto back = stepAt(true);
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Confirmed);
  EXPECT_EQ(back->reacquisitions, 0);
  for (int k = 0; k < 3; ++k) {
    stepAt(false);
  }
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Lost);  // 0.3 s > 0.25 s
  auto again = stepAt(true);
  EXPECT_EQ(m.tracks()[0].status, TrackStatus::Confirmed);
  EXPECT_EQ(again->reacquisitions, 1);
}

TEST(TrackManager, TrackKeepsItsBirthTimeFusedScoreAndPoseCovariance) {
  TrackerConfig config = smallConfig();
  config.scoreMemory = 4;
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  const std::int64_t t0 = 3 * kFrame_ns;
  const float scores[] = {0.9f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f};
  std::int64_t t = t0;
  for (float score : scores) {
    ASSERT_TRUE(m.step(t, std::vector{car(0.0, 0.0, 0.0, t, score)}).hasValue());
    t += kFrame_ns;
  }
  ASSERT_EQ(m.tracks().size(), 1u);
  const TrackState& s = m.tracks()[0];
  EXPECT_EQ(s.birth_ns, t0);
  // A running mean over the first 4 frames (0.6), then forgetting at the rate of a 4-frame
  // mean over the next 4: 0.5 + 0.1 * (3/4)^4.
  EXPECT_NEAR(s.score, 0.5 + 0.1 * std::pow(0.75, 4), 1e-6);
  // The pose covariance is symmetric, positive definite, and agrees with the position sigma.
  EXPECT_TRUE(s.poseCovariance.isApprox(s.poseCovariance.transpose()));
  EXPECT_GT(s.poseCovariance.determinant(), 0.0);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s.poseCovariance.topLeftCorner<2, 2>());
  EXPECT_NEAR(std::sqrt(eig.eigenvalues().maxCoeff()), s.positionSigma_m, 1e-9);
  EXPECT_GT(s.poseCovariance(2, 2), 0.0);
  EXPECT_LT(std::sqrt(s.poseCovariance(2, 2)), config.noise.measurementHeading_rad);
  EXPECT_GE(s.yawRateSigma_radps, 0.0);

  config.scoreMemory = 0;
  TrackManager bad;
  std::string why;
  EXPECT_FALSE(bad.init(config, &why));
  EXPECT_NE(why.find("scoreMemory"), std::string::npos) << why;
}

// Length and width variances: the weighted spread of the detected sizes about the fused size
// (equal scores: the population variance of the detections), 0 after one detection, and the
// same spread once the weight cap forgets old frames.
TEST(TrackManager, SizeVariancesAreTheSpreadOfTheDetectedSizes) {
  const TrackerConfig config = smallConfig();
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  const double lengths[] = {4.3, 4.9, 4.5, 4.4, 4.6, 4.1, 4.7, 4.5};
  std::int64_t t = kFrame_ns;
  double sum = 0.0;
  double sumSq = 0.0;
  int n = 0;
  for (const double length : lengths) {
    WorldDetection d = car(0.0, 0.0, 0.0, t);
    d.length_m = length;
    ASSERT_TRUE(m.step(t, std::vector{d}).hasValue());
    ASSERT_EQ(m.tracks().size(), 1u);
    sum += length;
    sumSq += length * length;
    ++n;
    const double mean = sum / n;
    const TrackState& s = m.tracks()[0];
    EXPECT_NEAR(s.length_m, mean, 1e-9);
    EXPECT_NEAR(s.lengthVariance_m2, sumSq / n - mean * mean, 1e-9) << n;
    EXPECT_NEAR(s.widthVariance_m2, 0.0, 1e-12);  // every width 1.8
    t += kFrame_ns;
  }
  EXPECT_GT(m.tracks()[0].lengthVariance_m2, 0.0);

  // Long after the weight cap (shapeMaxWeight) started forgetting: lengths alternating 4.3 and
  // 4.7 keep a spread near 0.04 m^2 (a little less: the weights favour recent frames).
  for (int k = 0; k < 200; ++k) {
    WorldDetection d = car(0.0, 0.0, 0.0, t);
    d.length_m = k % 2 == 0 ? 4.3 : 4.7;
    ASSERT_TRUE(m.step(t, std::vector{d}).hasValue());
    t += kFrame_ns;
  }
  const TrackState& s = m.tracks()[0];
  EXPECT_NEAR(s.length_m, 4.5, 0.01);
  EXPECT_NEAR(s.lengthVariance_m2, 0.04, 0.004);
  EXPECT_GT(config.shapeMaxWeight, 0.0);
}

TEST(TrackManager, ParkedCarReacquiredAfterLongOcclusionKeepsId) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::int64_t t = 0;
  for (int k = 0; k < 20; ++k, t += kFrame_ns) {
    m.step(t, std::vector{car(3.0, 4.0, 1.0, t)});
  }
  const std::uint32_t id = m.tracks()[0].id;
  for (int k = 0; k < 25; ++k, t += kFrame_ns) {
    m.step(t, {});
  }
  m.step(t, std::vector{car(3.05, 4.0, 1.0, t)});
  ASSERT_EQ(m.tracks().size(), 1u);
  EXPECT_EQ(m.tracks()[0].id, id);
  EXPECT_LT(std::abs(m.tracks()[0].speed_mps), 0.3);
}

TEST(TrackManager, FlippedDetectionsAreCorrectedByMotion) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::int64_t t = 0;
  int corrections = 0;
  // Driving north at 8 m/s; the first detection and every 4th are flipped.
  for (int k = 0; k < 40; ++k, t += kFrame_ns) {
    const bool flip = k % 4 == 0;
    const double heading = 0.5 * geometry::kPi + (flip ? geometry::kPi : 0.0);
    auto r = m.step(t, std::vector{car(0.0, 0.8 * k, heading, t)});
    ASSERT_TRUE(r.hasValue());
    corrections += r->headingCorrections;
    ASSERT_EQ(m.tracks().size(), 1u);
  }
  const TrackState& s = m.tracks()[0];
  EXPECT_LT(geometry::absAngleDifference(s.headingEnu_rad, 0.5 * geometry::kPi), 0.05);
  EXPECT_NEAR(s.speed_mps, 8.0, 0.3);
  EXPECT_GE(corrections, 9);
  // Rear axle behind the centre (south of it) when driving north.
  EXPECT_LT(s.rearAxleEnu.y(), s.centreEnu.y());
}

TEST(TrackManager, StandingCarBornFlippedTurnsOnAgreeingDetections) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::int64_t t = 0;
  m.step(t, std::vector{car(0.0, 0.0, geometry::kPi, t)});  // flipped first detection
  for (int k = 1; k < 10; ++k) {
    t += kFrame_ns;
    m.step(t, std::vector{car(0.0, 0.0, 0.0, t)});
  }
  EXPECT_LT(geometry::absAngleDifference(m.tracks()[0].headingEnu_rad, 0.0), 0.1);
}

// A vehicle cut by the frame's border (partial detections) whose boxes point the other way
// keeps its heading: the detector may see one end of it only. Whole boxes do turn it.
TEST(TrackManager, PartialDetectionsDoNotVoteOnTheDirection) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::int64_t t = 0;
  m.step(t, std::vector{car(0.0, 0.0, 0.0, t)});
  for (int k = 1; k < 10; ++k) {
    t += kFrame_ns;
    WorldDetection d = car(0.0, 0.0, geometry::kPi, t);
    d.insideShare = 0.8;  // below partialInsideShare
    m.step(t, std::vector{d});
  }
  EXPECT_LT(geometry::absAngleDifference(m.tracks()[0].headingEnu_rad, 0.0), 0.1);
  for (int k = 0; k < 3; ++k) {
    t += kFrame_ns;
    m.step(t, std::vector{car(0.0, 0.0, geometry::kPi, t)});
  }
  EXPECT_LT(geometry::absAngleDifference(m.tracks()[0].headingEnu_rad, geometry::kPi), 0.1);
}

// A large vehicle standing in place is not confirmed on its second box: the first stage may box
// a truck's cab, which can stand still for frames while the truck drives; it waits for
// confirmHits as a moving vehicle does.
TEST(TrackManager, LargeVehicleWaitsForConfirmHitsLarge) {
  // A standing large vehicle and a standing car, side by side: the car confirms on its second
  // whole box (confirmHitsStanding), the large one neither then nor at confirmHits but at
  // confirmHitsLarge (its first boxes may be parts of a bus that stand still while it drives).
  TrackerConfig config = smallConfig();
  ASSERT_EQ(config.confirmHitsStanding, 2);
  ASSERT_EQ(config.confirmHits, 3);
  config.confirmHitsLarge = 6;
  TrackManager m;
  ASSERT_TRUE(m.init(config));
  std::int64_t t = 0;
  for (int k = 0; k < 7; ++k, t += kFrame_ns) {
    WorldDetection large = car(5.0, 3.0, 1.0, t);
    large.length_m = 9.0;
    large.typeProbabilities.fill(0.02f);
    large.typeProbabilities[static_cast<std::size_t>(shape::VehicleType::Large)] = 0.88f;
    WorldDetection small = car(5.0, 13.0, 1.0, t);
    small.typeProbabilities.fill(0.02f);
    small.typeProbabilities[static_cast<std::size_t>(shape::VehicleType::Sedan)] = 0.88f;
    ASSERT_TRUE(m.step(t, std::vector<WorldDetection>{large, small}).hasValue());
    ASSERT_EQ(m.tracks().size(), 2U);
    for (const TrackState& s : m.tracks()) {
      const bool isLarge = s.type == shape::VehicleType::Large;
      const int confirmAt = isLarge ? 6 : 2;
      EXPECT_EQ(s.status, k + 1 < confirmAt ? TrackStatus::Tentative : TrackStatus::Confirmed)
          << (isLarge ? "large" : "car") << ", match " << k + 1;
    }
  }
}

TEST(TrackManager, TypeIsFusedFromProbabilities) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::int64_t t = 0;
  // Per frame the argmax alternates between sedan (3) and SUV (4), but the SUV probability is
  // consistently high while sedan's swings: the product favours SUV although votes tie.
  for (int k = 0; k < 10; ++k, t += kFrame_ns) {
    WorldDetection d = car(k * 1.0, 0.0, 0.0, t);
    d.typeProbabilities.fill(0.02f);
    if (k % 2 == 0) {
      d.typeProbabilities[3] = 0.50f;
      d.typeProbabilities[4] = 0.40f;
    } else {
      d.typeProbabilities[3] = 0.05f;
      d.typeProbabilities[4] = 0.85f;
    }
    m.step(t, std::vector{d});
  }
  const TrackState& s = m.tracks()[0];
  EXPECT_EQ(s.type, shape::VehicleType::Suv);
  EXPECT_GT(s.typeProbabilities[4], 0.9f);
  float sum = 0.0f;
  for (float p : s.typeProbabilities) {
    sum += p;
  }
  EXPECT_NEAR(sum, 1.0f, 1e-5f);
}

TEST(TrackManager, BadInputIsCountedNotUsed) {
  TrackManager m;
  ASSERT_TRUE(m.init(smallConfig()));
  std::vector<WorldDetection> d = {car(0, 0, 0, 0), car(5, 0, 0, 0), car(10, 0, 0, 0),
                                   car(15, 0, 0, 0)};
  d[1].centreEnu.x() = std::nan("");
  d[2].length_m = 0.0;
  d[3].insideShare = std::nan("");
  auto r = m.step(0, d);
  ASSERT_TRUE(r.hasValue());
  EXPECT_EQ(r->rejectedDetections, 3);
  EXPECT_EQ(m.tracks().size(), 1u);
  EXPECT_EQ(m.step(-1, {}).error(), TrackError::TimeWentBackwards);
  // Over capacity: counted.
  std::vector<WorldDetection> many;
  for (int i = 0; i < 12; ++i) {
    many.push_back(car(20.0 * i, 50.0, 0.0, kFrame_ns));
  }
  r = m.step(kFrame_ns, many);
  ASSERT_TRUE(r.hasValue());
  EXPECT_EQ(r->droppedDetections, 4);
  EXPECT_GT(r->droppedBirths, 0);
}

TEST(TrajectoryCsv, HeaderAndRowCarrySeedColumnsFirst) {
  std::array<char, kTrajectoryCsvMaxLine> line{};
  ASSERT_GT(trajectoryCsvHeader(line, 3), 0);
  EXPECT_EQ(std::strncmp(line.data(),
                         "frame_id,class_id,track_id,velocity,coordinate_world_x_opt,"
                         "coordinate_world_y_opt,coordinate_world_x,coordinate_world_y,",
                         120),
            0);
  EXPECT_NE(std::string(line.data()).find("gamma_3\n"), std::string::npos);
  TrackState s;
  s.id = 42;
  s.type = shape::VehicleType::Suv;
  s.speed_mps = 8.5;
  s.rearAxleEnu = {1.0, 2.0};
  s.centreEnu = {2.25, 2.0};
  s.status = TrackStatus::Confirmed;
  s.shape.count = 3;
  const Wgs84Position p{47.1, 8.5, 420.0};
  const int n = trajectoryCsvRow(line, 17, s, &p, 3);
  ASSERT_GT(n, 0);
  const std::string row(line.data(), static_cast<std::size_t>(n));
  EXPECT_EQ(row.rfind("17,4,42,8.500,1.000,2.000,2.250,2.000,0.000,confirmed,47.10000000", 0), 0u)
      << row;
  // Column count = header column count.
  std::array<char, kTrajectoryCsvMaxLine> header{};
  trajectoryCsvHeader(header, 3);
  auto commas = [](const char* text) { return std::count(text, text + std::strlen(text), ','); };
  EXPECT_EQ(commas(line.data()), commas(header.data()));
  // The type's name, the variances, UTM and the rear axle's WGS84 after the wheelbase.
  s.lengthVariance_m2 = 0.0625;
  s.widthVariance_m2 = 0.01;
  TrajectoryPlace place;
  place.utmZone = 32;
  place.utmNorth = true;
  place.utmEasting_m = 461344.25;
  place.utmNorthing_m = 5216914.5;
  place.hasRearAxle = true;
  place.rearAxle = {47.09999, 8.49998, 419.875};
  const int m = trajectoryCsvRow(line, 17, s, &p, 3, &place);
  ASSERT_GT(m, 0);
  const std::string placed(line.data(), static_cast<std::size_t>(m));
  EXPECT_NE(placed.find(",suv,0.062500,0.010000,32,N,461344.250,5216914.500,47.09999000,"
                        "8.49998000,419.875,"),
            std::string::npos)
      << placed;
  std::array<char, 16> tiny{};
  EXPECT_EQ(trajectoryCsvRow(tiny, 1, s, nullptr, 3), -1);
}

TEST(TrackManager, NoHeapAllocationPerStepWith200Tracks) {
  TrackerConfig c = test::seedOneTracker();
  c.maxTracks = 256;
  c.maxDetections = 256;
  TrackManager m;
  ASSERT_TRUE(m.init(c));
  std::vector<std::vector<WorldDetection>> frames;
  for (int k = 0; k < 40; ++k) {
    frames.push_back(test::makeConvoyFrame(200, k, 10.0));
  }
  for (int k = 0; k < 10; ++k) {
    ASSERT_TRUE(m.step(frames[static_cast<std::size_t>(k)][0].timestamp_ns,
                       frames[static_cast<std::size_t>(k)])
                    .hasValue());
  }
  ASSERT_EQ(m.tracks().size(), 200u);
  vp::test::AllocationCounter counter;
  for (int k = 10; k < 40; ++k) {
    // Every fifth frame drops a tenth of the cars (lost tracks, re-acquisitions).
    auto& f = frames[static_cast<std::size_t>(k)];
    const std::size_t n = k % 5 == 0 ? 180 : f.size();
    auto r = m.step(f[0].timestamp_ns, std::span(f).first(n));
    ASSERT_TRUE(r.hasValue());
  }
  counter.stop();
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(m.tracks().size(), 200u);
  for (const TrackState& s : m.tracks()) {
    EXPECT_NEAR(s.speed_mps, 10.0, 0.5);
  }
}

}  // namespace
}  // namespace vp::tracking
