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
  out.keypointsM = model.shape(params);
  if (!out.keypointsM.allFinite()) {
    out.keypointsM.setZero();
    return out;
  }
  out.sizeM = boundingBoxSize(out.keypointsM);
  if (!(out.sizeM.x() > 0.0) || !(out.sizeM.y() > 0.0)) {
    out.sizeM.setZero();
    return out;
  }
  const Eigen::Vector3d lo = out.keypointsM.rowwise().minCoeff();
  const Eigen::Vector3d hi = out.keypointsM.rowwise().maxCoeff();
  out.footprintCentreM = 0.5 * (lo.head<2>() + hi.head<2>());
  // Seed 002's reference point: the road point under the middle of the rear wheel centres.
  const auto& wheels = wheelCentreKeypoints();
  const Eigen::Vector3d rearMid =
      0.5 * (out.keypointsM.col(wheels[2]) + out.keypointsM.col(wheels[3]));
  out.rearAxleM = {rearMid.x(), rearMid.y(), 0.0};
  out.hasKeypoints = true;
  return out;
}

Eigen::Vector2d planPositionEnu(const VehicleGeometry& geometry, const GroundFootprint& footprint,
                                const Eigen::Vector3d& pointVehicleM) {
  Eigen::Vector2d local;
  if (geometry.hasKeypoints) {
    // Scale about the shape's footprint centre so its extents match the detected footprint.
    local.x() = (pointVehicleM.x() - geometry.footprintCentreM.x()) *
                (footprint.lengthM / geometry.sizeM.x());
    local.y() = (pointVehicleM.y() - geometry.footprintCentreM.y()) *
                (footprint.widthM / geometry.sizeM.y());
  } else {
    local = pointVehicleM.head<2>();
  }
  const double c = std::cos(footprint.headingEnuRad);
  const double s = std::sin(footprint.headingEnuRad);
  return {footprint.centreEnu.x() + c * local.x() - s * local.y(),
          footprint.centreEnu.y() + s * local.x() + c * local.y()};
}

}  // namespace vp::shape
