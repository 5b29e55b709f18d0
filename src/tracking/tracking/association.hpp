// tracking/association: which detection belongs to which track, in the world frame.
//
// Contract: an Associator is sized once by init() (maximum tracks and detections) and then
// associates without allocating. Each track is shown as a TrackView (predicted box centre,
// heading, size, innovation covariance S of its centre). A pair is considered only if it
// passes the gates, cheapest first: centre distance, then the heading axis (front/back
// ignored: flipped detections are corrected later by the track manager), then the squared
// Mahalanobis distance of the centre under S. A pair that passes costs
//   mahalanobisWeight * d2 / gate + iouWeight * (1 - rotated IoU of the world footprints),
// and the optimal assignment (an AssignmentSolver, Hungarian by default) is found in two
// passes as in ByteTrack: detections with score >= highScore against every track, then
// detections with lowScore <= score < highScore against the tracks still unmatched that
// allow it (confirmed and lost ones). Detections below lowScore are never used.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "tracking/hungarian.hpp"
#include "tracking/world_detection.hpp"

namespace vp::tracking {

struct AssociationParams {
  double maxDistance_m = 6.0;      // gate 1: centre distance
  double maxAxisAngle_rad = 0.6;   // gate 2: heading axis difference (~34 deg)
  double mahalanobisGate = 13.82;  // gate 3: chi-square, 2 dof, 99.9 %
  double mahalanobisWeight = 1.0;
  double iouWeight = 1.0;
  float highScore = 0.45f;  // first pass (and track birth) from here, [0, 1]
  float lowScore = 0.1f;    // second pass from here up to highScore, [0, highScore]
};

struct TrackView {
  Eigen::Vector2d centre{0.0, 0.0};
  double heading_rad = 0.0;
  double length_m = 4.5;
  double width_m = 1.8;
  Eigen::Matrix2d centreInnovationCov{Eigen::Matrix2d::Identity()};  // S = H P H^T + R, m^2
  bool secondPass = true;  // may take low-score detections
};

struct AssociationStats {
  int firstPassMatches = 0;
  int secondPassMatches = 0;
  int gatedPairs = 0;  // pairs that passed all three gates
};

class Associator {
 public:
  Associator() = default;
  // Start-up: work space for up to maxTracks x maxDetections. Replaces the solver with
  // the caller's (borrowed; must outlive the Associator) when given.
  bool init(int maxTracks, int maxDetections, const AssociationParams& params,
            AssignmentSolver* solver = nullptr);

  // trackToDet[t] / detToTrack[d] receive the partner index or -1. Spans must hold at least
  // tracks.size() / detections.size() entries and those sizes must not exceed init()'s.
  bool associate(std::span<const TrackView> tracks, std::span<const WorldDetection> detections,
                 std::span<int> trackToDet, std::span<int> detToTrack,
                 AssociationStats* stats = nullptr);

  // Cost of one pair after the gates, or kInfeasibleCost when a gate rejects it.
  float pairCost(const TrackView& track, const WorldDetection& detection) const;

  const AssociationParams& params() const { return params_; }

 private:
  bool runPass(std::span<const TrackView> tracks, std::span<const WorldDetection> detections,
               bool secondPass, std::span<int> trackToDet, std::span<int> detToTrack, int* matches,
               int* gated);

  AssociationParams params_{};
  HungarianSolver hungarian_{};
  AssignmentSolver* solver_ = nullptr;
  int maxTracks_ = 0;
  int maxDetections_ = 0;
  std::vector<float> costs_;
  std::vector<int> rows_, cols_, assignment_;
};

}  // namespace vp::tracking
