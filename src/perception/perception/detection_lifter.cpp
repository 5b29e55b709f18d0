#include "perception/detection_lifter.hpp"

#include <cmath>
#include <optional>

namespace vp::perception {

const char* toString(LiftStatus status) {
  switch (status) {
    case LiftStatus::Ok:
      return "ok";
    case LiftStatus::NoPose:
      return "no pose";
    case LiftStatus::StalePose:
      return "stale pose";
    case LiftStatus::InvalidPose:
      return "invalid pose";
    case LiftStatus::InvalidBox:
      return "invalid box";
    case LiftStatus::OutsideLens:
      return "outside the lens model's valid field";
    case LiftStatus::BehindCamera:
      return "behind the camera";
    case LiftStatus::OutsideDtm:
      return "outside the DTM";
    case LiftStatus::NoData:
      return "DTM has no data there";
    case LiftStatus::NoIntersection:
      return "ray does not meet the terrain";
  }
  return "unknown lift status";
}

LiftStatus liftStatusFrom(lifting::LiftError error) {
  switch (error) {
    case lifting::LiftError::InvalidPose:
      return LiftStatus::InvalidPose;
    case lifting::LiftError::OutsideLens:
      return LiftStatus::OutsideLens;
    case lifting::LiftError::BehindCamera:
      return LiftStatus::BehindCamera;
    case lifting::LiftError::OutsideDtm:
      return LiftStatus::OutsideDtm;
    case lifting::LiftError::NoData:
      return LiftStatus::NoData;
    case lifting::LiftError::NoIntersection:
      break;
  }
  return LiftStatus::NoIntersection;
}

LiftStatus liftStatusFrom(telemetry::PoseStatus status) {
  switch (status) {
    case telemetry::PoseStatus::Ok:
      return LiftStatus::Ok;
    case telemetry::PoseStatus::NoPose:
      return LiftStatus::NoPose;
    case telemetry::PoseStatus::Stale:
      return LiftStatus::StalePose;
    case telemetry::PoseStatus::Invalid:
      break;
  }
  return LiftStatus::InvalidPose;
}

shape::VehicleType mostLikelyType(const detection::Detection& detection, float* probability) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < detection.typeProbabilities.size(); ++i) {
    if (detection.typeProbabilities[i] > detection.typeProbabilities[best]) {
      best = i;
    }
  }
  if (probability != nullptr) {
    *probability = detection.typeProbabilities[best];
  }
  return static_cast<shape::VehicleType>(best);
}

lifting::DronePose toDronePose(const telemetry::PoseSample& sample) {
  lifting::DronePose pose;
  pose.position = sample.position;
  pose.bodyToNed = sample.bodyToNed;
  pose.gimbal = sample.gimbal;
  return pose;
}

namespace {

// The options' ranges, the same for a DTM and a plane.
bool optionsValid(const DetectionLifterOptions& options, std::string* why) {
  if (options.boxHeightShare >= 0.0 && options.boxHeightShare <= 1.0 &&
      options.nominalHeight_m > 0.0 && options.nominalHeight_m <= 10.0) {
    return true;
  }
  if (why != nullptr) {
    *why =
        "detection lifter: box height share must be in [0, 1] and the nominal height in "
        "(0, 10] m, got " +
        std::to_string(options.boxHeightShare) + " and " + std::to_string(options.nominalHeight_m);
  }
  return false;
}

}  // namespace

bool DetectionLifter::init(const terrain::TerrainModel& terrain, const geodesy::LocalFrame& frame,
                           const shape::ActiveShapeModel& shapeModel, std::string* why) {
  return init(terrain, frame, shapeModel, DetectionLifterOptions{}, why);
}

bool DetectionLifter::init(const terrain::TerrainModel& terrain, const geodesy::LocalFrame& frame,
                           const shape::ActiveShapeModel& shapeModel,
                           const DetectionLifterOptions& options, std::string* why) {
  if (terrain.grid().cols < 2 || terrain.grid().rows < 2) {
    if (why != nullptr) {
      *why = "detection lifter: the terrain model is not initialised";
    }
    return false;
  }
  if (!optionsValid(options, why)) {
    return false;
  }
  options_ = options;
  terrain_ = &terrain;
  plane_ = nullptr;
  frame_ = &frame;
  shapeModel_ = &shapeModel;
  return true;
}

bool DetectionLifter::init(const lifting::PlaneLifter& plane, const geodesy::LocalFrame& frame,
                           const shape::ActiveShapeModel& shapeModel,
                           const DetectionLifterOptions& options, std::string* why) {
  if (!plane.initialised()) {
    if (why != nullptr) {
      *why = "detection lifter: the plane lifter is not initialised";
    }
    return false;
  }
  if (!optionsValid(options, why)) {
    return false;
  }
  options_ = options;
  terrain_ = nullptr;
  plane_ = &plane;
  frame_ = &frame;
  shapeModel_ = &shapeModel;
  return true;
}

std::optional<double> DetectionLifter::groundHeightAt(const Eigen::Vector3d& pointEnu) const {
  if (plane_ != nullptr) {
    return plane_->groundHeightAt(pointEnu.x(), pointEnu.y());
  }
  const auto h = terrain_->heightAtEnu(pointEnu);
  if (!h) {
    return std::nullopt;
  }
  return *h;
}

FrameFootprint frameFootprint(const lifting::PlaneLifter& plane, int width_px, int height_px) {
  FrameFootprint footprint;
  const double w = width_px - 1.0;
  const double h = height_px - 1.0;
  for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0),
                                       Eigen::Vector2d(w, h), Eigen::Vector2d(0, h)}) {
    const auto ground = plane.pixelToGround(pixel);
    if (!ground) {
      footprint.count = 0;
      return footprint;
    }
    footprint.cornersEnu[footprint.count++] = ground->head<2>();
  }
  return footprint;
}

FrameFootprint frameFootprint(const lifting::Lifter& lifter, const FrameLiftSummary& summary,
                              int width_px, int height_px) {
  FrameFootprint footprint;
  if (summary.poseStatus != LiftStatus::Ok) {
    return footprint;
  }
  const double w = width_px - 1.0;
  const double h = height_px - 1.0;
  for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0),
                                       Eigen::Vector2d(w, h), Eigen::Vector2d(0, h)}) {
    const auto ground = lifter.pixelToWorld(summary.cameraPose, pixel);
    if (!ground) {
      footprint.count = 0;
      return footprint;
    }
    footprint.cornersEnu[footprint.count++] = ground->head<2>();
  }
  return footprint;
}

FrameLiftSummary DetectionLifter::liftFrame(const lifting::Lifter& lifter,
                                            std::int64_t timestamp_ns,
                                            const telemetry::PoseEstimate& pose,
                                            std::span<const detection::Detection> detections,
                                            std::span<VehicleObservation> out) const {
  return liftFrame(lifter, timestamp_ns, pose.status, toDronePose(pose.pose), detections, out);
}

FrameLiftSummary DetectionLifter::liftFrame(const lifting::Lifter& lifter,
                                            std::int64_t timestamp_ns,
                                            telemetry::PoseStatus poseStatus,
                                            const lifting::DronePose& pose,
                                            std::span<const detection::Detection> detections,
                                            std::span<VehicleObservation> out) const {
  return liftFrame(lifter, timestamp_ns, cameraPoseFor(lifter, poseStatus, pose), detections, out);
}

FrameCameraPose DetectionLifter::cameraPoseFor(const lifting::Lifter& lifter,
                                               telemetry::PoseStatus poseStatus,
                                               const lifting::DronePose& pose) const {
  FrameCameraPose camera;
  if (plane_ != nullptr) {
    // A fixed view: the camera is the one the ground control points give, whatever the pose.
    camera.status = LiftStatus::Ok;
    camera.pose = plane_->cameraPose();
    return camera;
  }
  camera.status = liftStatusFrom(poseStatus);
  if (terrain_ == nullptr) {
    camera.status = LiftStatus::NoPose;  // not initialised: nothing can be lifted
  }
  if (camera.status == LiftStatus::Ok) {
    const auto cameraPose = lifter.cameraPose(pose);
    if (cameraPose) {
      camera.pose = *cameraPose;
    } else {
      camera.status = liftStatusFrom(cameraPose.error());
    }
  }
  return camera;
}

FrameLiftSummary DetectionLifter::liftFrame(const lifting::Lifter& lifter,
                                            std::int64_t timestamp_ns,
                                            const FrameCameraPose& camera,
                                            std::span<const detection::Detection> detections,
                                            std::span<VehicleObservation> out) const {
  FrameLiftSummary summary;
  summary.written = std::min(detections.size(), out.size());
  summary.dropped = detections.size() - summary.written;
  summary.poseStatus = initialised() ? camera.status : LiftStatus::NoPose;
  if (summary.poseStatus == LiftStatus::Ok) {
    summary.cameraPose = camera.pose;
  }
  for (std::size_t i = 0; i < summary.written; ++i) {
    VehicleObservation& observation = out[i];
    observation = VehicleObservation{};
    observation.timestamp_ns = timestamp_ns;
    observation.detection = detections[i];
    observation.liftStatus = summary.poseStatus;
    if (summary.poseStatus != LiftStatus::Ok) {
      continue;
    }
    liftOne(lifter, summary.cameraPose, observation);
    if (observation.liftStatus == LiftStatus::Ok) {
      ++summary.lifted;
    }
  }
  return summary;
}

double DetectionLifter::boxHeight_m(const detection::Detection& detection) const {
  const shape::VehicleGeometry geometry =
      shape::vehicleGeometry(*shapeModel_, mostLikelyType(detection, nullptr), detection.gamma);
  return options_.boxHeightShare *
         (geometry.hasKeypoints ? geometry.size_m.z() : options_.nominalHeight_m);
}

void DetectionLifter::liftOne(const lifting::Lifter& lifter,
                              const lifting::CameraPoseWorld& cameraPose,
                              VehicleObservation& observation) const {
  const geometry::RotatedBox& box = observation.detection.box;
  if (!std::isfinite(box.cx) || !std::isfinite(box.cy) || !std::isfinite(box.angle) ||
      !(box.length > 0.0) || !(box.width > 0.0) || !std::isfinite(box.length) ||
      !std::isfinite(box.width)) {
    observation.liftStatus = LiftStatus::InvalidBox;
    return;
  }
  // The shape first: its height places the box (a world value, kept only when lifted).
  const shape::VehicleType type = mostLikelyType(observation.detection, nullptr);
  const shape::VehicleGeometry geometry =
      shape::vehicleGeometry(*shapeModel_, type, observation.detection.gamma);
  const double vehicleHeight_m =
      geometry.hasKeypoints ? geometry.size_m.z() : options_.nominalHeight_m;
  const double boxHeight_m = options_.boxHeightShare * vehicleHeight_m;
  const auto ground = plane_ != nullptr ? plane_->boxToGround(box, boxHeight_m)
                                        : lifter.boxToGround(cameraPose, box, boxHeight_m);
  if (!ground) {
    observation.liftStatus = liftStatusFrom(ground.error());
    return;
  }
  observation.liftStatus = LiftStatus::Ok;
  observation.type = type;
  observation.ground = *ground;
  // Width across the driving direction. boxToGround() measures it between the lifted side
  // midpoints; where perspective (a tilted view, a slope) skews the footprint in the image,
  // the image box's cross axis does not lift to the ground's cross axis and that distance
  // picks up an along-axis part. Its component perpendicular to the forward axis does not.
  const auto& corners = observation.ground.cornersEnu;
  const Eigen::Vector3d forward = 0.5 * (corners[0] + corners[1]) - 0.5 * (corners[2] + corners[3]);
  const Eigen::Vector3d side = 0.5 * (corners[0] + corners[3]) - 0.5 * (corners[1] + corners[2]);
  const double forwardNorm = forward.norm();
  if (forwardNorm > 0.0) {
    const Eigen::Vector3d f = forward / forwardNorm;
    observation.ground.width_m = (side - side.dot(f) * f).norm();
  }
  observation.height_m = geometry.hasKeypoints ? geometry.size_m.z() : 0.0;

  // Heights of the points around the centre: the centre's ENU z plus the DTM's height
  // difference. Over a car's few metres ENU z and ellipsoidal height change alike (the
  // difference is d * 5 m / R: 0.8 mm at 1 km from the origin), and one geodetic conversion
  // per point is cheaper than groundPointEnu()'s iteration.
  const Eigen::Vector3d& centre = observation.ground.centreEnu;
  const auto centreHeight = groundHeightAt(centre);
  if (!centreHeight) {
    return;  // the centre was lifted onto the DTM, so this cannot happen; stay conservative
  }
  const double zOffset = centre.z() - *centreHeight;
  const auto groundZ = [this, &centre,
                        zOffset](const Eigen::Vector2d& xy) -> std::optional<double> {
    const auto h = groundHeightAt({xy.x(), xy.y(), centre.z()});
    if (!h) {
      return std::nullopt;
    }
    return *h + zOffset;
  };
  shape::GroundFootprint footprint;
  footprint.centreEnu = centre;
  footprint.headingEnu_rad = observation.ground.headingEnu_rad;
  // The footprint's plan size: GroundBox sizes run along the (possibly sloping) ground, while
  // the keypoints are placed in plan and then stood on the DTM.
  const Eigen::Vector2d planForward = forward.head<2>();
  const Eigen::Vector2d planSide = side.head<2>();
  footprint.length_m = planForward.norm();
  footprint.width_m =
      footprint.length_m > 0.0
          ? std::abs(planSide.x() * planForward.y() - planSide.y() * planForward.x()) /
                footprint.length_m
          : 0.0;
  shape::PlacedVehicle placed;
  if (shape::placeOnGround(geometry, footprint, groundZ, &placed)) {
    observation.hasRearAxle = true;
    observation.rearAxleEnu = placed.rearAxleEnu;
    observation.rearAxleWgs84 = frame_->toGeodetic(placed.rearAxleEnu);
    observation.hasKeypoints = placed.hasKeypoints;
    if (placed.hasKeypoints) {
      observation.keypointsEnu = placed.keypointsEnu;
    }
    return;
  }
  // Some keypoint stands off the DTM (a car at the DTM's edge): keep the rear axle alone
  // when its own ground is known.
  if (geometry.hasKeypoints) {
    const Eigen::Vector2d axleXy = shape::planPositionEnu(geometry, footprint, geometry.rearAxle_m);
    const auto z = groundZ(axleXy);
    if (z) {
      observation.hasRearAxle = true;
      observation.rearAxleEnu = {axleXy.x(), axleXy.y(), *z};
      observation.rearAxleWgs84 = frame_->toGeodetic(observation.rearAxleEnu);
    }
  }
}

}  // namespace vp::perception
