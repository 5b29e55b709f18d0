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
// their sigmas, yaw rate, size, wheelbase, the type probabilities and the ASM gamma.
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

// shapeComponents: how many gamma columns (n_s of the ASM, <= shape::kMaxShapeComponents).
int trajectoryCsvHeader(std::span<char> out, int shapeComponents);
int trajectoryCsvRow(std::span<char> out, std::int64_t frameId, const TrackState& track,
                     const Wgs84Position* centreWgs84, int shapeComponents);

}  // namespace vp::tracking
