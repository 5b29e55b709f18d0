// tracking/from_perception: the tracker's input from the perception stage's observations.
//
// Contract: only an observation whose liftStatus is Ok becomes a WorldDetection: one that
// was not lifted has no world position and is never given one. The conversion keeps the
// frame time, the footprint centre (ENU x, y), the driving direction and whether the
// detector knew front from back (headingKnown = detection.directionKnown), the ground
// length and width, the score, the type probabilities and the ASM gamma unchanged. Pure,
// allocation-free.
#pragma once

#include <cstddef>
#include <span>

#include "perception/detection_lifter.hpp"
#include "tracking/world_detection.hpp"

namespace vp::tracking {

// False (and *out untouched) unless observation.liftStatus is Ok.
bool toWorldDetection(const perception::VehicleObservation& observation, WorldDetection* out);

// Converts the lifted observations in order into out; returns how many were written (at most
// out.size(); the rest of the lifted ones are left out, see the return value).
std::size_t toWorldDetections(std::span<const perception::VehicleObservation> observations,
                              std::span<WorldDetection> out);

}  // namespace vp::tracking
