#include "tracking/track_manager.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotated_box.hpp"

namespace vp::tracking {
namespace {

constexpr double kNsPerS = 1e9;
// Without an ASM: a car's wheelbase is ~60 % of its length, its rear axle ~28 % of the
// length behind the centre (typical overhangs).
constexpr double kWheelbasePerLength = 0.60;
constexpr double kRearAxlePerLength = 0.28;

// The type with the largest fused log-probability.
shape::VehicleType mostLikelyType(const std::array<double, shape::kVehicleTypeCount>& typeLog) {
  const auto best = std::max_element(typeLog.begin(), typeLog.end());
  return static_cast<shape::VehicleType>(best - typeLog.begin());
}

bool valid(const WorldDetection& d) {
  if (!std::isfinite(d.centreEnu.x()) || !std::isfinite(d.centreEnu.y()) ||
      !std::isfinite(d.headingEnu_rad) || !std::isfinite(d.length_m) || !std::isfinite(d.width_m) ||
      !(d.length_m > 0.0) || !(d.width_m > 0.0) || !(d.score >= 0.0f) || !(d.score <= 1.0f) ||
      !(d.insideShare >= 0.0 && d.insideShare <= 1.0)) {
    return false;
  }
  for (float p : d.typeProbabilities) {
    if (!std::isfinite(p) || p < 0.0f) {
      return false;
    }
  }
  for (int s = 0; s < d.shape.count && s < shape::kMaxShapeComponents; ++s) {
    if (!std::isfinite(d.shape.gamma[static_cast<std::size_t>(s)])) {
      return false;
    }
  }
  return d.shape.count >= 0 && d.shape.count <= shape::kMaxShapeComponents;
}

}  // namespace

const char* toString(TrackError error) {
  switch (error) {
    case TrackError::NotInitialised:
      return "tracker not initialised";
    case TrackError::TimeWentBackwards:
      return "frame time went backwards";
    case TrackError::AssociationFailed:
      return "association failed (capacity)";
  }
  return "?";
}

bool TrackManager::init(const TrackerConfig& config, std::string* why) {
  auto fail = [&](const char* message) {
    if (why != nullptr) {
      *why = message;
    }
    return false;
  };
  if (config.maxTracks <= 0 || config.maxDetections <= 0) {
    return fail("tracking: maxTracks and maxDetections must be > 0");
  }
  if (config.confirmHits < 1 || config.flipVotes < 1 || config.scoreMemory < 1) {
    return fail("tracking: confirmHits, flipVotes and scoreMemory must be >= 1");
  }
  if (!(config.maxLost_s >= 0.0) || !(config.maxLostAtFrameEdge_s >= 0.0) ||
      !(config.maxTentativeGap_s >= 0.0) || !(config.noise.measurementPosition_m > 0.0) ||
      !(config.noise.measurementHeading_rad > 0.0) || !(config.noise.accelerationDecay_s > 0.0) ||
      !(config.typeFloor > 0.0) || !(config.shapeMaxWeight > 0.0)) {
    return fail("tracking: times, noise sigmas, typeFloor and shapeMaxWeight must be > 0");
  }
  if (!(config.maxCoast_s >= 0.0) || !(config.noise.steeringDecay_s >= 0.0) ||
      !(config.partialAlongNoiseFactor >= 1.0) ||
      !(config.partialInsideShare >= 0.0 && config.partialInsideShare <= 1.0) ||
      !(config.frameEdgeShapeWeight > 0.0 && config.frameEdgeShapeWeight <= 1.0) ||
      !(config.longVehicleLength_m >= 0.0) ||
      !(config.maxOverlap >= 0.0 && config.maxOverlap <= 1.0)) {
    return fail(
        "tracking: maxCoast_s and steeringDecay_s must be >= 0, partialAlongNoiseFactor >= 1, "
        "partialInsideShare in [0, 1], frameEdgeShapeWeight in (0, 1], longVehicleLength_m >= 0, "
        "maxOverlap in [0, 1]");
  }
  if (!(config.confirmMinScore >= 0.0 && config.confirmMinScore <= 1.0)) {
    return fail("tracking: confirmMinScore must be in [0, 1]");
  }
  if (config.confirmWholeHits < 0 || config.confirmHitsAnyway < 1 ||
      config.confirmHitsStanding < 1 || config.confirmHitsLarge < 1) {
    return fail(
        "tracking: confirmWholeHits must be >= 0, confirmHitsAnyway, confirmHitsStanding and "
        "confirmHitsLarge >= 1");
  }
  config_ = config;
  if (!associator_.init(config.maxTracks, config.maxDetections, config.association)) {
    return fail("tracking: association parameters invalid (lowScore > highScore?)");
  }
  const auto nt = static_cast<std::size_t>(config.maxTracks);
  const auto nd = static_cast<std::size_t>(config.maxDetections);
  slots_.assign(nt, Slot{});
  detections_.assign(nd, WorldDetection{});
  // Twice: the step's births are appended to the live tracks' views, and a slot freed in the
  // step (a deleted track) may take a birth while its old view is still listed.
  views_.assign(2 * nt, TrackView{});
  viewSlot_.assign(2 * nt, -1);
  trackToDet_.assign(nt, -1);
  detToTrack_.assign(nd, -1);
  published_.assign(nt, TrackState{});
  publishedCount_ = 0;
  started_ = false;
  nextId_ = 1;
  initialised_ = true;
  return true;
}

void TrackManager::updateGeometry(Slot& slot) {
  TrackState& out = slot.out;
  double wheelbase = kWheelbasePerLength * out.length_m;
  double rearToCentre = kRearAxlePerLength * out.length_m;
  if (config_.asmModel != nullptr && out.type != shape::VehicleType::Large &&
      config_.asmModel->componentCount() > 0 && out.shape.count > 0) {
    const shape::KeypointModel model = config_.asmModel->shape(out.shape);
    const auto& wheels = shape::wheelCentreKeypoints();
    const double front = 0.5 * (model(0, wheels[0]) + model(0, wheels[1]));
    const double rear = 0.5 * (model(0, wheels[2]) + model(0, wheels[3]));
    if (front - rear > 1.0) {
      wheelbase = front - rear;
      rearToCentre = -rear;
    }
  }
  if (std::abs(wheelbase - slot.motion.wheelbase()) > 0.01 ||
      std::abs(rearToCentre - slot.motion.rearToCentre()) > 0.01) {
    slot.motion.setGeometry(wheelbase, rearToCentre);
  }
}

void TrackManager::birth(Slot& slot, const WorldDetection& d, std::int64_t timestamp_ns) {
  slot = Slot{};
  slot.live = true;
  slot.lastUpdate_ns = timestamp_ns;
  TrackState& out = slot.out;
  out.id = nextId_++;
  out.status = TrackStatus::Tentative;
  out.hits = 1;
  slot.wholeHits = partial(d) ? 0 : 1;
  slot.lastAtFrameEdge = d.atFrameEdge;
  out.birth_ns = timestamp_ns;
  out.score = static_cast<double>(d.score);
  out.updated = true;
  out.length_m = d.length_m;
  out.width_m = d.width_m;
  slot.sizeWeight = std::max(1e-3, static_cast<double>(d.score));
  for (std::size_t k = 0; k < slot.typeLog.size(); ++k) {
    slot.typeLog[k] =
        config_.typeEvidenceWeight *
        std::log(std::max(config_.typeFloor, static_cast<double>(d.typeProbabilities[k])));
  }
  if (d.shape.count > 0) {
    slot.gammaWeight = slot.sizeWeight;
    for (int s = 0; s < d.shape.count; ++s) {
      slot.gammaSum[static_cast<std::size_t>(s)] =
          slot.sizeWeight * static_cast<double>(d.shape.gamma[static_cast<std::size_t>(s)]);
    }
    out.shape = d.shape;
  }
  // The type decides whether the ASM applies; set it before the geometry.
  out.type = mostLikelyType(slot.typeLog);
  slot.motion.initialise(d.centreEnu, d.headingEnu_rad, kWheelbasePerLength * d.length_m,
                         kRearAxlePerLength * d.length_m, config_.noise,
                         alongAxisFactor(d, d.length_m));
  updateGeometry(slot);
}

void TrackManager::fuse(Slot& slot, const WorldDetection& d, std::int64_t timestamp_ns,
                        StepReport& report) {
  TrackState& out = slot.out;
  const MotionModel& m = slot.motion;
  const double v = m.state()[kV];
  const double sigmaV = std::sqrt(std::max(0.0, m.covariance()(kV, kV)));
  const bool movingForward = v > config_.movingSpeed_mps && v > 3.0 * sigmaV;

  double heading = d.headingEnu_rad;
  if (d.headingKnown) {
    if (geometry::absAngleDifference(heading, m.heading()) > 0.5 * geometry::kPi) {
      heading = geometry::wrapTwoPi(heading + geometry::kPi);
      ++out.headingCorrections;
      ++report.headingCorrections;
      // Disagreement counts against the track only while motion cannot vouch for it, and
      // only from whole vehicles: of a vehicle cut by the border the detector may see just
      // one end, and tells front from back worst there.
      if (!partial(d)) {
        slot.disagreeRun = movingForward ? 0 : slot.disagreeRun + 1;
      }
    } else if (!partial(d)) {
      slot.disagreeRun = 0;
    }
  }
  // A vehicle cut off by the image border is seen in part: its box centre lags behind the
  // vehicle's (entering) or runs ahead (leaving). A partial detection says little about where
  // along its axis the vehicle is (partialAlongNoiseFactor).
  slot.motion.update(d.centreEnu, heading, d.headingKnown, config_.noise,
                     alongAxisFactor(d, out.length_m));

  // Direction of travel decides the heading of a moving car; a run of disagreeing
  // detections decides it for a standing one (its first detection may have been flipped).
  const double vNow = slot.motion.state()[kV];
  const double sigmaNow = std::sqrt(std::max(0.0, slot.motion.covariance()(kV, kV)));
  const bool movingBackward = vNow < -config_.movingSpeed_mps && -vNow > 3.0 * sigmaNow;
  if (movingBackward || slot.disagreeRun >= config_.flipVotes) {
    slot.motion.flipDirection();
    slot.disagreeRun = 0;
  }

  // Type: tempered naive Bayes in log space, renormalised so the logs stay bounded.
  double maxLog = -1e300;
  for (std::size_t k = 0; k < slot.typeLog.size(); ++k) {
    slot.typeLog[k] +=
        config_.typeEvidenceWeight *
        std::log(std::max(config_.typeFloor, static_cast<double>(d.typeProbabilities[k])));
    maxLog = std::max(maxLog, slot.typeLog[k]);
  }
  for (double& l : slot.typeLog) {
    l = std::max(l - maxLog, -50.0);
  }

  // Shape and size: score-weighted running means with a capped weight.
  const double w = std::max(1e-3, static_cast<double>(d.score)) *
                   (d.atFrameEdge ? config_.frameEdgeShapeWeight : 1.0);
  const double total = slot.sizeWeight + w;
  const double keep = std::min(1.0, config_.shapeMaxWeight / total);
  const double lengthBefore = out.length_m;
  const double widthBefore = out.width_m;
  out.length_m = (slot.sizeWeight * out.length_m + w * d.length_m) / total;
  out.width_m = (slot.sizeWeight * out.width_m + w * d.width_m) / total;
  // West's weighted update: S += w (x - mean_before) (x - mean_after), then forgotten like the
  // weight, so S / weight stays the weighted spread.
  slot.lengthDeviationSq =
      (slot.lengthDeviationSq + w * (d.length_m - lengthBefore) * (d.length_m - out.length_m)) *
      keep;
  slot.widthDeviationSq =
      (slot.widthDeviationSq + w * (d.width_m - widthBefore) * (d.width_m - out.width_m)) * keep;
  slot.sizeWeight = total * keep;
  out.lengthVariance_m2 = std::max(0.0, slot.lengthDeviationSq / slot.sizeWeight);
  out.widthVariance_m2 = std::max(0.0, slot.widthDeviationSq / slot.sizeWeight);
  if (d.shape.count > 0) {
    const double keepG = std::min(1.0, config_.shapeMaxWeight / (slot.gammaWeight + w));
    for (int s = 0; s < d.shape.count; ++s) {
      auto& sum = slot.gammaSum[static_cast<std::size_t>(s)];
      sum = (sum + w * static_cast<double>(d.shape.gamma[static_cast<std::size_t>(s)])) * keepG;
    }
    slot.gammaWeight = (slot.gammaWeight + w) * keepG;
    out.shape.count = std::max(out.shape.count, d.shape.count);
    for (int s = 0; s < out.shape.count; ++s) {
      out.shape.gamma[static_cast<std::size_t>(s)] =
          static_cast<float>(slot.gammaSum[static_cast<std::size_t>(s)] / slot.gammaWeight);
    }
  }
  updateGeometry(slot);

  slot.lastUpdate_ns = timestamp_ns;
  slot.lastAtFrameEdge = d.atFrameEdge;
  out.updated = true;
  ++out.hits;
  slot.wholeHits += partial(d) ? 0 : 1;
  const double scoreGain = 1.0 / std::min(out.hits, config_.scoreMemory);
  out.score += scoreGain * (static_cast<double>(d.score) - out.score);
  if (out.status == TrackStatus::Lost) {
    out.status = TrackStatus::Confirmed;
    ++report.reacquisitions;
  } else if (out.status == TrackStatus::Tentative && out.score >= config_.confirmMinScore) {
    // Not for a large vehicle: the first stage may box only the cab of a truck or bus, and
    // such boxes can stand still for frames while the vehicle drives on.
    const bool large = mostLikelyType(slot.typeLog) == shape::VehicleType::Large;
    const bool standing = !large && std::abs(slot.motion.state()[kV]) < config_.movingSpeed_mps &&
                          slot.wholeHits == out.hits && out.hits >= config_.confirmHitsStanding;
    if (standing ||
        (out.hits >= config_.confirmHits && (!large || out.hits >= config_.confirmHitsLarge) &&
         (slot.wholeHits >= config_.confirmWholeHits || out.hits >= config_.confirmHitsAnyway))) {
      out.status = TrackStatus::Confirmed;
    }
  }
}

bool TrackManager::overlapping(const geometry::RotatedBox& a, const geometry::RotatedBox& b) const {
  // Boxes of one vehicle lie along one axis; vehicles crossing each other's path do not (and
  // the simulator's may drive through each other).
  if (geometry::axisAngleDifference(a.angle, b.angle) > config_.association.maxAxisAngle_rad) {
    return false;
  }
  const double reach = 0.5 * (a.length + b.length);
  if ((a.cx - b.cx) * (a.cx - b.cx) + (a.cy - b.cy) * (a.cy - b.cy) > reach * reach) {
    return false;
  }
  // Of the smaller footprint: a bus's part lies inside the bus's box with a small IoU.
  const double smaller = std::min(geometry::area(a), geometry::area(b));
  return geometry::intersectionArea(a, b) > config_.maxOverlap * smaller;
}

int TrackManager::overlappingView(const WorldDetection& d, int nViews) const {
  if (config_.maxOverlap >= 1.0) {
    return -1;
  }
  const geometry::RotatedBox box{d.centreEnu.x(), d.centreEnu.y(), d.length_m, d.width_m,
                                 d.headingEnu_rad};
  int found = -1;
  for (int v = 0; v < nViews; ++v) {
    const TrackView& view = views_[static_cast<std::size_t>(v)];
    const Slot& slot = slots_[static_cast<std::size_t>(viewSlot_[static_cast<std::size_t>(v)])];
    if (!slot.live ||
        !overlapping(box, geometry::RotatedBox{view.centre.x(), view.centre.y(), view.length_m,
                                               view.width_m, view.heading_rad})) {
      continue;
    }
    if (!slot.out.updated) {
      return v;
    }
    found = v;
  }
  return found;
}

int TrackManager::deleteYoungerDuplicates() {
  if (config_.maxOverlap >= 1.0) {
    return 0;
  }
  auto box = [](const Slot& s) {
    const Eigen::Vector2d c = s.motion.centre();
    return geometry::RotatedBox{c.x(), c.y(), s.out.length_m, s.out.width_m, s.motion.heading()};
  };
  // A lost track's prediction may drift onto another vehicle: lost tracks take no part.
  auto candidate = [](const Slot& s) { return s.live && s.out.status != TrackStatus::Lost; };
  int deleted = 0;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (!candidate(slots_[i])) {
      continue;
    }
    const geometry::RotatedBox boxI = box(slots_[i]);
    for (std::size_t j = i + 1; j < slots_.size() && slots_[i].live; ++j) {
      // Both fed by a detection this step: two boxes the detector kept apart; a duplicate
      // track takes the detections its twin does not (one vehicle, one box per frame).
      if (!candidate(slots_[j]) || (slots_[i].out.updated && slots_[j].out.updated) ||
          !overlapping(boxI, box(slots_[j]))) {
        continue;
      }
      Slot& younger = slots_[i].out.birth_ns > slots_[j].out.birth_ns ||
                              (slots_[i].out.birth_ns == slots_[j].out.birth_ns &&
                               slots_[i].out.id > slots_[j].out.id)
                          ? slots_[i]
                          : slots_[j];
      younger.live = false;
      ++deleted;
    }
  }
  return deleted;
}

void TrackManager::publish(Slot& slot, std::int64_t timestamp_ns) {
  TrackState& out = slot.out;
  const MotionModel& m = slot.motion;
  const StateVector& x = m.state();
  const StateMatrix& p = m.covariance();
  out.timestamp_ns = timestamp_ns;
  out.lastUpdate_ns = slot.lastUpdate_ns;
  out.centreEnu = m.centre();
  out.rearAxleEnu = m.rearAxle();
  out.headingEnu_rad = m.heading();
  out.speed_mps = x[kV];
  out.speedSigma_mps = std::sqrt(std::max(0.0, p(kV, kV)));
  out.acceleration_mps2 = x[kA];
  out.accelerationSigma_mps2 = std::sqrt(std::max(0.0, p(kA, kA)));
  out.yawRate_radps = m.yawRate();
  out.yawRateSigma_radps = m.yawRateSigma();
  out.steering_rad = x[kDelta];
  out.wheelbase_m = m.wheelbase();
  out.poseCovariance = m.poseCovariance();
  const Eigen::Matrix2d c = out.poseCovariance.topLeftCorner<2, 2>();
  const double tr = 0.5 * (c(0, 0) + c(1, 1));
  const double det = c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0);
  out.positionSigma_m = std::sqrt(std::max(0.0, tr + std::sqrt(std::max(0.0, tr * tr - det))));
  double total = 0.0;
  for (double l : slot.typeLog) {
    total += std::exp(l);
  }
  std::size_t best = 0;
  for (std::size_t k = 0; k < slot.typeLog.size(); ++k) {
    out.typeProbabilities[k] = static_cast<float>(std::exp(slot.typeLog[k]) / total);
    if (slot.typeLog[k] > slot.typeLog[best]) {
      best = k;
    }
  }
  out.type = static_cast<shape::VehicleType>(best);
}

Expected<StepReport, TrackError> TrackManager::step(std::int64_t timestamp_ns,
                                                    std::span<const WorldDetection> detections) {
  if (!initialised_) {
    return unexpected(TrackError::NotInitialised);
  }
  if (started_ && timestamp_ns < lastTimeNs_) {
    return unexpected(TrackError::TimeWentBackwards);
  }
  const double dt = started_ ? static_cast<double>(timestamp_ns - lastTimeNs_) / kNsPerS : 0.0;
  started_ = true;
  lastTimeNs_ = timestamp_ns;
  StepReport report;

  int nDet = 0;
  for (const WorldDetection& d : detections) {
    if (!valid(d)) {
      ++report.rejectedDetections;
    } else if (nDet >= config_.maxDetections) {
      ++report.droppedDetections;
    } else {
      detections_[static_cast<std::size_t>(nDet++)] = d;
    }
  }
  report.detectionsUsed = nDet;

  // Predict every live track to this frame and show it to the associator.
  int nViews = 0;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    Slot& slot = slots_[i];
    if (!slot.live) {
      continue;
    }
    slot.motion.predict(dt, config_.noise);
    slot.out.updated = false;
    TrackView& view = views_[static_cast<std::size_t>(nViews)];
    view.centre = slot.motion.centre();
    view.heading_rad = slot.motion.heading();
    view.length_m = slot.out.length_m;
    view.width_m = slot.out.width_m;
    // R as in the update: a long vehicle's detection is less sure along its axis.
    const double along = longVehicleFactor(slot.out.length_m);
    const Eigen::Vector2d axis(std::cos(view.heading_rad), std::sin(view.heading_rad));
    view.centreInnovationCov =
        slot.motion.centreCovariance() +
        config_.noise.measurementPosition_m * config_.noise.measurementPosition_m *
            (Eigen::Matrix2d::Identity() + (along * along - 1.0) * axis * axis.transpose());
    view.secondPass = slot.out.status != TrackStatus::Tentative;
    viewSlot_[static_cast<std::size_t>(nViews)] = static_cast<int>(i);
    ++nViews;
  }

  const std::span<const WorldDetection> dets(detections_.data(), static_cast<std::size_t>(nDet));
  if (!associator_.associate(
          std::span<const TrackView>(views_.data(), static_cast<std::size_t>(nViews)), dets,
          std::span<int>(trackToDet_.data(), static_cast<std::size_t>(nViews)),
          std::span<int>(detToTrack_.data(), static_cast<std::size_t>(nDet)),
          &report.association)) {
    return unexpected(TrackError::AssociationFailed);
  }

  for (int v = 0; v < nViews; ++v) {
    Slot& slot = slots_[static_cast<std::size_t>(viewSlot_[static_cast<std::size_t>(v)])];
    const int d = trackToDet_[static_cast<std::size_t>(v)];
    if (d >= 0) {
      fuse(slot, detections_[static_cast<std::size_t>(d)], timestamp_ns, report);
      continue;
    }
    const double since = static_cast<double>(timestamp_ns - slot.lastUpdate_ns) / kNsPerS;
    switch (slot.out.status) {
      case TrackStatus::Tentative:
        if (since > config_.maxTentativeGap_s) {
          slot.live = false;
        }
        break;
      case TrackStatus::Confirmed:
        // Coasting: a miss or two (the detector's, a short occlusion) does not demote a
        // confirmed track; its prediction stands in (updated = false) until maxCoast_s.
        if (since <= config_.maxCoast_s) {
          break;
        }
        slot.out.status = TrackStatus::Lost;
        [[fallthrough]];
      case TrackStatus::Lost:
        // Last seen at the frame's border: it has most likely left the view, and a vehicle
        // entering there must not inherit its id and motion.
        if (since > (slot.lastAtFrameEdge ? config_.maxLostAtFrameEdge_s : config_.maxLost_s)) {
          slot.live = false;
        }
        break;
    }
    if (!slot.live) {
      ++report.deletions;
    }
  }

  report.mergedTracks = deleteYoungerDuplicates();
  report.deletions += report.mergedTracks;

  // Births from unmatched confident detections, into free slots.
  std::size_t freeSearch = 0;
  for (int d = 0; d < nDet; ++d) {
    const WorldDetection& det = detections_[static_cast<std::size_t>(d)];
    if (detToTrack_[static_cast<std::size_t>(d)] >= 0 ||
        det.score < config_.association.highScore) {
      continue;
    }
    const int overlapped = overlappingView(det, nViews);
    if (overlapped >= 0) {
      Slot& slot =
          slots_[static_cast<std::size_t>(viewSlot_[static_cast<std::size_t>(overlapped)])];
      if (slot.out.updated) {
        ++report.suppressedBirths;
      } else {
        fuse(slot, det, timestamp_ns, report);
        ++report.overlapMatches;
      }
      continue;
    }
    while (freeSearch < slots_.size() && slots_[freeSearch].live) {
      ++freeSearch;
    }
    if (freeSearch == slots_.size()) {
      ++report.droppedBirths;
      continue;
    }
    birth(slots_[freeSearch], det, timestamp_ns);
    ++report.births;
    // A second box of the same vehicle later in this list must see the newborn track.
    TrackView& view = views_[static_cast<std::size_t>(nViews)];
    view.centre = det.centreEnu;
    view.heading_rad = det.headingEnu_rad;
    view.length_m = det.length_m;
    view.width_m = det.width_m;
    viewSlot_[static_cast<std::size_t>(nViews++)] = static_cast<int>(freeSearch);
  }

  publishedCount_ = 0;
  for (Slot& slot : slots_) {
    if (slot.live) {
      publish(slot, timestamp_ns);
      published_[static_cast<std::size_t>(publishedCount_++)] = slot.out;
    }
  }
  return report;
}

}  // namespace vp::tracking
