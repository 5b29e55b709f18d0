// firmware_app/vehicle_state: a tracker state as the vehicle-state message the drone publishes.
//
// Contract: toVehicleState() fills every field of messages::VehicleState from a
// tracking::TrackState, the world frame and DTM (the tracker works in the plane: the centre is
// put on the terrain, else at the origin's height when the DTM has no height there; WGS84 and
// true-north heading from the frame), the ASM (height of the fused type and shape; 0 for large
// vehicles, which have none) and the fixed offset that maps the frames' clock to UTC (DDS times
// are UTC ns, docs/dds.md). The tracker reports one position sigma (the larger axis of its
// centre covariance) and no heading variance, so the pose covariance is diagonal with the
// heading term 0, and it keeps no detector score per track, so detectionConfidence is 0 ("not
// reported"). Pure, no allocation.
//
// TrackAges remembers when each live track was first published-or-seen (the tracker keeps a
// hit count, not a birth time): a fixed table of kCapacity ids, forgotten when a track is gone.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "geodesy/geodesy.hpp"
#include "messages/messages.hpp"
#include "shape/vehicle_model.hpp"
#include "terrain/terrain_model.hpp"
#include "tracking/track_manager.hpp"

namespace vp::app {

messages::VehicleState toVehicleState(const tracking::TrackState& track, double trackAge_s,
                                      std::uint32_t droneId, std::int64_t toUtcOffsetNs,
                                      const geodesy::LocalFrame& frame,
                                      const terrain::TerrainModel* terrain,
                                      const shape::ActiveShapeModel* shapeModel);

class TrackAges {
 public:
  static constexpr std::size_t kCapacity = 1024;

  // Age of the track at timestampNs, s (0 at its first call); remembers new ids.
  double ageOf(std::uint32_t trackId, std::int64_t timestampNs);
  // Forgets every id not among `live`.
  void retain(std::span<const tracking::TrackState> live);

 private:
  struct Entry {
    std::uint32_t id = 0;
    std::int64_t firstNs = 0;
  };
  std::array<Entry, kCapacity> entries_{};
  std::size_t count_ = 0;
};

}  // namespace vp::app
