// perception/detection_lifter: one frame's image detections placed in the world.
//
// Contract: DetectionLifter::liftFrame() takes the frame's capture time, the pose status and
// drone pose at that time (telemetry::PoseBuffer::poseAt), the Lifter whose camera model is
// the one of the frame the detections are in (the pinhole of the undistorted frame when the
// pipeline undistorts, else the raw lens model), and the detections, and fills one
// VehicleObservation per detection in a caller-owned array. Every detection is kept, in
// order: its image-space values are always copied, and its world values are filled only when
// liftStatus is Ok. A missing, stale or invalid pose, a box that is not finite or not
// positive, or a ray that misses the lens field or the DTM gives the matching status and
// leaves the world values zero: never a made-up position. For a lifted detection: the ground
// footprint (Lifter::boxToGround: the four box corners and the box centre intersected with
// the DTM; the centre is the vehicle's position; the width is taken across the lifted forward
// axis, which perspective skew would otherwise inflate), the most likely type's geometry
// (shape/vehicle_geometry: ASM keypoints scaled in plan to the footprint, standing on the
// DTM) and the rear-axle reference point of seed 002 in ENU and WGS84. Keypoints or the rear
// axle whose ground lies off the DTM are left out (hasKeypoints / hasRearAxle false) while
// the footprint stays lifted. The terrain, frame and ASM given to init() must be the ones the
// Lifter was built with; all are borrowed and must outlive the DetectionLifter.
// Without telemetry, a fixed view georeferenced by ground control points is lifted instead
// through a lifting::PlaneLifter (the init() overload that takes one): the pose and its status
// are then not used (every frame has the view's camera), boxes are lifted to the ground plane by
// the homography, and keypoints and the rear axle stand on that plane; everything else is as
// above. liftFrame() is const, never allocates and never throws. frameFootprint() gives the ground
// the whole frame shows (its corner pixels lifted to the DTM), e.g. the observed area of an
// occupancy grid; it is pure and allocation-free too.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include <Eigen/Core>

#include "detection/detection.hpp"
#include "geodesy/geodesy.hpp"
#include "lifting/lifting.hpp"
#include "lifting/plane_lifter.hpp"
#include "shape/vehicle_geometry.hpp"
#include "shape/vehicle_model.hpp"
#include "telemetry/pose_buffer.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::perception {

enum class LiftStatus : std::uint8_t {
  Ok,
  NoPose,          // no telemetry at the frame's time
  StalePose,       // nearest telemetry sample older than the buffer's max age
  InvalidPose,     // telemetry rejected (NaN/inf, zero quaternion) or the pose is unusable
  InvalidBox,      // the detection's box is not finite or has a size <= 0
  OutsideLens,     // a box point lies beyond the lens model's valid field
  BehindCamera,    // (projection only) a point behind the image plane
  OutsideDtm,      // a viewing ray meets the ground off the DTM
  NoData,          // a viewing ray meets the DTM where it has no data
  NoIntersection,  // a viewing ray points above the horizon or leaves the DTM first
};
const char* toString(LiftStatus status);
LiftStatus liftStatusFrom(lifting::LiftError error);
LiftStatus liftStatusFrom(telemetry::PoseStatus status);  // Ok -> Ok

struct VehicleObservation {
  std::int64_t timestamp_ns = 0;     // frame capture time
  detection::Detection detection{};  // the image-space detection, copied
  LiftStatus liftStatus = LiftStatus::NoPose;
  // World values: set only when liftStatus is Ok, zero otherwise.
  lifting::GroundBox ground{};  // footprint centre (ENU, WGS84), corners, heading, size
  shape::VehicleType type = shape::VehicleType::Sedan;  // most likely type (shape source)
  double height_m = 0.0;                                // ASM shape height, m (0 without keypoints)
  bool hasKeypoints = false;                            // a car shape stood on the DTM
  shape::KeypointModel keypointsEnu = shape::KeypointModel::Zero();  // world ENU, m
  bool hasRearAxle = false;
  Eigen::Vector3d rearAxleEnu = Eigen::Vector3d::Zero();  // seed 002 reference point, m
  geodesy::GeodeticPoint rearAxleWgs84{};
  // Set by the site's scene prior (site_prior.hpp, site.off_road: flag): the footprint centre
  // lies off every drivable and parking area, or on an exclusion area.
  bool offSite = false;
  // Set by the surface prior (surface_prior.hpp, terrain.dsm_path): the vehicle stands on a
  // structure of the surface model that no drivable or parking area marks (a roof; kept only with
  // site.on_structure: flag or keep), or it was lifted again onto a deck (a bridge, a parking
  // deck) whose surface its world values now lie on.
  bool onStructure = false;
  bool onDeck = false;
};

// What a frame's lift did.
struct FrameLiftSummary {
  LiftStatus poseStatus = LiftStatus::NoPose;  // Ok when the camera pose was computed
  lifting::CameraPoseWorld cameraPose{};       // valid when poseStatus is Ok
  std::size_t written = 0;  // observations filled (min of detections and capacity)
  std::size_t lifted = 0;   // of those, with liftStatus Ok
  std::size_t dropped = 0;  // detections beyond the output's capacity
};

// The ground a frame shows: its corner pixels (0, 0), (w-1, 0), (w-1, h-1), (0, h-1) lifted to
// the DTM, as east/north (m) in that order. Either all four corners or none (count 0): a
// partial outline would mark a wrong area as observed.
struct FrameFootprint {
  std::array<Eigen::Vector2d, 4> cornersEnu{};
  std::size_t count = 0;  // 4, or 0 without a camera pose or when a corner misses the DTM
  std::span<const Eigen::Vector2d> corners() const { return {cornersEnu.data(), count}; }
};

// The footprint of a width_px x height_px frame seen with the summary's camera pose (empty when
// summary.poseStatus is not Ok). The Lifter is the one the summary was lifted with.
FrameFootprint frameFootprint(const lifting::Lifter& lifter, const FrameLiftSummary& summary,
                              int width_px, int height_px);
// The same for a fixed view lifted through the ground plane.
FrameFootprint frameFootprint(const lifting::PlaneLifter& plane, int width_px, int height_px);

// The camera's pose for one frame, or the status saying why there is none (computed once per
// frame; the pipeline also uses it for the second stage's ground sample distance).
struct FrameCameraPose {
  LiftStatus status = LiftStatus::NoPose;
  lifting::CameraPoseWorld pose{};  // valid when status is Ok
};

// The most likely type of a detection and its probability (first on ties).
shape::VehicleType mostLikelyType(const detection::Detection& detection, float* probability);

lifting::DronePose toDronePose(const telemetry::PoseSample& sample);

struct DetectionLifterOptions {
  // Height above the ground at which a box is lifted, as a share of the vehicle's height (the
  // ASM shape of its most likely type, else nominalHeight_m): 0 for boxes that outline the
  // footprint on the ground; 0.5 for a detector's boxes, which enclose the whole vehicle, so
  // their centre shows the vehicle's middle, about half its height up (Lifter::boxToGround).
  double boxHeightShare = 0.5;   // [0, 1]; the shipped detector's boxes
  double nominalHeight_m = 1.5;  // vehicles without an ASM shape (large vehicles), m
};

class DetectionLifter {
 public:
  DetectionLifter() = default;

  // Borrows the terrain and the world frame the Lifters are built with, and the ASM.
  bool init(const terrain::TerrainModel& terrain, const geodesy::LocalFrame& frame,
            const shape::ActiveShapeModel& shapeModel, std::string* why = nullptr);
  bool init(const terrain::TerrainModel& terrain, const geodesy::LocalFrame& frame,
            const shape::ActiveShapeModel& shapeModel, const DetectionLifterOptions& options,
            std::string* why = nullptr);
  // The fixed view of a planar ground (no pose, no DTM): borrows the plane lifter too.
  bool init(const lifting::PlaneLifter& plane, const geodesy::LocalFrame& frame,
            const shape::ActiveShapeModel& shapeModel, const DetectionLifterOptions& options,
            std::string* why = nullptr);
  // Lifting through a PlaneLifter (null: through the pose and the DTM).
  const lifting::PlaneLifter* plane() const { return plane_; }

  FrameLiftSummary liftFrame(const lifting::Lifter& lifter, std::int64_t timestamp_ns,
                             telemetry::PoseStatus poseStatus, const lifting::DronePose& pose,
                             std::span<const detection::Detection> detections,
                             std::span<VehicleObservation> out) const;
  // The camera pose of a frame from the drone pose (status Ok only when the pose is usable).
  FrameCameraPose cameraPoseFor(const lifting::Lifter& lifter, telemetry::PoseStatus poseStatus,
                                const lifting::DronePose& pose) const;
  // The same lift with the frame's camera pose already computed.
  FrameLiftSummary liftFrame(const lifting::Lifter& lifter, std::int64_t timestamp_ns,
                             const FrameCameraPose& camera,
                             std::span<const detection::Detection> detections,
                             std::span<VehicleObservation> out) const;
  // The same with the buffer's estimate (its pose is used only when its status is Ok).
  FrameLiftSummary liftFrame(const lifting::Lifter& lifter, std::int64_t timestamp_ns,
                             const telemetry::PoseEstimate& pose,
                             std::span<const detection::Detection> detections,
                             std::span<VehicleObservation> out) const;

  // Lifts one observation's detection with the given Lifter and camera pose, as liftFrame()
  // does: liftStatus and the world values are set (the caller passes an observation whose world
  // values are zero). The surface prior lifts a vehicle on a deck again with a DetectionLifter
  // and a Lifter over the surface model. Never allocates.
  void liftObservation(const lifting::Lifter& lifter, const lifting::CameraPoseWorld& cameraPose,
                       VehicleObservation& observation) const {
    liftOne(lifter, cameraPose, observation);
  }
  // The height above the ground at which a detection's box is lifted (the options' share of its
  // most likely type's height).
  double boxHeight_m(const detection::Detection& detection) const;

 private:
  void liftOne(const lifting::Lifter& lifter, const lifting::CameraPoseWorld& cameraPose,
               VehicleObservation& observation) const;

  bool initialised() const { return terrain_ != nullptr || plane_ != nullptr; }
  std::optional<double> groundHeightAt(const Eigen::Vector3d& pointEnu) const;

  const terrain::TerrainModel* terrain_ = nullptr;
  const lifting::PlaneLifter* plane_ = nullptr;
  const geodesy::LocalFrame* frame_ = nullptr;
  const shape::ActiveShapeModel* shapeModel_ = nullptr;
  DetectionLifterOptions options_{};
};

}  // namespace vp::perception
