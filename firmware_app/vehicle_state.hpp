// firmware_app/vehicle_state: a tracker state as the vehicle-state message the drone publishes.
//
// Contract: toVehicleState() fills every field of messages::VehicleState from a
// tracking::TrackState, the world frame and DTM (the tracker works in the plane: the centre is
// put on the terrain, else at the origin's height when the DTM has no height there; WGS84 and
// true-north heading from the frame), the ASM (height of the fused type and shape; 0 for large
// vehicles, which have none) and the fixed offset that maps the frames' clock to UTC (DDS times
// are UTC ns, docs/dds.md). The pose covariance is the tracker's (centre east, north, heading);
// the height variance is 0 (the ASM height of the fused shape, no spread kept); the length and
// width variances are the tracker's spreads of the detected sizes; the detection confidence is
// the track's fused detector score. UTM is that of the reference point (geodesy::tryUtm: the
// standard zone, Norway/Svalbard exceptions applied; zone 0 and easting/northing 0 outside
// UTM's band, latitude [-80, 84)). The rear axle and the keypoints come from the fused type and
// shape placed at the track's centre and heading (shape::placeOnGround; every point on the DTM,
// or at the centre's height where the DTM has none): for a car with an ASM, the shape at its own
// size (not scaled to the fused box: M(gamma) measures a car's length better than the box),
// its 36 keypoints in world ENU (keypointCount 36) and the road point under the middle of its
// rear wheel centres; for a large vehicle or without an ASM, no keypoints (count 0) and the rear
// axle shape::kRearAxleBehindCentrePerLength (0.28) of the fused length behind the centre; a
// track without a positive size has its rear axle at the reference
// point. Pure, no allocation.
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
