// lifting/lifting: from image to world and back, with the drone's pose and the DTM.
//
// Contract: a Lifter borrows the camera model, the camera mount, the terrain model and the
// world frame given to init(); they must outlive it and stay unchanged. Once per frame,
// cameraPose() turns the drone's pose (WGS84 position of the body origin, autopilot
// attitude, gimbal state) into the camera's centre and orientation in the world ENU frame;
// the per-detection calls then use that result. pixelToWorld() intersects the pixel's
// viewing ray with the DTM; worldToPixel() projects a world point through the lens;
// boxToGround() lifts an image rotated box lying on the ground to its footprint, heading
// and size. Every failure is a LiftError value (never an exception, never a made-up
// point); all calls are const, allocation-free and thread-safe.
#pragma once

#include <array>
#include <span>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "camera/camera_model.hpp"
#include "core/expected.hpp"
#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "geometry/rotated_box.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::lifting {

struct DronePose {
  geodesy::GeodeticPoint position{};                             // body origin, WGS84
  Eigen::Quaterniond bodyToNed{Eigen::Quaterniond::Identity()};  // autopilot attitude q_nb
  geodesy::GimbalState gimbal{};
};

struct CameraPoseWorld {
  Eigen::Vector3d centreEnu{Eigen::Vector3d::Zero()};        // projection centre, m
  Eigen::Matrix3d cameraToEnu{Eigen::Matrix3d::Identity()};  // OpenCV camera -> world ENU
};

enum class LiftError {
  InvalidPose,     // NaN/inf or out-of-range position, or a zero quaternion
  OutsideLens,     // pixel or point beyond the lens model's valid field
  BehindCamera,    // world point behind the image plane
  OutsideDtm,      // the ray misses the DTM's extent
  NoData,          // the ray meets the DTM where it has no data
  NoIntersection,  // the ray points above the horizon or leaves the DTM first
};
const char* toString(LiftError error);

// A rotated box lifted to the ground.
struct GroundBox {
  std::array<Eigen::Vector3d, 4> cornersEnu{};  // in geometry::corners() order
  Eigen::Vector3d centreEnu{Eigen::Vector3d::Zero()};
  geodesy::GeodeticPoint centreWgs84{};
  double headingEnu_rad = 0.0;        // forward axis, counter-clockwise from east, [0, 2 pi)
  double headingTrueNorth_deg = 0.0;  // forward axis, clockwise from true north, [0, 360)
  double length_m = 0.0;              // along the ground between the rear and front edges
  double width_m = 0.0;               // along the ground between the side edges
};

class Lifter {
 public:
  Lifter() = default;

  // Borrows all four; fails when the camera has no valid intrinsics or the DTM is empty.
  bool init(const camera::CameraModel& camera, const geodesy::CameraMount& mount,
            const terrain::TerrainModel& terrain, const geodesy::LocalFrame& frame,
            std::string* why = nullptr);

  // The same camera, mount and world frame over another surface (e.g. a surface model with
  // buildings and decks, terrain.dsm_path): borrows it as init() does. Fails (returns false)
  // when this Lifter is not initialised or the surface is empty.
  bool initOnSurface(const Lifter& other, const terrain::TerrainModel& surface,
                     std::string* why = nullptr);
  bool initialised() const { return camera_ != nullptr; }

  Expected<CameraPoseWorld, LiftError> cameraPose(const DronePose& pose) const;

  // Distorted pixel -> first point of the DTM its viewing ray meets (world ENU).
  Expected<Eigen::Vector3d, LiftError> pixelToWorld(const CameraPoseWorld& pose,
                                                    const Eigen::Vector2d& pixel) const;
  // World ENU point -> distorted pixel (may lie outside the image; check inImage()).
  Expected<Eigen::Vector2d, LiftError> worldToPixel(const CameraPoseWorld& pose,
                                                    const Eigen::Vector3d& pointEnu) const;
  // Image rotated box -> ground footprint, heading, size. With boxHeight_m = 0 the box is the
  // vehicle's outline on the ground. A detector's box encloses the whole vehicle, roof
  // included, so on a tilted view its centre is the image of a point about half the vehicle's
  // height above the ground, not of the footprint centre (0.27 m off for a 1.5 m car seen 20 deg
  // off nadir): boxHeight_m > 0 intersects the rays with the DTM raised by that height and
  // returns the ground points below the intersections.
  Expected<GroundBox, LiftError> boxToGround(const CameraPoseWorld& pose,
                                             const geometry::RotatedBox& box,
                                             double boxHeight_m = 0.0) const;

  // The image box that encloses world points, its axis along the image direction from
  // originEnu to aheadEnu (angle = that direction over 360 degrees): the box a whole vehicle
  // (its vertices or keypoints; origin and a point ahead on its axis) makes in the image — the
  // simulator's ground truth and so the detector's target. Fails when a point cannot be
  // projected.
  Expected<geometry::RotatedBox, LiftError> enclosingImageBox(
      const CameraPoseWorld& pose, const Eigen::Vector3d& originEnu,
      const Eigen::Vector3d& aheadEnu, std::span<const Eigen::Vector3d> pointsEnu) const;

  // The ground point below where the pixel's ray is height_m above the DTM (boxToGround()'s
  // points; pixelToWorld() with height_m = 0).
  Expected<Eigen::Vector3d, LiftError> pixelToGroundBelow(const CameraPoseWorld& pose,
                                                          const Eigen::Vector2d& pixel,
                                                          double height_m) const;

 private:
  const camera::CameraModel* camera_ = nullptr;
  const terrain::TerrainModel* terrain_ = nullptr;
  const geodesy::LocalFrame* frame_ = nullptr;
  geodesy::CameraMount mount_{};
};

}  // namespace vp::lifting
