// perception/footprint_type: each lifted car's type probabilities weighed by its footprint.
#include "perception/footprint_type.hpp"

#include <algorithm>
#include <cmath>

namespace vp::perception {

namespace {

constexpr int kLarge = static_cast<int>(shape::VehicleType::Large);

bool allFinite(const std::array<double, shape::kVehicleTypeCount>& weights) {
  for (const double w : weights) {
    if (!std::isfinite(w)) {
      return false;
    }
  }
  return true;
}

}  // namespace

bool FootprintType::init(const FootprintTypeOptions& options, const DetectionLifter* lifter,
                         std::string* why) {
  active_ = false;
  const auto fail = [why](const std::string& message) {
    if (why != nullptr) {
      *why = message;
    }
    return false;
  };
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(options.referenceLength_m) || !positive(options.lengthScale_m) ||
      !positive(options.referenceAspect) || !positive(options.aspectScale) ||
      !positive(options.maxTerm)) {
    return fail(
        "footprint type evidence: the reference length and aspect, their scales and "
        "the largest term must be positive and finite");
  }
  if (!allFinite(options.lengthWeight) || !allFinite(options.aspectWeight)) {
    return fail("footprint type evidence: every weight must be finite");
  }
  options_ = options;
  lifter_ = lifter;
  active_ = options.enabled && lifter != nullptr;
  return true;
}

FootprintTypeScreening FootprintType::apply(std::span<VehicleObservation> observations,
                                            const lifting::Lifter& lifter,
                                            const lifting::CameraPoseWorld& cameraPose) const {
  FootprintTypeScreening result;
  if (!active_) {
    return result;
  }
  const double logReferenceAspect = std::log(options_.referenceAspect);
  for (VehicleObservation& observation : observations) {
    const detection::Detection& detection = observation.detection;
    const double length_m = observation.ground.length_m;
    const double width_m = observation.ground.width_m;
    if (observation.liftStatus != LiftStatus::Ok || detection.atFrameEdge ||
        mostLikelyType(detection, nullptr) == shape::VehicleType::Large || !(length_m > 0.0) ||
        !(width_m > 0.0) || !std::isfinite(length_m) || !std::isfinite(width_m)) {
      continue;
    }
    const double lengthTerm =
        std::clamp((length_m - options_.referenceLength_m) / options_.lengthScale_m,
                   -options_.maxTerm, options_.maxTerm);
    const double aspectTerm =
        std::clamp((std::log(length_m / width_m) - logReferenceAspect) / options_.aspectScale,
                   -options_.maxTerm, options_.maxTerm);
    // Softmax over the car types of log p + evidence, scaled to the cars' former total; a type
    // with probability 0 stays 0. Shifted by the largest exponent against overflow.
    std::array<double, shape::kCarTypeCount> logit{};
    double carTotal = 0.0;
    double maxLogit = -HUGE_VAL;
    for (int t = 0; t < shape::kCarTypeCount; ++t) {
      const double p = detection.typeProbabilities[t];
      carTotal += p;
      logit[t] = p > 0.0 ? std::log(p) + options_.lengthWeight[t] * lengthTerm +
                               options_.aspectWeight[t] * aspectTerm
                         : -HUGE_VAL;
      maxLogit = std::max(maxLogit, logit[t]);
    }
    if (!(carTotal > 0.0) || !std::isfinite(maxLogit)) {
      continue;
    }
    std::array<double, shape::kCarTypeCount> weight{};
    double sum = 0.0;
    for (int t = 0; t < shape::kCarTypeCount; ++t) {
      weight[t] = std::isfinite(logit[t]) ? std::exp(logit[t] - maxLogit) : 0.0;
      sum += weight[t];
    }
    detection::Detection weighed = detection;
    for (int t = 0; t < shape::kCarTypeCount; ++t) {
      weighed.typeProbabilities[t] = static_cast<float>(carTotal * weight[t] / sum);
    }
    weighed.typeProbabilities[kLarge] = detection.typeProbabilities[kLarge];
    ++result.weighed;
    if (mostLikelyType(weighed, nullptr) == observation.type) {
      observation.detection = weighed;
      continue;
    }
    // Another type is now the most likely: lifted again, its height placing the box and its
    // shape standing on the ground; the world values start from zero, as liftFrame()'s do.
    VehicleObservation retyped;
    retyped.timestamp_ns = observation.timestamp_ns;
    retyped.detection = weighed;
    lifter_->liftObservation(lifter, cameraPose, retyped);
    if (retyped.liftStatus != LiftStatus::Ok) {
      observation.detection = weighed;  // cannot happen for a box that lifted before
      continue;
    }
    observation = retyped;
    ++result.retyped;
  }
  return result;
}

}  // namespace vp::perception
