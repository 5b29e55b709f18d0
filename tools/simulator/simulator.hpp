// simulator/simulator: one simulated sequence, from the seed to the recorded-sequence
// directory: world, scene, camera rig, traffic, rendering, sensor and ground truth.
//
// Contract: init() draws everything from one std::mt19937_64 seeded by options.seed, in a
// fixed order (origin, terrain, scene, camera, sensor, hover, traffic warm-up); nextFrame()
// advances the drone and the traffic by one frame (10 Hz) and renders it. The same options
// give byte-identical output, independent of the thread count; no wall clock is read.
// Command-line overrides (altitude, tilt) replace drawn values without changing the draw
// order, so the rest of the scene stays the same. write() produces the documented
// recorded-sequence format (docs/recorded_sequence.md) through sequence::SequenceWriter.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"
#include "geodesy/attitude.hpp"
#include "lifting/lifting.hpp"
#include "renderer.hpp"
#include "scene.hpp"
#include "sensor.hpp"
#include "sequence/recorded_sequence.hpp"
#include "shape/vehicle_model.hpp"
#include "traffic.hpp"
#include "vehicles.hpp"
#include "world.hpp"

namespace vp::sim {

struct SimOptions {
  SceneKind scene = SceneKind::Intersection;
  std::uint64_t seed = 0;
  int frames = 10;
  std::string outDir;
  int width = 2592;
  int height = 2048;
  std::optional<double> altitude_m;  // above the ground at the view centre, 60..150
  std::optional<double> tilt_deg;    // optical axis from nadir, 0..35
  bool png = false;
  int jpegQuality = 92;
  int threads = 1;
  int supersampling = 2;
  std::string asmPath;          // default: models/asm/default_asm.yaml of the source tree
  bool telemetryNoise = false;  // recorded pose = true pose + small noise
  // The drone holds one pose (no hover sway of position, attitude and gimbal): a fixed view, as
  // ground control points assume. The random draws are the same, so the scene is too.
  bool staticHover = false;
  bool instanceMasks = false;  // also write instances/<frame>.png (16-bit object ids)
  double warmUpS = 30.0;
  // Share of cars with a roof in a contrasting colour (a white roof on a dark car, a black one on
  // a light car), 0..1. The scene of a seed is the same whatever the share; 0 renders as before.
  double twoToneShare = 0.0;
  // Share of compact cars shortened to city cars (2.5-3.6 m, vehicles.hpp), 0..1; drawn from
  // each car's own shape like the two-tone share. Their ground truth has no gamma.
  double cityCarShare = 0.0;
  // Share of SUVs drawn as pickup trucks with an open bed (car_generator.hpp), 0..1; drawn from
  // each car's own shape like the two shares above. Their ground truth has no gamma or keypoints.
  double pickupShare = 0.0;
  // Share of buses and coaches with roof details (car_generator.hpp addBusRoofDetails: an
  // air-conditioning unit, hatches, fans, a fleet number), 0..1; drawn from each bus's own
  // dimensions, so the scene and every other vehicle stay those of the seed.
  double busRoofShare = 0.0;
  // Share of the vehicles entering the roads that are buses or trucks, 0..1, instead of the
  // scene's own draw (0-10 %); unset: the scene's. The scene itself is the same; the traffic
  // differs once a share is given (its draws follow the vehicles drawn).
  std::optional<double> largeVehicleShare;
  // Sign posts and street lamps along the kerbs (addPoles); the rest of a seed's scene is the
  // same with or without them.
  bool poles = false;
  // Road users that are not vehicles (road_users.cpp): rows of parked motorbikes, bicycle
  // racks, groups of pedestrians; the rest of a seed's scene is the same with or without them.
  bool roadUsers = false;
  // Raised traffic islands in the medians (islands.cpp): their roads are widened, so the scene
  // differs from the seed's scene without them.
  bool islands = false;
};

struct RigSpec {
  camera::Intrinsics intrinsics{};
  camera::Distortion distortion{};
  geodesy::CameraMount mount{};
  geodesy::GimbalReference gimbalReference = geodesy::GimbalReference::Earth;
  double altitude_m = 90.0;
  double tilt_deg = 0.0;
  double viewAzimuth_deg = 0.0;    // horizontal direction of the optical axis, clockwise from north
  double bodyYawOffset_deg = 0.0;  // earth gimbal: the airframe's heading relative to the view
  double positionSigma_m = 0.3;
  double positionTauS = 5.0;
  double attitudeSigma_deg = 1.0;
  double attitudeTauS = 2.0;
  double gimbalSigma_deg = 0.05;
};

// A static non-vehicle object in one frame: its image box (enclosing its footprint corners at
// the ground and at its top, length axis along the object's) and its visible pixel count.
struct StaticObjectTruth {
  std::int64_t frameId = 0;
  std::string kind;
  std::uint32_t index = 0;  // in the scene's furniture list
  geometry::RotatedBox box{};
  long visiblePixels = 0;
};

struct FrameOutput {
  std::int64_t frameId = 0;
  std::int64_t timestamp_ns = 0;
  cv::Mat image;  // CV_8UC3 BGR, camera size
  cv::Mat ids;    // CV_32SC1 object ids (0 ground, > 0 vehicle track ids, < 0 static objects)
  lifting::DronePose truePose{};
  lifting::DronePose recordedPose{};
  std::vector<sequence::ObjectTruth> objects;
  std::vector<sequence::KeypointTruth> keypoints;
  // Street furniture in view (not vehicles): hard negatives for the detector's training.
  std::vector<StaticObjectTruth> furniture;
};

class Simulator {
 public:
  Simulator();
  ~Simulator();

  bool init(const SimOptions& options, std::string* why);
  bool nextFrame(FrameOutput& out, std::string* why);
  // Renders options.frames frames into options.outDir; onFrame (optional) sees each frame
  // after it is written (tests use the object-id buffer).
  bool write(std::string* why, const std::function<void(const FrameOutput&)>& onFrame = {});

  const SimOptions& options() const { return options_; }
  const SceneSpec& scene() const { return scene_; }
  const World& world() const { return world_; }
  const RigSpec& rig() const { return rig_; }
  const camera::CameraModel& camera() const { return camera_; }
  const lifting::Lifter& lifter() const { return lifter_; }
  const Renderer& renderer() const { return renderer_; }
  const Sensor& sensor() const { return sensor_; }
  const Traffic& traffic() const { return traffic_; }
  const shape::ActiveShapeModel& asmModel() const { return asm_; }
  const PinholeView& view() const { return view_; }
  // rig.yaml text (application configuration schema) naming dtm.tif, dsm.tif and site.geojson.
  std::string rigYaml() const;
  // One-line summary of the drawn parameters (sequence.yaml notes).
  std::string summary() const;

 private:
  // The street furniture in view in out.ids, with image boxes (out.furniture).
  void listFurniture(FrameOutput& out, const lifting::CameraPoseWorld& pose) const;
  void drawRig();
  lifting::DronePose hoverPose();

  SimOptions options_{};
  std::unique_ptr<Rng> rng_;
  geodesy::GeodeticPoint origin_{};
  TerrainSpec terrainSpec_{};
  SceneSpec scene_{};
  World world_{};
  RigSpec rig_{};
  SensorSpec sensorSpec_{};
  camera::CameraModel camera_{};
  lifting::Lifter lifter_{};
  shape::ActiveShapeModel asm_{};
  std::unique_ptr<VehicleFactory> factory_;
  Traffic traffic_{};
  Renderer renderer_{};
  Sensor sensor_{};
  Canvas canvas_{};
  PinholeView view_{};
  Eigen::Vector3d target_{0, 0, 0};
  // Hover state: Ornstein-Uhlenbeck offsets of position (m) and attitude (deg).
  Eigen::Vector3d positionOffset_{0, 0, 0};
  Eigen::Vector3d attitudeOffset_{0, 0, 0};  // roll, pitch, yaw of the body
  Eigen::Vector3d gimbalOffset_{0, 0, 0};
  double logExposure_ = 0.0;
  double exposureBase_ = -1.0;
  std::int64_t frameIndex_ = 0;
};

}  // namespace vp::sim
