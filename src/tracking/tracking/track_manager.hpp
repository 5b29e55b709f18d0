// tracking/track_manager: the multi-vehicle tracker: lifecycle, heading disambiguation and
// fusion of type, shape and size over each track's frames.
//
// Contract: TrackManager() never fails; init() checks the configuration and allocates every
// buffer for config.maxTracks tracks and config.maxDetections detections per step; after
// that step() performs no heap allocation. step() takes one frame's world detections (all
// with the frame's timestamp) and returns a StepReport or a TrackError value, never throws.
// Bad detections (non-finite, size <= 0, score outside [0, 1]) are skipped and counted;
// detections beyond maxDetections and births beyond maxTracks are dropped and counted. Time
// must not go backwards (TrackError::TimeWentBackwards; nothing changes).
//
// Lifecycle (times in seconds of the detections' clock):
//   birth: an unmatched detection with score >= association.highScore -> Tentative
//   Tentative -> Confirmed after confirmHits matched frames of which confirmWholeHits were
//              not partial (cut by the frame border), or after confirmHitsAnyway matches,
//              or after confirmHitsStanding whole matches when its speed estimate is below
//              movingSpeed_mps and its fused type is not Large; in every case only while
//              the track's score (the mean of its detections' scores, TrackState::score)
//              is at least confirmMinScore
//              deleted when unmatched for longer than maxTentativeGap_s
//   Confirmed -> Lost when a frame brings no match; Lost -> Confirmed (same id) when a
//              detection matches again (re-acquisition after an occlusion); Lost -> deleted
//              after maxLost_s without a match. Lost tracks are predicted (a parked car
//              stays put), so the gates find the vehicle where it reappears; a lost track
//              last seen at the frame's border is deleted after maxLostAtFrameEdge_s.
// Heading: a matched detection whose heading differs from the track's by more than 90
// degrees is turned by 180 degrees before the update (counted). The track itself turns
// when it moves backwards faster than movingSpeed_mps with confidence (cars drive forwards),
// or, when it is not moving, when flipVotes whole detections in a row disagreed with it
// (partial ones neither count nor break the run).
// Type: p(type) ~ prod_frames p_det(type)^typeEvidenceWeight (a tempered naive Bayes in log
// space, floored at typeFloor: frames of one car are not independent). Shape gamma, length
// and width: score-weighted means with the total weight capped at shapeMaxWeight, so a slow
// change is still followed. Beside each size mean a running weighted variance (West's update
// with the same weights and forgetting): the spread of the track's detected lengths (widths)
// about the fused value, m^2, 0 while the track has a single detection. It is the spread of
// one detection, not the variance of the mean: a car's frames share their bias, so dividing
// by the number of frames would claim a precision the tracker does not have. The wheelbase and
// rear-axle offset come from the fused gamma through the ASM (when one is given and the type is a
// car), else from the length.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/expected.hpp"
#include "geometry/rotated_box.hpp"
#include "shape/vehicle_model.hpp"
#include "tracking/association.hpp"
#include "tracking/motion_model.hpp"
#include "tracking/track_status.hpp"
#include "tracking/world_detection.hpp"

namespace vp::tracking {

enum class TrackError : std::uint8_t {
  NotInitialised,
  TimeWentBackwards,
  AssociationFailed,  // a capacity check failed inside the associator (a bug, reported)
};
const char* toString(TrackError error);

struct TrackerConfig {
  int maxTracks = 256;
  int maxDetections = 512;
  MotionNoise noise{};
  AssociationParams association{};
  int confirmHits = 3;
  // Of those, at least this many whole (not partial, see below) detections: a vehicle seen only
  // in part has an unobserved speed, which a confirmed track would publish. A track confirms
  // after confirmHitsAnyway matches in any case (a car parked at the frame's border).
  int confirmWholeHits = 2;
  int confirmHitsAnyway = 5;
  // A track whose matches were all whole and whose speed estimate is below movingSpeed_mps
  // confirms after this many: the hold-off protects against one-off false detections and waits
  // until the speed is observable, and two whole boxes in place show both. A vehicle that moves
  // waits for confirmHits (its speed from two boxes 0.1 s apart is too rough to publish).
  int confirmHitsStanding = 2;
  // A track most likely of a large vehicle confirms after at least this many matches: the first
  // stage boxes buses and trucks in parts that stand still and jump, so their first boxes give
  // a wrong speed.
  int confirmHitsLarge = 6;
  // A tentative track confirms only while its score (mean of its detections' scores over the
  // last scoreMemory frames) is at least this. Off (0) by default: with detector v5, 0.5 kept
  // a few false tracks on shadows out on the tuning seeds but cost more occluded parked cars on
  // the held-out ones (docs/tracking.md); an option for detectors whose scores separate better.
  double confirmMinScore = 0.0;
  double maxTentativeGap_s = 0.25;
  double maxLost_s = 3.0;
  // A lost track whose last detection touched the frame's border (atFrameEdge) is deleted after
  // this instead: the vehicle has most likely driven out of view, and kept for maxLost_s the
  // track was re-acquired by a vehicle driving in at the same place, which inherited its id and
  // its motion the wrong way round (tuning seeds: docs/tracking.md).
  double maxLostAtFrameEdge_s = 1.0;
  double maxCoast_s = 0.3;  // a confirmed track unmatched this long stays confirmed, then lost
  double movingSpeed_mps = 1.5;
  int flipVotes = 3;
  double typeEvidenceWeight = 0.5;
  double typeFloor = 0.02;
  double shapeMaxWeight = 30.0;
  int scoreMemory = 10;  // frames over which TrackState::score averages, >= 1
  // A detection is partial when less than partialInsideShare of its image box lies inside the
  // frame (WorldDetection::insideShare): the detector places a vehicle driving into view too
  // far inside, so its centre hardly moves while the vehicle appears. Its position noise along
  // the track's axis is scaled by partialAlongNoiseFactor (across the axis it is as good as
  // any), at birth as in updates. A detection touching the border (atFrameEdge) weighs
  // frameEdgeShapeWeight in the size and shape means (its length may be short).
  double partialInsideShare = 0.97;
  double partialAlongNoiseFactor = 10.0;
  // A long vehicle's box jitters along its axis by more than a car's: the first stage places a
  // bus's or truck's ends less surely, frame to frame (metres, where a car's move by decimetres).
  // A vehicle longer than longVehicleLength_m (the track's fused length; the detection's at
  // birth) has its position sigma along the axis scaled by length / longVehicleLength_m, in the
  // association gate as in updates; without it a standing bus's jumping box failed the gate
  // and started a second track. 0 = off.
  double longVehicleLength_m = 6.0;
  // Two vehicles cannot stand in one place. Footprints along one axis (within the association's
  // maxAxisAngle_rad) overlapping by more than this share of the smaller of the two belong to
  // one vehicle. An unmatched confident detection that overlaps the predicted footprint of a
  // track left without a detection in this step is fused into it (StepReport::overlapMatches:
  // the first stage's box of a bus stands still for frames, then jumps by metres, past the
  // gates); one that overlaps only tracks fed in this step starts no track
  // (StepReport::suppressedBirths: a second box of a vehicle already followed, a part of a
  // bus). Of two tracks, neither lost and not both fed by a detection in this step, that
  // overlap after the step's updates the younger is deleted (StepReport::mergedTracks: twins
  // of one vehicle take every other detection). Cars queued bumper to bumper overlap by 0.
  // 1 = off.
  double maxOverlap = 0.3;
  double frameEdgeShapeWeight = 0.05;
  const shape::ActiveShapeModel* asmModel = nullptr;  // borrowed; wheelbase from gamma
};

// One track as published (a copy; valid until the next step).
struct TrackState {
  std::uint32_t id = 0;
  TrackStatus status = TrackStatus::Tentative;
  bool updated = false;                   // a detection was fused in this step
  std::int64_t timestamp_ns = 0;          // time of the state (this step)
  int hits = 0;                           // matched frames over the track's life
  std::int64_t birth_ns = 0;              // time of the track's first detection
  std::int64_t lastUpdate_ns = 0;         // time of the last fused detection
  Eigen::Vector2d centreEnu{0.0, 0.0};    // footprint centre, m
  Eigen::Vector2d rearAxleEnu{0.0, 0.0};  // rear-axle centre (seed 002's reference), m
  double headingEnu_rad = 0.0;
  double speed_mps = 0.0;
  double speedSigma_mps = 0.0;
  double acceleration_mps2 = 0.0;
  double accelerationSigma_mps2 = 0.0;
  double yawRate_radps = 0.0;
  double yawRateSigma_radps = 0.0;
  double steering_rad = 0.0;
  double positionSigma_m = 0.0;  // sqrt of the larger eigenvalue of the centre covariance
  // Covariance of (centre east, centre north, heading), m^2, m rad, rad^2.
  Eigen::Matrix3d poseCovariance{Eigen::Matrix3d::Zero()};
  // The detector's score fused over the track: mean of the matched detections' scores over
  // the last ~scoreMemory frames (a running mean while younger), [0, 1].
  double score = 0.0;
  double length_m = 0.0;
  double width_m = 0.0;
  // Weighted spread of the matched detections' lengths / widths about length_m / width_m,
  // m^2 (see the contract); 0 after the first detection.
  double lengthVariance_m2 = 0.0;
  double widthVariance_m2 = 0.0;
  double wheelbase_m = 0.0;
  std::array<float, shape::kVehicleTypeCount> typeProbabilities{};
  shape::VehicleType type = shape::VehicleType::Sedan;  // argmax of typeProbabilities
  shape::ShapeParams shape{};
  int headingCorrections = 0;  // detections turned by 180 degrees over the track's life
};

struct StepReport {
  int detectionsUsed = 0;
  int rejectedDetections = 0;  // non-finite, bad size or score
  int droppedDetections = 0;   // beyond maxDetections
  int droppedBirths = 0;       // no free track slot
  int suppressedBirths = 0;    // overlapping a live track (TrackerConfig::maxOverlap)
  int mergedTracks = 0;        // deleted as a younger duplicate (TrackerConfig::maxOverlap)
  int overlapMatches = 0;      // gated out, fused into the overlapping unmatched track
  int births = 0;
  int deletions = 0;
  int reacquisitions = 0;
  int headingCorrections = 0;
  AssociationStats association{};
};

class TrackManager {
 public:
  TrackManager() = default;
  TrackManager(const TrackManager&) = delete;
  TrackManager& operator=(const TrackManager&) = delete;

  bool init(const TrackerConfig& config, std::string* why = nullptr);
  Expected<StepReport, TrackError> step(std::int64_t timestamp_ns,
                                        std::span<const WorldDetection> detections);

  // Every live track (tentative, confirmed, lost), in slot order.
  std::span<const TrackState> tracks() const {
    return {published_.data(), static_cast<std::size_t>(publishedCount_)};
  }
  const TrackerConfig& config() const { return config_; }

 private:
  struct Slot {
    bool live = false;
    TrackState out{};
    MotionModel motion{};
    std::array<double, shape::kVehicleTypeCount> typeLog{};
    std::array<double, shape::kMaxShapeComponents> gammaSum{};
    double gammaWeight = 0.0;
    double sizeWeight = 0.0;
    // Weighted sums of squared deviations of the detected length and width from the running
    // means, forgotten like sizeWeight (variance = sum / sizeWeight).
    double lengthDeviationSq = 0.0;
    double widthDeviationSq = 0.0;
    int wholeHits = 0;             // matched detections that were not partial
    bool lastAtFrameEdge = false;  // the last matched detection touched the frame's border
    std::int64_t lastUpdate_ns = 0;
    int disagreeRun = 0;
  };

  void birth(Slot& slot, const WorldDetection& detection, std::int64_t timestamp_ns);
  void fuse(Slot& slot, const WorldDetection& detection, std::int64_t timestamp_ns,
            StepReport& report);
  void updateGeometry(Slot& slot);
  bool partial(const WorldDetection& detection) const {
    return detection.insideShare < config_.partialInsideShare;
  }
  // Position sigma factor along the vehicle's axis (>= 1) for a detection of a vehicle of
  // that length: partial detections and long vehicles (see TrackerConfig).
  double alongAxisFactor(const WorldDetection& detection, double length_m) const {
    return std::max(partial(detection) ? config_.partialAlongNoiseFactor : 1.0,
                    longVehicleFactor(length_m));
  }
  double longVehicleFactor(double length_m) const {
    return config_.longVehicleLength_m > 0.0 && length_m > config_.longVehicleLength_m
               ? length_m / config_.longVehicleLength_m
               : 1.0;
  }
  // The view of a live track the detection overlaps, preferring one not updated in this step;
  // -1 when none.
  int overlappingView(const WorldDetection& detection, int nViews) const;
  bool overlapping(const geometry::RotatedBox& a, const geometry::RotatedBox& b) const;
  int deleteYoungerDuplicates();
  void publish(Slot& slot, std::int64_t timestamp_ns);

  TrackerConfig config_{};
  bool initialised_ = false;
  bool started_ = false;
  std::int64_t lastTimeNs_ = 0;
  std::uint32_t nextId_ = 1;
  Associator associator_{};
  std::vector<Slot> slots_;
  std::vector<WorldDetection> detections_;  // this step's valid detections
  std::vector<TrackView> views_;
  std::vector<int> viewSlot_;
  std::vector<int> trackToDet_, detToTrack_;
  std::vector<TrackState> published_;
  int publishedCount_ = 0;
};

}  // namespace vp::tracking
