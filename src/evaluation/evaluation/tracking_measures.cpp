#include "evaluation/tracking_measures.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotated_box.hpp"

namespace vp::evaluation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kFlipAngle_rad = 0.5 * geometry::kPi;  // heading error above: front/back swapped

double share(int count, int samples) {
  return samples > 0 ? static_cast<double>(count) / samples : kNaN;
}

bool isFlip(double truthHeading_rad, double heading_rad) {
  return geometry::absAngleDifference(truthHeading_rad, heading_rad) > kFlipAngle_rad;
}

}  // namespace

TrackingEvaluator::TrackingEvaluator(const TrackingOptions& options)
    : options_(options),
      mot_(MotParams{options.matchDistance_m, options.mostlyTrackedShare,
                     options.mostlyLostShare}) {}

void TrackingEvaluator::beginSequence() {
  ++sequence_;
  previousMatch_.clear();
}

int TrackingEvaluator::truthKey(std::int64_t id) {
  const auto [it, added] =
      truthKeys_.emplace(std::make_pair(sequence_, id), static_cast<int>(truthKeys_.size()));
  return it->second;
}

int TrackingEvaluator::trackKey(std::int64_t id) {
  const auto [it, added] =
      trackKeys_.emplace(std::make_pair(sequence_, id), static_cast<int>(trackKeys_.size()));
  return it->second;
}

namespace {

// The observations (at these positions) that the matching rule pairs with an ignored vehicle.
std::vector<bool> pairedWithIgnored(std::span<const TruthVehicle> truth,
                                    std::span<const Eigen::Vector2d> positions,
                                    std::span<const int> previous, double matchDistance_m) {
  std::vector<Eigen::Vector2d> truthPositions(truth.size());
  for (std::size_t g = 0; g < truth.size(); ++g) {
    truthPositions[g] = truth[g].positionEnu;
  }
  const std::vector<int> pairs =
      matchByDistance(truthPositions, positions, previous, matchDistance_m);
  std::vector<bool> paired(positions.size(), false);
  for (std::size_t g = 0; g < truth.size(); ++g) {
    if (truth[g].ignore && pairs[g] >= 0) {
      paired[static_cast<std::size_t>(pairs[g])] = true;
    }
  }
  return paired;
}

template <typename T, typename Drop>
std::vector<T> keepUnless(std::span<const T> items, Drop drop) {
  std::vector<T> kept;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (!drop(i)) {
      kept.push_back(items[i]);
    }
  }
  return kept;
}

bool anyIgnored(std::span<const TruthVehicle> truth) {
  return std::any_of(truth.begin(), truth.end(), [](const TruthVehicle& t) { return t.ignore; });
}

}  // namespace

void TrackingEvaluator::addFrame(std::span<const TruthVehicle> truth,
                                 std::span<const TrackObservation> tracks) {
  if (sequence_ < 0) {
    beginSequence();
  }
  if (!anyIgnored(truth)) {
    addCountedFrame(truth, tracks);
    return;
  }
  std::vector<Eigen::Vector2d> positions(tracks.size());
  for (std::size_t h = 0; h < tracks.size(); ++h) {
    positions[h] = tracks[h].centreEnu;
  }
  const std::vector<bool> drop =
      pairedWithIgnored(truth, positions, previousPairs(truth, tracks), options_.matchDistance_m);
  const std::vector<TruthVehicle> keptTruth =
      keepUnless(truth, [&](std::size_t g) { return truth[g].ignore; });
  const std::vector<TrackObservation> keptTracks =
      keepUnless(tracks, [&](std::size_t h) { return drop[h]; });
  ignoredTruth_ += static_cast<int>(truth.size() - keptTruth.size());
  ignoredTrackRows_ += static_cast<int>(tracks.size() - keptTracks.size());
  addCountedFrame(keptTruth, keptTracks);
}

std::vector<int> TrackingEvaluator::previousPairs(std::span<const TruthVehicle> truth,
                                                  std::span<const TrackObservation> tracks) {
  std::vector<int> previous(truth.size(), -1);
  for (std::size_t g = 0; g < truth.size(); ++g) {
    const auto it = previousMatch_.find(truthKey(truth[g].id));
    if (it == previousMatch_.end()) {
      continue;
    }
    for (std::size_t h = 0; h < tracks.size(); ++h) {
      if (trackKey(tracks[h].id) == it->second) {
        previous[g] = static_cast<int>(h);
        break;
      }
    }
  }
  return previous;
}

void TrackingEvaluator::addCountedFrame(std::span<const TruthVehicle> truth,
                                        std::span<const TrackObservation> tracks) {
  std::vector<int> truthKeys(truth.size());
  std::vector<int> trackKeys(tracks.size());
  std::vector<Eigen::Vector2d> truthPositions(truth.size());
  std::vector<Eigen::Vector2d> trackPositions(tracks.size());
  std::vector<MotObject> truthObjects(truth.size());
  std::vector<MotObject> trackObjects(tracks.size());
  for (std::size_t g = 0; g < truth.size(); ++g) {
    truthKeys[g] = truthKey(truth[g].id);
    truthType_.emplace(truthKeys[g], truth[g].type);
    truthId_.emplace(truthKeys[g], truth[g].id);
    truthPositions[g] = truth[g].positionEnu;
    truthObjects[g].id = truthKeys[g];
    truthObjects[g].position = truth[g].positionEnu;
  }
  for (std::size_t h = 0; h < tracks.size(); ++h) {
    trackKeys[h] = trackKey(tracks[h].id);
    TrackRecord& record = tracks_[trackKeys[h]];
    record.sequence = sequence_;
    record.id = tracks[h].id;
    record.lastType = tracks[h].type;
    trackPositions[h] = tracks[h].centreEnu;
    trackObjects[h].id = trackKeys[h];
    trackObjects[h].position = tracks[h].centreEnu;
  }
  mot_.addFrame(truthObjects, trackObjects);

  const std::vector<int> pairs = matchByDistance(
      truthPositions, trackPositions, previousPairs(truth, tracks), options_.matchDistance_m);
  std::map<int, int> current;
  for (std::size_t g = 0; g < truth.size(); ++g) {
    const TruthVehicle& t = truth[g];
    const bool moving = std::abs(t.speed_mps) > options_.movingSpeed_mps;
    truthMoving_ += moving ? 1 : 0;
    if (pairs[g] < 0) {
      continue;
    }
    const auto h = static_cast<std::size_t>(pairs[g]);
    const TrackObservation& track = tracks[h];
    current[truthKeys[g]] = trackKeys[h];
    auto [entry, added] =
        tracks_[trackKeys[h]].truthFrames.emplace(truthKeys[g], std::make_pair(0, matchOrder_));
    ++entry->second.first;
    ++matchOrder_;
    if (moving) {
      const double e = std::abs(track.speed_mps) - std::abs(t.speed_mps);
      const int flip = isFlip(t.headingEnu_rad, track.headingEnu_rad) ? 1 : 0;
      speedSquaredSum_ += e * e;
      ++speedSamples_;
      ++trackHeadingSamples_;
      trackHeadingFlips_ += flip;
      TrackRecord& record = tracks_[trackKeys[h]];
      record.speedSquaredSum += e * e;
      ++record.speedSamples;
      record.headingFlips += flip;
    }
    if (t.type >= 0 && track.type >= 0) {
      ++trackFrameTypeSamples_;
      trackFrameTypeCorrect_ += t.type == track.type ? 1 : 0;
    }
  }
  previousMatch_ = std::move(current);
}

void TrackingEvaluator::addDetectorFrame(std::span<const TruthVehicle> truth,
                                         std::span<const DetectionObservation> detections) {
  if (!anyIgnored(truth)) {
    addCountedDetectorFrame(truth, detections);
    return;
  }
  std::vector<Eigen::Vector2d> positions(detections.size());
  for (std::size_t d = 0; d < detections.size(); ++d) {
    positions[d] = detections[d].positionEnu;
  }
  const std::vector<bool> drop = pairedWithIgnored(truth, positions, {}, options_.matchDistance_m);
  const std::vector<DetectionObservation> keptDetections =
      keepUnless(detections, [&](std::size_t d) { return drop[d]; });
  ignoredDetections_ += static_cast<int>(detections.size() - keptDetections.size());
  // The ignored vehicles themselves are counted once, by addFrame.
  addCountedDetectorFrame(keepUnless(truth, [&](std::size_t g) { return truth[g].ignore; }),
                          keptDetections);
}

void TrackingEvaluator::addCountedDetectorFrame(std::span<const TruthVehicle> truth,
                                                std::span<const DetectionObservation> detections) {
  ++detectorFrames_;
  detections_ += static_cast<int>(detections.size());
  std::vector<Eigen::Vector2d> truthPositions(truth.size());
  std::vector<Eigen::Vector2d> positions(detections.size());
  for (std::size_t g = 0; g < truth.size(); ++g) {
    truthPositions[g] = truth[g].positionEnu;
  }
  for (std::size_t d = 0; d < detections.size(); ++d) {
    positions[d] = detections[d].positionEnu;
  }
  const std::vector<int> pairs =
      matchByDistance(truthPositions, positions, {}, options_.matchDistance_m);
  for (std::size_t g = 0; g < truth.size(); ++g) {
    if (pairs[g] < 0) {
      continue;
    }
    const TruthVehicle& t = truth[g];
    const DetectionObservation& detection = detections[static_cast<std::size_t>(pairs[g])];
    ++detectionsMatched_;
    if (std::abs(t.speed_mps) > options_.movingSpeed_mps) {
      if (detection.headingKnown) {
        ++detectorHeadingSamples_;
        detectorHeadingFlips_ += isFlip(t.headingEnu_rad, detection.headingEnu_rad) ? 1 : 0;
      } else {
        ++detectorDirectionUnknown_;
      }
    }
    if (t.type >= 0 && detection.type >= 0) {
      ++detectorTypeSamples_;
      detectorTypeCorrect_ += t.type == detection.type ? 1 : 0;
    }
  }
}

TrackingSummary TrackingEvaluator::summary() const {
  TrackingSummary s;
  s.mot = mot_.summary();
  s.sequences = sequence_ + 1;
  s.tracks = static_cast<int>(tracks_.size());
  s.truthMoving = truthMoving_;
  s.ignoredTruth = ignoredTruth_;
  s.ignoredTrackRows = ignoredTrackRows_;
  s.ignoredDetections = ignoredDetections_;
  s.speedSamples = speedSamples_;
  s.speedRmse_mps = speedSamples_ > 0 ? std::sqrt(speedSquaredSum_ / speedSamples_) : kNaN;
  s.speedSquaredErrorSum = speedSquaredSum_;
  s.trackHeadingSamples = trackHeadingSamples_;
  s.trackHeadingFlips = trackHeadingFlips_;
  s.trackFlipShare = share(trackHeadingFlips_, trackHeadingSamples_);
  s.detectorHeadingSamples = detectorHeadingSamples_;
  s.detectorHeadingFlips = detectorHeadingFlips_;
  s.detectorFlipShare = share(detectorHeadingFlips_, detectorHeadingSamples_);
  s.detectorDirectionUnknown = detectorDirectionUnknown_;
  for (const auto& [key, record] : tracks_) {
    if (record.truthFrames.empty()) {
      ++s.unmatchedTracks;
      continue;
    }
    // The vehicle matched in most frames; ties: the one matched first.
    auto best = record.truthFrames.begin();
    for (auto it = record.truthFrames.begin(); it != record.truthFrames.end(); ++it) {
      if (it->second.first > best->second.first ||
          (it->second.first == best->second.first && it->second.second < best->second.second)) {
        best = it;
      }
    }
    const int truthType = truthType_.at(best->first);
    if (truthType >= 0 && record.lastType >= 0) {
      ++s.typedTracks;
      s.typeCorrectTracks += truthType == record.lastType ? 1 : 0;
    }
    if (record.speedSamples > 0) {
      s.largestSpeedErrors.push_back({record.sequence, record.id, truthId_.at(best->first),
                                      truthType, record.speedSamples, record.speedSquaredSum,
                                      record.headingFlips});
    }
  }
  std::sort(s.largestSpeedErrors.begin(), s.largestSpeedErrors.end(),
            [](const TrackSpeedError& a, const TrackSpeedError& b) {
              return a.squaredErrorSum > b.squaredErrorSum;
            });
  const auto listed = static_cast<std::size_t>(std::max(0, options_.largestSpeedErrors));
  if (s.largestSpeedErrors.size() > listed) {
    s.largestSpeedErrors.resize(listed);
  }
  s.trackTypeOa1 = share(s.typeCorrectTracks, s.typedTracks);
  s.trackFrameTypeSamples = trackFrameTypeSamples_;
  s.trackFrameTypeOa1 = share(trackFrameTypeCorrect_, trackFrameTypeSamples_);
  s.detectorTypeSamples = detectorTypeSamples_;
  s.detectorTypeOa1 = share(detectorTypeCorrect_, detectorTypeSamples_);
  s.detectorFrames = detectorFrames_;
  s.detections = detections_;
  s.detectionsMatched = detectionsMatched_;
  return s;
}

}  // namespace vp::evaluation
