#include "lifting/lifting.hpp"

#include <algorithm>
#include <cmath>

namespace vp::lifting {

namespace {

LiftError fromTerrain(terrain::TerrainError error) {
  switch (error) {
    case terrain::TerrainError::OutsideDtm:
      return LiftError::OutsideDtm;
    case terrain::TerrainError::NoData:
      return LiftError::NoData;
    case terrain::TerrainError::NoIntersection:
      break;
  }
  return LiftError::NoIntersection;
}

LiftError fromCamera(camera::CameraError error) {
  return error == camera::CameraError::PointBehindCamera ? LiftError::BehindCamera
                                                         : LiftError::OutsideLens;
}

}  // namespace

const char* toString(LiftError error) {
  switch (error) {
    case LiftError::InvalidPose:
      return "invalid pose";
    case LiftError::OutsideLens:
      return "outside the lens model's valid field";
    case LiftError::BehindCamera:
      return "behind the camera";
    case LiftError::OutsideDtm:
      return "outside the DTM";
    case LiftError::NoData:
      return "DTM has no data there";
    case LiftError::NoIntersection:
      return "ray does not meet the terrain";
  }
  return "unknown lift error";
}

bool Lifter::init(const camera::CameraModel& camera, const geodesy::CameraMount& mount,
                  const terrain::TerrainModel& terrain, const geodesy::LocalFrame& frame,
                  std::string* why) {
  if (camera.intrinsics().width_px <= 0 || camera.intrinsics().fx_px <= 0.0) {
    if (why != nullptr) {
      *why = "lifting: the camera model is not initialised";
    }
    return false;
  }
  if (terrain.grid().cols < 2 || terrain.grid().rows < 2) {
    if (why != nullptr) {
      *why = "lifting: the terrain model is not initialised";
    }
    return false;
  }
  if (!mount.leverArm_m.allFinite()) {
    if (why != nullptr) {
      *why = "lifting: the camera lever arm is not finite";
    }
    return false;
  }
  camera_ = &camera;
  terrain_ = &terrain;
  frame_ = &frame;
  mount_ = mount;
  return true;
}

bool Lifter::initOnSurface(const Lifter& other, const terrain::TerrainModel& surface,
                           std::string* why) {
  if (!other.initialised()) {
    if (why != nullptr) {
      *why = "lifting: the lifter to copy is not initialised";
    }
    return false;
  }
  return init(*other.camera_, other.mount_, surface, *other.frame_, why);
}

Expected<CameraPoseWorld, LiftError> Lifter::cameraPose(const DronePose& pose) const {
  const Eigen::Vector4d q = pose.bodyToNed.coeffs();
  const auto finite = [](const geodesy::EulerAnglesDeg& e) {
    return std::isfinite(e.roll_deg) && std::isfinite(e.pitch_deg) && std::isfinite(e.yaw_deg);
  };
  if (!geodesy::isValid(pose.position) || !q.allFinite() || q.norm() < 1e-6 ||
      !finite(pose.gimbal.angles)) {
    return unexpected(LiftError::InvalidPose);
  }
  // The attitude is relative to NED at the drone; the world frame is ENU at the origin.
  // localToWorld carries vectors between the two tangent planes (meridian convergence).
  Eigen::Matrix3d localToWorld;
  const Eigen::Vector3d bodyOriginEnu = frame_->toEnu(pose.position, &localToWorld);
  const Eigen::Matrix3d bodyToNed = pose.bodyToNed.normalized().toRotationMatrix();
  CameraPoseWorld out;
  out.centreEnu =
      bodyOriginEnu + localToWorld * geodesy::enuFromNed() * bodyToNed * mount_.leverArm_m;
  out.cameraToEnu = localToWorld * geodesy::cameraToLocalEnu(pose.bodyToNed, mount_, pose.gimbal);
  return out;
}

Expected<Eigen::Vector3d, LiftError> Lifter::pixelToWorld(const CameraPoseWorld& pose,
                                                          const Eigen::Vector2d& pixel) const {
  return pixelToGroundBelow(pose, pixel, 0.0);
}

Expected<Eigen::Vector3d, LiftError> Lifter::pixelToGroundBelow(const CameraPoseWorld& pose,
                                                                const Eigen::Vector2d& pixel,
                                                                double height_m) const {
  const auto ray = camera_->pixelToRay(pixel);
  if (!ray) {
    return unexpected(fromCamera(ray.error()));
  }
  // The ray meets the DTM raised by h where the same ray lowered by h meets the DTM, at the
  // same east/north: that point is the ground below the raised intersection.
  const Eigen::Vector3d origin = pose.centreEnu - Eigen::Vector3d(0.0, 0.0, height_m);
  const auto hit = terrain_->intersectRay(origin, pose.cameraToEnu * *ray);
  if (!hit) {
    return unexpected(fromTerrain(hit.error()));
  }
  return *hit;
}

Expected<Eigen::Vector2d, LiftError> Lifter::worldToPixel(const CameraPoseWorld& pose,
                                                          const Eigen::Vector3d& pointEnu) const {
  const Eigen::Vector3d inCamera = pose.cameraToEnu.transpose() * (pointEnu - pose.centreEnu);
  const auto pixel = camera_->projectToPixel(inCamera);
  if (!pixel) {
    return unexpected(fromCamera(pixel.error()));
  }
  return *pixel;
}

Expected<geometry::RotatedBox, LiftError> Lifter::enclosingImageBox(
    const CameraPoseWorld& pose, const Eigen::Vector3d& originEnu, const Eigen::Vector3d& aheadEnu,
    std::span<const Eigen::Vector3d> pointsEnu) const {
  const auto p0 = worldToPixel(pose, originEnu);
  if (!p0) {
    return unexpected(p0.error());
  }
  const auto p1 = worldToPixel(pose, aheadEnu);
  if (!p1) {
    return unexpected(p1.error());
  }
  const Eigen::Vector2d d = *p1 - *p0;
  const double angle = geometry::wrapTwoPi(std::atan2(d.y(), d.x()));
  const Eigen::Vector2d f(std::cos(angle), std::sin(angle));
  const Eigen::Vector2d n(-f.y(), f.x());
  double fMin = 1e18, fMax = -1e18, nMin = 1e18, nMax = -1e18;
  for (const Eigen::Vector3d& point : pointsEnu) {
    const auto p = worldToPixel(pose, point);
    if (!p) {
      return unexpected(p.error());
    }
    const Eigen::Vector2d r = *p - *p0;
    fMin = std::min(fMin, r.dot(f));
    fMax = std::max(fMax, r.dot(f));
    nMin = std::min(nMin, r.dot(n));
    nMax = std::max(nMax, r.dot(n));
  }
  const Eigen::Vector2d c = *p0 + f * (0.5 * (fMin + fMax)) + n * (0.5 * (nMin + nMax));
  return geometry::RotatedBox{c.x(), c.y(), fMax - fMin, nMax - nMin, angle};
}

Expected<GroundBox, LiftError> Lifter::boxToGround(const CameraPoseWorld& pose,
                                                   const geometry::RotatedBox& box,
                                                   double boxHeight_m) const {
  GroundBox out;
  const std::array<Eigen::Vector2d, 4> corners = geometry::corners(box);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const auto corner = pixelToGroundBelow(pose, corners[i], boxHeight_m);
    if (!corner) {
      return unexpected(corner.error());
    }
    out.cornersEnu[i] = *corner;
  }
  const auto centre = pixelToGroundBelow(pose, {box.cx, box.cy}, boxHeight_m);
  if (!centre) {
    return unexpected(centre.error());
  }
  out.centreEnu = *centre;
  out.centreWgs84 = frame_->toGeodetic(out.centreEnu);

  // Edge midpoints on the ground: the box's axes as they lie on the terrain.
  const Eigen::Vector3d front = 0.5 * (out.cornersEnu[0] + out.cornersEnu[1]);
  const Eigen::Vector3d rear = 0.5 * (out.cornersEnu[2] + out.cornersEnu[3]);
  const Eigen::Vector3d sideA = 0.5 * (out.cornersEnu[0] + out.cornersEnu[3]);
  const Eigen::Vector3d sideB = 0.5 * (out.cornersEnu[1] + out.cornersEnu[2]);
  out.length_m = (front - rear).norm();
  out.width_m = (sideA - sideB).norm();
  const Eigen::Vector3d forward = front - rear;
  out.headingEnu_rad = geometry::wrapTwoPi(std::atan2(forward.y(), forward.x()));
  out.headingTrueNorth_deg =
      geodesy::azimuth_deg(frame_->toGeodetic(rear), frame_->toGeodetic(front));
  return out;
}

}  // namespace vp::lifting
