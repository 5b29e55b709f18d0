#include "tracking/from_perception.hpp"

namespace vp::tracking {

bool toWorldDetection(const perception::VehicleObservation& observation, WorldDetection* out) {
  if (observation.liftStatus != perception::LiftStatus::Ok) {
    return false;
  }
  const detection::Detection& d = observation.detection;
  out->timestampNs = observation.timestampNs;
  out->centreEnu = observation.ground.centreEnu.head<2>();
  out->headingEnuRad = observation.ground.headingEnuRad;
  out->headingKnown = d.directionKnown;
  out->lengthM = observation.ground.lengthM;
  out->widthM = observation.ground.widthM;
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
