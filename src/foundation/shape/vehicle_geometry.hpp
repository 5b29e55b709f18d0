// shape/vehicle_geometry: what a detected vehicle's type and ASM gamma say about its body:
// keypoints, size and rear-axle reference point in the vehicle frame, and the same keypoints
// placed in the world on a lifted ground footprint.
//
// Contract: the vehicle frame is vehicle_model.hpp's (origin at the footprint centre on the
// road, x forward, y left, z up, metres). vehicleGeometry() evaluates Eq. 1 of seed 000 for a
// car type; a car whose gamma was not estimated (count 0) gets its type's prior mean gamma
// from the ASM file (the mean shape when the file has no prior). Large vehicles (and a model
// with no components) have no keypoints: only the rear-axle rule below applies to them.
// The rear-axle reference point is the one seed 002 uses for its trajectories
// (coordinate_world_x_opt / _y_opt): the centre of the rear axle projected to street level,
// i.e. the road point under the middle of the two rear wheel centres (z = 0). Without
// keypoints it lies kRearAxleBehindCentrePerLength * length behind the footprint centre
// (the tracker's rule for the same case).
// Placement (placeOnGround) scales the shape in plan so that its footprint (the keypoints'
// x and y extents) matches the detected length and width exactly: the detector measures the
// footprint in the image far better than the three shape parameters can (docs/perception.md
// "Shape and lifting"); heights stay the ASM's, as a near-nadir image hardly observes them.
// Each placed point stands on the terrain under it: its world z is the caller's ground height
// there plus its height in the vehicle frame, so on a slope the body follows the ground.
// Everything here is pure, allocation-free and thread-safe.
#pragma once

#include <cmath>
#include <optional>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"

namespace vp::shape {

// Rear axle of a vehicle without keypoints: this share of its length behind the centre.
constexpr double kRearAxleBehindCentrePerLength = 0.28;

struct VehicleGeometry {
  VehicleType type = VehicleType::Sedan;
  bool hasKeypoints = false;                          // a car with an ASM shape
  KeypointModel keypoints_m = KeypointModel::Zero();  // vehicle frame, m (when hasKeypoints)
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();   // length, width, height; 0 without
  Eigen::Vector2d footprintCentre_m = Eigen::Vector2d::Zero();  // middle of the x/y extents
  Eigen::Vector3d rearAxle_m =
      Eigen::Vector3d::Zero();  // vehicle frame, road (z = 0); with keypoints
};

// The geometry of a vehicle of `type` with shape `gamma` (see the contract for count 0).
VehicleGeometry vehicleGeometry(const ActiveShapeModel& model, VehicleType type,
                                const ShapeParams& gamma);

// A footprint on the ground in the world ENU frame (e.g. a lifted detection).
struct GroundFootprint {
  Eigen::Vector3d centreEnu = Eigen::Vector3d::Zero();  // footprint centre on the terrain, m
  double headingEnu_rad = 0.0;                          // forward axis, counter-clockwise from east
  double length_m = 0.0;                                // along the heading, > 0
  double width_m = 0.0;                                 // across it, > 0
};

struct PlacedVehicle {
  bool hasKeypoints = false;
  KeypointModel keypointsEnu = KeypointModel::Zero();     // columns = keypoints, world ENU, m
  Eigen::Vector3d rearAxleEnu = Eigen::Vector3d::Zero();  // on the terrain, world ENU, m
  double lengthScale = 1.0;  // detected length / shape length (1 without keypoints)
  double widthScale = 1.0;   // detected width / shape width
};

// Plan position (world ENU x, y) of a vehicle-frame point on the footprint. With keypoints the
// point is scaled about the shape's footprint centre like the keypoints (see the contract);
// without, it is taken as metres from the footprint centre.
Eigen::Vector2d planPositionEnu(const VehicleGeometry& geometry, const GroundFootprint& footprint,
                                const Eigen::Vector3d& pointVehicle_m);

// Places the keypoints and the rear-axle point on the ground. groundZ(Eigen::Vector2d xyEnu)
// returns std::optional<double>: the world ENU z of the terrain at that plan position, or
// nullopt where the terrain has no height. Returns false when the footprint is not finite or
// has a size <= 0, or when any needed ground height is missing (*out then holds no keypoints).
template <class GroundZ>
bool placeOnGround(const VehicleGeometry& geometry, const GroundFootprint& footprint,
                   GroundZ&& groundZ, PlacedVehicle* out) {
  out->hasKeypoints = false;
  if (!footprint.centreEnu.allFinite() || !std::isfinite(footprint.headingEnu_rad) ||
      !(footprint.length_m > 0.0) || !(footprint.width_m > 0.0)) {
    return false;
  }
  const Eigen::Vector3d axleVehicle_m =
      geometry.hasKeypoints
          ? geometry.rearAxle_m
          : Eigen::Vector3d(-kRearAxleBehindCentrePerLength * footprint.length_m, 0.0, 0.0);
  const Eigen::Vector2d axle = planPositionEnu(geometry, footprint, axleVehicle_m);
  const std::optional<double> axleZ = groundZ(axle);
  if (!axleZ) {
    return false;
  }
  out->rearAxleEnu = {axle.x(), axle.y(), *axleZ};
  out->lengthScale = 1.0;
  out->widthScale = 1.0;
  if (!geometry.hasKeypoints) {
    return true;
  }
  for (int k = 0; k < kKeypointCount; ++k) {
    const Eigen::Vector3d p = geometry.keypoints_m.col(k);
    const Eigen::Vector2d xy = planPositionEnu(geometry, footprint, p);
    const std::optional<double> z = groundZ(xy);
    if (!z) {
      return false;
    }
    out->keypointsEnu.col(k) = Eigen::Vector3d(xy.x(), xy.y(), *z + p.z());
  }
  out->lengthScale = footprint.length_m / geometry.size_m.x();
  out->widthScale = footprint.width_m / geometry.size_m.y();
  out->hasKeypoints = true;
  return true;
}

}  // namespace vp::shape
