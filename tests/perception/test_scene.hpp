// A small world for the perception and annotation tests: a local frame at Madison, WI, a
// DTM (flat or sloped grid built here, or the shipped fixture tests/fixtures/dtm), a camera
// 100 m above the ground, the Lifter over them, the default ASM and ground-truth vehicles.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "camera/camera_model.hpp"
#include "detection/detection.hpp"
#include "geodesy/geodesy.hpp"
#include "io/dtm_file.hpp"
#include "lifting/lifting.hpp"
#include "perception/detection_lifter.hpp"
#include "perception/footprint_projection.hpp"
#include "plane_dtm.hpp"
#include "shape/vehicle_model.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::perception::testworld {

inline const geodesy::GeodeticPoint kOrigin{43.0731, -89.4012, 260.0};
constexpr double kGround_m = 260.0;    // ellipsoidal height of the ground at the origin
constexpr double kAltitude_m = 100.0;  // drone above it

// UTM grid of 2 m cells, +-halfExtent around the origin:
// height = 260 + slopeEast * dE + slopeNorth * dN (m).
inline terrain::TerrainGrid plane(double slopeEast, double slopeNorth,
                                  double halfExtent_m = 300.0) {
  return test::planeDtm(kOrigin, kGround_m, slopeEast, slopeNorth, halfExtent_m);
}

inline terrain::TerrainGrid fixtureDtm() {
  terrain::TerrainGrid grid;
  std::string why;
  EXPECT_TRUE(
      io::loadDtm(std::string(VP_FIXTURE_DIR) + "/dtm/sloped_utm16n.tif", std::nullopt, grid, &why))
      << why;
  return grid;
}

inline camera::CameraModel makeCamera(camera::LensModel model) {
  camera::Intrinsics in{2592, 2048, 2900.0, 2900.0, 1295.5, 1023.5};
  camera::Distortion d;
  d.model = model;
  if (model == camera::LensModel::BrownConrady) {
    d.k1 = -0.12;
    d.k2 = 0.08;
    d.p1 = 1e-4;
    d.p2 = -2e-4;
    d.k3 = -0.01;
  }
  camera::CameraModel cam;
  std::string why;
  EXPECT_TRUE(cam.init(in, d, &why)) << why;
  return cam;
}

inline lifting::DronePose hoveringPose(double yaw_deg, double gimbalPitch_deg) {
  lifting::DronePose pose;
  pose.position = {kOrigin.latitude_deg, kOrigin.longitude_deg, kGround_m + kAltitude_m};
  pose.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({1.5, -2.0, yaw_deg}));
  pose.gimbal.angles = {0.0, gimbalPitch_deg, 0.0};
  return pose;
}

// Everything a frame's lift borrows; not copyable (the Lifter points into it).
struct Scene {
  geodesy::LocalFrame frame{kOrigin};
  terrain::TerrainModel terrain;
  camera::CameraModel camera;
  geodesy::CameraMount mount;
  lifting::Lifter lifter;
  shape::ActiveShapeModel asmModel;
  DetectionLifter detectionLifter;

  Scene(terrain::TerrainGrid grid, camera::LensModel lens) {
    std::string why;
    EXPECT_TRUE(terrain.init(std::move(grid), frame, &why)) << why;
    camera = makeCamera(lens);
    mount.leverArm_m = {0.10, 0.0, 0.20};
    EXPECT_TRUE(lifter.init(camera, mount, terrain, frame, &why)) << why;
    EXPECT_TRUE(asmModel.load(std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml", &why))
        << why;
    // The scenes' boxes are ground-truth footprints: lifted on the ground.
    EXPECT_TRUE(detectionLifter.init(terrain, frame, asmModel,
                                     DetectionLifterOptions{.boxHeightShare = 0.0}, &why))
        << why;
  }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
};

// A ground-truth vehicle: footprint centre on the DTM at (x, y), heading, size.
struct TruthVehicle {
  shape::GroundFootprint footprint{};
  shape::VehicleType type = shape::VehicleType::Sedan;
};

// A detection as a perfect detector would report the vehicle (box through the Lifter).
inline bool perfectDetection(const Scene& scene, const lifting::CameraPoseWorld& pose,
                             const TruthVehicle& truth, detection::Detection* out) {
  const auto box = footprintToImageBox(scene.lifter, pose, scene.terrain, truth.footprint);
  if (!box || !scene.camera.inImage({box->cx, box->cy}, 50.0)) {
    return false;
  }
  *out = detection::Detection{};
  out->box = *box;
  out->score = 0.9F;
  out->directionKnown = true;
  out->typeProbabilities.fill(0.02F);
  out->typeProbabilities[static_cast<std::size_t>(truth.type)] = 0.88F;
  out->gamma.count = 3;
  out->gamma.gamma = {0.3F, -0.4F, 0.1F};
  return true;
}

// Vehicles on a grid of positions with varied headings and sizes, their centres on the DTM.
inline std::vector<TruthVehicle> truthVehicles(const terrain::TerrainModel& terrain, double span_m,
                                               double step_m) {
  std::vector<TruthVehicle> out;
  int i = 0;
  for (double x = -span_m; x <= span_m; x += step_m) {
    for (double y = -span_m; y <= span_m; y += step_m, ++i) {
      const auto ground = terrain.groundPointEnu(x, y);
      if (!ground) {
        continue;
      }
      TruthVehicle v;
      v.footprint.centreEnu = *ground;
      v.footprint.headingEnu_rad = std::fmod(0.37 * i, 2.0 * 3.141592653589793);
      v.footprint.length_m = 4.2 + 0.05 * (i % 13);
      v.footprint.width_m = 1.75 + 0.02 * (i % 7);
      v.type = static_cast<shape::VehicleType>(i % shape::kCarTypeCount);
      out.push_back(v);
    }
  }
  return out;
}

}  // namespace vp::perception::testworld
