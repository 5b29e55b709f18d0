#include "detection/detection.hpp"

namespace vp::detection {

TopTwoTypes topTwoTypes(const Detection& detection) {
  // Ties keep the lower type index first, so the result is deterministic.
  int first = 0;
  for (int t = 1; t < shape::kVehicleTypeCount; ++t) {
    if (detection.typeProbabilities[t] > detection.typeProbabilities[first]) {
      first = t;
    }
  }
  int second = first == 0 ? 1 : 0;
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    if (t != first && detection.typeProbabilities[t] > detection.typeProbabilities[second]) {
      second = t;
    }
  }
  TopTwoTypes result;
  result.first = static_cast<shape::VehicleType>(first);
  result.firstProbability = detection.typeProbabilities[first];
  result.second = static_cast<shape::VehicleType>(second);
  result.secondProbability = detection.typeProbabilities[second];
  return result;
}

}  // namespace vp::detection
