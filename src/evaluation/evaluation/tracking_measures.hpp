// evaluation/tracking_measures: the tracking measures of recorded sequences: the
// CLEAR MOT and identity measures of the confirmed tracks against the ground-truth vehicles,
// speed and driving-direction errors of moving vehicles, and the vehicle type per track, each
// beside the same figure of the detector alone where one exists.
//
// Contract: a TrackingEvaluator is given, frame by frame, the ground-truth vehicles and the
// confirmed tracks (addFrame), and optionally the same frame's lifted detections
// (addDetectorFrame); summary() computes the measures. Definitions (docs/evaluation.md):
//   - ignored truth: a vehicle marked ignore (hardly visible: the detection evaluation's
//     occlusion / truncation limits) is neither a miss when no track is on it nor makes the
//     track on it a false positive: per frame, tracks are first paired with all vehicles by
//     the rule below; the ignored vehicles and the tracks paired with them are then left out
//     of every measure (the MOT Challenge's treatment of distractors);
//   - matching, per frame in world ENU: a truth/track pair counts when the footprint centres
//     are at most matchDistance_m apart; a pair matched in the previous frame is kept while it
//     stays within the distance, the rest are paired by minimum total distance (Hungarian) —
//     the rule of MotAccumulator (matchByDistance), which gives MOTA, MOTP, IDF1, id switches,
//     fragmentations and mostly tracked / lost. Detections are paired the same way without
//     the previous frame (they have no identity);
//   - moving: a truth vehicle with |speed| > movingSpeed_mps in that frame;
//   - speed RMSE over matched track-frames of moving vehicles, on |speed| (the direction is
//     judged by the heading measure);
//   - heading flips: share of matched track-frames (detections) of moving vehicles whose
//     heading differs from the truth's by more than 90 degrees; detections whose front/back is
//     unknown are left out and counted;
//   - the tracks that carry the speed error: per confirmed track its moving track-frames, sum
//     of squared speed errors and heading flips; summary() lists the largest sums (diagnosis:
//     one badly tracked vehicle can decide the RMSE);
//   - type OA-1 per track: each track's last fused type against the type of the truth vehicle
//     it was matched to in most frames (ties: the one matched first); tracks never matched are
//     counted apart. Also per track-frame (the type of each matched track row) and per frame
//     for the detector (top type of each matched detection).
// Several sequences: call beginSequence() before each one; ids are then kept apart per
// sequence. Offline: it allocates; the real-time loop never calls it. Values without samples
// are NaN, never 0.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "evaluation/mot_metrics.hpp"

namespace vp::evaluation {

constexpr double kDefaultTrackMatchDistance_m = 2.0;  // world gate of a truth/track pair
constexpr double kDefaultMovingSpeed_mps = 0.5;       // truth speed above which a vehicle moves

struct TruthVehicle {
  std::int64_t id = 0;                    // ground-truth track_id (unique within a sequence)
  Eigen::Vector2d positionEnu{0.0, 0.0};  // footprint centre, world ENU, m
  double headingEnu_rad = 0.0;            // driving direction
  double speed_mps = 0.0;
  int type = -1;        // static_cast<int>(shape::VehicleType), -1 unknown
  bool ignore = false;  // hardly visible: left out with whatever is paired with it
};

struct TrackObservation {
  std::int64_t id = 0;                  // track_id (unique within a sequence)
  Eigen::Vector2d centreEnu{0.0, 0.0};  // footprint (box) centre, world ENU, m
  double headingEnu_rad = 0.0;
  double speed_mps = 0.0;  // signed
  int type = -1;           // the fused type of this row
};

struct DetectionObservation {
  Eigen::Vector2d positionEnu{0.0, 0.0};  // lifted footprint centre, world ENU, m
  double headingEnu_rad = 0.0;
  bool headingKnown = true;  // false: front/back undecided (left out of the flip share)
  int type = -1;             // top type
};

struct TrackingOptions {
  double matchDistance_m = kDefaultTrackMatchDistance_m;
  int largestSpeedErrors = 10;  // how many tracks TrackingSummary::largestSpeedErrors lists
  double movingSpeed_mps = kDefaultMovingSpeed_mps;
  double mostlyTrackedShare = 0.8;  // matched in >= this share of its frames
  double mostlyLostShare = 0.2;     // matched in <= this share
};

// One track's part of the speed error (TrackingSummary::largestSpeedErrors).
struct TrackSpeedError {
  int sequence = 0;            // index of the sequence (beginSequence order)
  std::int64_t trackId = 0;    // track_id in that sequence
  std::int64_t vehicleId = 0;  // the truth vehicle matched in most frames
  int vehicleType = -1;        // its type, -1 unknown
  int samples = 0;             // matched track-frames of moving vehicles
  double squaredErrorSum = 0.0;
  int headingFlips = 0;
};

struct TrackingSummary {
  MotSummary mot{};  // MOTA, MOTP, IDF1, id switches, ... (its speed/heading/type
                     // fields are unused: see the fields below)
  int sequences = 0;
  int tracks = 0;             // distinct confirmed tracks
  int ignoredTruth = 0;       // truth vehicle-frames marked ignore (not in truthObjects)
  int ignoredTrackRows = 0;   // track rows paired with them (not in hypotheses)
  int ignoredDetections = 0;  // detections paired with them (detector alone)
  int truthMoving = 0;        // truth vehicle-frames that move
  // speed (matched track-frames of moving vehicles)
  int speedSamples = 0;
  double speedRmse_mps = 0.0;
  double speedSquaredErrorSum = 0.0;
  std::vector<TrackSpeedError> largestSpeedErrors;  // largest squaredErrorSum first
  // heading > 90 degrees on moving vehicles
  int trackHeadingSamples = 0;
  int trackHeadingFlips = 0;
  double trackFlipShare = 0.0;
  int detectorHeadingSamples = 0;
  int detectorHeadingFlips = 0;
  double detectorFlipShare = 0.0;
  int detectorDirectionUnknown = 0;  // matched detections of moving vehicles without front/back
  // type
  int typedTracks = 0;  // confirmed tracks matched at least once to a vehicle of known type
  int typeCorrectTracks = 0;
  double trackTypeOa1 = 0.0;
  int unmatchedTracks = 0;  // confirmed tracks never matched
  int trackFrameTypeSamples = 0;
  double trackFrameTypeOa1 = 0.0;
  int detectorTypeSamples = 0;
  double detectorTypeOa1 = 0.0;
  // detector alone
  int detectorFrames = 0;  // frames given to addDetectorFrame
  int detections = 0;
  int detectionsMatched = 0;
};

class TrackingEvaluator {
 public:
  explicit TrackingEvaluator(const TrackingOptions& options = {});

  // Starts a new sequence: its ids never meet the previous sequences' ids.
  void beginSequence();
  // One frame: every truth vehicle present and the confirmed tracks.
  void addFrame(std::span<const TruthVehicle> truth, std::span<const TrackObservation> tracks);
  // The same frame's lifted detections (the detector alone).
  void addDetectorFrame(std::span<const TruthVehicle> truth,
                        std::span<const DetectionObservation> detections);
  TrackingSummary summary() const;

 private:
  struct TrackRecord {
    int sequence = 0;
    std::int64_t id = 0;
    int lastType = -1;
    int speedSamples = 0;
    double speedSquaredSum = 0.0;
    int headingFlips = 0;
    std::map<int, std::pair<int, int>> truthFrames;  // truth key -> (frames matched, order)
  };
  int truthKey(std::int64_t id);
  int trackKey(std::int64_t id);
  // For each truth, the index of the track it was paired with in the last frame, or -1.
  std::vector<int> previousPairs(std::span<const TruthVehicle> truth,
                                 std::span<const TrackObservation> tracks);
  // The frame without ignored vehicles and what is paired with them.
  void addCountedFrame(std::span<const TruthVehicle> truth,
                       std::span<const TrackObservation> tracks);
  void addCountedDetectorFrame(std::span<const TruthVehicle> truth,
                               std::span<const DetectionObservation> detections);

  TrackingOptions options_;
  MotAccumulator mot_;
  int sequence_ = -1;
  std::map<std::pair<int, std::int64_t>, int> truthKeys_;  // (sequence, truth id) -> key
  std::map<std::pair<int, std::int64_t>, int> trackKeys_;  // (sequence, track id) -> key
  std::map<int, int> truthType_;                           // truth key -> type
  std::map<int, std::int64_t> truthId_;                    // truth key -> truth id
  std::map<int, int> previousMatch_;                       // truth key -> track key
  std::map<int, TrackRecord> tracks_;                      // track key -> record
  int matchOrder_ = 0;
  int truthMoving_ = 0;
  int ignoredTruth_ = 0;
  int ignoredTrackRows_ = 0;
  int ignoredDetections_ = 0;
  int speedSamples_ = 0;
  double speedSquaredSum_ = 0.0;
  int trackHeadingSamples_ = 0;
  int trackHeadingFlips_ = 0;
  int trackFrameTypeSamples_ = 0;
  int trackFrameTypeCorrect_ = 0;
  int detectorFrames_ = 0;
  int detections_ = 0;
  int detectionsMatched_ = 0;
  int detectorHeadingSamples_ = 0;
  int detectorHeadingFlips_ = 0;
  int detectorDirectionUnknown_ = 0;
  int detectorTypeSamples_ = 0;
  int detectorTypeCorrect_ = 0;
};

}  // namespace vp::evaluation
