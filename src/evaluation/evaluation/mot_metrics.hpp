// evaluation/mot_metrics: multi-object tracking measures against ground truth, in the world.
//
// Contract: an offline evaluation helper (it allocates; never call it in the loop).
// MotAccumulator takes, frame by frame, the true objects and the tracker's hypotheses (id +
// world position, optionally speed, heading and type) and summarises them as CLEAR MOT
// (Bernardin & Stiefelhagen 2008) and identity measures (Ristani et al. 2016):
//   match: a truth/hypothesis pair closer than matchDistance_m; a pair matched in the
//          previous frame is kept while it stays within the distance, the rest are paired by
//          minimum total distance (Hungarian): matchByDistance(), the one matcher that
//          evaluation/tracking_measures uses too;
//   MOTA = 1 - (misses + false positives + id switches) / truth objects;
//   MOTP = mean distance of the matched pairs, m (lower is better);
//   id switch: a truth object matched to a hypothesis other than the one it was last matched
//          to; fragmentation: a truth trajectory that becomes tracked again after having
//          been tracked and then missed;
//   mostly tracked / lost: matched in >= 80 % / <= 20 % of the frames it is present;
//   IDF1 = 2 IDTP / (truth objects + hypotheses), IDTP from the one-to-one truth-id to
//          hypothesis-id mapping that maximises the frames matched within the distance.
// On matched pairs it also gathers the speed RMSE, the count of heading errors > 90 degrees
// and top-1 type accuracy (fields that are NaN / -1 are skipped).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace vp::evaluation {

// The pairs of one frame under the rule above: for each truth, the index of its hypothesis or
// -1. previous (truth index -> hypothesis index kept from the last frame, or -1) may be empty.
std::vector<int> matchByDistance(std::span<const Eigen::Vector2d> truth,
                                 std::span<const Eigen::Vector2d> hypotheses,
                                 std::span<const int> previous, double matchDistance_m);

struct MotObject {
  int id = 0;
  Eigen::Vector2d position{0.0, 0.0};  // world ENU, m
  double speed_mps = std::numeric_limits<double>::quiet_NaN();
  double heading_rad = std::numeric_limits<double>::quiet_NaN();
  int type = -1;  // static_cast<int>(shape::VehicleType), -1 unknown
};

struct MotParams {
  double matchDistance_m = 1.5;
  double mostlyTrackedShare = 0.8;
  double mostlyLostShare = 0.2;
};

struct MotSummary {
  int frames = 0;
  int truthObjects = 0;
  int hypotheses = 0;
  int matches = 0;
  int misses = 0;
  int falsePositives = 0;
  int idSwitches = 0;
  int fragmentations = 0;
  int truthTracks = 0;
  int mostlyTracked = 0;
  int partiallyTracked = 0;
  int mostlyLost = 0;
  double mota = 0.0;
  double motp_m = 0.0;
  double idf1 = 0.0;
  double idPrecision = 0.0;
  double idRecall = 0.0;
  double speedRmse_mps = 0.0;
  int speedSamples = 0;
  int headingOver90 = 0;
  int headingSamples = 0;
  int typeCorrect = 0;
  int typeSamples = 0;
};

class MotAccumulator {
 public:
  explicit MotAccumulator(const MotParams& params = {}) : params_(params) {}
  void addFrame(std::span<const MotObject> truth, std::span<const MotObject> hypotheses);
  MotSummary summary() const;

 private:
  struct TruthTrack {
    int present = 0;
    int matched = 0;
    int lastHypothesis = -1;  // last hypothesis id it was matched to (ever), -1 none
    bool trackedBefore = false;
    bool trackedLastPresent = false;
  };
  MotParams params_;
  MotSummary sums_{};
  double distanceSum_ = 0.0;
  double speedSquaredSum_ = 0.0;
  std::map<int, TruthTrack> truthTracks_;
  std::map<int, int> previousMatch_;  // truth id -> hypothesis id matched in the last frame
  std::map<std::pair<int, int>, int> pairFrames_;  // (truth id, hyp id) -> frames within distance
  std::map<int, int> hypothesisCount_;             // hyp id -> frames present
};

}  // namespace vp::evaluation
