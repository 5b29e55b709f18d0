#include "tracking/from_perception.hpp"

namespace vp::tracking {

bool toWorldDetection(const perception::VehicleObservation& observation, WorldDetection* out) {
  if (observation.liftStatus != perception::LiftStatus::Ok) {
    return false;
  }
  const detection::Detection& d = observation.detection;
  out->timestamp_ns = observation.timestamp_ns;
  out->centreEnu = observation.ground.centreEnu.head<2>();
  out->headingEnu_rad = observation.ground.headingEnu_rad;
  out->headingKnown = d.directionKnown;
  out->length_m = observation.ground.length_m;
  out->width_m = observation.ground.width_m;
  out->score = d.score;
  out->typeProbabilities = d.typeProbabilities;
  out->shape = d.gamma;
  out->atFrameEdge = d.atFrameEdge;
  out->insideShare = d.insideShare;
  return true;
}

std::size_t toWorldDetections(std::span<const perception::VehicleObservation> observations,
                              std::span<WorldDetection> out) {
  std::size_t written = 0;
  for (const perception::VehicleObservation& observation : observations) {
    if (written == out.size()) {
      break;
    }
    if (toWorldDetection(observation, &out[written])) {
      ++written;
    }
  }
  return written;
}

}  // namespace vp::tracking
