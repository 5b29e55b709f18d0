// messages/occupancy: rasterises the observed area and vehicle footprints into the bird's-eye
// occupancy grid (seed 001's occupancy picture).
//
// Contract: rasterizeOccupancy() overwrites every cell of a grid already sized with
// OccupancyGrid::resize(): cells whose centre lies inside the observed polygon become Free,
// cells whose centre lies inside a vehicle's footprint (length x width rectangle about its
// ENU position, rotated by headingEnu_rad) become Occupied (whether observed or not: a
// tracked vehicle is known to be there), the rest Unobserved. Tentative tracks are skipped.
// The polygon is a simple polygon in world ENU metres (e.g. the camera footprint on the
// ground); an empty polygon marks nothing as observed. No allocation; O(cells + footprint
// cells).
#pragma once

#include <span>

#include <Eigen/Core>

#include "messages/messages.hpp"

namespace vp::messages {

void rasterizeOccupancy(std::span<const Eigen::Vector2d> observedPolygon,
                        std::span<const VehicleState> vehicles, OccupancyGrid& grid);

}  // namespace vp::messages
