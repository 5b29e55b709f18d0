// The tracking measures (docs/evaluation.md, "Tracking"): hand-made truth/track cases with known
// MOTA, IDF1, id switches, fragmentations, speed RMSE, heading-flip shares and type OA-1, the
// matching rule against MotAccumulator, and sequences kept apart.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "evaluation/tracking_measures.hpp"
#include "geometry/rotated_box.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::evaluation {
namespace {

using geometry::kPi;
constexpr int kSedan = static_cast<int>(shape::VehicleType::Sedan);
constexpr int kSuv = static_cast<int>(shape::VehicleType::Suv);
constexpr int kVan = static_cast<int>(shape::VehicleType::Van);

TruthVehicle vehicle(std::int64_t id, double east, double north, double speed = 10.0,
                     int type = kSedan, double heading = 0.0) {
  TruthVehicle t;
  t.id = id;
  t.positionEnu = {east, north};
  t.headingEnu_rad = heading;
  t.speed_mps = speed;
  t.type = type;
  return t;
}

// A track on the truth vehicle (offset by `offset` m east), same heading, speed and type.
TrackObservation trackOn(std::int64_t id, const TruthVehicle& t, double offset = 0.0) {
  TrackObservation o;
  o.id = id;
  o.centreEnu = t.positionEnu + Eigen::Vector2d(offset, 0.0);
  o.headingEnu_rad = t.headingEnu_rad;
  o.speed_mps = t.speed_mps;
  o.type = t.type;
  return o;
}

TEST(TrackingMeasures, PerfectTracksArePerfect) {
  TrackingEvaluator e;
  for (int f = 0; f < 10; ++f) {
    const std::vector<TruthVehicle> truth{vehicle(1, f, 0.0), vehicle(2, -f, 10.0, 8.0, kSuv, kPi),
                                          vehicle(3, 30.0, 30.0, 0.0, kVan)};
    const std::vector<TrackObservation> tracks{trackOn(7, truth[0], 0.1), trackOn(8, truth[1]),
                                               trackOn(9, truth[2])};
    e.addFrame(truth, tracks);
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.mot.truthObjects, 30);
  EXPECT_EQ(s.mot.matches, 30);
  EXPECT_DOUBLE_EQ(s.mot.mota, 1.0);
  EXPECT_DOUBLE_EQ(s.mot.idf1, 1.0);
  EXPECT_EQ(s.mot.idSwitches, 0);
  EXPECT_EQ(s.mot.fragmentations, 0);
  EXPECT_EQ(s.mot.mostlyTracked, 3);
  EXPECT_NEAR(s.mot.motp_m, 0.1 / 3.0, 1e-12);
  EXPECT_EQ(s.tracks, 3);
  EXPECT_EQ(s.truthMoving, 20);  // vehicle 3 is parked
  EXPECT_EQ(s.speedSamples, 20);
  EXPECT_DOUBLE_EQ(s.speedRmse_mps, 0.0);
  EXPECT_EQ(s.trackHeadingSamples, 20);
  EXPECT_DOUBLE_EQ(s.trackFlipShare, 0.0);
  EXPECT_EQ(s.typedTracks, 3);
  EXPECT_DOUBLE_EQ(s.trackTypeOa1, 1.0);
  EXPECT_DOUBLE_EQ(s.trackFrameTypeOa1, 1.0);
  EXPECT_EQ(s.unmatchedTracks, 0);
  // Nothing from the detector: its figures have no samples.
  EXPECT_EQ(s.detectorFrames, 0);
  EXPECT_TRUE(std::isnan(s.detectorFlipShare));
  EXPECT_TRUE(std::isnan(s.detectorTypeOa1));
}

TEST(TrackingMeasures, IdSwapHalfWayCountsTwoSwitchesAndHalvesIdf1) {
  // Vehicles A (y = 0) and B (y = 10); tracks 10 and 20 trade vehicles at frame 5.
  TrackingEvaluator e;
  for (int f = 0; f < 10; ++f) {
    const TruthVehicle a = vehicle(1, f, 0.0);
    const TruthVehicle b = vehicle(2, f, 10.0);
    const bool swapped = f >= 5;
    const std::vector<TrackObservation> tracks{trackOn(swapped ? 20 : 10, a),
                                               trackOn(swapped ? 10 : 20, b)};
    e.addFrame(std::vector<TruthVehicle>{a, b}, tracks);
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.mot.idSwitches, 2);
  EXPECT_DOUBLE_EQ(s.mot.mota, 1.0 - 2.0 / 20.0);
  // Best one-to-one identity mapping keeps 5 + 5 of 20 truth and 20 track frames.
  EXPECT_DOUBLE_EQ(s.mot.idf1, 2.0 * 10.0 / 40.0);
  EXPECT_EQ(s.mot.fragmentations, 0);
  EXPECT_EQ(s.mot.falsePositives, 0);
  // Each track matched both vehicles 5 frames each: its vehicle is the one matched first.
  EXPECT_EQ(s.typedTracks, 2);
}

TEST(TrackingMeasures, MissesFalseTracksAndFragmentation) {
  // Vehicle A in frames 0..9; track 1 follows it except frames 4 and 5; a false track far
  // away in frames 0..2; a track 3 m beside A (beyond the 2 m gate) in frame 9.
  TrackingEvaluator e;
  for (int f = 0; f < 10; ++f) {
    const TruthVehicle a = vehicle(1, f, 0.0);
    std::vector<TrackObservation> tracks;
    if (f < 4 || f > 5) {
      tracks.push_back(trackOn(1, a));
    }
    if (f < 3) {
      tracks.push_back(trackOn(2, vehicle(99, 50.0, 50.0)));
    }
    if (f == 9) {
      tracks.push_back(trackOn(3, a, 3.0));
    }
    e.addFrame(std::vector<TruthVehicle>{a}, tracks);
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.mot.misses, 2);
  EXPECT_EQ(s.mot.falsePositives, 4);
  EXPECT_EQ(s.mot.idSwitches, 0);
  EXPECT_EQ(s.mot.fragmentations, 1);
  EXPECT_DOUBLE_EQ(s.mot.mota, 1.0 - (2.0 + 4.0) / 10.0);
  EXPECT_EQ(s.mot.mostlyTracked, 1);  // 8 of 10 frames
  EXPECT_EQ(s.tracks, 3);
  EXPECT_EQ(s.unmatchedTracks, 2);
  EXPECT_EQ(s.typedTracks, 1);
}

TEST(TrackingMeasures, IgnoredVehiclesAndWhatIsPairedWithThemAreNotCounted) {
  // Vehicle A is tracked throughout; vehicle B is hardly visible (ignore) in frames 0..4 and
  // has a track on it only in frames 3..9; vehicle C is ignore and never tracked.
  TrackingEvaluator e;
  for (int f = 0; f < 10; ++f) {
    const TruthVehicle a = vehicle(1, f, 0.0);
    TruthVehicle b = vehicle(2, f, 10.0);
    b.ignore = f < 5;
    TruthVehicle c = vehicle(3, 40.0, 40.0, 0.0);
    c.ignore = true;
    std::vector<TrackObservation> tracks{trackOn(1, a)};
    if (f >= 3) {
      tracks.push_back(trackOn(2, b, 0.5));
    }
    e.addFrame(std::vector<TruthVehicle>{a, b, c}, tracks);
    e.addDetectorFrame(std::vector<TruthVehicle>{a, b, c},
                       std::vector<DetectionObservation>{{a.positionEnu, 0.0, true, kSedan},
                                                         {c.positionEnu, 0.0, true, kSedan}});
  }
  const TrackingSummary s = e.summary();
  // Counted: A in 10 frames, B in frames 5..9; C never.
  EXPECT_EQ(s.mot.truthObjects, 15);
  EXPECT_EQ(s.ignoredTruth, 15);
  EXPECT_EQ(s.ignoredTrackRows, 2);  // track 2 on B in frames 3 and 4
  EXPECT_EQ(s.mot.hypotheses, 15);
  EXPECT_EQ(s.mot.misses, 0);
  EXPECT_EQ(s.mot.falsePositives, 0);
  EXPECT_DOUBLE_EQ(s.mot.mota, 1.0);
  EXPECT_DOUBLE_EQ(s.mot.idf1, 1.0);
  EXPECT_EQ(s.mot.truthTracks, 2);
  // The detector's detection on C is paired with it and left out as well.
  EXPECT_EQ(s.ignoredDetections, 10);
  EXPECT_EQ(s.detections, 10);
  EXPECT_EQ(s.detectionsMatched, 10);
}

TEST(TrackingMeasures, SpeedAndHeadingOfMovingVehiclesOnly) {
  // A drives east at 10 m/s; B is parked. Track on A: 11, 9, 11, ... m/s for frames 0..7,
  // then reversed (heading pi, -10 m/s) for frames 8 and 9. Track on B: 3 m/s, flipped.
  TrackingEvaluator e;
  for (int f = 0; f < 10; ++f) {
    const TruthVehicle a = vehicle(1, f, 0.0, 10.0);
    const TruthVehicle b = vehicle(2, 20.0, 20.0, 0.2);
    TrackObservation onA = trackOn(1, a);
    if (f < 8) {
      onA.speed_mps = f % 2 == 0 ? 11.0 : 9.0;
    } else {
      onA.speed_mps = -10.0;
      onA.headingEnu_rad = kPi;
    }
    TrackObservation onB = trackOn(2, b);
    onB.speed_mps = 3.0;
    onB.headingEnu_rad = kPi;
    e.addFrame(std::vector<TruthVehicle>{a, b}, std::vector<TrackObservation>{onA, onB});
    // The detector alone: on A flipped in frames 0..2, front/back unknown in frame 3; on B
    // flipped (parked: not counted); one detection far from everything.
    DetectionObservation dA;
    dA.positionEnu = a.positionEnu + Eigen::Vector2d(0.0, 1.5);
    dA.headingEnu_rad = f < 3 ? kPi + 0.3 : 6.2;
    dA.headingKnown = f != 3;
    dA.type = kSedan;
    DetectionObservation dB;
    dB.positionEnu = b.positionEnu;
    dB.headingEnu_rad = kPi;
    dB.type = f < 4 ? kSuv : kSedan;
    DetectionObservation far;
    far.positionEnu = {-100.0, 0.0};
    e.addDetectorFrame(std::vector<TruthVehicle>{a, b},
                       std::vector<DetectionObservation>{far, dB, dA});
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.truthMoving, 10);
  EXPECT_EQ(s.speedSamples, 10);
  EXPECT_NEAR(s.speedRmse_mps, std::sqrt(8.0 / 10.0), 1e-12);  // |-10| - 10 = 0 when reversed
  EXPECT_EQ(s.trackHeadingSamples, 10);
  EXPECT_EQ(s.trackHeadingFlips, 2);
  EXPECT_DOUBLE_EQ(s.trackFlipShare, 0.2);
  EXPECT_EQ(s.detectorFrames, 10);
  EXPECT_EQ(s.detections, 30);
  EXPECT_EQ(s.detectionsMatched, 20);
  EXPECT_EQ(s.detectorHeadingSamples, 9);
  EXPECT_EQ(s.detectorHeadingFlips, 3);
  EXPECT_EQ(s.detectorDirectionUnknown, 1);
  EXPECT_DOUBLE_EQ(s.detectorFlipShare, 3.0 / 9.0);
  EXPECT_EQ(s.detectorTypeSamples, 20);
  EXPECT_DOUBLE_EQ(s.detectorTypeOa1, 16.0 / 20.0);  // B called an SUV in 4 frames
}

TEST(TrackingMeasures, LargestSpeedErrorsListTheTracksThatCarryTheRmse) {
  // Three moving vehicles in two sequences: tracks off by 1, 3 and 0.5 m/s; one parked vehicle
  // (no speed samples: not listed). The list holds the largest sums first, capped by the option.
  TrackingOptions options;
  options.largestSpeedErrors = 2;
  TrackingEvaluator e(options);
  e.beginSequence();
  for (int f = 0; f < 4; ++f) {
    const TruthVehicle a = vehicle(1, f, 0.0, 10.0);
    const TruthVehicle b = vehicle(2, f, 10.0, 5.0, kVan, kPi);
    const TruthVehicle parked = vehicle(3, 40.0, 0.0, 0.0);
    TrackObservation onA = trackOn(11, a);
    onA.speed_mps = 11.0;
    TrackObservation onB = trackOn(12, b);
    onB.speed_mps = -8.0;  // |-8| - 5 = 3 m/s
    onB.headingEnu_rad = f < 1 ? 0.0 : kPi;
    TrackObservation onParked = trackOn(13, parked);
    onParked.speed_mps = 2.0;
    e.addFrame(std::vector<TruthVehicle>{a, b, parked},
               std::vector<TrackObservation>{onA, onB, onParked});
  }
  e.beginSequence();
  for (int f = 0; f < 2; ++f) {
    const TruthVehicle c = vehicle(1, f, 0.0, 10.0, kSuv);
    TrackObservation onC = trackOn(11, c);
    onC.speed_mps = 9.5;
    e.addFrame(std::vector<TruthVehicle>{c}, std::vector<TrackObservation>{onC});
  }
  const TrackingSummary s = e.summary();
  EXPECT_DOUBLE_EQ(s.speedSquaredErrorSum, 4 * 1.0 + 4 * 9.0 + 2 * 0.25);
  ASSERT_EQ(s.largestSpeedErrors.size(), 2U);
  const TrackSpeedError& first = s.largestSpeedErrors[0];
  EXPECT_EQ(first.sequence, 0);
  EXPECT_EQ(first.trackId, 12);
  EXPECT_EQ(first.vehicleId, 2);
  EXPECT_EQ(first.vehicleType, kVan);
  EXPECT_EQ(first.samples, 4);
  EXPECT_DOUBLE_EQ(first.squaredErrorSum, 36.0);
  EXPECT_EQ(first.headingFlips, 1);
  EXPECT_EQ(s.largestSpeedErrors[1].trackId, 11);
  EXPECT_EQ(s.largestSpeedErrors[1].sequence, 0);
  EXPECT_DOUBLE_EQ(s.largestSpeedErrors[1].squaredErrorSum, 4.0);
}

TEST(TrackingMeasures, TypePerTrackUsesTheLastFusedTypeAndTheMostMatchedVehicle) {
  TrackingEvaluator e;
  for (int f = 0; f < 6; ++f) {
    const TruthVehicle a = vehicle(1, f, 0.0, 10.0, kSedan);
    const TruthVehicle b = vehicle(2, f, 10.0, 10.0, kSuv);
    const TruthVehicle c = vehicle(3, f, 20.0, 10.0, kVan);
    TrackObservation t1 = trackOn(1, a);
    t1.type = f < 5 ? kSuv : kSedan;  // wrong for 5 frames, right at the end: right per track
    TrackObservation t2 = trackOn(2, b);
    t2.type = f < 5 ? kSuv : kSedan;  // right for 5 frames, wrong at the end: wrong per track
    // Track 3 follows C for frames 0..3, then drifts 10 m away and matches nothing.
    TrackObservation t3 = trackOn(3, c);
    if (f >= 4) {
      t3.centreEnu = {f, 30.0};
    }
    e.addFrame(std::vector<TruthVehicle>{a, b, c}, std::vector<TrackObservation>{t1, t2, t3});
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.typedTracks, 3);
  EXPECT_EQ(s.typeCorrectTracks, 2);
  EXPECT_DOUBLE_EQ(s.trackTypeOa1, 2.0 / 3.0);
  EXPECT_EQ(s.trackFrameTypeSamples, 16);
  EXPECT_DOUBLE_EQ(s.trackFrameTypeOa1, (1.0 + 5.0 + 4.0) / 16.0);
}

TEST(TrackingMeasures, TieBetweenVehiclesGoesToTheOneMatchedFirst) {
  TrackingEvaluator e;
  for (int f = 0; f < 4; ++f) {
    const TruthVehicle a = vehicle(1, 0.0, 0.0, 10.0, kSedan);
    const TruthVehicle b = vehicle(2, 0.0, 10.0, 10.0, kVan);
    // Track 5 on A for frames 0, 1, then on B for frames 2, 3; typed van throughout.
    TrackObservation t = trackOn(5, f < 2 ? a : b);
    t.type = kVan;
    e.addFrame(std::vector<TruthVehicle>{a, b}, std::vector<TrackObservation>{t});
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.typedTracks, 1);
  EXPECT_EQ(s.typeCorrectTracks, 0);  // A (a sedan) was matched first
}

TEST(TrackingMeasures, MatchingIsMotAccumulatorsRule) {
  // A crowded scene where the 2 m gate often holds several vehicles: the evaluator's own
  // pairs (behind speed, heading and type) are the pairs MotAccumulator counts.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.8);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  TrackingEvaluator e;
  for (int f = 0; f < 50; ++f) {
    std::vector<TruthVehicle> truth;
    std::vector<TrackObservation> tracks;
    for (int v = 0; v < 12; ++v) {
      truth.push_back(vehicle(v, 1.5 * v + 0.2 * f, 0.0, 10.0));
      if (unit(rng) < 0.85) {
        TrackObservation t = trackOn(unit(rng) < 0.1 ? 100 + v : v, truth.back());
        t.centreEnu += Eigen::Vector2d(noise(rng), noise(rng));
        t.speed_mps = 11.0;  // whichever vehicle it matches: error 1 m/s
        tracks.push_back(t);
      }
    }
    e.addFrame(truth, tracks);
  }
  const TrackingSummary s = e.summary();
  EXPECT_GT(s.mot.idSwitches, 0);
  EXPECT_GT(s.mot.misses, 0);
  EXPECT_EQ(s.speedSamples, s.mot.matches);
  EXPECT_EQ(s.trackFrameTypeSamples, s.mot.matches);
  EXPECT_NEAR(s.speedRmse_mps, 1.0, 1e-12);
}

TEST(TrackingMeasures, SequencesKeepTheirIdsApart) {
  // The same ids in two sequences are different vehicles and tracks: no switch, IDF1 1.
  TrackingEvaluator e;
  for (int sequence = 0; sequence < 2; ++sequence) {
    e.beginSequence();
    for (int f = 0; f < 5; ++f) {
      const TruthVehicle a = vehicle(1, f + 100.0 * sequence, 0.0);
      e.addFrame(std::vector<TruthVehicle>{a}, std::vector<TrackObservation>{trackOn(1, a)});
    }
  }
  const TrackingSummary s = e.summary();
  EXPECT_EQ(s.sequences, 2);
  EXPECT_EQ(s.mot.truthTracks, 2);
  EXPECT_EQ(s.tracks, 2);
  EXPECT_EQ(s.mot.idSwitches, 0);
  EXPECT_DOUBLE_EQ(s.mot.idf1, 1.0);
}

TEST(TrackingMeasures, MatchByDistanceKeepsLastFramesPairAndOtherwiseMinimisesDistance) {
  const std::vector<Eigen::Vector2d> truth{{0.0, 0.0}, {1.0, 0.0}};
  const std::vector<Eigen::Vector2d> hyps{{0.9, 0.0}, {2.5, 0.0}};
  // Without history: total distance 0.9 + 1.5 beats 0.1 + 2.5 (beyond the gate for truth 0).
  EXPECT_EQ(matchByDistance(truth, hyps, {}, 2.0), (std::vector<int>{0, 1}));
  // Truth 1 kept hypothesis 0 from the last frame: truth 0 gets nothing within 2 m.
  const std::vector<int> previous{-1, 0};
  EXPECT_EQ(matchByDistance(truth, hyps, previous, 2.0), (std::vector<int>{-1, 0}));
  EXPECT_EQ(matchByDistance(truth, {}, {}, 2.0), (std::vector<int>{-1, -1}));
}

}  // namespace
}  // namespace vp::evaluation
