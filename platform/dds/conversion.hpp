// platform/dds/conversion: messages/ structs <-> the idlc-generated samples of
// vp_perception.idl, field by field.
//
// Contract: toSample() overwrites every field of a preallocated sample and never allocates;
// the occupancy sample borrows the grid's cell buffer (_release = false), so the grid must
// outlive the write. fromSample() is the exact inverse (doubles and floats are copied, not
// rounded), which is what the round-trip tests compare. Enumerations outside the IDL's range
// are mapped to the nearest safe value (an unknown type -> Sedan, an unknown status -> Lost).
#pragma once

#include "messages/messages.hpp"
#include "vp_perception.h"

namespace vp::platform::dds {

void toSample(const messages::VehicleState& state, vp_msg_VehicleState& sample);
void toSample(const messages::DroneStatus& status, vp_msg_DroneStatus& sample);
void toSample(const messages::OccupancyGrid& grid, vp_msg_OccupancyGrid& sample);

messages::VehicleState fromSample(const vp_msg_VehicleState& sample);
messages::DroneStatus fromSample(const vp_msg_DroneStatus& sample);
// Copies the cells into grid (allocates only when the grid is smaller than the sample).
void fromSample(const vp_msg_OccupancyGrid& sample, messages::OccupancyGrid& grid);

}  // namespace vp::platform::dds
