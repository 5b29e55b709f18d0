// tracking/trajectory_csv: the trajectory CSV of seed 002 plus our columns, as text.
//
// Contract: pure formatting, no file I/O (the caller owns the file; src modules stay pure):
// trajectoryCsvHeader() and trajectoryCsvRow() write one line, '\n'-terminated and NUL-
// terminated, into a caller buffer and return the number of characters written without the
// NUL, or -1 when the buffer is too small (kTrajectoryCsvMaxLine always suffices). No
// allocation, so the loop may log every step. The columns are documented in
// docs/tracking.md: seed 002's frame_id, class_id, track_id, velocity,
// coordinate_world_x_opt, coordinate_world_y_opt (rear axle), coordinate_world_x,
// coordinate_world_y (box centre), then time, status, WGS84 (precomputed by the caller with
// geodesy::LocalFrame; empty fields when not given), heading, speed and acceleration with
// their sigmas, yaw rate, size, wheelbase, the type's name, the length and width variances,
// UTM of the centre and WGS84 of the rear axle (TrajectoryPlace, precomputed by the caller
// like the WGS84 of the centre; empty fields when not given), the type probabilities and the
// ASM gamma.
#pragma once

#include <cstdint>
#include <span>

#include "tracking/track_manager.hpp"

namespace vp::tracking {

constexpr int kTrajectoryCsvMaxLine = 1024;

struct Wgs84Position {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;  // ellipsoidal
};

// Where the published state puts the vehicle beyond the tracker's plane (the vehicle-state
// message's UTM and rear axle, docs/dds.md).
struct TrajectoryPlace {
  int utmZone = 0;  // 1..60; 0 = not computed (the UTM fields stay empty)
  bool utmNorth = true;
  double utmEasting_m = 0.0;
  double utmNorthing_m = 0.0;
  bool hasRearAxle = false;  // false: the rear-axle WGS84 fields stay empty
  Wgs84Position rearAxle{};
};

// shapeComponents: how many gamma columns (n_s of the ASM, <= shape::kMaxShapeComponents).
int trajectoryCsvHeader(std::span<char> out, int shapeComponents);
int trajectoryCsvRow(std::span<char> out, std::int64_t frameId, const TrackState& track,
                     const Wgs84Position* centreWgs84, int shapeComponents,
                     const TrajectoryPlace* place = nullptr);

}  // namespace vp::tracking
