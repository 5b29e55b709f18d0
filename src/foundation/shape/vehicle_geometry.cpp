#include "shape/vehicle_geometry.hpp"

#include <cmath>

namespace vp::shape {

VehicleGeometry vehicleGeometry(const ActiveShapeModel& model, VehicleType type,
                                const ShapeParams& gamma) {
  VehicleGeometry out;
  out.type = type;
  const bool isCar = static_cast<int>(type) < kCarTypeCount;
  if (!isCar || model.componentCount() <= 0) {
    return out;  // placeOnGround() applies the length rule for the rear axle
  }
  ShapeParams params = gamma;
  if (params.count == 0) {
    // No estimate: the type's mean shape is the best guess (gamma 0 = the fleet's mean).
    const TypePrior& prior = model.typePrior(type);
    params.count = prior.sampleCount > 0 ? model.componentCount() : 0;
    for (int s = 0; s < params.count; ++s) {
      params.gamma[static_cast<std::size_t>(s)] =
          static_cast<float>(prior.mean[static_cast<std::size_t>(s)]);
    }
  }
  out.keypoints_m = model.shape(params);
  if (!out.keypoints_m.allFinite()) {
    out.keypoints_m.setZero();
    return out;
  }
  out.size_m = boundingBoxSize(out.keypoints_m);
  if (!(out.size_m.x() > 0.0) || !(out.size_m.y() > 0.0)) {
    out.size_m.setZero();
    return out;
  }
  const Eigen::Vector3d lo = out.keypoints_m.rowwise().minCoeff();
  const Eigen::Vector3d hi = out.keypoints_m.rowwise().maxCoeff();
  out.footprintCentre_m = 0.5 * (lo.head<2>() + hi.head<2>());
  // Seed 002's reference point: the road point under the middle of the rear wheel centres.
  const auto& wheels = wheelCentreKeypoints();
  const Eigen::Vector3d rearMid =
      0.5 * (out.keypoints_m.col(wheels[2]) + out.keypoints_m.col(wheels[3]));
  out.rearAxle_m = {rearMid.x(), rearMid.y(), 0.0};
  out.hasKeypoints = true;
  return out;
}

Eigen::Vector2d planPositionEnu(const VehicleGeometry& geometry, const GroundFootprint& footprint,
                                const Eigen::Vector3d& pointVehicle_m) {
  Eigen::Vector2d local;
  if (geometry.hasKeypoints) {
    // Scale about the shape's footprint centre so its extents match the detected footprint.
    local.x() = (pointVehicle_m.x() - geometry.footprintCentre_m.x()) *
                (footprint.length_m / geometry.size_m.x());
    local.y() = (pointVehicle_m.y() - geometry.footprintCentre_m.y()) *
                (footprint.width_m / geometry.size_m.y());
  } else {
    local = pointVehicle_m.head<2>();
  }
  const double c = std::cos(footprint.headingEnu_rad);
  const double s = std::sin(footprint.headingEnu_rad);
  return {footprint.centreEnu.x() + c * local.x() - s * local.y(),
          footprint.centreEnu.y() + s * local.x() + c * local.y()};
}

}  // namespace vp::shape
