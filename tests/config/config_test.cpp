// Tests of config/config: the shipped default file, the documented defaults, and that every
// malformed key is reported with the file and its full key path.
#include "config/config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace vp::config {
namespace {

namespace fs = std::filesystem;

// A complete configuration with every key; the malformed cases below edit one line of it.
constexpr const char* kFullConfig = R"(origin:
  latitude_deg: 43.0731
  longitude_deg: -89.4012
  height_m: 260.0
camera:
  width_px: 2592
  height_px: 2048
  fx_px: 2900.0
  fy_px: 2910.0
  cx_px: 1295.5
  cy_px: 1023.5
  lens_model: brown_conrady
  distortion:
    k1: -0.12
    k2: 0.08
    p1: 0.0001
    p2: -0.0002
    k3: -0.01
mount:
  roll_deg: 1.0
  pitch_deg: 2.0
  yaw_deg: 3.0
  lever_arm_m: [0.0, 0.0, 0.1]
  gimbal:
    reference: body
    roll_deg: 0.0
    pitch_deg: -90.0
    yaw_deg: 0.0
terrain:
  dtm_path: dtm/site.tif
  crs: utm:16N
dds:
  enabled: true
  domain_id: 7
  partition: site_a
  drone_id: 12
  topic_prefix: vpx
  status_rate_hz: 2.0
  occupancy_rate_hz: 1.5
  qos:
    vehicle_state:
      reliability: reliable
      max_blocking_s: 0.02
      durability: volatile
      history_depth: 2
      deadline_s: 0.4
      lifespan_s: 0.6
      liveliness_lease_s: 3.0
    drone_status:
      reliability: best_effort
      max_blocking_s: 0.03
      durability: transient_local
      history_depth: 3
      deadline_s: 4.0
      lifespan_s: 0.7
      liveliness_lease_s: 6.0
    occupancy:
      reliability: best_effort
      max_blocking_s: 0.04
      durability: volatile
      history_depth: 4
      deadline_s: 0.0
      lifespan_s: 2.0
      liveliness_lease_s: 0.0
    traffic_statistics:
      reliability: best_effort
      max_blocking_s: 0.05
      durability: volatile
      history_depth: 7
      deadline_s: 120.0
      lifespan_s: 0.0
      liveliness_lease_s: 7.0
    traffic_events:
      reliability: best_effort
      max_blocking_s: 0.06
      durability: volatile
      history_depth: 64
      deadline_s: 2.0
      lifespan_s: 30.0
      liveliness_lease_s: 8.0
  occupancy_grid:
    origin_east_m: -40.0
    origin_north_m: -30.0
    resolution_m: 0.25
    rows: 300
    cols: 400
  security:
    enabled: false
    plugin_dir: /opt/dds/plugins
    identity_ca: certs/ca.pem
    identity_certificate: certs/drone.pem
    private_key: certs/drone_key.pem
    permissions_ca: certs/permissions_ca.pem
    governance: certs/governance.p7s
    permissions: certs/permissions.p7s
  telemetry:
    source: px4
    domain_id: 3
    ardupilot_geopose_topic: rt/ap/geopose/filtered
    px4_attitude_topic: rt/px4_1/fmu/out/vehicle_attitude
    px4_global_position_topic: rt/px4_1/fmu/out/vehicle_global_position
    ardupilot_altitude_offset_m: -33.5
    history_depth: 5
perception:
  detector_model: models/det.onnx
  crop_model: models/crop.onnx
  asm: models/asm.yaml
  backend: fp32
  threads: 2
  crop_threads: 3
  plan_memory: false
  undistort: false
  white_balance: true
  white_balance_regions: [2, 5]
  white_balance_sample_stride_px: 8
  white_balance_white_share: 0.2
  white_balance_max_gain: 3.0
  exposure: false
  exposure_dark_mean: 30
  exposure_target_mean: 90
  exposure_max_gain: 6
  exposure_sample_stride_px: 4
  working_scale: 0.5
  tile_overlap_px: 64
  score_threshold: 0.35
  top_k_per_tile: 100
  nms_iou: 0.45
  duplicate_overlap: 0.6
  cut_edge_margin_px: 5.0
  max_crops: 64
  apply_flip: false
  apply_refine: false
  crop_refine_size: false
  crop_mirror_average: false
  crop_mirror_refine: false
  crop_large_vehicle_ends: false
  crop_turn_type_weight: 0.65
  crop_min_vehicle_probability: 0.25
  crop_frame_edge_keep_box: false
  crop_frame_edge_min_vehicle_probability: 0.15
  crop_frame_edge_own_verifier: false
  fixed_gsd_m: 0.03
  nominal_car_length_m: 4.4
  lift_height_share: 0.4
pose:
  max_age_s: 0.3
  buffer_capacity: 128
  limits:
    min_height_m: -400.0
    max_height_m: 5000.0
    quaternion_norm_tolerance: 0.02
    max_tilt_deg: 70.0
    min_gimbal_roll_deg: -45.0
    max_gimbal_roll_deg: 45.0
    min_gimbal_pitch_deg: -100.0
    max_gimbal_pitch_deg: 10.0
    min_gimbal_yaw_deg: -180.0
    max_gimbal_yaw_deg: 180.0
    max_horizontal_speed_mps: 40.0
    max_vertical_speed_mps: 20.0
    max_angular_rate_degps: 360.0
    jump_tolerance_m: 5.0
    jump_tolerance_deg: 4.0
    consistency_window_s: 2.0
tracking:
  max_tracks: 300
  confirm_hits: 4
  max_tentative_gap_s: 0.3
  max_lost_s: 2.5
  max_lost_at_edge_s: 0.7
  coast_s: 0.4
  moving_speed_mps: 1.2
  flip_votes: 5
  type_evidence_weight: 0.4
  shape_max_weight: 20.0
  max_distance_m: 5.0
  high_score: 0.6
  low_score: 0.15
  measurement_position_m: 0.3
  measurement_heading_deg: 5.0
  steering_decay_s: 2.0
  confirm_whole_hits: 1
  confirm_hits_anyway: 7
  confirm_hits_standing: 4
  confirm_hits_large: 8
  confirm_min_score: 0.55
  partial_inside_share: 0.8
  partial_along_noise_factor: 5
  long_vehicle_length_m: 7.5
  max_overlap: 0.4
source:
  kind: v4l2
  sequence_dir: seq/run1
  paced: false
  loop: true
  v4l2:
    device: /dev/video2
    bus_info: usb-0000:00:14.0-2
    width_px: 1920
    height_px: 1080
    formats: [nv12, yuyv]
    buffers: 6
    dequeue_timeout_ms: 500
  video:
    path: flights/DJI_0001.MP4
    srt: flights/DJI_0001.SRT
    altitude: rel
    geoid_separation_m: -31.75
    home_height_m: 251.25
    yaw_min_speed_mps: 2.5
telemetry:
  source: mavlink_udp
  udp_bind_address: 127.0.0.1
  udp_port: 14551
  serial_device: /dev/ttyUSB0
  serial_baud: 57600
  system_id: 1
  geoid_separation_m: -33.5
  link_latency_s: 0.002
  replay_lookahead_s: 0.3
georef:
  gcp_file: none
  max_residual_m: 2.5
site:
  file: maps/site.geojson
  off_road: flag
traffic:
  period_s: 30.0
  stop_speed_mps: 0.5
  lane_heading_tolerance_deg: 30.0
  wrong_way_angle_deg: 150.0
  wrong_way_speed_mps: 3.0
  wrong_way_s: 2.0
  box_junction_stop_s: 4.0
  max_tracks: 512
  max_events_per_step: 128
  max_lane_samples: 300
app:
  queue_depth: 2
  pipeline: on
  frame_pool_size: 6
  lock_memory: true
  realtime_priority: 50
  capture_cpus: [0]
  processing_cpus: [1, 2]
  stats_period_s: 10.0
  trajectory_csv: out/tracks.csv
  detections_csv: out/detections.csv
  traffic_dir: out/traffic
  annotated_video: out/annotated.avi
  annotated_video_fps: 5.0
  record:
    dir: out/flight1
    jpeg_quality: 80
    every_nth_frame: 2
    queue_frames: 6
    max_disk_mib: 4096
    min_free_disk_mib: 512
    on_full: ring
)";

// Only the required keys.
constexpr const char* kMinimalConfig = R"(origin:
  latitude_deg: 43.0731
  longitude_deg: -89.4012
  height_m: 260.0
camera:
  width_px: 640
  height_px: 480
  fx_px: 500.0
  fy_px: 501.0
terrain:
  dtm_path: dtm.tif
)";

constexpr const char* kSource = "site.yaml";
constexpr const char* kBaseDir = "/data/site";

AppConfig parse(const std::string& text) {
  return parseConfig(text, kSource, kBaseDir);
}

// The message of the ConfigError that parsing throws, or "" when it does not throw.
std::string errorOf(const std::string& text) {
  try {
    parse(text);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

// kFullConfig with `from` (which must occur exactly once) replaced by `to`.
std::string edited(const std::string& from, const std::string& to) {
  std::string text = kFullConfig;
  const std::size_t at = text.find(from);
  if (at == std::string::npos || text.find(from, at + 1) != std::string::npos) {
    ADD_FAILURE() << "'" << from << "' does not occur exactly once in the base config";
    return text;
  }
  return text.replace(at, from.size(), to);
}

TEST(ConfigDefaultFile, ParsesWithoutWarningsToTheDocumentedValues) {
  const std::string path = std::string(VP_SOURCE_DIR) + "/config/default.yaml";
  const AppConfig config = loadConfig(path);
  EXPECT_TRUE(config.warnings.empty()) << config.warnings.front();
  EXPECT_EQ(config.sourcePath, path);

  EXPECT_DOUBLE_EQ(config.origin.latitude_deg, 43.0731);
  EXPECT_DOUBLE_EQ(config.origin.longitude_deg, -89.4012);
  EXPECT_DOUBLE_EQ(config.origin.height_m, 260.0);

  const camera::Intrinsics& in = config.camera.intrinsics;
  EXPECT_EQ(in.width_px, 2592);
  EXPECT_EQ(in.height_px, 2048);
  EXPECT_DOUBLE_EQ(in.fx_px, 2900.0);
  EXPECT_DOUBLE_EQ(in.fy_px, 2900.0);
  EXPECT_DOUBLE_EQ(in.cx_px, 1295.5);
  EXPECT_DOUBLE_EQ(in.cy_px, 1023.5);
  const camera::Distortion& lens = config.camera.distortion;
  EXPECT_EQ(lens.model, camera::LensModel::BrownConrady);
  EXPECT_DOUBLE_EQ(lens.k1, -0.12);
  EXPECT_DOUBLE_EQ(lens.k2, 0.08);
  EXPECT_DOUBLE_EQ(lens.p1, 0.0001);
  EXPECT_DOUBLE_EQ(lens.p2, -0.0002);
  EXPECT_DOUBLE_EQ(lens.k3, -0.01);

  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.roll_deg, 0.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.pitch_deg, 0.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.yaw_deg, 0.0);
  EXPECT_EQ(config.mount.mount.leverArm_m, Eigen::Vector3d(0.0, 0.0, 0.1));
  EXPECT_EQ(config.mount.gimbal.reference, geodesy::GimbalReference::Body);
  EXPECT_DOUBLE_EQ(config.mount.gimbal.angles.roll_deg, 0.0);
  EXPECT_DOUBLE_EQ(config.mount.gimbal.angles.pitch_deg, -90.0);
  EXPECT_DOUBLE_EQ(config.mount.gimbal.angles.yaw_deg, 0.0);

  const fs::path dtm =
      (fs::path(VP_SOURCE_DIR) / "tests/fixtures/dtm/sloped_utm16n.tif").lexically_normal();
  EXPECT_EQ(config.terrain.dtmPath, dtm.string());
  EXPECT_FALSE(config.terrain.crs.has_value());

  // The dds: section of the shipped file holds the documented defaults.
  const DdsConfig defaults;
  const DdsConfig& dds = config.dds;
  EXPECT_EQ(dds.enabled, defaults.enabled);
  EXPECT_EQ(dds.domainId, defaults.domainId);
  EXPECT_EQ(dds.partition, defaults.partition);
  EXPECT_EQ(dds.droneId, defaults.droneId);
  EXPECT_EQ(dds.topicPrefix, defaults.topicPrefix);
  EXPECT_EQ(dds.statusRate_hz, defaults.statusRate_hz);
  EXPECT_EQ(dds.occupancyRate_hz, defaults.occupancyRate_hz);
  const std::pair<const QosProfile*, const QosProfile*> profiles[] = {
      {&dds.vehicleState, &defaults.vehicleState},
      {&dds.droneStatus, &defaults.droneStatus},
      {&dds.occupancy, &defaults.occupancy},
      {&dds.trafficStatistics, &defaults.trafficStatistics},
      {&dds.trafficEvents, &defaults.trafficEvents}};
  for (const auto& [got, want] : profiles) {
    EXPECT_EQ(got->reliability, want->reliability);
    EXPECT_EQ(got->maxBlocking_s, want->maxBlocking_s);
    EXPECT_EQ(got->durability, want->durability);
    EXPECT_EQ(got->historyDepth, want->historyDepth);
    EXPECT_EQ(got->deadline_s, want->deadline_s);
    EXPECT_EQ(got->lifespan_s, want->lifespan_s);
    EXPECT_EQ(got->livelinessLease_s, want->livelinessLease_s);
  }
  EXPECT_EQ(dds.grid.originEast_m, defaults.grid.originEast_m);
  EXPECT_EQ(dds.grid.originNorth_m, defaults.grid.originNorth_m);
  EXPECT_EQ(dds.grid.resolution_m, defaults.grid.resolution_m);
  EXPECT_EQ(dds.grid.rows, defaults.grid.rows);
  EXPECT_EQ(dds.grid.cols, defaults.grid.cols);
  EXPECT_EQ(dds.security.enabled, defaults.security.enabled);
  EXPECT_EQ(dds.security.pluginDir, defaults.security.pluginDir);
  EXPECT_EQ(dds.telemetry.source, defaults.telemetry.source);
  EXPECT_EQ(dds.telemetry.domainId, defaults.telemetry.domainId);
  EXPECT_EQ(dds.telemetry.ardupilotGeoPoseTopic, defaults.telemetry.ardupilotGeoPoseTopic);
  EXPECT_EQ(dds.telemetry.px4AttitudeTopic, defaults.telemetry.px4AttitudeTopic);
  EXPECT_EQ(dds.telemetry.px4GlobalPositionTopic, defaults.telemetry.px4GlobalPositionTopic);
  EXPECT_EQ(dds.telemetry.ardupilotAltitudeOffset_m, defaults.telemetry.ardupilotAltitudeOffset_m);
  EXPECT_EQ(dds.telemetry.historyDepth, defaults.telemetry.historyDepth);

  // The loop's sections: the shipped models of the repository, replay with recorded telemetry.
  const fs::path models = fs::path(VP_SOURCE_DIR) / "models";
  EXPECT_EQ(config.perception.detection.detectorModelPath,
            (models / "detector/detector_int8.onnx").lexically_normal().string());
  EXPECT_EQ(config.perception.detection.cropModelPath,
            (models / "detector/crop_int8.onnx").lexically_normal().string());
  EXPECT_EQ(config.asmPath, (models / "asm/default_asm.yaml").lexically_normal().string());
  EXPECT_TRUE(fs::is_regular_file(config.asmPath));
  EXPECT_EQ(config.perception.detection.engine.backend, inference::Backend::Auto);
  EXPECT_EQ(config.perception.preprocess.whiteBalanceOptions.regionRows, 3);
  EXPECT_EQ(config.perception.preprocess.whiteBalanceOptions.regionCols, 4);
  EXPECT_EQ(config.source.kind, FrameSourceKind::Replay);
  EXPECT_EQ(config.telemetry.source, TelemetrySourceKind::Recording);
  EXPECT_EQ(config.app.queueDepth, 1);
  EXPECT_EQ(config.app.pipeline, PipelineMode::Off);
  EXPECT_TRUE(config.app.trajectoryCsv.empty());
}

TEST(ConfigDefaults, RequiredKeysOnlyGetTheDocumentedDefaults) {
  const AppConfig config = parse(kMinimalConfig);
  EXPECT_TRUE(config.warnings.empty());
  EXPECT_EQ(config.sourcePath, kSource);

  const camera::Intrinsics& in = config.camera.intrinsics;
  EXPECT_EQ(in.width_px, 640);
  EXPECT_EQ(in.height_px, 480);
  EXPECT_DOUBLE_EQ(in.fx_px, 500.0);
  EXPECT_DOUBLE_EQ(in.fy_px, 501.0);
  EXPECT_DOUBLE_EQ(in.cx_px, 319.5);  // (width_px - 1) / 2
  EXPECT_DOUBLE_EQ(in.cy_px, 239.5);  // (height_px - 1) / 2
  const camera::Distortion& lens = config.camera.distortion;
  EXPECT_EQ(lens.model, camera::LensModel::Pinhole);
  EXPECT_EQ(lens.k1, 0.0);
  EXPECT_EQ(lens.k2, 0.0);
  EXPECT_EQ(lens.p1, 0.0);
  EXPECT_EQ(lens.p2, 0.0);
  EXPECT_EQ(lens.k3, 0.0);

  EXPECT_EQ(config.mount.mount.bodyToBase.roll_deg, 0.0);
  EXPECT_EQ(config.mount.mount.bodyToBase.pitch_deg, 0.0);
  EXPECT_EQ(config.mount.mount.bodyToBase.yaw_deg, 0.0);
  EXPECT_EQ(config.mount.mount.leverArm_m, Eigen::Vector3d::Zero());
  EXPECT_EQ(config.mount.gimbal.reference, geodesy::GimbalReference::Body);
  EXPECT_EQ(config.mount.gimbal.angles.roll_deg, 0.0);
  EXPECT_EQ(config.mount.gimbal.angles.pitch_deg, -90.0);  // nadir
  EXPECT_EQ(config.mount.gimbal.angles.yaw_deg, 0.0);

  EXPECT_EQ(config.terrain.dtmPath, "/data/site/dtm.tif");
  EXPECT_FALSE(config.terrain.crs.has_value());  // auto
}

TEST(ConfigValues, FullConfigReadsEveryKey) {
  const AppConfig config = parse(kFullConfig);
  EXPECT_TRUE(config.warnings.empty());
  EXPECT_DOUBLE_EQ(config.camera.intrinsics.fy_px, 2910.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.roll_deg, 1.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.pitch_deg, 2.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.yaw_deg, 3.0);
  ASSERT_TRUE(config.terrain.crs.has_value());
  EXPECT_EQ(config.terrain.crs->kind, terrain::HorizontalCrs::Utm);
  EXPECT_EQ(config.terrain.crs->utmZone, 16);
  EXPECT_TRUE(config.terrain.crs->utmNorth);
}

TEST(ConfigValues, OtherEnumValuesAndNumberSpellings) {
  std::string text = edited("lens_model: brown_conrady", "lens_model: equivalent_spherical");
  text.replace(text.find("distortion:"), std::string("distortion:").size(), "x_distortion:");
  const std::size_t gimbal = text.find("reference: body");
  text.replace(gimbal, std::string("reference: body").size(), "reference: earth");
  text.replace(text.find("crs: utm:16N"), std::string("crs: utm:16N").size(), "crs: WGS84");
  text.replace(text.find("fx_px: 2900.0"), std::string("fx_px: 2900.0").size(), "fx_px: +2.9e3");
  const AppConfig config = parse(text);
  EXPECT_EQ(config.camera.distortion.model, camera::LensModel::EquivalentSpherical);
  EXPECT_EQ(config.mount.gimbal.reference, geodesy::GimbalReference::Earth);
  ASSERT_TRUE(config.terrain.crs.has_value());
  EXPECT_EQ(config.terrain.crs->kind, terrain::HorizontalCrs::Wgs84Geographic);
  EXPECT_DOUBLE_EQ(config.camera.intrinsics.fx_px, 2900.0);
  ASSERT_EQ(config.warnings.size(), 1U);  // the renamed distortion section
  EXPECT_EQ(config.warnings[0], "site.yaml: unknown key 'camera.x_distortion'");
}

// The acceptance test: one malformed key per row; the error must name the source and the
// key's full path, and say what is wrong.
struct MalformedCase {
  const char* from;     // text of kFullConfig to replace (occurs once)
  const char* to;       // its replacement
  const char* path;     // full key path the message must name
  const char* problem;  // part of the message after the path
};

const MalformedCase kMalformedCases[] = {
    // origin
    {"origin:\n  latitude_deg: 43.0731\n  longitude_deg: -89.4012\n  height_m: 260.0\n", "",
     "origin", "missing (required)"},
    {"origin:\n  latitude_deg: 43.0731\n  longitude_deg: -89.4012\n  height_m: 260.0\n",
     "origin: 43.0\n", "origin", "expected a map, got '43.0'"},
    {"  latitude_deg: 43.0731\n", "", "origin.latitude_deg", "missing (required)"},
    {"latitude_deg: 43.0731", "latitude_deg: abc", "origin.latitude_deg",
     "expected a number, got 'abc'"},
    {"latitude_deg: 43.0731", "latitude_deg: 90.5", "origin.latitude_deg",
     "must be in [-90, 90], got 90.5"},
    {"latitude_deg: 43.0731", "latitude_deg: .nan", "origin.latitude_deg",
     "must be finite, got .nan"},
    {"  longitude_deg: -89.4012\n", "", "origin.longitude_deg", "missing (required)"},
    {"longitude_deg: -89.4012", "longitude_deg: -180.5", "origin.longitude_deg",
     "must be in [-180, 180], got -180.5"},
    {"longitude_deg: -89.4012", "longitude_deg: [1, 2]", "origin.longitude_deg",
     "expected a number, got a sequence of 2 element(s)"},
    {"  height_m: 260.0\n", "", "origin.height_m", "missing (required)"},
    {"height_m: 260.0", "height_m: 9001", "origin.height_m", "must be in [-500, 9000], got 9001"},
    {"height_m: 260.0", "height_m: -.inf", "origin.height_m", "must be finite, got -.inf"},
    {"height_m: 260.0", "height_m:", "origin.height_m", "expected a number, got nothing (null)"},
    // camera
    {"camera:\n  width_px", "cam:\n  width_px", "camera", "missing (required)"},
    {"camera:\n  width_px: 2592\n", "camera: [1]\nx:\n  width_px: 2592\n", "camera",
     "expected a map, got a sequence of 1 element(s)"},
    {"  width_px: 2592\n", "", "camera.width_px", "missing (required)"},
    {"width_px: 2592", "width_px: 2592.5", "camera.width_px", "expected an integer, got '2592.5'"},
    {"width_px: 2592", "width_px: 15", "camera.width_px", "must be in [16, 16384], got 15"},
    {"width_px: 2592", "width_px: wide", "camera.width_px", "expected an integer, got 'wide'"},
    {"  height_px: 2048\n", "", "camera.height_px", "missing (required)"},
    {"height_px: 2048", "height_px: 16385", "camera.height_px",
     "must be in [16, 16384], got 16385"},
    {"height_px: 2048", "height_px: .inf", "camera.height_px", "must be finite, got .inf"},
    {"  fx_px: 2900.0\n", "", "camera.fx_px", "missing (required)"},
    {"fx_px: 2900.0", "fx_px: -3", "camera.fx_px", "must be > 0, got -3"},
    {"fx_px: 2900.0", "fx_px: 0", "camera.fx_px", "must be > 0, got 0"},
    {"fx_px: 2900.0", "fx_px: {value: 2900}", "camera.fx_px", "expected a number, got a map"},
    {"fx_px: 2900.0", "fx_px: \"2900\"", "camera.fx_px",
     "expected a number, got the quoted string '2900'"},
    {"fx_px: 2900.0", "fx_px: 2900.0\n  fx_px: 2901.0", "camera.fx_px", "duplicate key"},
    {"  fy_px: 2910.0\n", "", "camera.fy_px", "missing (required)"},
    {"fy_px: 2910.0", "fy_px: .NaN", "camera.fy_px", "must be finite, got .NaN"},
    {"fy_px: 2910.0", "fy_px: 2910px", "camera.fy_px", "expected a number, got '2910px'"},
    {"cx_px: 1295.5", "cx_px: 2592", "camera.cx_px", "must be in [-0.5, 2591.5], got 2592"},
    {"cx_px: 1295.5", "cx_px: centre", "camera.cx_px", "expected a number, got 'centre'"},
    {"cy_px: 1023.5", "cy_px: -1", "camera.cy_px", "must be in [-0.5, 2047.5], got -1"},
    {"cy_px: 1023.5", "cy_px: [1, 2]", "camera.cy_px", "expected a number, got a sequence"},
    {"lens_model: brown_conrady", "lens_model: fisheye", "camera.lens_model",
     "unknown value 'fisheye' (expected pinhole, brown_conrady, equivalent_spherical)"},
    {"lens_model: brown_conrady", "lens_model: [pinhole]", "camera.lens_model",
     "expected a string, got a sequence of 1 element(s)"},
    {"lens_model: brown_conrady", "lens_model: ''", "camera.lens_model", "must not be empty"},
    {"  distortion:\n", "  distortion: 0.1\n  x:\n", "camera.distortion",
     "expected a map, got '0.1'"},
    {"k1: -0.12", "k1: abc", "camera.distortion.k1", "expected a number, got 'abc'"},
    {"k2: 0.08", "k2: .inf", "camera.distortion.k2", "must be finite, got .inf"},
    {"p1: 0.0001", "p1: 1000", "camera.distortion.p1", "must be in [-100, 100], got 1000"},
    {"p2: -0.0002", "p2: {a: 1}", "camera.distortion.p2", "expected a number, got a map"},
    {"k3: -0.01", "k3: nan", "camera.distortion.k3", "must be finite, got nan"},
    // mount
    {"mount:\n  roll_deg: 1.0\n", "mount: level\nx:\n  roll_deg: 1.0\n", "mount",
     "expected a map, got 'level'"},
    {"  roll_deg: 1.0", "  roll_deg: 181", "mount.roll_deg", "must be in [-180, 180], got 181"},
    {"  pitch_deg: 2.0", "  pitch_deg: 90.1", "mount.pitch_deg", "must be in [-90, 90], got 90.1"},
    {"  yaw_deg: 3.0", "  yaw_deg: east", "mount.yaw_deg", "expected a number, got 'east'"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0.0, 0.1]", "mount.lever_arm_m",
     "expected a sequence of 3 numbers [x, y, z], got a sequence of 2 element(s)"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0, 0, 0, 1]", "mount.lever_arm_m",
     "got a sequence of 4 element(s)"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: 0.1", "mount.lever_arm_m",
     "expected a sequence of 3 numbers [x, y, z], got '0.1'"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: {x: 0}", "mount.lever_arm_m",
     "expected a sequence of 3 numbers [x, y, z], got a map"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0.0, x, 0.1]", "mount.lever_arm_m[1]",
     "expected a number, got 'x'"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0.0, 0.0, 11]", "mount.lever_arm_m[2]",
     "must be in [-10, 10], got 11"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [.nan, 0.0, 0.1]", "mount.lever_arm_m[0]",
     "must be finite, got .nan"},
    {"  gimbal:\n", "  gimbal: [0, -90, 0]\n  x:\n", "mount.gimbal",
     "expected a map, got a sequence of 3 element(s)"},
    {"reference: body", "reference: world", "mount.gimbal.reference",
     "unknown value 'world' (expected body, earth)"},
    {"reference: body", "reference: {frame: body}", "mount.gimbal.reference",
     "expected a string, got a map"},
    {"    roll_deg: 0.0", "    roll_deg: 200", "mount.gimbal.roll_deg",
     "must be in [-180, 180], got 200"},
    {"    pitch_deg: -90.0", "    pitch_deg: -121", "mount.gimbal.pitch_deg",
     "must be in [-120, 30], got -121"},
    {"    pitch_deg: -90.0", "    pitch_deg: 31", "mount.gimbal.pitch_deg",
     "must be in [-120, 30], got 31"},
    {"    yaw_deg: 0.0", "    yaw_deg: abc", "mount.gimbal.yaw_deg",
     "expected a number, got 'abc'"},
    {"    yaw_deg: 0.0", "    yaw_deg: .inf", "mount.gimbal.yaw_deg", "must be finite, got .inf"},
    // terrain
    {"terrain:\n  dtm_path: dtm/site.tif\n  crs: utm:16N\n", "", "terrain", "missing (required)"},
    {"terrain:\n  dtm_path", "terrain: dtm.tif\nx:\n  dtm_path", "terrain",
     "expected a map, got 'dtm.tif'"},
    {"  dtm_path: dtm/site.tif\n", "", "terrain.dtm_path", "missing (required)"},
    {"dtm_path: dtm/site.tif", "dtm_path: \"\"", "terrain.dtm_path", "must not be empty"},
    {"dtm_path: dtm/site.tif", "dtm_path: [a.tif, b.tif]", "terrain.dtm_path",
     "expected a string, got a sequence of 2 element(s)"},
    {"dtm_path: dtm/site.tif", "dtm_path:", "terrain.dtm_path",
     "expected a string, got nothing (null)"},
    {"crs: utm:16N", "crs: utm:61N", "terrain.crs", "unknown value 'utm:61N' (expected auto"},
    {"crs: utm:16N", "crs: utm:16X", "terrain.crs", "unknown value 'utm:16X'"},
    {"crs: utm:16N", "crs: epsg:4326", "terrain.crs", "unknown value 'epsg:4326'"},
    {"crs: utm:16N", "crs: {zone: 16}", "terrain.crs", "expected a string, got a map"},
    // dds
    {"dds:\n  enabled: true\n", "dds: [1]\nx:\n  enabled: true\n", "dds",
     "expected a map, got a sequence of 1 element(s)"},
    {"enabled: true\n  domain_id", "enabled: yes\n  domain_id", "dds.enabled",
     "expected true or false, got 'yes'"},
    {"domain_id: 7", "domain_id: 233", "dds.domain_id", "must be in [0, 232], got 233"},
    {"domain_id: 7", "domain_id: 1.5", "dds.domain_id", "expected an integer, got '1.5'"},
    {"partition: site_a", "partition: ''", "dds.partition", "must not be empty"},
    {"drone_id: 12", "drone_id: -1", "dds.drone_id", "must be in [0, 4294967295], got -1"},
    {"topic_prefix: vpx", "topic_prefix: [a]", "dds.topic_prefix",
     "expected a string, got a sequence of 1 element(s)"},
    {"status_rate_hz: 2.0", "status_rate_hz: 0", "dds.status_rate_hz",
     "must be in [0.01, 100], got 0"},
    {"occupancy_rate_hz: 1.5", "occupancy_rate_hz: fast", "dds.occupancy_rate_hz",
     "expected a number, got 'fast'"},
    {"  qos:\n    vehicle_state:", "  qos: 1\n  x:\n    vehicle_state:", "dds.qos",
     "expected a map, got '1'"},
    {"    vehicle_state:\n", "    vehicle_state: fast\n    x:\n", "dds.qos.vehicle_state",
     "expected a map, got 'fast'"},
    {"reliability: reliable", "reliability: maybe", "dds.qos.vehicle_state.reliability",
     "unknown value 'maybe' (expected reliable, best_effort)"},
    {"max_blocking_s: 0.02", "max_blocking_s: 11", "dds.qos.vehicle_state.max_blocking_s",
     "must be in [0, 10], got 11"},
    {"0.02\n      durability: volatile", "0.02\n      durability: persistent",
     "dds.qos.vehicle_state.durability",
     "unknown value 'persistent' (expected volatile, transient_local)"},
    {"history_depth: 2", "history_depth: 0", "dds.qos.vehicle_state.history_depth",
     "must be in [1, 1000], got 0"},
    {"deadline_s: 0.4", "deadline_s: -1", "dds.qos.vehicle_state.deadline_s",
     "must be in [0, 3600], got -1"},
    {"lifespan_s: 0.6", "lifespan_s: .inf", "dds.qos.vehicle_state.lifespan_s",
     "must be finite, got .inf"},
    {"liveliness_lease_s: 3.0", "liveliness_lease_s: 3601",
     "dds.qos.vehicle_state.liveliness_lease_s", "must be in [0, 3600], got 3601"},
    {"    drone_status:\n", "    drone_status: [1]\n    x:\n", "dds.qos.drone_status",
     "expected a map, got a sequence of 1 element(s)"},
    {"drone_status:\n      reliability: best_effort", "drone_status:\n      reliability: lossy",
     "dds.qos.drone_status.reliability", "unknown value 'lossy'"},
    {"max_blocking_s: 0.03", "max_blocking_s: x", "dds.qos.drone_status.max_blocking_s",
     "expected a number, got 'x'"},
    {"durability: transient_local", "durability: durable", "dds.qos.drone_status.durability",
     "unknown value 'durable' (expected volatile, transient_local)"},
    {"history_depth: 3", "history_depth: 1001", "dds.qos.drone_status.history_depth",
     "must be in [1, 1000], got 1001"},
    {"deadline_s: 4.0", "deadline_s: [4]", "dds.qos.drone_status.deadline_s",
     "expected a number, got a sequence of 1 element(s)"},
    {"lifespan_s: 0.7", "lifespan_s: -0.1", "dds.qos.drone_status.lifespan_s",
     "must be in [0, 3600], got -0.1"},
    {"liveliness_lease_s: 6.0", "liveliness_lease_s: .nan",
     "dds.qos.drone_status.liveliness_lease_s", "must be finite, got .nan"},
    {"    occupancy:\n", "    occupancy: 2\n    x:\n", "dds.qos.occupancy",
     "expected a map, got '2'"},
    {"occupancy:\n      reliability: best_effort", "occupancy:\n      reliability: BEST_EFFORT",
     "dds.qos.occupancy.reliability", "unknown value 'BEST_EFFORT'"},
    {"max_blocking_s: 0.04", "max_blocking_s: -0.04", "dds.qos.occupancy.max_blocking_s",
     "must be in [0, 10], got -0.04"},
    {"0.04\n      durability: volatile", "0.04\n      durability: {a: 1}",
     "dds.qos.occupancy.durability", "expected a string, got a map"},
    {"history_depth: 4", "history_depth: 4.5", "dds.qos.occupancy.history_depth",
     "expected an integer, got '4.5'"},
    {"deadline_s: 0.0", "deadline_s: 1e9", "dds.qos.occupancy.deadline_s",
     "must be in [0, 3600], got 1e9"},
    {"lifespan_s: 2.0", "lifespan_s: two", "dds.qos.occupancy.lifespan_s",
     "expected a number, got 'two'"},
    {"liveliness_lease_s: 0.0", "liveliness_lease_s: -1", "dds.qos.occupancy.liveliness_lease_s",
     "must be in [0, 3600], got -1"},
    {"    traffic_statistics:\n", "    traffic_statistics: 1\n    x:\n",
     "dds.qos.traffic_statistics", "expected a map, got '1'"},
    {"reliability: best_effort\n      max_blocking_s: 0.05",
     "reliability: sometimes\n      max_blocking_s: 0.05", "dds.qos.traffic_statistics.reliability",
     "unknown value 'sometimes'"},
    {"max_blocking_s: 0.05", "max_blocking_s: 12", "dds.qos.traffic_statistics.max_blocking_s",
     "must be in [0, 10], got 12"},
    {"durability: volatile\n      history_depth: 7",
     "durability: persistent\n      history_depth: 7", "dds.qos.traffic_statistics.durability",
     "unknown value 'persistent'"},
    {"history_depth: 7", "history_depth: 1001", "dds.qos.traffic_statistics.history_depth",
     "must be in [1, 1000], got 1001"},
    {"deadline_s: 120.0", "deadline_s: -2", "dds.qos.traffic_statistics.deadline_s",
     "must be in [0, 3600], got -2"},
    {"lifespan_s: 0.0\n      liveliness_lease_s: 7.0",
     "lifespan_s: x\n      liveliness_lease_s: 7.0", "dds.qos.traffic_statistics.lifespan_s",
     "expected a number, got 'x'"},
    {"liveliness_lease_s: 7.0", "liveliness_lease_s: 4000",
     "dds.qos.traffic_statistics.liveliness_lease_s", "must be in [0, 3600], got 4000"},
    {"    traffic_events:\n", "    traffic_events: [2]\n    x:\n", "dds.qos.traffic_events",
     "expected a map, got a sequence"},
    {"reliability: best_effort\n      max_blocking_s: 0.06",
     "reliability: often\n      max_blocking_s: 0.06", "dds.qos.traffic_events.reliability",
     "unknown value 'often'"},
    {"max_blocking_s: 0.06", "max_blocking_s: -1", "dds.qos.traffic_events.max_blocking_s",
     "must be in [0, 10], got -1"},
    {"durability: volatile\n      history_depth: 64",
     "durability: durable\n      history_depth: 64", "dds.qos.traffic_events.durability",
     "unknown value 'durable'"},
    {"history_depth: 64", "history_depth: 0", "dds.qos.traffic_events.history_depth",
     "must be in [1, 1000], got 0"},
    {"deadline_s: 2.0", "deadline_s: 3601", "dds.qos.traffic_events.deadline_s",
     "must be in [0, 3600], got 3601"},
    {"lifespan_s: 30.0", "lifespan_s: -30", "dds.qos.traffic_events.lifespan_s",
     "must be in [0, 3600], got -30"},
    {"liveliness_lease_s: 8.0", "liveliness_lease_s: 9999",
     "dds.qos.traffic_events.liveliness_lease_s", "must be in [0, 3600], got 9999"},
    {"  occupancy_grid:\n", "  occupancy_grid: none\n  x:\n", "dds.occupancy_grid",
     "expected a map, got 'none'"},
    {"origin_east_m: -40.0", "origin_east_m: 1e6", "dds.occupancy_grid.origin_east_m",
     "must be in [-100000, 100000], got 1e6"},
    {"origin_north_m: -30.0", "origin_north_m: north", "dds.occupancy_grid.origin_north_m",
     "expected a number, got 'north'"},
    {"resolution_m: 0.25", "resolution_m: 0.01", "dds.occupancy_grid.resolution_m",
     "must be in [0.05, 10], got 0.01"},
    {"rows: 300", "rows: 2049", "dds.occupancy_grid.rows", "must be in [1, 2048], got 2049"},
    {"cols: 400", "cols: 1.5", "dds.occupancy_grid.cols", "expected an integer, got '1.5'"},
    {"  security:\n", "  security: on\n  x:\n", "dds.security", "expected a map, got 'on'"},
    {"enabled: false", "enabled: on", "dds.security.enabled", "expected true or false, got 'on'"},
    {"enabled: false", "enabled: true", "dds.security.plugin_dir",
     "no DDS Security plugins (libdds_security_auth.so) in /opt/dds/plugins"},
    {"plugin_dir: /opt/dds/plugins", "plugin_dir: [a]", "dds.security.plugin_dir",
     "expected a string, got a sequence of 1 element(s)"},
    {"identity_ca: certs/ca.pem", "identity_ca: ''", "dds.security.identity_ca",
     "must not be empty"},
    {"identity_certificate: certs/drone.pem", "identity_certificate: [a, b]",
     "dds.security.identity_certificate", "expected a string, got a sequence of 2 element(s)"},
    {"private_key: certs/drone_key.pem", "private_key: {file: k}", "dds.security.private_key",
     "expected a string, got a map"},
    {"permissions_ca: certs/permissions_ca.pem", "permissions_ca:", "dds.security.permissions_ca",
     "expected a string, got nothing (null)"},
    {"governance: certs/governance.p7s", "governance: ''", "dds.security.governance",
     "must not be empty"},
    {"permissions: certs/permissions.p7s", "permissions: [p]", "dds.security.permissions",
     "expected a string, got a sequence of 1 element(s)"},
    {"  telemetry:\n", "  telemetry: px4\n  x:\n", "dds.telemetry", "expected a map, got 'px4'"},
    {"source: px4", "source: mavlink", "dds.telemetry.source",
     "unknown value 'mavlink' (expected none, ardupilot, px4)"},
    {"domain_id: 3", "domain_id: 300", "dds.telemetry.domain_id", "must be in [0, 232], got 300"},
    {"ardupilot_geopose_topic: rt/ap/geopose/filtered", "ardupilot_geopose_topic: ''",
     "dds.telemetry.ardupilot_geopose_topic", "must not be empty"},
    {"px4_attitude_topic: rt/px4_1/fmu/out/vehicle_attitude", "px4_attitude_topic: {a: 1}",
     "dds.telemetry.px4_attitude_topic", "expected a string, got a map"},
    {"px4_global_position_topic: rt/px4_1/fmu/out/vehicle_global_position",
     "px4_global_position_topic: [a]", "dds.telemetry.px4_global_position_topic",
     "expected a string, got a sequence of 1 element(s)"},
    {"ardupilot_altitude_offset_m: -33.5", "ardupilot_altitude_offset_m: 500",
     "dds.telemetry.ardupilot_altitude_offset_m", "must be in [-200, 200], got 500"},
    {"history_depth: 5", "history_depth: 0", "dds.telemetry.history_depth",
     "must be in [1, 1000], got 0"},
    // perception
    {"perception:\n  detector_model", "perception: 1\nx:\n  detector_model", "perception",
     "expected a map, got '1'"},
    {"detector_model: models/det.onnx", "detector_model: ''", "perception.detector_model",
     "must not be empty"},
    {"crop_model: models/crop.onnx", "crop_model: [a]", "perception.crop_model",
     "expected a string, got a sequence of 1 element(s)"},
    {"asm: models/asm.yaml", "asm: {a: 1}", "perception.asm", "expected a string, got a map"},
    {"backend: fp32", "backend: int4", "perception.backend",
     "unknown value 'int4' (expected int8, fp32, opencv, int8-dnnl, auto)"},
    {"  threads: 2", "  threads: 0", "perception.threads", "must be in [1, 16], got 0"},
    {"crop_threads: 3", "crop_threads: 17", "perception.crop_threads",
     "must be in [1, 16], got 17"},
    {"plan_memory: false", "plan_memory: no", "perception.plan_memory",
     "expected true or false, got 'no'"},
    {"undistort: false", "undistort: maybe", "perception.undistort",
     "expected true or false, got 'maybe'"},
    {"white_balance: true", "white_balance: 1", "perception.white_balance",
     "expected true or false, got '1'"},
    {"white_balance_regions: [2, 5]", "white_balance_regions: [2]",
     "perception.white_balance_regions",
     "expected a sequence of 2 integers, got a sequence of 1 element(s)"},
    {"white_balance_regions: [2, 5]", "white_balance_regions: [2, 9]",
     "perception.white_balance_regions[1]", "must be in [1, 8], got 9"},
    {"white_balance_sample_stride_px: 8", "white_balance_sample_stride_px: 0",
     "perception.white_balance_sample_stride_px", "must be in [1, 64], got 0"},
    {"white_balance_white_share: 0.2", "white_balance_white_share: 0",
     "perception.white_balance_white_share", "must be in (0, 1], got 0"},
    {"white_balance_max_gain: 3.0", "white_balance_max_gain: 0.5",
     "perception.white_balance_max_gain", "must be in [1, 16], got 0.5"},
    {"exposure: false", "exposure: off", "perception.exposure",
     "expected true or false, got 'off'"},
    {"exposure_dark_mean: 30", "exposure_dark_mean: 256", "perception.exposure_dark_mean",
     "must be in [0, 255], got 256"},
    {"exposure_target_mean: 90", "exposure_target_mean: 20", "perception.exposure_target_mean",
     "must be >= exposure_dark_mean (30), got 20"},
    {"exposure_max_gain: 6", "exposure_max_gain: 17", "perception.exposure_max_gain",
     "must be in [1, 16], got 17"},
    {"exposure_sample_stride_px: 4", "exposure_sample_stride_px: 0",
     "perception.exposure_sample_stride_px", "must be in [1, 64], got 0"},
    {"working_scale: 0.5", "working_scale: 1.5", "perception.working_scale",
     "must be in (0, 1], got 1.5"},
    {"tile_overlap_px: 64", "tile_overlap_px: -1", "perception.tile_overlap_px",
     "must be in [0, 1024], got -1"},
    {"score_threshold: 0.35", "score_threshold: 2", "perception.score_threshold",
     "must be in [0, 1], got 2"},
    {"top_k_per_tile: 100", "top_k_per_tile: 0", "perception.top_k_per_tile",
     "must be in [1, 512], got 0"},
    {"nms_iou: 0.45", "nms_iou: 0", "perception.nms_iou", "must be in (0, 1], got 0"},
    {"duplicate_overlap: 0.6", "duplicate_overlap: x", "perception.duplicate_overlap",
     "expected a number, got 'x'"},
    {"cut_edge_margin_px: 5.0", "cut_edge_margin_px: .nan", "perception.cut_edge_margin_px",
     "must be finite, got .nan"},
    {"max_crops: 64", "max_crops: 513", "perception.max_crops", "must be in [0, 512], got 513"},
    {"apply_flip: false", "apply_flip: no", "perception.apply_flip",
     "expected true or false, got 'no'"},
    {"crop_mirror_average: false", "crop_mirror_average: 1", "perception.crop_mirror_average",
     "expected true or false, got '1'"},
    {"crop_mirror_refine: false", "crop_mirror_refine: yes please", "perception.crop_mirror_refine",
     "expected true or false, got 'yes please'"},
    {"crop_large_vehicle_ends: false", "crop_large_vehicle_ends: 2",
     "perception.crop_large_vehicle_ends", "expected true or false, got '2'"},
    {"crop_turn_type_weight: 0.65", "crop_turn_type_weight: 1.2",
     "perception.crop_turn_type_weight", "must be in [0, 1], got 1.2"},
    {"crop_min_vehicle_probability: 0.25", "crop_min_vehicle_probability: 1.5",
     "perception.crop_min_vehicle_probability", "must be in [0, 1], got 1.5"},
    {"crop_frame_edge_keep_box: false", "crop_frame_edge_keep_box: maybe",
     "perception.crop_frame_edge_keep_box", "expected true or false, got 'maybe'"},
    {"crop_frame_edge_own_verifier: false", "crop_frame_edge_own_verifier: inside",
     "perception.crop_frame_edge_own_verifier", "expected true or false, got 'inside'"},
    {"crop_frame_edge_min_vehicle_probability: 0.15",
     "crop_frame_edge_min_vehicle_probability: -0.2",
     "perception.crop_frame_edge_min_vehicle_probability", "must be in [0, 1], got -0.2"},
    {"apply_refine: false", "apply_refine: []", "perception.apply_refine",
     "expected true or false, got a sequence of 0 element(s)"},
    {"crop_refine_size: false", "crop_refine_size: 0.5", "perception.crop_refine_size",
     "expected true or false, got '0.5'"},
    {"fixed_gsd_m: 0.03", "fixed_gsd_m: -0.1", "perception.fixed_gsd_m",
     "must be in [0, 1], got -0.1"},
    {"nominal_car_length_m: 4.4", "nominal_car_length_m: 0", "perception.nominal_car_length_m",
     "must be in (0, 30], got 0"},
    {"lift_height_share: 0.4", "lift_height_share: 1.5", "perception.lift_height_share",
     "must be in [0, 1], got 1.5"},
    // pose
    {"pose:\n  max_age_s", "pose: 1\nx:\n  max_age_s", "pose", "expected a map, got '1'"},
    {"max_age_s: 0.3", "max_age_s: 0", "pose.max_age_s", "must be in (0, 10], got 0"},
    {"buffer_capacity: 128", "buffer_capacity: 1", "pose.buffer_capacity",
     "must be in [2, 100000], got 1"},
    {"  limits:\n    min_height_m", "  limits: 3\n  x:\n    min_height_m", "pose.limits",
     "expected a map, got '3'"},
    {"min_height_m: -400.0", "min_height_m: -2000", "pose.limits.min_height_m",
     "must be in [-1000, 100000], got -2000"},
    {"max_height_m: 5000.0", "max_height_m: -450", "pose.limits.max_height_m",
     "must be greater than min_height_m (-400), got -450"},
    {"quaternion_norm_tolerance: 0.02", "quaternion_norm_tolerance: 0",
     "pose.limits.quaternion_norm_tolerance", "must be in (0, 0.5], got 0"},
    {"max_tilt_deg: 70.0", "max_tilt_deg: 200", "pose.limits.max_tilt_deg",
     "must be in (0, 180], got 200"},
    {"min_gimbal_roll_deg: -45.0", "min_gimbal_roll_deg: -400", "pose.limits.min_gimbal_roll_deg",
     "must be in [-360, 360], got -400"},
    {"max_gimbal_roll_deg: 45.0", "max_gimbal_roll_deg: -50", "pose.limits.max_gimbal_roll_deg",
     "must be greater than min_gimbal_roll_deg (-45), got -50"},
    {"min_gimbal_pitch_deg: -100.0", "min_gimbal_pitch_deg: x", "pose.limits.min_gimbal_pitch_deg",
     "expected a number, got 'x'"},
    {"max_gimbal_pitch_deg: 10.0", "max_gimbal_pitch_deg: -100", "pose.limits.max_gimbal_pitch_deg",
     "must be greater than min_gimbal_pitch_deg (-100)"},
    {"min_gimbal_yaw_deg: -180.0", "min_gimbal_yaw_deg: 361", "pose.limits.min_gimbal_yaw_deg",
     "must be in [-360, 360], got 361"},
    {"max_gimbal_yaw_deg: 180.0", "max_gimbal_yaw_deg: -180", "pose.limits.max_gimbal_yaw_deg",
     "must be greater than min_gimbal_yaw_deg (-180), got -180"},
    {"max_horizontal_speed_mps: 40.0", "max_horizontal_speed_mps: 0",
     "pose.limits.max_horizontal_speed_mps", "must be in (0, 1000], got 0"},
    {"max_vertical_speed_mps: 20.0", "max_vertical_speed_mps: 2000",
     "pose.limits.max_vertical_speed_mps", "must be in (0, 1000], got 2000"},
    {"max_angular_rate_degps: 360.0", "max_angular_rate_degps: -1",
     "pose.limits.max_angular_rate_degps", "must be in (0, 100000], got -1"},
    {"jump_tolerance_m: 5.0", "jump_tolerance_m: -1", "pose.limits.jump_tolerance_m",
     "must be in [0, 10000], got -1"},
    {"jump_tolerance_deg: 4.0", "jump_tolerance_deg: 400", "pose.limits.jump_tolerance_deg",
     "must be in [0, 360], got 400"},
    {"consistency_window_s: 2.0", "consistency_window_s: 61", "pose.limits.consistency_window_s",
     "must be in [0, 60], got 61"},
    // tracking
    {"tracking:\n  max_tracks", "tracking: [1]\nx:\n  max_tracks", "tracking",
     "expected a map, got a sequence of 1 element(s)"},
    {"max_tracks: 300", "max_tracks: 1025", "tracking.max_tracks",
     "must be in [1, 1024], got 1025"},
    {"confirm_hits: 4", "confirm_hits: 0", "tracking.confirm_hits", "must be in [1, 100], got 0"},
    {"max_tentative_gap_s: 0.3", "max_tentative_gap_s: -1", "tracking.max_tentative_gap_s",
     "must be in [0, 60], got -1"},
    {"max_lost_s: 2.5", "max_lost_s: 61", "tracking.max_lost_s", "must be in [0, 60], got 61"},
    {"max_lost_at_edge_s: 0.7", "max_lost_at_edge_s: -1", "tracking.max_lost_at_edge_s",
     "must be in [0, 60], got -1"},
    {"coast_s: 0.4", "coast_s: -0.1", "tracking.coast_s", "must be in [0, 60], got -0.1"},
    {"moving_speed_mps: 1.2", "moving_speed_mps: x", "tracking.moving_speed_mps",
     "expected a number, got 'x'"},
    {"flip_votes: 5", "flip_votes: 0", "tracking.flip_votes", "must be in [1, 100], got 0"},
    {"type_evidence_weight: 0.4", "type_evidence_weight: 0", "tracking.type_evidence_weight",
     "must be in (0, 1], got 0"},
    {"shape_max_weight: 20.0", "shape_max_weight: 0", "tracking.shape_max_weight",
     "must be in (0, 1000000], got 0"},
    {"max_distance_m: 5.0", "max_distance_m: 0", "tracking.max_distance_m",
     "must be in (0, 100], got 0"},
    {"high_score: 0.6", "high_score: 1.5", "tracking.high_score", "must be in [0, 1], got 1.5"},
    {"low_score: 0.15", "low_score: 0.7", "tracking.low_score", "must be in [0, 0.6], got 0.7"},
    {"measurement_position_m: 0.3", "measurement_position_m: 0", "tracking.measurement_position_m",
     "must be in (0, 10], got 0"},
    {"measurement_heading_deg: 5.0", "measurement_heading_deg: 95",
     "tracking.measurement_heading_deg", "must be in (0, 90], got 95"},
    {"steering_decay_s: 2.0", "steering_decay_s: -1", "tracking.steering_decay_s",
     "must be in [0, 60], got -1"},
    {"confirm_whole_hits: 1", "confirm_whole_hits: -1", "tracking.confirm_whole_hits",
     "must be in [0, 100], got -1"},
    {"confirm_hits_anyway: 7", "confirm_hits_anyway: 0", "tracking.confirm_hits_anyway",
     "must be in [1, 100], got 0"},
    {"confirm_hits_standing: 4", "confirm_hits_standing: 101", "tracking.confirm_hits_standing",
     "must be in [1, 100], got 101"},
    {"confirm_hits_large: 8", "confirm_hits_large: 0", "tracking.confirm_hits_large",
     "must be in [1, 100], got 0"},
    {"confirm_min_score: 0.55", "confirm_min_score: 1.5", "tracking.confirm_min_score",
     "must be in [0, 1], got 1.5"},
    {"partial_inside_share: 0.8", "partial_inside_share: 1.2", "tracking.partial_inside_share",
     "must be in [0, 1], got 1.2"},
    {"partial_along_noise_factor: 5", "partial_along_noise_factor: 0.5",
     "tracking.partial_along_noise_factor", "must be in [1, 1000], got 0.5"},
    {"long_vehicle_length_m: 7.5", "long_vehicle_length_m: -2", "tracking.long_vehicle_length_m",
     "must be in [0, 100], got -2"},
    {"max_overlap: 0.4", "max_overlap: 1.2", "tracking.max_overlap", "must be in [0, 1], got 1.2"},
    // source
    {"source:\n  kind", "source: camera\nx:\n  kind", "source", "expected a map, got 'camera'"},
    {"kind: v4l2", "kind: file", "source.kind",
     "unknown value 'file' (expected replay, v4l2, video)"},
    {"altitude: rel", "altitude: msl", "source.video.altitude",
     "unknown value 'msl' (expected abs, rel)"},
    {"geoid_separation_m: -31.75", "geoid_separation_m: 300", "source.video.geoid_separation_m",
     "must be in [-200, 200], got 300"},
    {"yaw_min_speed_mps: 2.5", "yaw_min_speed_mps: 0", "source.video.yaw_min_speed_mps",
     "must be in (0, 100], got 0"},
    {"sequence_dir: seq/run1", "sequence_dir: ''", "source.sequence_dir", "must not be empty"},
    {"paced: false", "paced: fast", "source.paced", "expected true or false, got 'fast'"},
    {"loop: true", "loop: 2", "source.loop", "expected true or false, got '2'"},
    {"  v4l2:\n", "  v4l2: cam\n  x:\n", "source.v4l2", "expected a map, got 'cam'"},
    {"device: /dev/video2", "device: ''", "source.v4l2.device", "must not be empty"},
    {"bus_info: usb-0000:00:14.0-2", "bus_info: [a]", "source.v4l2.bus_info",
     "expected a string, got a sequence of 1 element(s)"},
    {"width_px: 1920", "width_px: 15", "source.v4l2.width_px", "must be in [16, 16384], got 15"},
    {"height_px: 1080", "height_px: x", "source.v4l2.height_px", "expected an integer, got 'x'"},
    {"formats: [nv12, yuyv]", "formats: []", "source.v4l2.formats",
     "expected a non-empty sequence of yuyv, nv12, mjpeg, got a sequence of 0 element(s)"},
    {"formats: [nv12, yuyv]", "formats: [nv12, rgb]", "source.v4l2.formats[1]",
     "unknown value 'rgb' (expected yuyv, nv12, mjpeg)"},
    {"buffers: 6", "buffers: 1", "source.v4l2.buffers", "must be in [2, 16], got 1"},
    {"dequeue_timeout_ms: 500", "dequeue_timeout_ms: 0", "source.v4l2.dequeue_timeout_ms",
     "must be in [1, 60000], got 0"},
    // telemetry
    {"telemetry:\n  source: mavlink_udp", "telemetry: udp\nx:\n  source: mavlink_udp", "telemetry",
     "expected a map, got 'udp'"},
    {"source: mavlink_udp", "source: mavlink", "telemetry.source",
     "unknown value 'mavlink' (expected recording, mavlink_udp, mavlink_serial, dds, none)"},
    {"udp_bind_address: 127.0.0.1", "udp_bind_address: ''", "telemetry.udp_bind_address",
     "must not be empty"},
    {"udp_port: 14551", "udp_port: 70000", "telemetry.udp_port",
     "must be in [0, 65535], got 70000"},
    {"serial_device: /dev/ttyUSB0", "serial_device: [a]", "telemetry.serial_device",
     "expected a string, got a sequence of 1 element(s)"},
    {"serial_baud: 57600", "serial_baud: 12345", "telemetry.serial_baud",
     "unknown value '12345' (expected 9600, 19200"},
    {"system_id: 1", "system_id: 256", "telemetry.system_id", "must be in [0, 255], got 256"},
    {"geoid_separation_m: -33.5", "geoid_separation_m: 300", "telemetry.geoid_separation_m",
     "must be in [-200, 200], got 300"},
    {"link_latency_s: 0.002", "link_latency_s: 2", "telemetry.link_latency_s",
     "must be in [0, 1], got 2"},
    {"replay_lookahead_s: 0.3", "replay_lookahead_s: -1", "telemetry.replay_lookahead_s",
     "must be in [0, 10], got -1"},
    // georef
    {"georef:\n  gcp_file", "georef: 1\nx:\n  gcp_file", "georef", "expected a map, got '1'"},
    {"gcp_file: none", "gcp_file: ''", "georef.gcp_file", "must not be empty"},
    {"max_residual_m: 2.5", "max_residual_m: 0", "georef.max_residual_m",
     "must be in (0, 100], got 0"},
    // site
    {"site:\n  file", "site: 1\nx:\n  file", "site", "expected a map, got '1'"},
    {"file: maps/site.geojson", "file: ''", "site.file", "must not be empty"},
    {"off_road: flag", "off_road: ignore", "site.off_road",
     "unknown value 'ignore' (expected drop, flag, keep)"},
    // traffic
    {"traffic:\n  period_s", "traffic: 1\nx:\n  period_s", "traffic", "expected a map, got '1'"},
    {"traffic:\n  period_s", "traffic:\n  enabled: maybe\n  period_s", "traffic.enabled",
     "expected true or false"},
    {"period_s: 30.0", "period_s: 0.5", "traffic.period_s", "must be in [1, 86400], got 0.5"},
    {"stop_speed_mps: 0.5", "stop_speed_mps: 11", "traffic.stop_speed_mps",
     "must be in [0, 10], got 11"},
    {"lane_heading_tolerance_deg: 30.0", "lane_heading_tolerance_deg: 0",
     "traffic.lane_heading_tolerance_deg", "must be in (0, 90], got 0"},
    {"wrong_way_angle_deg: 150.0", "wrong_way_angle_deg: 180", "traffic.wrong_way_angle_deg",
     "must be in [90, 179], got 180"},
    {"wrong_way_speed_mps: 3.0", "wrong_way_speed_mps: -1", "traffic.wrong_way_speed_mps",
     "must be in [0, 50], got -1"},
    {"wrong_way_s: 2.0", "wrong_way_s: 61", "traffic.wrong_way_s", "must be in [0, 60], got 61"},
    {"box_junction_stop_s: 4.0", "box_junction_stop_s: 601", "traffic.box_junction_stop_s",
     "must be in [0, 600], got 601"},
    {"max_tracks: 512", "max_tracks: 0", "traffic.max_tracks", "must be in [1, 65536], got 0"},
    {"max_events_per_step: 128", "max_events_per_step: 70000", "traffic.max_events_per_step",
     "must be in [1, 65536], got 70000"},
    {"max_lane_samples: 300", "max_lane_samples: 1.5", "traffic.max_lane_samples",
     "expected an integer"},
    {"off_road: flag", "off_road: flag\n  max_structure_height_m: 0.2",
     "site.max_structure_height_m", "must be in [0.5, 50], got 0.2"},
    {"off_road: flag", "off_road: flag\n  on_structure: ignore", "site.on_structure",
     "unknown value 'ignore' (expected drop, flag, keep)"},
    // app
    {"app:\n  queue_depth", "app: 1\nx:\n  queue_depth", "app", "expected a map, got '1'"},
    {"queue_depth: 2", "queue_depth: 9", "app.queue_depth", "must be in [1, 8], got 9"},
    {"pipeline: on\n  frame_pool_size: 6", "pipeline: off\n  frame_pool_size: 3",
     "app.frame_pool_size", "must be 0 (automatic) or >= queue_depth + 2 = 4, got 3"},
    {"frame_pool_size: 6", "frame_pool_size: 4", "app.frame_pool_size",
     "must be 0 (automatic) or >= queue_depth + 3 (pipeline on) = 5, got 4"},
    {"pipeline: on", "pipeline: both", "app.pipeline", "unknown value 'both' (expected off, on)"},
    {"frame_pool_size: 6", "frame_pool_size: 65", "app.frame_pool_size",
     "must be in [0, 64], got 65"},
    {"lock_memory: true", "lock_memory: yes", "app.lock_memory",
     "expected true or false, got 'yes'"},
    {"realtime_priority: 50", "realtime_priority: 100", "app.realtime_priority",
     "must be in [0, 99], got 100"},
    {"capture_cpus: [0]", "capture_cpus: 0", "app.capture_cpus",
     "expected a sequence of integers, got '0'"},
    {"processing_cpus: [1, 2]", "processing_cpus: {a: 1}", "app.processing_cpus",
     "expected a sequence of integers, got a map"},
    {"processing_cpus: [1, 2]", "processing_cpus: [1, -1]", "app.processing_cpus[1]",
     "must be in [0, 1023], got -1"},
    {"stats_period_s: 10.0", "stats_period_s: 0", "app.stats_period_s",
     "must be in [0.1, 3600], got 0"},
    {"trajectory_csv: out/tracks.csv", "trajectory_csv: ''", "app.trajectory_csv",
     "must not be empty"},
    {"detections_csv: out/detections.csv", "detections_csv: [a]", "app.detections_csv",
     "expected a string, got a sequence of 1 element(s)"},
    {"traffic_dir: out/traffic", "traffic_dir: ''", "app.traffic_dir", "must not be empty"},
    {"annotated_video: out/annotated.avi", "annotated_video: {a: b}", "app.annotated_video",
     "expected a string, got a map"},
    {"annotated_video_fps: 5.0", "annotated_video_fps: 0", "app.annotated_video_fps",
     "must be in (0, 1000], got 0"},
    {"  record:\n", "  record: rec\n  x:\n", "app.record", "expected a map, got 'rec'"},
    {"dir: out/flight1", "dir: ''", "app.record.dir", "must not be empty"},
    {"jpeg_quality: 80", "jpeg_quality: 101", "app.record.jpeg_quality",
     "must be in [1, 100], got 101"},
    {"every_nth_frame: 2", "every_nth_frame: 0", "app.record.every_nth_frame",
     "must be in [1, 1000], got 0"},
    {"queue_frames: 6", "queue_frames: 65", "app.record.queue_frames",
     "must be in [1, 64], got 65"},
    {"max_disk_mib: 4096", "max_disk_mib: -1", "app.record.max_disk_mib",
     "must be in [0, 2147483647], got -1"},
    {"min_free_disk_mib: 512", "min_free_disk_mib: 1.5", "app.record.min_free_disk_mib",
     "expected an integer, got '1.5'"},
    {"on_full: ring", "on_full: wrap", "app.record.on_full",
     "unknown value 'wrap' (expected stop, ring)"},
};

TEST(ConfigMalformed, EachBrokenKeyIsReportedWithSourceAndFullPath) {
  for (const MalformedCase& row : kMalformedCases) {
    SCOPED_TRACE(std::string(row.path) + " <- '" + row.to + "'");
    const std::string message = errorOf(edited(row.from, row.to));
    const std::string prefix = std::string(kSource) + ": " + row.path + ": ";
    EXPECT_EQ(message.rfind(prefix, 0), 0U) << message;
    EXPECT_NE(message.find(row.problem, prefix.size()), std::string::npos) << message;
  }
}

TEST(ConfigMalformed, TableCoversEveryKeyOfTheSchema) {
  const std::vector<std::string> schemaKeys = {"origin",
                                               "origin.latitude_deg",
                                               "origin.longitude_deg",
                                               "origin.height_m",
                                               "camera",
                                               "camera.width_px",
                                               "camera.height_px",
                                               "camera.fx_px",
                                               "camera.fy_px",
                                               "camera.cx_px",
                                               "camera.cy_px",
                                               "camera.lens_model",
                                               "camera.distortion",
                                               "camera.distortion.k1",
                                               "camera.distortion.k2",
                                               "camera.distortion.p1",
                                               "camera.distortion.p2",
                                               "camera.distortion.k3",
                                               "mount",
                                               "mount.roll_deg",
                                               "mount.pitch_deg",
                                               "mount.yaw_deg",
                                               "mount.lever_arm_m",
                                               "mount.gimbal",
                                               "mount.gimbal.reference",
                                               "mount.gimbal.roll_deg",
                                               "mount.gimbal.pitch_deg",
                                               "mount.gimbal.yaw_deg",
                                               "terrain",
                                               "terrain.dtm_path",
                                               "terrain.crs",
                                               "dds",
                                               "dds.enabled",
                                               "dds.domain_id",
                                               "dds.partition",
                                               "dds.drone_id",
                                               "dds.topic_prefix",
                                               "dds.status_rate_hz",
                                               "dds.occupancy_rate_hz",
                                               "dds.qos",
                                               "dds.occupancy_grid",
                                               "dds.occupancy_grid.origin_east_m",
                                               "dds.occupancy_grid.origin_north_m",
                                               "dds.occupancy_grid.resolution_m",
                                               "dds.occupancy_grid.rows",
                                               "dds.occupancy_grid.cols",
                                               "dds.security",
                                               "dds.security.enabled",
                                               "dds.security.plugin_dir",
                                               "dds.security.identity_ca",
                                               "dds.security.identity_certificate",
                                               "dds.security.private_key",
                                               "dds.security.permissions_ca",
                                               "dds.security.governance",
                                               "dds.security.permissions",
                                               "dds.telemetry",
                                               "dds.telemetry.source",
                                               "dds.telemetry.domain_id",
                                               "dds.telemetry.ardupilot_geopose_topic",
                                               "dds.telemetry.px4_attitude_topic",
                                               "dds.telemetry.px4_global_position_topic",
                                               "dds.telemetry.ardupilot_altitude_offset_m",
                                               "dds.telemetry.history_depth",
                                               "perception",
                                               "perception.detector_model",
                                               "perception.crop_model",
                                               "perception.asm",
                                               "perception.backend",
                                               "perception.threads",
                                               "perception.crop_threads",
                                               "perception.plan_memory",
                                               "perception.undistort",
                                               "perception.white_balance",
                                               "perception.white_balance_regions",
                                               "perception.white_balance_sample_stride_px",
                                               "perception.white_balance_white_share",
                                               "perception.white_balance_max_gain",
                                               "perception.working_scale",
                                               "perception.tile_overlap_px",
                                               "perception.score_threshold",
                                               "perception.top_k_per_tile",
                                               "perception.nms_iou",
                                               "perception.duplicate_overlap",
                                               "perception.cut_edge_margin_px",
                                               "perception.max_crops",
                                               "perception.apply_flip",
                                               "perception.apply_refine",
                                               "perception.crop_refine_size",
                                               "perception.crop_mirror_average",
                                               "perception.crop_mirror_refine",
                                               "perception.crop_large_vehicle_ends",
                                               "perception.crop_turn_type_weight",
                                               "perception.crop_min_vehicle_probability",
                                               "perception.crop_frame_edge_keep_box",
                                               "perception.crop_frame_edge_min_vehicle_probability",
                                               "perception.crop_frame_edge_own_verifier",
                                               "perception.fixed_gsd_m",
                                               "perception.nominal_car_length_m",
                                               "perception.lift_height_share",
                                               "pose",
                                               "pose.max_age_s",
                                               "pose.buffer_capacity",
                                               "pose.limits",
                                               "pose.limits.min_height_m",
                                               "pose.limits.max_height_m",
                                               "pose.limits.quaternion_norm_tolerance",
                                               "pose.limits.max_tilt_deg",
                                               "pose.limits.min_gimbal_roll_deg",
                                               "pose.limits.max_gimbal_roll_deg",
                                               "pose.limits.min_gimbal_pitch_deg",
                                               "pose.limits.max_gimbal_pitch_deg",
                                               "pose.limits.min_gimbal_yaw_deg",
                                               "pose.limits.max_gimbal_yaw_deg",
                                               "pose.limits.max_horizontal_speed_mps",
                                               "pose.limits.max_vertical_speed_mps",
                                               "pose.limits.max_angular_rate_degps",
                                               "pose.limits.jump_tolerance_m",
                                               "pose.limits.jump_tolerance_deg",
                                               "pose.limits.consistency_window_s",
                                               "tracking",
                                               "tracking.max_tracks",
                                               "tracking.confirm_hits",
                                               "tracking.max_tentative_gap_s",
                                               "tracking.max_lost_s",
                                               "tracking.max_lost_at_edge_s",
                                               "tracking.coast_s",
                                               "tracking.moving_speed_mps",
                                               "tracking.flip_votes",
                                               "tracking.type_evidence_weight",
                                               "tracking.shape_max_weight",
                                               "tracking.max_distance_m",
                                               "tracking.high_score",
                                               "tracking.low_score",
                                               "tracking.measurement_position_m",
                                               "tracking.measurement_heading_deg",
                                               "tracking.steering_decay_s",
                                               "tracking.confirm_whole_hits",
                                               "tracking.confirm_hits_anyway",
                                               "tracking.confirm_hits_standing",
                                               "tracking.confirm_hits_large",
                                               "tracking.confirm_min_score",
                                               "tracking.partial_inside_share",
                                               "tracking.partial_along_noise_factor",
                                               "source",
                                               "source.kind",
                                               "source.sequence_dir",
                                               "source.paced",
                                               "source.loop",
                                               "source.v4l2",
                                               "source.v4l2.device",
                                               "source.v4l2.bus_info",
                                               "source.v4l2.width_px",
                                               "source.v4l2.height_px",
                                               "source.v4l2.formats",
                                               "source.v4l2.buffers",
                                               "source.v4l2.dequeue_timeout_ms",
                                               "telemetry",
                                               "telemetry.source",
                                               "telemetry.udp_bind_address",
                                               "telemetry.udp_port",
                                               "telemetry.serial_device",
                                               "telemetry.serial_baud",
                                               "telemetry.system_id",
                                               "telemetry.geoid_separation_m",
                                               "telemetry.link_latency_s",
                                               "telemetry.replay_lookahead_s",
                                               "georef",
                                               "georef.gcp_file",
                                               "georef.max_residual_m",
                                               "site",
                                               "site.file",
                                               "site.off_road",
                                               "traffic",
                                               "traffic.enabled",
                                               "traffic.period_s",
                                               "traffic.stop_speed_mps",
                                               "traffic.lane_heading_tolerance_deg",
                                               "traffic.wrong_way_angle_deg",
                                               "traffic.wrong_way_speed_mps",
                                               "traffic.wrong_way_s",
                                               "traffic.box_junction_stop_s",
                                               "traffic.max_tracks",
                                               "traffic.max_events_per_step",
                                               "traffic.max_lane_samples",
                                               "app",
                                               "app.queue_depth",
                                               "app.frame_pool_size",
                                               "app.lock_memory",
                                               "app.realtime_priority",
                                               "app.capture_cpus",
                                               "app.processing_cpus",
                                               "app.stats_period_s",
                                               "app.trajectory_csv",
                                               "app.detections_csv",
                                               "app.traffic_dir",
                                               "app.annotated_video",
                                               "app.annotated_video_fps",
                                               "app.record",
                                               "app.record.dir",
                                               "app.record.jpeg_quality",
                                               "app.record.every_nth_frame",
                                               "app.record.queue_frames",
                                               "app.record.max_disk_mib",
                                               "app.record.min_free_disk_mib",
                                               "app.record.on_full"};
  // Every key of the three QoS profiles.
  std::vector<std::string> keys = schemaKeys;
  for (const char* topic :
       {"vehicle_state", "drone_status", "occupancy", "traffic_statistics", "traffic_events"}) {
    const std::string profile = std::string("dds.qos.") + topic;
    keys.push_back(profile);
    for (const char* key : {"reliability", "max_blocking_s", "durability", "history_depth",
                            "deadline_s", "lifespan_s", "liveliness_lease_s"}) {
      keys.push_back(profile + "." + key);
    }
  }
  for (const std::string& key : keys) {
    bool covered = false;
    for (const MalformedCase& row : kMalformedCases) {
      covered = covered || key == row.path;
    }
    EXPECT_TRUE(covered) << key;
  }
}

TEST(ConfigMalformed, MessagesReadAsDocumented) {
  EXPECT_EQ(errorOf(edited("fx_px: 2900.0", "fx_px: -3")),
            "site.yaml: camera.fx_px: must be > 0, got -3");
  EXPECT_EQ(errorOf(edited("  width_px: 2592\n", "")),
            "site.yaml: camera.width_px: missing (required)");
  EXPECT_EQ(errorOf(edited("lens_model: brown_conrady", "lens_model: fisheye")),
            "site.yaml: camera.lens_model: unknown value 'fisheye' (expected pinhole, "
            "brown_conrady, equivalent_spherical)");
  EXPECT_EQ(errorOf(edited("latitude_deg: 43.0731", "latitude_deg: abc")),
            "site.yaml: origin.latitude_deg: expected a number, got 'abc'");
  EXPECT_EQ(errorOf(edited("history_depth: 2", "history_depth: 0")),
            "site.yaml: dds.qos.vehicle_state.history_depth: must be in [1, 1000], got 0");
}

TEST(ConfigWarnings, UnknownKeysAtEveryLevelAreNamedButNotFatal) {
  std::string text = edited("  fx_px: 2900.0\n", "  fx_px: 2900.0\n  fxx: 1\n");
  text.replace(text.find("origin:\n"), 8, "origin:\n  datum: wgs84\n");
  text.replace(text.find("    k3: -0.01\n"), 14, "    k3: -0.01\n    k4: 0.0\n");
  text.replace(text.find("  gimbal:\n"), 10, "  gimbal:\n    mode: follow\n");
  text.replace(text.find("  crs: utm:16N\n"), 15, "  crs: utm:16N\n  geoid: egm96\n");
  text += "logging:\n  level: debug\n";
  const AppConfig config = parse(text);
  const std::vector<std::string> expected = {
      "site.yaml: unknown key 'origin.datum'",
      "site.yaml: unknown key 'camera.distortion.k4'",  // a section reports when it is read
      "site.yaml: unknown key 'camera.fxx'",
      "site.yaml: unknown key 'mount.gimbal.mode'",
      "site.yaml: unknown key 'terrain.geoid'",
      "site.yaml: unknown key 'logging'",  // a whole unknown section is one warning
  };
  EXPECT_EQ(config.warnings, expected);
  EXPECT_DOUBLE_EQ(config.camera.intrinsics.fx_px, 2900.0);
}

TEST(ConfigWarnings, DistortionWithAnotherLensModelIsIgnoredWithAWarning) {
  const AppConfig config = parse(edited("lens_model: brown_conrady", "lens_model: pinhole"));
  ASSERT_EQ(config.warnings.size(), 1U);
  EXPECT_EQ(config.warnings[0],
            "site.yaml: camera.distortion: ignored: only lens_model brown_conrady uses it");
  EXPECT_EQ(config.camera.distortion.model, camera::LensModel::Pinhole);
  EXPECT_EQ(config.camera.distortion.k1, 0.0);
  EXPECT_EQ(config.camera.distortion.k3, 0.0);
}

// A value inside its range can still be surely wrong for the rig it configures (an error) or
// merely unusual (a warning naming the key, the configuration is still used).
TEST(ConfigWarnings, WorkingScaleTooSmallForTheFrameIsAnErrorAndUnusualOnesAreWarned) {
  EXPECT_EQ(errorOf(edited("working_scale: 0.5", "working_scale: 0.001")),
            "site.yaml: perception.working_scale: 0.001 makes the 2592 x 2048 frame 3 x 2 working "
            "px; the shorter side must be at least 16 px");
  const AppConfig small = parse(edited("working_scale: 0.5", "working_scale: 0.05"));
  ASSERT_EQ(small.warnings.size(), 1U);
  EXPECT_EQ(small.warnings[0],
            "site.yaml: perception.working_scale: unusual: 0.05 makes the frame 130 x 102 working "
            "px (below 0.1; vehicles shrink to a few pixels, check the value)");
  EXPECT_DOUBLE_EQ(small.perception.preprocess.workingScale, 0.05);
  EXPECT_TRUE(parse(edited("working_scale: 0.5", "working_scale: 0.1")).warnings.empty());
}

TEST(ConfigWarnings, LensCoefficientsThatFoldTheImageAreAnErrorAndStrongOnesAreWarned) {
  // k1 = 99 (a unit or copy mistake): points at the image corner move outwards 33-fold.
  const AppConfig strong = parse(edited("k1: -0.12", "k1: 99"));
  ASSERT_EQ(strong.warnings.size(), 1U);
  EXPECT_EQ(strong.warnings[0].rfind("site.yaml: camera.distortion: unusual: k1, k2, k3 move image "
                                     "points radially by 3",
                                     0),
            0U)
      << strong.warnings[0];
  EXPECT_NE(strong.warnings[0].find("check the coefficients' units and order"), std::string::npos);
  // Strongly negative: the radial model turns back inside the image, two rays share a pixel.
  const std::string folded = errorOf(edited("k1: -0.12", "k1: -5"));
  EXPECT_EQ(folded.rfind("site.yaml: camera.distortion: k1, k2, k3 fold the image over at "
                         "normalised radius ",
                         0),
            0U)
      << folded;
  // Tangential coefficients of a real lens are tiny.
  const AppConfig decentred = parse(edited("p1: 0.0001", "p1: 0.2"));
  ASSERT_EQ(decentred.warnings.size(), 1U);
  EXPECT_EQ(decentred.warnings[0],
            "site.yaml: camera.distortion.p1: unusual: 0.2 (real lenses: |p| below 0.05)");
  // A real wide-angle calibration passes silently.
  EXPECT_TRUE(parse(edited("k1: -0.12", "k1: -0.3")).warnings.empty());
}

TEST(ConfigSyntax, YamlErrorNamesTheSourceAndLine) {
  const std::string message = errorOf("origin:\n  latitude_deg: [43.0\ncamera: {\n");
  EXPECT_EQ(message.rfind("site.yaml: YAML syntax error at line 3, column ", 0), 0U) << message;
  const std::string badIndent = errorOf("origin:\n  latitude_deg: 1\n longitude_deg: 2\n");
  EXPECT_EQ(badIndent.rfind("site.yaml: YAML syntax error at line 3, column ", 0), 0U) << badIndent;
}

TEST(ConfigSyntax, EmptyOrNonMapDocumentIsAClearError) {
  EXPECT_EQ(errorOf(""),
            "site.yaml: the configuration is empty (expected the sections origin, camera, "
            "terrain)");
  EXPECT_EQ(errorOf("# only a comment\n"), errorOf(""));
  EXPECT_EQ(errorOf("- origin\n- camera\n"),
            "site.yaml: expected a map of sections at the top level, got a sequence of 2 "
            "element(s)");
}

TEST(ConfigPaths, RelativeDtmPathIsResolvedAgainstTheBaseDirectory) {
  EXPECT_EQ(parse(kFullConfig).terrain.dtmPath, "/data/site/dtm/site.tif");
  EXPECT_FALSE(parse(edited("crs: utm:16N", "crs: Auto")).terrain.crs.has_value());
  const std::string up = edited("dtm_path: dtm/site.tif", "dtm_path: ../shared/./dtm.tif");
  EXPECT_EQ(parse(up).terrain.dtmPath, "/data/shared/dtm.tif");
  const std::string absolute = edited("dtm_path: dtm/site.tif", "dtm_path: /maps/dtm.tif");
  EXPECT_EQ(parse(absolute).terrain.dtmPath, "/maps/dtm.tif");
}

TEST(ConfigFile, LoadResolvesAgainstTheFilesDirectoryAndReportsMissingFiles) {
  const fs::path dir = fs::temp_directory_path() / "vp_config_test" / "site";
  fs::create_directories(dir);
  const fs::path file = dir / "site.yaml";
  std::ofstream(file) << kFullConfig;
  const AppConfig config = loadConfig(file.string());
  EXPECT_EQ(config.terrain.dtmPath,
            (fs::absolute(dir) / "dtm/site.tif").lexically_normal().string());
  EXPECT_EQ(config.sourcePath, file.string());

  const std::string missing = (dir / "absent.yaml").string();
  try {
    loadConfig(missing);
    ADD_FAILURE() << "no error for a missing file";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()), missing + ": cannot open configuration file");
  }
  // Errors from a file carry the path it was loaded from.
  std::ofstream(file) << "origin: 1\n";
  try {
    loadConfig(file.string());
    ADD_FAILURE() << "no error for a malformed file";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()), file.string() + ": origin: expected a map, got '1'");
  }
  fs::remove_all(dir.parent_path());
}

TEST(ConfigDds, AbsentSectionGivesTheDocumentedDefaults) {
  const DdsConfig dds = parse(kMinimalConfig).dds;
  EXPECT_TRUE(dds.enabled);
  EXPECT_EQ(dds.domainId, 0U);
  EXPECT_EQ(dds.partition, "vp");
  EXPECT_EQ(dds.droneId, 1U);
  EXPECT_EQ(dds.topicPrefix, "vp");
  EXPECT_DOUBLE_EQ(dds.statusRate_hz, 1.0);
  EXPECT_DOUBLE_EQ(dds.occupancyRate_hz, 2.0);
  EXPECT_EQ(dds.vehicleState.reliability, Reliability::Reliable);
  EXPECT_EQ(dds.vehicleState.durability, Durability::TransientLocal);
  EXPECT_EQ(dds.vehicleState.historyDepth, 1);
  EXPECT_DOUBLE_EQ(dds.vehicleState.maxBlocking_s, 0.01);
  EXPECT_DOUBLE_EQ(dds.vehicleState.deadline_s, 0.3);
  EXPECT_DOUBLE_EQ(dds.vehicleState.lifespan_s, 0.5);
  EXPECT_DOUBLE_EQ(dds.vehicleState.livelinessLease_s, 2.0);
  EXPECT_EQ(dds.droneStatus.reliability, Reliability::Reliable);
  EXPECT_EQ(dds.droneStatus.durability, Durability::TransientLocal);
  EXPECT_DOUBLE_EQ(dds.droneStatus.deadline_s, 3.0);
  EXPECT_DOUBLE_EQ(dds.droneStatus.lifespan_s, 0.0);
  EXPECT_DOUBLE_EQ(dds.droneStatus.livelinessLease_s, 5.0);
  EXPECT_EQ(dds.occupancy.reliability, Reliability::BestEffort);
  EXPECT_DOUBLE_EQ(dds.occupancy.deadline_s, 0.0);
  EXPECT_DOUBLE_EQ(dds.occupancy.lifespan_s, 1.0);
  EXPECT_EQ(dds.trafficStatistics.reliability, Reliability::Reliable);
  EXPECT_EQ(dds.trafficStatistics.durability, Durability::TransientLocal);
  EXPECT_EQ(dds.trafficStatistics.historyDepth, 4);
  EXPECT_EQ(dds.trafficEvents.reliability, Reliability::Reliable);
  EXPECT_EQ(dds.trafficEvents.durability, Durability::Volatile);
  EXPECT_EQ(dds.trafficEvents.historyDepth, 256);
  EXPECT_DOUBLE_EQ(dds.grid.originEast_m, -50.0);
  EXPECT_DOUBLE_EQ(dds.grid.originNorth_m, -50.0);
  EXPECT_DOUBLE_EQ(dds.grid.resolution_m, 0.5);
  EXPECT_EQ(dds.grid.rows, 200U);
  EXPECT_EQ(dds.grid.cols, 200U);
  EXPECT_FALSE(dds.security.enabled);
  EXPECT_EQ(dds.security.pluginDir, defaultDdsPluginDir());
#if defined(__x86_64__)
  EXPECT_STREQ(defaultDdsPluginDir(), "/usr/lib/x86_64-linux-gnu/libddsc0debian");
#elif defined(__aarch64__)
  EXPECT_STREQ(defaultDdsPluginDir(), "/usr/lib/aarch64-linux-gnu/libddsc0debian");
#endif
  EXPECT_TRUE(dds.security.identityCa.empty());
  EXPECT_EQ(dds.telemetry.source, TelemetrySource::None);
  EXPECT_EQ(dds.telemetry.domainId, 0U);
  EXPECT_EQ(dds.telemetry.ardupilotGeoPoseTopic, "rt/ap/geopose/filtered");
  EXPECT_EQ(dds.telemetry.px4AttitudeTopic, "rt/fmu/out/vehicle_attitude");
  EXPECT_EQ(dds.telemetry.px4GlobalPositionTopic, "rt/fmu/out/vehicle_global_position");
  EXPECT_DOUBLE_EQ(dds.telemetry.ardupilotAltitudeOffset_m, 0.0);
  EXPECT_EQ(dds.telemetry.historyDepth, 8);
}

TEST(ConfigDds, FullSectionReadsEveryKey) {
  const AppConfig config = parse(kFullConfig);
  EXPECT_TRUE(config.warnings.empty());
  const DdsConfig& dds = config.dds;
  EXPECT_TRUE(dds.enabled);
  EXPECT_EQ(dds.domainId, 7U);
  EXPECT_EQ(dds.partition, "site_a");
  EXPECT_EQ(dds.droneId, 12U);
  EXPECT_EQ(dds.topicPrefix, "vpx");
  EXPECT_DOUBLE_EQ(dds.statusRate_hz, 2.0);
  EXPECT_DOUBLE_EQ(dds.occupancyRate_hz, 1.5);
  const QosProfile& vs = dds.vehicleState;
  EXPECT_EQ(vs.reliability, Reliability::Reliable);
  EXPECT_DOUBLE_EQ(vs.maxBlocking_s, 0.02);
  EXPECT_EQ(vs.durability, Durability::Volatile);
  EXPECT_EQ(vs.historyDepth, 2);
  EXPECT_DOUBLE_EQ(vs.deadline_s, 0.4);
  EXPECT_DOUBLE_EQ(vs.lifespan_s, 0.6);
  EXPECT_DOUBLE_EQ(vs.livelinessLease_s, 3.0);
  const QosProfile& st = dds.droneStatus;
  EXPECT_EQ(st.reliability, Reliability::BestEffort);
  EXPECT_DOUBLE_EQ(st.maxBlocking_s, 0.03);
  EXPECT_EQ(st.durability, Durability::TransientLocal);
  EXPECT_EQ(st.historyDepth, 3);
  EXPECT_DOUBLE_EQ(st.deadline_s, 4.0);
  EXPECT_DOUBLE_EQ(st.lifespan_s, 0.7);
  EXPECT_DOUBLE_EQ(st.livelinessLease_s, 6.0);
  const QosProfile& oc = dds.occupancy;
  EXPECT_EQ(oc.reliability, Reliability::BestEffort);
  EXPECT_DOUBLE_EQ(oc.maxBlocking_s, 0.04);
  EXPECT_EQ(oc.historyDepth, 4);
  EXPECT_DOUBLE_EQ(oc.lifespan_s, 2.0);
  const QosProfile& ts = dds.trafficStatistics;
  EXPECT_EQ(ts.reliability, Reliability::BestEffort);
  EXPECT_DOUBLE_EQ(ts.maxBlocking_s, 0.05);
  EXPECT_EQ(ts.durability, Durability::Volatile);
  EXPECT_EQ(ts.historyDepth, 7);
  EXPECT_DOUBLE_EQ(ts.deadline_s, 120.0);
  EXPECT_DOUBLE_EQ(ts.livelinessLease_s, 7.0);
  const QosProfile& te = dds.trafficEvents;
  EXPECT_DOUBLE_EQ(te.maxBlocking_s, 0.06);
  EXPECT_EQ(te.historyDepth, 64);
  EXPECT_DOUBLE_EQ(te.deadline_s, 2.0);
  EXPECT_DOUBLE_EQ(te.lifespan_s, 30.0);
  EXPECT_DOUBLE_EQ(te.livelinessLease_s, 8.0);
  EXPECT_DOUBLE_EQ(dds.grid.originEast_m, -40.0);
  EXPECT_DOUBLE_EQ(dds.grid.originNorth_m, -30.0);
  EXPECT_DOUBLE_EQ(dds.grid.resolution_m, 0.25);
  EXPECT_EQ(dds.grid.rows, 300U);
  EXPECT_EQ(dds.grid.cols, 400U);
  // Disabled security: the paths are resolved but not required to exist.
  EXPECT_FALSE(dds.security.enabled);
  EXPECT_EQ(dds.security.pluginDir, "/opt/dds/plugins");
  EXPECT_EQ(dds.security.identityCa, "/data/site/certs/ca.pem");
  EXPECT_EQ(dds.security.identityCertificate, "/data/site/certs/drone.pem");
  EXPECT_EQ(dds.security.privateKey, "/data/site/certs/drone_key.pem");
  EXPECT_EQ(dds.security.permissionsCa, "/data/site/certs/permissions_ca.pem");
  EXPECT_EQ(dds.security.governance, "/data/site/certs/governance.p7s");
  EXPECT_EQ(dds.security.permissions, "/data/site/certs/permissions.p7s");
  EXPECT_EQ(dds.telemetry.source, TelemetrySource::Px4);
  EXPECT_EQ(dds.telemetry.domainId, 3U);
  EXPECT_EQ(dds.telemetry.px4AttitudeTopic, "rt/px4_1/fmu/out/vehicle_attitude");
  EXPECT_EQ(dds.telemetry.px4GlobalPositionTopic, "rt/px4_1/fmu/out/vehicle_global_position");
  EXPECT_DOUBLE_EQ(dds.telemetry.ardupilotAltitudeOffset_m, -33.5);
  EXPECT_EQ(dds.telemetry.historyDepth, 5);
}

TEST(ConfigDds, EnabledSecurityNeedsEveryFileAndSaysWhichIsMissing) {
  const fs::path dir = fs::temp_directory_path() / ("vp_config_dds_" + std::to_string(getpid()));
  fs::create_directories(dir / "certs");
  for (const char* name : {"ca.pem", "drone.pem", "drone_key.pem", "permissions_ca.pem",
                           "governance.p7s", "permissions.p7s"}) {
    std::ofstream(dir / "certs" / name) << "test\n";
  }
  // A plugin folder with the file the check looks for.
  fs::create_directories(dir / "plugins");
  std::ofstream(dir / "plugins" / "libdds_security_auth.so") << "";
  std::string text = edited("enabled: false", "enabled: true");
  text.replace(text.find("/opt/dds/plugins"), 16, (dir / "plugins").string());
  const AppConfig config = parseConfig(text, kSource, dir.string());
  EXPECT_TRUE(config.dds.security.enabled);
  EXPECT_EQ(config.dds.security.governance, (dir / "certs/governance.p7s").string());

  fs::remove(dir / "certs" / "permissions.p7s");
  try {
    parseConfig(text, kSource, dir.string());
    ADD_FAILURE() << "no error for a missing permissions file";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()), "site.yaml: dds.security.permissions: file not found: " +
                                             (dir / "certs/permissions.p7s").string());
  }
  text.replace(text.find("    private_key: certs/drone_key.pem\n"), 37, "");
  try {
    parseConfig(text, kSource, dir.string());
    ADD_FAILURE() << "no error for an absent private_key";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()),
              "site.yaml: dds.security.private_key: missing (required when "
              "dds.security.enabled is true)");
  }
  fs::remove_all(dir);
}

TEST(ConfigDds, SectionAloneIgnoresTheOtherSections) {
  // A roadside unit's file: no origin, camera or terrain, and sections it does not know.
  const DdsSection alone = parseDdsSection(
      "dds:\n  domain_id: 12\n  partition: site_b\n  colour: blue\nlogging: {level: 1}\n",
      "rsu.yaml", "/cfg");
  EXPECT_EQ(alone.dds.domainId, 12U);
  EXPECT_EQ(alone.dds.partition, "site_b");
  EXPECT_EQ(alone.warnings, std::vector<std::string>{"rsu.yaml: unknown key 'dds.colour'"});
  EXPECT_EQ(parseDdsSection("", "rsu.yaml", "/cfg").dds.partition, "vp");
  // The whole application file reads the same as the section alone.
  EXPECT_EQ(parseDdsSection(kFullConfig, kSource, kBaseDir).dds.security.identityCa,
            parse(kFullConfig).dds.security.identityCa);
  try {
    parseDdsSection("dds:\n  qos:\n    occupancy:\n      history_depth: 0\n", "rsu.yaml", "/");
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()),
              "rsu.yaml: dds.qos.occupancy.history_depth: must be in [1, 1000], got 0");
  }
}

TEST(ConfigDds, Ros2NativeAndAutowareKeys) {
  const DdsSection read = parseDdsSection(
      "dds:\n  native: {enabled: false}\n"
      "  ros2: {enabled: false, namespace: /drone_7/vp, frame_id: site_enu}\n"
      "  autoware: {enabled: true, topic: /perception/objects, frame_id: world,\n"
      "             stationary_speed_mps: 0.2}\n",
      "site.yaml", "/cfg");
  EXPECT_TRUE(read.warnings.empty());
  EXPECT_FALSE(read.dds.native.enabled);
  EXPECT_FALSE(read.dds.ros2.enabled);
  EXPECT_EQ(read.dds.ros2.topicNamespace, "drone_7/vp");  // the leading '/' is dropped
  EXPECT_EQ(read.dds.ros2.frameId, "site_enu");
  EXPECT_TRUE(read.dds.autoware.enabled);
  EXPECT_EQ(read.dds.autoware.topic, "/perception/objects");
  EXPECT_EQ(read.dds.autoware.frameId, "world");
  EXPECT_DOUBLE_EQ(read.dds.autoware.stationarySpeed_mps, 0.2);
  EXPECT_EQ(
      parseDdsSection("dds:\n  ros2: {namespace: /}\n", "s.yaml", "/").dds.ros2.topicNamespace, "");
  const std::pair<const char*, const char*> bad[] = {
      {"dds:\n  ros2: {namespace: vp//a}\n",
       "site.yaml: dds.ros2.namespace: not a ROS namespace (letters, digits, _ in tokens joined "
       "by /): 'vp//a'"},
      {"dds:\n  ros2: {namespace: 7up}\n", "site.yaml: dds.ros2.namespace: not a ROS namespace"},
      {"dds:\n  ros2: {frame_id: ''}\n", "site.yaml: dds.ros2.frame_id: must not be empty"},
      {"dds:\n  autoware: {topic: perception/objects}\n",
       "site.yaml: dds.autoware.topic: not an absolute ROS topic name"},
      {"dds:\n  autoware: {topic: /a-b}\n",
       "site.yaml: dds.autoware.topic: not an absolute ROS topic name"},
      {"dds:\n  autoware: {stationary_speed_mps: -1}\n",
       "site.yaml: dds.autoware.stationary_speed_mps: must be in [0, 10], got -1"},
      {"dds:\n  native: {enabled: maybe}\n", "site.yaml: dds.native.enabled: expected true or"},
  };
  for (const auto& [yaml, message] : bad) {
    SCOPED_TRACE(yaml);
    try {
      parseDdsSection(yaml, "site.yaml", "/cfg");
      ADD_FAILURE() << "no error";
    } catch (const ConfigError& error) {
      EXPECT_EQ(std::string(error.what()).rfind(message, 0), 0U) << error.what();
    }
  }
}

TEST(ConfigLoop, FullSectionsReadEveryKey) {
  const AppConfig config = parse(kFullConfig);
  EXPECT_TRUE(config.warnings.empty());
  const preprocess::PreprocessOptions& pre = config.perception.preprocess;
  const detection::DetectionStageOptions& det = config.perception.detection;
  EXPECT_EQ(det.detectorModelPath, "/data/site/models/det.onnx");
  EXPECT_EQ(det.cropModelPath, "/data/site/models/crop.onnx");
  EXPECT_EQ(config.asmPath, "/data/site/models/asm.yaml");
  EXPECT_EQ(det.engine.backend, inference::Backend::XnnpackFp32);
  EXPECT_EQ(det.engine.threads, 2);
  EXPECT_EQ(pre.threads, 2);
  EXPECT_EQ(det.cropEngineThreads, 3);
  EXPECT_FALSE(det.engine.planMemory);
  EXPECT_FALSE(pre.undistort);
  EXPECT_TRUE(pre.whiteBalance);
  EXPECT_EQ(pre.whiteBalanceOptions.regionRows, 2);
  EXPECT_EQ(pre.whiteBalanceOptions.regionCols, 5);
  EXPECT_EQ(pre.whiteBalanceOptions.sampleStride_px, 8);
  EXPECT_DOUBLE_EQ(pre.whiteBalanceOptions.whitePointShare, 0.2);
  EXPECT_DOUBLE_EQ(pre.whiteBalanceOptions.maxGain, 3.0);
  EXPECT_FALSE(pre.exposure.enabled);
  EXPECT_DOUBLE_EQ(pre.exposure.darkMeanLuma, 30.0);
  EXPECT_DOUBLE_EQ(pre.exposure.targetMeanLuma, 90.0);
  EXPECT_DOUBLE_EQ(pre.exposure.maxGain, 6.0);
  EXPECT_EQ(pre.exposure.sampleStride_px, 4);
  EXPECT_DOUBLE_EQ(pre.workingScale, 0.5);
  EXPECT_EQ(pre.tileOverlap_px, 64);
  EXPECT_FLOAT_EQ(det.decoder.scoreThreshold, 0.35F);
  EXPECT_EQ(det.decoder.topKPerTile, 100);
  EXPECT_DOUBLE_EQ(det.decoder.nmsIou, 0.45);
  EXPECT_DOUBLE_EQ(det.decoder.duplicateOverlap, 0.6);
  EXPECT_DOUBLE_EQ(det.decoder.cutEdgeMargin_px, 5.0);
  EXPECT_EQ(det.maxCrops, 64);
  EXPECT_FALSE(det.secondStage.applyFlip);
  EXPECT_FALSE(det.secondStage.applyRefine);
  EXPECT_FALSE(det.secondStage.refineSize);
  EXPECT_FALSE(det.secondStage.mirrorAverage);
  EXPECT_FALSE(det.secondStage.mirrorRefine);
  EXPECT_FALSE(det.secondStage.largeVehicleEnds);
  EXPECT_FLOAT_EQ(det.secondStage.turnTypeWeight, 0.65F);
  EXPECT_FLOAT_EQ(det.secondStage.minVehicleProbability, 0.25F);
  EXPECT_FALSE(det.secondStage.frameEdgeKeepBox);
  EXPECT_FLOAT_EQ(det.secondStage.frameEdgeMinVehicleProbability, 0.15F);
  EXPECT_FALSE(det.secondStage.frameEdgeOwnVerifier);
  EXPECT_DOUBLE_EQ(det.gsd.fixedGsd_m, 0.03);
  EXPECT_DOUBLE_EQ(det.gsd.nominalCarLength_m, 4.4);
  EXPECT_DOUBLE_EQ(config.perception.lift.boxHeightShare, 0.4);
  EXPECT_EQ(config.pose.maxAge_ns, 300'000'000);
  EXPECT_EQ(config.pose.capacity, 128U);
  const telemetry::PoseLimits& limits = config.pose.limits;
  EXPECT_DOUBLE_EQ(limits.minHeight_m, -400.0);
  EXPECT_DOUBLE_EQ(limits.maxHeight_m, 5000.0);
  EXPECT_DOUBLE_EQ(limits.quaternionNormTolerance, 0.02);
  EXPECT_DOUBLE_EQ(limits.maxTilt_deg, 70.0);
  EXPECT_DOUBLE_EQ(limits.minGimbalRoll_deg, -45.0);
  EXPECT_DOUBLE_EQ(limits.maxGimbalRoll_deg, 45.0);
  EXPECT_DOUBLE_EQ(limits.minGimbalPitch_deg, -100.0);
  EXPECT_DOUBLE_EQ(limits.maxGimbalPitch_deg, 10.0);
  EXPECT_DOUBLE_EQ(limits.minGimbalYaw_deg, -180.0);
  EXPECT_DOUBLE_EQ(limits.maxGimbalYaw_deg, 180.0);
  EXPECT_DOUBLE_EQ(limits.maxHorizontalSpeed_mps, 40.0);
  EXPECT_DOUBLE_EQ(limits.maxVerticalSpeed_mps, 20.0);
  EXPECT_DOUBLE_EQ(limits.maxAngularRate_degps, 360.0);
  EXPECT_DOUBLE_EQ(limits.jumpTolerance_m, 5.0);
  EXPECT_DOUBLE_EQ(limits.jumpTolerance_deg, 4.0);
  EXPECT_EQ(limits.consistencyWindow_ns, 2'000'000'000);
  const tracking::TrackerConfig& t = config.tracking;
  EXPECT_EQ(t.maxTracks, 300);
  EXPECT_EQ(t.confirmHits, 4);
  EXPECT_DOUBLE_EQ(t.maxTentativeGap_s, 0.3);
  EXPECT_DOUBLE_EQ(t.maxLost_s, 2.5);
  EXPECT_DOUBLE_EQ(t.maxLostAtFrameEdge_s, 0.7);
  EXPECT_DOUBLE_EQ(t.maxCoast_s, 0.4);
  EXPECT_DOUBLE_EQ(t.movingSpeed_mps, 1.2);
  EXPECT_EQ(t.flipVotes, 5);
  EXPECT_DOUBLE_EQ(t.typeEvidenceWeight, 0.4);
  EXPECT_DOUBLE_EQ(t.shapeMaxWeight, 20.0);
  EXPECT_DOUBLE_EQ(t.association.maxDistance_m, 5.0);
  EXPECT_FLOAT_EQ(t.association.highScore, 0.6F);
  EXPECT_FLOAT_EQ(t.association.lowScore, 0.15F);
  EXPECT_DOUBLE_EQ(t.noise.measurementPosition_m, 0.3);
  EXPECT_DOUBLE_EQ(t.noise.measurementHeading_rad, 5.0 * (geometry::kPi / 180.0));
  EXPECT_DOUBLE_EQ(t.noise.steeringDecay_s, 2.0);
  EXPECT_EQ(t.confirmWholeHits, 1);
  EXPECT_EQ(t.confirmHitsAnyway, 7);
  EXPECT_EQ(t.confirmHitsStanding, 4);
  EXPECT_EQ(t.confirmHitsLarge, 8);
  EXPECT_DOUBLE_EQ(t.confirmMinScore, 0.55);
  EXPECT_DOUBLE_EQ(t.partialInsideShare, 0.8);
  EXPECT_DOUBLE_EQ(t.partialAlongNoiseFactor, 5.0);
  EXPECT_DOUBLE_EQ(t.longVehicleLength_m, 7.5);
  EXPECT_DOUBLE_EQ(t.maxOverlap, 0.4);
  const SourceConfig& src = config.source;
  EXPECT_EQ(src.kind, FrameSourceKind::V4l2);
  EXPECT_EQ(src.sequenceDir, "/data/site/seq/run1");
  EXPECT_FALSE(src.paced);
  EXPECT_TRUE(src.loop);
  EXPECT_EQ(src.v4l2.device, "/dev/video2");
  EXPECT_EQ(src.v4l2.busInfo, "usb-0000:00:14.0-2");
  EXPECT_EQ(src.v4l2.width_px, 1920);
  EXPECT_EQ(src.v4l2.height_px, 1080);
  EXPECT_EQ(src.v4l2.formats,
            (std::vector<CameraPixelFormat>{CameraPixelFormat::Nv12, CameraPixelFormat::Yuyv}));
  EXPECT_EQ(src.v4l2.buffers, 6);
  EXPECT_EQ(src.v4l2.dequeueTimeout_ms, 500);
  EXPECT_TRUE(src.video.path.ends_with("/flights/DJI_0001.MP4")) << src.video.path;
  EXPECT_TRUE(src.video.srt.ends_with("/flights/DJI_0001.SRT")) << src.video.srt;
  EXPECT_TRUE(src.video.telemetryCsv.empty());
  EXPECT_EQ(src.video.subtitles.altitude, subtitle::AltitudeSource::Relative);
  EXPECT_DOUBLE_EQ(src.video.subtitles.geoidSeparation_m, -31.75);
  EXPECT_DOUBLE_EQ(src.video.subtitles.homeHeight_m, 251.25);
  EXPECT_DOUBLE_EQ(src.video.subtitles.yawMinSpeed_mps, 2.5);
  const TelemetryLinkConfig& link = config.telemetry;
  EXPECT_EQ(link.source, TelemetrySourceKind::MavlinkUdp);
  EXPECT_EQ(link.udpBindAddress, "127.0.0.1");
  EXPECT_EQ(link.udpPort, 14551);
  EXPECT_EQ(link.serialDevice, "/dev/ttyUSB0");
  EXPECT_EQ(link.serialBaud, 57600);
  EXPECT_EQ(link.systemId, 1);
  EXPECT_DOUBLE_EQ(link.geoidSeparation_m, -33.5);
  EXPECT_DOUBLE_EQ(link.linkLatency_s, 0.002);
  EXPECT_DOUBLE_EQ(link.replayLookahead_s, 0.3);
  const LoopConfig& app = config.app;
  EXPECT_EQ(app.queueDepth, 2);
  EXPECT_EQ(app.pipeline, PipelineMode::On);
  EXPECT_EQ(app.framePoolSize, 6);
  EXPECT_TRUE(app.lockMemory);
  EXPECT_EQ(app.realtimePriority, 50);
  EXPECT_EQ(app.captureCpus, std::vector<int>{0});
  EXPECT_EQ(app.processingCpus, (std::vector<int>{1, 2}));
  EXPECT_DOUBLE_EQ(app.statsPeriod_s, 10.0);
  EXPECT_EQ(app.trajectoryCsv, "/data/site/out/tracks.csv");
  EXPECT_EQ(app.detectionsCsv, "/data/site/out/detections.csv");
  EXPECT_EQ(app.trafficDir, "/data/site/out/traffic");
  EXPECT_EQ(app.annotatedVideo, "/data/site/out/annotated.avi");
  EXPECT_DOUBLE_EQ(app.annotatedVideoFps, 5.0);
  EXPECT_EQ(app.record.dir, "/data/site/out/flight1");
  EXPECT_EQ(app.record.jpegQuality, 80);
  EXPECT_EQ(app.record.everyNthFrame, 2);
  EXPECT_EQ(app.record.queueFrames, 6);
  EXPECT_EQ(app.record.maxDisk_mib, 4096);
  EXPECT_EQ(app.record.minFreeDisk_mib, 512);
  EXPECT_EQ(app.record.onFull, RecordFullPolicy::Ring);
}

TEST(ConfigLoop, AbsentSectionsGiveTheDocumentedDefaults) {
  const AppConfig config = parse(kMinimalConfig);
  const preprocess::PreprocessOptions& pre = config.perception.preprocess;
  const detection::DetectionStageOptions& det = config.perception.detection;
  // Model paths default to the repository's models/, beside the configuration's folder.
  EXPECT_EQ(det.detectorModelPath, "/data/models/detector/detector_int8.onnx");
  EXPECT_EQ(det.cropModelPath, "/data/models/detector/crop_int8.onnx");
  EXPECT_EQ(config.asmPath, "/data/models/asm/default_asm.yaml");
  EXPECT_EQ(det.engine.backend, inference::Backend::Auto);
  EXPECT_EQ(det.engine.threads, 1);
  EXPECT_FALSE(pre.undistort);
  EXPECT_FALSE(pre.whiteBalance);
  EXPECT_DOUBLE_EQ(pre.workingScale, 0.25);
  EXPECT_EQ(pre.tileOverlap_px, 96);
  EXPECT_FLOAT_EQ(det.decoder.scoreThreshold, 0.4F);
  EXPECT_EQ(det.maxCrops, 512);
  EXPECT_EQ(config.pose.maxAge_ns, 200'000'000);
  EXPECT_EQ(config.pose.capacity, 256U);
  EXPECT_EQ(config.tracking.maxTracks, 256);
  EXPECT_EQ(config.tracking.confirmHits, 3);
  EXPECT_EQ(config.source.kind, FrameSourceKind::Replay);
  EXPECT_TRUE(config.source.sequenceDir.empty());
  EXPECT_TRUE(config.source.paced);
  EXPECT_FALSE(config.source.loop);
  EXPECT_EQ(config.source.v4l2.device, "/dev/video0");
  EXPECT_EQ(config.source.v4l2.formats.size(), 3U);
  EXPECT_EQ(config.telemetry.source, TelemetrySourceKind::Recording);
  EXPECT_EQ(config.telemetry.udpPort, 14550);
  EXPECT_EQ(config.telemetry.serialBaud, 921600);
  EXPECT_EQ(config.app.queueDepth, 1);
  EXPECT_EQ(config.app.framePoolSize, 0);
  EXPECT_FALSE(config.app.lockMemory);
  EXPECT_EQ(config.app.realtimePriority, 0);
  EXPECT_TRUE(config.app.captureCpus.empty());
  EXPECT_DOUBLE_EQ(config.app.statsPeriod_s, 5.0);
  EXPECT_TRUE(config.app.trajectoryCsv.empty());
  EXPECT_TRUE(config.app.detectionsCsv.empty());
  EXPECT_TRUE(config.app.trafficDir.empty());
  EXPECT_TRUE(config.app.annotatedVideo.empty());
}

TEST(ConfigLoop, NoneSwitchesAnOptionalFileOffAndDdsTelemetryNeedsAFlightStack) {
  const AppConfig config = parse(edited("crop_model: models/crop.onnx", "crop_model: none"));
  EXPECT_TRUE(config.perception.detection.cropModelPath.empty());
  EXPECT_TRUE(parse(edited("trajectory_csv: out/tracks.csv", "trajectory_csv: none"))
                  .app.trajectoryCsv.empty());
  // kFullConfig reads PX4 telemetry over DDS: dds is a valid pose source there.
  EXPECT_EQ(parse(edited("source: mavlink_udp", "source: dds")).telemetry.source,
            TelemetrySourceKind::Dds);
  std::string text = edited("source: mavlink_udp", "source: dds");
  text.replace(text.find("source: px4"), 11, "source: none");
  EXPECT_EQ(errorOf(text),
            "site.yaml: telemetry.source: dds needs dds.telemetry.source ardupilot or px4 (it is "
            "none)");
}

TEST(ConfigLoop, TheSiteFileIsRelativeToTheConfigurationAndOffRoadIsRead) {
  const AppConfig full = parse(kFullConfig);
  EXPECT_EQ(full.site.file, "/data/site/maps/site.geojson");
  EXPECT_EQ(full.site.offRoad, site::OffRoadPolicy::Flag);
  const AppConfig none = parse(edited("file: maps/site.geojson", "file: none"));
  EXPECT_TRUE(none.site.file.empty());
  EXPECT_EQ(parse(edited("off_road: flag", "off_road: keep")).site.offRoad,
            site::OffRoadPolicy::Keep);
}

TEST(ConfigLoop, TheTrafficSectionFillsTheAnalyzersOptions) {
  const AppConfig full = parse(kFullConfig);
  EXPECT_TRUE(full.traffic.enabled);  // absent: the default
  EXPECT_FALSE(parse(edited("traffic:\n  period_s", "traffic:\n  enabled: false\n  period_s"))
                   .traffic.enabled);
  EXPECT_EQ(full.traffic.period_s, 30.0);
  EXPECT_EQ(full.traffic.stopSpeed_mps, 0.5);
  EXPECT_EQ(full.traffic.laneHeadingTolerance_deg, 30.0);
  EXPECT_EQ(full.traffic.wrongWayAngle_deg, 150.0);
  EXPECT_EQ(full.traffic.wrongWaySpeed_mps, 3.0);
  EXPECT_EQ(full.traffic.wrongWay_s, 2.0);
  EXPECT_EQ(full.traffic.boxJunctionStop_s, 4.0);
  EXPECT_EQ(full.traffic.maxTracks, 512U);
  EXPECT_EQ(full.traffic.maxEventsPerStep, 128U);
  EXPECT_EQ(full.traffic.maxLaneSamples, 300U);
  // What the file sets, the analyzer accepts.
  site::Site site("s");
  site::Feature zone;
  zone.kind = site::FeatureKind::Zone;
  zone.id = "z";
  const std::vector<Eigen::Vector2d> ring = {{0, 0}, {1, 0}, {1, 1}};
  site.append(zone, ring);
  traffic::TrafficAnalyzer analyzer;
  std::string why;
  EXPECT_TRUE(analyzer.init(site, full.traffic, &why)) << why;
}

TEST(ConfigLoop, TheSurfaceModelIsOptionalBesideTheDtmAndItsPriorIsRead) {
  const AppConfig full = parse(kFullConfig);
  EXPECT_TRUE(full.terrain.dsmPath.empty());
  EXPECT_EQ(full.site.maxStructureHeight_m, 2.5);
  EXPECT_EQ(full.site.onStructure, site::OffRoadPolicy::Drop);
  const AppConfig with = parse(edited("  dtm_path: dtm/site.tif\n",
                                      "  dtm_path: dtm/site.tif\n  dsm_path: dtm/surface.tif\n"));
  EXPECT_EQ(with.terrain.dsmPath, "/data/site/dtm/surface.tif");
  const AppConfig options = parse(edited(
      "off_road: flag", "off_road: flag\n  max_structure_height_m: 4\n  on_structure: flag"));
  EXPECT_EQ(options.site.maxStructureHeight_m, 4.0);
  EXPECT_EQ(options.site.onStructure, site::OffRoadPolicy::Flag);
}

TEST(ConfigLoop, GroundControlPointsNeedTelemetryOffAndResolveTheirPath) {
  const AppConfig full = parse(kFullConfig);
  EXPECT_TRUE(full.georef.gcpFile.empty());  // `none`
  EXPECT_EQ(full.georef.maxResidual_m, 2.5);
  std::string text = edited("gcp_file: none", "gcp_file: survey/gcp.csv");
  EXPECT_EQ(errorOf(text),
            "site.yaml: georef.gcp_file: ground control points place a fixed view without "
            "telemetry: set telemetry.source: none (it is mavlink_udp)");
  text.replace(text.find("source: mavlink_udp"), 19, "source: none");
  const AppConfig config = parse(text);
  EXPECT_EQ(config.georef.gcpFile, "/data/site/survey/gcp.csv");
  EXPECT_EQ(config.telemetry.source, TelemetrySourceKind::None);
}

// The rig reader (rig_config/rig_config.hpp): the rig sections exactly as parseConfig() reads
// them, the loop's sections left to the application's reader.
RigConfig parseRig(const std::string& text) {
  return parseRigConfig(text, kSource, kBaseDir);
}

std::string rigErrorOf(const std::string& text) {
  try {
    parseRig(text);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

bool isRigPath(const std::string& path) {
  for (const char* section : {"origin", "camera", "mount", "terrain"}) {
    const std::string name = section;
    if (path == name || path.rfind(name + ".", 0) == 0) {
      return true;
    }
  }
  return false;
}

TEST(RigConfig, ReadsTheRigSectionsAsTheWholeConfiguration) {
  const AppConfig app = parse(kFullConfig);
  const RigConfig rig = parseRig(kFullConfig);
  EXPECT_TRUE(rig.warnings.empty());
  EXPECT_EQ(rig.sourcePath, app.sourcePath);
  EXPECT_EQ(rig.origin.latitude_deg, app.origin.latitude_deg);
  EXPECT_EQ(rig.origin.height_m, app.origin.height_m);
  EXPECT_EQ(rig.camera.intrinsics.fx_px, app.camera.intrinsics.fx_px);
  EXPECT_EQ(rig.camera.intrinsics.cy_px, app.camera.intrinsics.cy_px);
  EXPECT_EQ(rig.camera.distortion.model, app.camera.distortion.model);
  EXPECT_EQ(rig.camera.distortion.k3, app.camera.distortion.k3);
  EXPECT_EQ(rig.mount.mount.leverArm_m, app.mount.mount.leverArm_m);
  EXPECT_EQ(rig.mount.gimbal.reference, app.mount.gimbal.reference);
  EXPECT_EQ(rig.mount.gimbal.angles.pitch_deg, app.mount.gimbal.angles.pitch_deg);
  EXPECT_EQ(rig.terrain.dtmPath, app.terrain.dtmPath);
  EXPECT_EQ(rig.terrain.crs.has_value(), app.terrain.crs.has_value());
}

TEST(RigConfig, RigProblemsGiveTheSameMessagesAsTheWholeConfiguration) {
  int rigCases = 0;
  for (const MalformedCase& row : kMalformedCases) {
    if (!isRigPath(row.path)) {
      continue;
    }
    SCOPED_TRACE(std::string(row.path) + " <- '" + row.to + "'");
    const std::string text = edited(row.from, row.to);
    EXPECT_EQ(rigErrorOf(text), errorOf(text));
    ++rigCases;
  }
  EXPECT_GT(rigCases, 20);
  EXPECT_EQ(rigErrorOf(""), errorOf(""));
  EXPECT_EQ(rigErrorOf("- origin\n- camera\n"), errorOf("- origin\n- camera\n"));
  EXPECT_EQ(rigErrorOf("origin:\n  latitude_deg: [43.0\ncamera: {\n"),
            errorOf("origin:\n  latitude_deg: [43.0\ncamera: {\n"));
}

TEST(RigConfig, LeavesTheLoopSectionsToTheApplicationAndWarnsOtherUnknownKeys) {
  std::string text = edited("  fx_px: 2900.0\n", "  fx_px: 2900.0\n  fxx: 1\n");
  text += "logging:\n  level: debug\n";
  const std::vector<std::string> expected = {"site.yaml: unknown key 'camera.fxx'",
                                             "site.yaml: unknown key 'logging'"};
  EXPECT_EQ(parseRig(text).warnings, expected);
  // Neither read nor checked here: a loop section is the application's.
  const std::string full = kFullConfig;
  const std::string loopAsides =
      full.substr(0, full.find("\ndds:\n") + 1) + "perception: 3\ntracking: {bad: 1}\napp:\n";
  EXPECT_TRUE(parseRig(loopAsides).warnings.empty());
  EXPECT_NE(errorOf(loopAsides), "");
}

// What a recorder writes as its sequence's rig.yaml reads back to the running rig exactly
// (shortest round-trip numbers), with the DTM named as the recorder copies it.
TEST(RigConfig, FormattedRigReadsBackToTheSameValues) {
  RigConfig rig = parseRig(kFullConfig);
  rig.origin.latitude_deg = 43.073100000000004;  // not short in decimal: written exactly
  rig.mount.mount.leverArm_m = {0.1, -0.025, 1.0 / 3.0};
  rig.mount.gimbal.angles.yaw_deg = -12.5;
  rig.terrain.load.maxSamples = 1000;
  const std::string text = formatRigYaml(rig, "dtm.tif", "recorded by a test");
  EXPECT_EQ(text.rfind("# recorded by a test\norigin:\n", 0), 0U) << text;
  const RigConfig back = parseRigConfig(text, "rig.yaml", "/seq");
  EXPECT_TRUE(back.warnings.empty());
  EXPECT_EQ(back.origin.latitude_deg, rig.origin.latitude_deg);
  EXPECT_EQ(back.origin.longitude_deg, rig.origin.longitude_deg);
  EXPECT_EQ(back.origin.height_m, rig.origin.height_m);
  const camera::Intrinsics& k = back.camera.intrinsics;
  EXPECT_EQ(k.width_px, rig.camera.intrinsics.width_px);
  EXPECT_EQ(k.height_px, rig.camera.intrinsics.height_px);
  EXPECT_EQ(k.fx_px, rig.camera.intrinsics.fx_px);
  EXPECT_EQ(k.fy_px, rig.camera.intrinsics.fy_px);
  EXPECT_EQ(k.cx_px, rig.camera.intrinsics.cx_px);
  EXPECT_EQ(k.cy_px, rig.camera.intrinsics.cy_px);
  const camera::Distortion& d = back.camera.distortion;
  EXPECT_EQ(d.model, rig.camera.distortion.model);
  EXPECT_EQ(d.k1, rig.camera.distortion.k1);
  EXPECT_EQ(d.k2, rig.camera.distortion.k2);
  EXPECT_EQ(d.p1, rig.camera.distortion.p1);
  EXPECT_EQ(d.p2, rig.camera.distortion.p2);
  EXPECT_EQ(d.k3, rig.camera.distortion.k3);
  EXPECT_EQ(back.mount.mount.bodyToBase.roll_deg, rig.mount.mount.bodyToBase.roll_deg);
  EXPECT_EQ(back.mount.mount.bodyToBase.pitch_deg, rig.mount.mount.bodyToBase.pitch_deg);
  EXPECT_EQ(back.mount.mount.bodyToBase.yaw_deg, rig.mount.mount.bodyToBase.yaw_deg);
  EXPECT_EQ(back.mount.mount.leverArm_m, rig.mount.mount.leverArm_m);
  EXPECT_EQ(back.mount.gimbal.reference, rig.mount.gimbal.reference);
  EXPECT_EQ(back.mount.gimbal.angles.roll_deg, rig.mount.gimbal.angles.roll_deg);
  EXPECT_EQ(back.mount.gimbal.angles.pitch_deg, rig.mount.gimbal.angles.pitch_deg);
  EXPECT_EQ(back.mount.gimbal.angles.yaw_deg, rig.mount.gimbal.angles.yaw_deg);
  EXPECT_EQ(back.terrain.dtmPath, "/seq/dtm.tif");
  ASSERT_EQ(back.terrain.crs.has_value(), rig.terrain.crs.has_value());
  if (rig.terrain.crs) {
    EXPECT_EQ(terrain::toString(*back.terrain.crs), terrain::toString(*rig.terrain.crs));
  }
  EXPECT_EQ(back.terrain.load.maxSamples, 1000U);
  // A pinhole camera has no distortion block; crs auto stays auto.
  rig.camera.distortion = camera::Distortion{};
  rig.terrain.crs.reset();
  const std::string pinhole = formatRigYaml(rig, "dtm.tif");
  EXPECT_EQ(pinhole.find("distortion"), std::string::npos) << pinhole;
  const RigConfig backPinhole = parseRigConfig(pinhole, "rig.yaml", "/seq");
  EXPECT_EQ(backPinhole.camera.distortion.model, camera::LensModel::Pinhole);
  EXPECT_FALSE(backPinhole.terrain.crs.has_value());
}

TEST(RigConfig, LoadReportsMissingFilesAsTheWholeConfiguration) {
  const std::string missing = "/nonexistent/vp_rig_config_test.yaml";
  std::string rigMessage;
  std::string appMessage;
  try {
    loadRigConfig(missing);
  } catch (const ConfigError& error) {
    rigMessage = error.what();
  }
  try {
    loadConfig(missing);
  } catch (const ConfigError& error) {
    appMessage = error.what();
  }
  EXPECT_EQ(rigMessage, missing + ": cannot open configuration file");
  EXPECT_EQ(rigMessage, appMessage);
}

}  // namespace
}  // namespace vp::config

namespace vp::config {
namespace {

// A model without its checksum file loads unverified (inference/model_checksum.hpp): the
// configuration says so once, as a start-up warning naming the key and the file.
TEST(ConfigPerception, ModelWithoutChecksumFileIsAWarning) {
  const fs::path dir = fs::temp_directory_path() / ("vp_config_sha_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "det.onnx") << "model bytes";
  std::ofstream(dir / "crop.onnx") << "model bytes";
  std::ofstream(dir / "crop.onnx.sha256") << "digest";
  const std::string text = std::string(kMinimalConfig) +
                           "perception:\n  detector_model: det.onnx\n  crop_model: crop.onnx\n";
  const AppConfig config = parseConfig(text, kSource, dir.string());
  ASSERT_EQ(config.warnings.size(), 1U);
  EXPECT_EQ(config.warnings[0],
            "site.yaml: perception.detector_model: " + (dir / "det.onnx").string() +
                " has no checksum file det.onnx.sha256: its integrity is not "
                "verified (scripts/model_checksums.sh)");
  std::ofstream(dir / "det.onnx.sha256") << "digest";
  EXPECT_TRUE(parseConfig(text, kSource, dir.string()).warnings.empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vp::config
