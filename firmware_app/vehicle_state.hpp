// firmware_app/vehicle_state: a tracker state as the vehicle-state message the drone publishes.
//
// Contract: toVehicleState() fills every field of messages::VehicleState from a
// tracking::TrackState, the world frame and DTM (the tracker works in the plane: the centre is
// put on the terrain, else at the origin's height when the DTM has no height there; WGS84 and
// true-north heading from the frame), the ASM (height of the fused type and shape; 0 for large
// vehicles, which have none) and the fixed offset that maps the frames' clock to UTC (DDS times
// are UTC ns, docs/dds.md). The pose covariance is the tracker's (centre east, north, heading);
// the height variance is 0 (the ASM height of the fused shape, no spread kept); the detection
// confidence is the track's fused detector score. Pure, no allocation.
#pragma once

#include <cstdint>

#include "geodesy/geodesy.hpp"
#include "messages/messages.hpp"
#include "shape/vehicle_model.hpp"
#include "terrain/terrain_model.hpp"
#include "tracking/track_manager.hpp"

namespace vp::app {

messages::VehicleState toVehicleState(const tracking::TrackState& track, std::uint32_t droneId,
                                      std::int64_t toUtcOffset_ns, const geodesy::LocalFrame& frame,
                                      const terrain::TerrainModel* terrain,
                                      const shape::ActiveShapeModel* shapeModel);

}  // namespace vp::app
