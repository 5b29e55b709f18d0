#include "lifting/plane_lifter.hpp"

#include <cmath>

namespace vp::lifting {

bool PlaneLifter::init(const georef::GroundHomography& view,
                       const std::optional<georef::RecoveredCamera>& recovered,
                       const camera::CameraModel& camera, const geodesy::LocalFrame& frame,
                       std::string* why) {
  if (camera.intrinsics().width_px <= 0 || camera.intrinsics().fx_px <= 0.0) {
    if (why != nullptr) {
      *why = "plane lifting: the camera model is not initialised";
    }
    return false;
  }
  imageToGround_ = view.imageToGround;
  groundToImage_ = view.groundToImage;
  plane_ = view.plane;
  hasCamera_ = recovered.has_value();
  cameraPose_ = CameraPoseWorld{};
  if (recovered) {
    cameraPose_.centreEnu = recovered->centreEnu;
    cameraPose_.cameraToEnu = recovered->cameraToEnu;
  }
  camera_ = &camera;
  frame_ = &frame;
  return true;
}

Expected<Eigen::Vector3d, LiftError> PlaneLifter::pixelToGround(
    const Eigen::Vector2d& pixel) const {
  return groundBelow(pixel, 0.0);
}

Expected<Eigen::Vector3d, LiftError> PlaneLifter::groundBelow(const Eigen::Vector2d& pixel,
                                                              double height_m) const {
  const auto ideal = camera_->undistortPixel(pixel);
  if (!ideal) {
    return unexpected(LiftError::OutsideLens);
  }
  const auto en = georef::mapToGround(imageToGround_, *ideal);
  if (!en) {
    return unexpected(LiftError::NoIntersection);
  }
  const Eigen::Vector3d onGround(en->x(), en->y(), plane_.heightAt(en->x(), en->y()));
  if (height_m <= 0.0 || !hasCamera_) {
    return onGround;
  }
  // Height above the plane is linear along the ray: 0 at the ground point, the camera's height
  // at the centre; the point at height_m lies that share of the way up.
  const Eigen::Vector3d& c = cameraPose_.centreEnu;
  const double cameraHeight = c.z() - plane_.heightAt(c.x(), c.y());
  if (!(cameraHeight > height_m)) {
    return unexpected(LiftError::NoIntersection);
  }
  const Eigen::Vector3d raised = onGround + (height_m / cameraHeight) * (c - onGround);
  return Eigen::Vector3d(raised.x(), raised.y(), plane_.heightAt(raised.x(), raised.y()));
}

Expected<Eigen::Vector2d, LiftError> PlaneLifter::groundToPixel(
    const Eigen::Vector3d& pointEnu) const {
  const auto ideal = georef::mapToImage(groundToImage_, pointEnu.head<2>());
  if (!ideal) {
    return unexpected(LiftError::BehindCamera);
  }
  if (camera_->distortion().model == camera::LensModel::Pinhole) {
    return *ideal;
  }
  return camera_->distortPixel(*ideal);
}

Expected<GroundBox, LiftError> PlaneLifter::boxToGround(const geometry::RotatedBox& box,
                                                        double boxHeight_m) const {
  GroundBox out;
  const std::array<Eigen::Vector2d, 4> corners = geometry::corners(box);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const auto corner = groundBelow(corners[i], boxHeight_m);
    if (!corner) {
      return unexpected(corner.error());
    }
    out.cornersEnu[i] = *corner;
  }
  const auto centre = groundBelow({box.cx, box.cy}, boxHeight_m);
  if (!centre) {
    return unexpected(centre.error());
  }
  out.centreEnu = *centre;
  out.centreWgs84 = frame_->toGeodetic(out.centreEnu);
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

double PlaneLifter::groundSampleDistance_m(const Eigen::Vector2d& pixel) const {
  const auto p0 = pixelToGround(pixel);
  const auto pu = pixelToGround(pixel + Eigen::Vector2d(1.0, 0.0));
  const auto pv = pixelToGround(pixel + Eigen::Vector2d(0.0, 1.0));
  if (!p0 || !pu || !pv) {
    return 0.0;
  }
  const double area = (*pu - *p0).cross(*pv - *p0).norm();
  return area > 0.0 && std::isfinite(area) ? std::sqrt(area) : 0.0;
}

}  // namespace vp::lifting
