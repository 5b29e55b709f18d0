// perception/footprint_projection: the inverse of lifting a detection, for the evaluation and
// the tests: a vehicle's ground footprint in the world -> the image rotated box the detector
// should report for it, through the same Lifter.
//
// Contract: the footprint's corners are placed on the DTM (TerrainModel::groundPointEnu at
// centre +- L/2 along the heading +- W/2 across it) and projected with
// Lifter::worldToPixel; its centre (given on the terrain, as ground truth records it) is
// projected the same way. The box is centred on the projected footprint centre, so lifting
// its centre returns that point exactly; its angle is the direction from the projected middle
// of the rear edge to that of the front edge (the driving direction in the image), its length
// the distance between those two midpoints and its width the spread of the projected side
// midpoints across the axis: the rectangle through the projected edge midpoints. Under
// perspective the projected footprint is a general quadrilateral, so the box's corners are
// not exactly the projected corners, and the lifted length and width differ from the true
// ones by the perspective's second-order terms (see docs/perception.md for measured figures),
// while the centre comes back to < 0.1 mm. (The simulator's ground-truth image box is a
// different thing: it encloses the projection of the whole 3D vehicle.)
// Errors: a corner off the DTM or without data (OutsideDtm, NoData), or behind the camera /
// outside the lens field (BehindCamera, OutsideLens). Pure, allocation-free.
#pragma once

#include "core/expected.hpp"
#include "geometry/rotated_box.hpp"
#include "lifting/lifting.hpp"
#include "shape/vehicle_geometry.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::perception {

Expected<geometry::RotatedBox, lifting::LiftError> footprintToImageBox(
    const lifting::Lifter& lifter, const lifting::CameraPoseWorld& cameraPose,
    const terrain::TerrainModel& terrain, const shape::GroundFootprint& footprint);

}  // namespace vp::perception
