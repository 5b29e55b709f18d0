#include "simulator.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>
#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include "ground_truth.hpp"
#include "io/dtm_file.hpp"
#include "site_map.hpp"
#include "surface_model.hpp"

#ifndef VP_SOURCE_DIR
#define VP_SOURCE_DIR "."
#endif

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFrameIntervalS = 0.1;
constexpr std::int64_t kStart_ns = 1'700'000'000'000'000'000;
constexpr std::int64_t kFrame_ns = 100'000'000;

std::string num(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

double wrap_deg(double a) {
  a = std::fmod(a + 180.0, 360.0);
  if (a < 0) {
    a += 360.0;
  }
  return a - 180.0;
}

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

Eigen::Quaterniond quaternionFromEuler(double roll_deg, double pitch_deg, double yaw_deg) {
  return Eigen::Quaterniond(geodesy::rotationFromEuler({roll_deg, pitch_deg, yaw_deg}));
}

}  // namespace

Simulator::Simulator() = default;
Simulator::~Simulator() = default;

void Simulator::drawRig() {
  Rng& rng = *rng_;
  RigSpec& r = rig_;
  const double scale = options_.width / 2592.0;
  for (int attempt = 0; attempt < 50; ++attempt) {
    camera::Intrinsics k;
    k.width_px = options_.width;
    k.height_px = options_.height;
    k.fx_px = 2900.0 * scale * rng.uniform(0.95, 1.05);
    k.fy_px = k.fx_px * (1.0 + rng.normal(0.0, 0.0005));
    k.cx_px = 0.5 * (k.width_px - 1) + rng.normal(0.0, 0.005 * k.width_px);
    k.cy_px = 0.5 * (k.height_px - 1) + rng.normal(0.0, 0.005 * k.height_px);
    camera::Distortion d;
    if (rng.chance(0.2)) {
      d.model = camera::LensModel::EquivalentSpherical;
    } else {
      d.model = camera::LensModel::BrownConrady;
      d.k1 = rng.uniform(-0.16, 0.04);
      d.k2 = rng.uniform(-0.04, 0.1);
      d.p1 = rng.normal(0.0, 3e-4);
      d.p2 = rng.normal(0.0, 3e-4);
      d.k3 = rng.uniform(-0.02, 0.02);
    }
    camera::CameraModel candidate;
    Canvas canvas;
    if (candidate.init(k, d) && makeCanvas(candidate, options_.supersampling, &canvas, nullptr)) {
      r.intrinsics = k;
      r.distortion = d;
      camera_ = candidate;
      canvas_ = canvas;
      break;
    }
  }
  r.mount.bodyToBase = {0.0, 0.0, 0.0};
  r.mount.leverArm_m = Eigen::Vector3d(rng.uniform(-0.1, 0.15), 0.0, rng.uniform(0.05, 0.25));
  r.gimbalReference =
      rng.chance(0.65) ? geodesy::GimbalReference::Earth : geodesy::GimbalReference::Body;
  r.altitude_m = rng.chance(0.7) ? rng.uniform(75.0, 115.0) : rng.uniform(60.0, 150.0);
  r.tilt_deg = rng.chance(0.6) ? rng.uniform(0.0, 8.0) : rng.uniform(8.0, 35.0);
  r.viewAzimuth_deg = rng.uniform(-180.0, 180.0);
  r.bodyYawOffset_deg = rng.uniform(-180.0, 180.0);
  r.positionSigma_m = rng.uniform(0.05, 0.4);
  r.positionTauS = rng.uniform(3.0, 10.0);
  if (r.gimbalReference == geodesy::GimbalReference::Earth) {
    r.attitudeSigma_deg = rng.uniform(0.5, 2.5);
    r.gimbalSigma_deg = rng.uniform(0.01, 0.08);
  } else {
    r.attitudeSigma_deg = rng.uniform(0.03, 0.3);
    r.gimbalSigma_deg = 0.0;
  }
  r.attitudeTauS = rng.uniform(1.0, 4.0);
  if (options_.altitude_m) {
    r.altitude_m = *options_.altitude_m;
  }
  if (options_.tilt_deg) {
    r.tilt_deg = *options_.tilt_deg;
  }
}

lifting::DronePose Simulator::hoverPose() {
  Rng& rng = *rng_;
  const RigSpec& r = rig_;
  const double aPos = std::exp(-kFrameIntervalS / r.positionTauS);
  const double aAtt = std::exp(-kFrameIntervalS / r.attitudeTauS);
  const double bPos = std::sqrt(1.0 - aPos * aPos);
  const double bAtt = std::sqrt(1.0 - aAtt * aAtt);
  const bool first = frameIndex_ == 0;
  for (int i = 0; i < 3; ++i) {
    const double zPos = rng.normal();
    const double zAtt = rng.normal();
    const double zGim = rng.normal();
    const double sPos = r.positionSigma_m * (i == 2 ? 0.5 : 1.0);
    const double sAtt = r.attitudeSigma_deg * (i == 2 ? 0.5 : 1.0);
    // The first frame starts from the stationary distribution.
    positionOffset_[i] = first ? sPos * zPos : aPos * positionOffset_[i] + bPos * sPos * zPos;
    attitudeOffset_[i] = first ? sAtt * zAtt : aAtt * attitudeOffset_[i] + bAtt * sAtt * zAtt;
    gimbalOffset_[i] = first ? r.gimbalSigma_deg * zGim
                             : aAtt * gimbalOffset_[i] + bAtt * r.gimbalSigma_deg * zGim;
  }
  if (options_.staticHover) {
    positionOffset_.setZero();
    attitudeOffset_.setZero();
    gimbalOffset_.setZero();
  }
  const double az = r.viewAzimuth_deg * kPi / 180.0;
  const double tilt = r.tilt_deg * kPi / 180.0;
  const Eigen::Vector3d horizontal(std::sin(az), std::cos(az), 0.0);
  const Eigen::Vector3d centre = target_ + Eigen::Vector3d(0, 0, r.altitude_m) -
                                 horizontal * (r.altitude_m * std::tan(tilt)) + positionOffset_;
  lifting::DronePose pose;
  const bool earth = r.gimbalReference == geodesy::GimbalReference::Earth;
  const double bodyYaw =
      wrap_deg(r.viewAzimuth_deg + (earth ? r.bodyYawOffset_deg : 0.0) + attitudeOffset_.z());
  pose.bodyToNed = quaternionFromEuler(attitudeOffset_.x(), attitudeOffset_.y(), bodyYaw);
  pose.gimbal.reference = r.gimbalReference;
  pose.gimbal.angles.roll_deg = gimbalOffset_.x();
  pose.gimbal.angles.pitch_deg = -90.0 + r.tilt_deg + gimbalOffset_.y();
  pose.gimbal.angles.yaw_deg = earth ? wrap_deg(r.viewAzimuth_deg + gimbalOffset_.z()) : 0.0;
  const Eigen::Vector3d lever =
      geodesy::enuFromNed() * (pose.bodyToNed.toRotationMatrix() * r.mount.leverArm_m);
  pose.position = world_.frame().toGeodetic(centre - lever);
  return pose;
}

bool Simulator::init(const SimOptions& options, std::string* why) {
  options_ = options;
  if (options.width < 16 || options.height < 16) {
    return fail(why, "image size must be at least 16 x 16");
  }
  rng_ = std::make_unique<Rng>(options.seed);
  Rng& rng = *rng_;
  origin_ = drawOrigin(rng);
  terrainSpec_ = drawTerrain(rng);
  scene_ = generateScene(options.scene, rng, options.islands);
  if (options.poles) {
    addPoles(scene_);
  }
  if (options.roadUsers) {
    addRoadUsers(scene_);
  }
  if (options.largeVehicleShare) {
    scene_.traffic.largeVehicleShare = *options.largeVehicleShare;
  }
  drawRig();
  if (canvas_.width == 0) {
    return fail(why, "could not draw a valid lens model");
  }
  sensorSpec_ = drawSensor(rng);

  // Ground region seen over the whole sequence (with margins for drift and for tall objects
  // beyond the field's edge), and the DTM around it.
  const double halfFov =
      std::atan(std::hypot(0.5 * canvas_.width, 0.5 * canvas_.height) / rig_.intrinsics.fx_px);
  const double reach =
      rig_.altitude_m * std::tan(std::min(rig_.tilt_deg * kPi / 180.0 + halfFov, 1.35)) + 45.0;
  const Eigen::Vector2d lo = scene_.viewCentre - Eigen::Vector2d(reach, reach);
  const Eigen::Vector2d hi = scene_.viewCentre + Eigen::Vector2d(reach, reach);
  const double pathHalf = reach + 30.0;
  if (!world_.build(origin_, terrainSpec_, scene_.viewCentre, pathHalf + 15.0, why)) {
    return false;
  }
  target_ = world_.ground(scene_.viewCentre.x(), scene_.viewCentre.y());
  if (!lifter_.init(camera_, rig_.mount, world_.terrain(), world_.frame(), why)) {
    return false;
  }
  const std::string asmPath = options.asmPath.empty()
                                  ? std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml"
                                  : options.asmPath;
  if (!asm_.load(asmPath, why)) {
    return false;
  }
  factory_ = std::make_unique<VehicleFactory>(asm_, options.twoToneShare, options.cityCarShare,
                                              options.pickupShare, options.busRoofShare);
  traffic_.init(scene_, *factory_, pathHalf, options.warmUpS, kFrameIntervalS, rng);
  sensor_.init(camera_, canvas_, sensorSpec_);
  renderer_.init(scene_, world_, lo, hi, rig_.altitude_m / rig_.intrinsics.fx_px,
                 canvas_.supersampling, options.threads);
  // Bilinear remap reads a canvas pixel's neighbours; lens curvature moves them < 2 px.
  renderer_.setCanvasMask(sensor_.neededCanvas(3));
  frameIndex_ = 0;
  return true;
}

bool Simulator::nextFrame(FrameOutput& out, std::string* why) {
  Rng& rng = *rng_;
  if (frameIndex_ > 0) {
    traffic_.step(rng);
  }
  out.frameId = frameIndex_;
  out.timestamp_ns = kStart_ns + frameIndex_ * kFrame_ns;
  out.truePose = hoverPose();
  const auto camPose = lifter_.cameraPose(out.truePose);
  if (!camPose) {
    return fail(why, std::string("camera pose: ") + lifting::toString(camPose.error()));
  }
  const int ss = canvas_.supersampling;
  view_.worldToCamera = camPose->cameraToEnu.transpose();
  view_.centre = camPose->centreEnu;
  view_.fx = rig_.intrinsics.fx_px * ss;
  view_.fy = rig_.intrinsics.fy_px * ss;
  view_.cx = (rig_.intrinsics.cx_px + canvas_.offsetX + 0.5) * ss - 0.5;
  view_.cy = (rig_.intrinsics.cy_px + canvas_.offsetY + 0.5) * ss - 0.5;
  view_.width = canvas_.width * ss;
  view_.height = canvas_.height * ss;

  cv::Mat linear;
  const std::vector<SimVehicle>& vehicles = traffic_.vehicles();
  renderer_.render(vehicles, view_, canvas_, linear);
  sensor_.outputIds(renderer_, out.ids);

  GroundTruthContext ctx;
  ctx.lifter = &lifter_;
  ctx.pose = *camPose;
  ctx.camera = &camera_;
  ctx.renderer = &renderer_;
  ctx.sensor = &sensor_;
  ctx.world = &world_;
  ctx.view = view_;
  ctx.ids = &out.ids;
  out.objects.clear();
  out.keypoints.clear();
  computeGroundTruth(out.frameId, vehicles, ctx, out.objects, out.keypoints);
  listFurniture(out, *camPose);

  // Auto exposure: set on the first frame, then a slow drift with occasional steps.
  if (exposureBase_ < 0.0) {
    exposureBase_ = sensorSpec_.exposureTargetGrey / std::max(1e-3, sensor_.meanLevel(linear));
  }
  logExposure_ += rng.normal(0.0, sensorSpec_.exposureDrift);
  if (rng.chance(sensorSpec_.exposureStepChance)) {
    logExposure_ += rng.normal(0.0, 0.08);
  }
  logExposure_ = std::clamp(logExposure_, -0.3, 0.3);
  const double exposure = exposureBase_ * std::exp(logExposure_);

  std::vector<MotionStreak> streaks;
  for (const sequence::ObjectTruth& o : out.objects) {
    if (o.speed_mps < 0.1) {
      continue;
    }
    const Eigen::Vector3d f(std::cos(o.headingEnu_rad), std::sin(o.headingEnu_rad), 0.0);
    const double half = 0.5 * o.speed_mps * sensorSpec_.exposureTimeS;
    const auto a = lifter_.worldToPixel(*camPose, o.positionEnu - half * f);
    const auto b = lifter_.worldToPixel(*camPose, o.positionEnu + half * f);
    if (a && b) {
      streaks.push_back({o.trackId, *b - *a});
    }
  }
  const std::uint32_t noiseKey = rng.nextU32();
  sensor_.develop(linear, out.ids, streaks, exposure, noiseKey, out.image);

  out.recordedPose = out.truePose;
  if (options_.telemetryNoise) {
    Eigen::Vector3d enu = world_.frame().toEnu(out.truePose.position);
    enu += Eigen::Vector3d(rng.normal(0.0, 0.03), rng.normal(0.0, 0.03), rng.normal(0.0, 0.05));
    out.recordedPose.position = world_.frame().toGeodetic(enu);
    const Eigen::Quaterniond noise =
        quaternionFromEuler(rng.normal(0.0, 0.03), rng.normal(0.0, 0.03), rng.normal(0.0, 0.05));
    out.recordedPose.bodyToNed = (out.truePose.bodyToNed * noise).normalized();
    out.recordedPose.gimbal.angles.roll_deg += rng.normal(0.0, 0.02);
    out.recordedPose.gimbal.angles.pitch_deg += rng.normal(0.0, 0.02);
    out.recordedPose.gimbal.angles.yaw_deg =
        wrap_deg(out.recordedPose.gimbal.angles.yaw_deg + rng.normal(0.0, 0.02));
  }
  ++frameIndex_;
  return true;
}

std::string Simulator::rigYaml() const {
  std::ostringstream y;
  const auto& k = rig_.intrinsics;
  const auto& d = rig_.distortion;
  y << "# Camera rig of a simulated sequence (vp_simulate), application configuration schema.\n";
  y << "origin:\n  latitude_deg: " << num(origin_.latitude_deg)
    << "\n  longitude_deg: " << num(origin_.longitude_deg)
    << "\n  height_m: " << num(origin_.height_m) << "\n";
  y << "camera:\n  width_px: " << k.width_px << "\n  height_px: " << k.height_px
    << "\n  fx_px: " << num(k.fx_px) << "\n  fy_px: " << num(k.fy_px)
    << "\n  cx_px: " << num(k.cx_px) << "\n  cy_px: " << num(k.cy_px)
    << "\n  lens_model: " << camera::toString(d.model) << "\n";
  if (d.model == camera::LensModel::BrownConrady) {
    y << "  distortion:\n    k1: " << num(d.k1) << "\n    k2: " << num(d.k2)
      << "\n    p1: " << num(d.p1) << "\n    p2: " << num(d.p2) << "\n    k3: " << num(d.k3)
      << "\n";
  }
  y << "mount:\n  roll_deg: 0\n  pitch_deg: 0\n  yaw_deg: 0\n  lever_arm_m: ["
    << num(rig_.mount.leverArm_m.x()) << ", " << num(rig_.mount.leverArm_m.y()) << ", "
    << num(rig_.mount.leverArm_m.z()) << "]\n";
  const bool earth = rig_.gimbalReference == geodesy::GimbalReference::Earth;
  y << "  gimbal:\n    reference: " << (earth ? "earth" : "body")
    << "\n    roll_deg: 0\n    pitch_deg: " << num(-90.0 + rig_.tilt_deg)
    << "\n    yaw_deg: " << num(earth ? wrap_deg(rig_.viewAzimuth_deg) : 0.0) << "\n";
  y << "terrain:\n  dtm_path: dtm.tif\n  crs: auto\n";
  y << "  dsm_path: dsm.tif  # the surface model: the DTM with the buildings (surface_model.hpp)\n";
  y << "site:\n  file: site.geojson  # the scene's site map (docs/site_map.md)\n";
  return y.str();
}

std::string Simulator::summary() const {
  std::ostringstream s;
  s << "scene " << toString(scene_.kind) << ", season " << scene_.season << ", relief "
    << toString(terrainSpec_.kind) << ", lens " << camera::toString(rig_.distortion.model)
    << ", altitude " << num(std::round(rig_.altitude_m * 10) / 10) << " m, tilt "
    << num(std::round(rig_.tilt_deg * 10) / 10) << " deg, sun elevation "
    << num(std::round(scene_.light.sunElevation_deg)) << " deg"
    << (scene_.light.overcast ? " (overcast)" : "") << ", " << scene_.buildings.size()
    << " buildings, " << scene_.trees.size() << " trees, " << scene_.furniture.size()
    << " street furniture, gimbal "
    << (rig_.gimbalReference == geodesy::GimbalReference::Earth ? "earth" : "body")
    << (options_.telemetryNoise ? ", telemetry with noise" : ", telemetry = true pose");
  if (options_.twoToneShare > 0.0) {
    s << ", two-tone share " << num(options_.twoToneShare);
  }
  if (options_.cityCarShare > 0.0) {
    s << ", city-car share " << num(options_.cityCarShare);
  }
  if (options_.pickupShare > 0.0) {
    s << ", pickup share " << num(options_.pickupShare);
  }
  if (options_.busRoofShare > 0.0) {
    s << ", bus-roof share " << num(options_.busRoofShare);
  }
  if (options_.largeVehicleShare) {
    s << ", large-vehicle share " << num(*options_.largeVehicleShare);
  }
  if (options_.poles) {
    s << ", sign posts and street lamps";
  }
  if (options_.roadUsers) {
    s << ", motorbikes, bicycles and pedestrians";
  }
  if (options_.islands) {
    s << ", " << scene_.islands.size() << " traffic islands";
  }
  return s.str();
}

void Simulator::listFurniture(FrameOutput& out, const lifting::CameraPoseWorld& pose) const {
  out.furniture.clear();
  const std::vector<StreetFurniture>& items = scene_.furniture;
  if (items.empty()) {
    return;
  }
  // Visible pixels per item from the object-id image (furniture ids are -3000 - index).
  std::vector<long> visible(items.size(), 0);
  for (int v = 0; v < out.ids.rows; ++v) {
    const auto* row = out.ids.ptr<std::int32_t>(v);
    for (int u = 0; u < out.ids.cols; ++u) {
      const long index = -3000L - row[u];
      if (index >= 0 && index < static_cast<long>(items.size())) {
        ++visible[static_cast<std::size_t>(index)];
      }
    }
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (visible[i] == 0) {
      continue;
    }
    const StreetFurniture& item = items[i];
    const Eigen::Vector2d f = item.axis();
    const Eigen::Vector2d n(-f.y(), f.x());
    std::vector<Eigen::Vector3d> corners;
    for (int a = -1; a <= 1; a += 2) {
      for (int b = -1; b <= 1; b += 2) {
        const Eigen::Vector2d p =
            item.centre + a * 0.5 * item.length_m * f + b * 0.5 * item.width_m * n;
        const double z = world_.groundZ(p.x(), p.y());
        corners.emplace_back(p.x(), p.y(), z);
        corners.emplace_back(p.x(), p.y(), z + item.height_m);
      }
    }
    const double z0 = world_.groundZ(item.centre.x(), item.centre.y());
    const Eigen::Vector3d origin(item.centre.x(), item.centre.y(), z0);
    const Eigen::Vector3d ahead(item.centre.x() + f.x(), item.centre.y() + f.y(), z0);
    const auto box = lifter_.enclosingImageBox(pose, origin, ahead, corners);
    if (!box) {
      continue;
    }
    StaticObjectTruth truth;
    truth.frameId = out.frameId;
    truth.kind = toString(item.kind);
    truth.index = static_cast<std::uint32_t>(i);
    truth.box = *box;
    truth.visiblePixels = visible[i];
    out.furniture.push_back(truth);
  }
}

bool Simulator::write(std::string* why, const std::function<void(const FrameOutput&)>& onFrame) {
  namespace fs = std::filesystem;
  const fs::path staging =
      fs::temp_directory_path() / ("vp_simulate_dtm_" + std::to_string(::getpid()) + ".tif");
  if (!io::writeDtmGeoTiff(staging.string(), world_.terrain().grid(), why)) {
    return false;
  }
  sequence::SequenceInfo info;
  info.name = std::string(toString(options_.scene)) + "_seed" + std::to_string(options_.seed);
  info.frameRate_hz = 1.0 / kFrameIntervalS;
  info.source = "vp_simulate 1.0 seed " + std::to_string(options_.seed) + " scene " +
                toString(options_.scene);
  info.notes = summary();
  sequence::SequenceWriter writer;
  writer.imageExtension = options_.png ? ".png" : ".jpg";
  writer.jpegQuality = options_.jpegQuality;
  writer.gammaColumns = asm_.componentCount();
  const bool opened = writer.open(options_.outDir, info, rigYaml(), staging.string(), why);
  std::error_code ignored;
  fs::remove(staging, ignored);
  if (!opened) {
    return false;
  }
  {
    // The surface model rig.yaml names (surface_model.hpp), in the DTM's format and grid.
    const fs::path dsmPath = fs::path(options_.outDir) / "dsm.tif";
    if (!io::writeDtmGeoTiff(dsmPath.string(), surfaceGrid(scene_, world_), why)) {
      return false;
    }
  }
  {
    // The site map rig.yaml names (site_map.hpp).
    const fs::path sitePath = fs::path(options_.outDir) / "site.geojson";
    std::ofstream site(sitePath, std::ios::binary | std::ios::trunc);
    site << siteGeoJson(scene_, world_.frame());
    site.close();
    if (!site) {
      return fail(why, sitePath.string() + ": cannot write");
    }
  }
  if (options_.instanceMasks) {
    fs::create_directories(fs::path(options_.outDir) / "instances");
  }
  // Street furniture in view per frame (not vehicles; docs/simulator.md): hard negatives.
  const fs::path furniturePath = fs::path(options_.outDir) / "ground_truth" / "furniture.csv";
  std::ofstream furniture(furniturePath, std::ios::binary | std::ios::trunc);
  furniture << "frame_id,kind,index,cx_px,cy_px,length_px,width_px,angle_rad,visible_px\n";
  FrameOutput frame;
  for (int i = 0; i < options_.frames; ++i) {
    if (!nextFrame(frame, why)) {
      return false;
    }
    sequence::FrameRecord record;
    record.frameId = frame.frameId;
    record.timestamp_ns = frame.timestamp_ns;
    sequence::TelemetryRecord telemetry;
    telemetry.timestamp_ns = frame.timestamp_ns;
    telemetry.position = frame.recordedPose.position;
    telemetry.bodyToNed = frame.recordedPose.bodyToNed;
    telemetry.gimbal = frame.recordedPose.gimbal;
    if (!writer.writeFrame(record, frame.image, why) || !writer.writeTelemetry(telemetry, why) ||
        !writer.writeObjects(frame.objects, why) || !writer.writeKeypoints(frame.keypoints, why)) {
      return false;
    }
    for (const StaticObjectTruth& t : frame.furniture) {
      char row[200];
      std::snprintf(row, sizeof(row), "%lld,%s,%u,%.2f,%.2f,%.2f,%.2f,%.5f,%ld\n",
                    static_cast<long long>(t.frameId), t.kind.c_str(), t.index, t.box.cx, t.box.cy,
                    t.box.length, t.box.width, t.box.angle, t.visiblePixels);
      furniture << row;
    }
    if (options_.instanceMasks) {
      cv::Mat mask(frame.ids.size(), CV_16UC1);
      for (int v = 0; v < mask.rows; ++v) {
        for (int u = 0; u < mask.cols; ++u) {
          const int id = frame.ids.at<std::int32_t>(v, u);
          mask.at<std::uint16_t>(v, u) =
              static_cast<std::uint16_t>(id < 0 ? 65535 : std::min(id, 65534));
        }
      }
      char name[32];
      std::snprintf(name, sizeof(name), "%06lld.png", static_cast<long long>(frame.frameId));
      const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, 3};
      if (!cv::imwrite((fs::path(options_.outDir) / "instances" / name).string(), mask, params)) {
        return fail(why, "cannot write instance mask " + std::string(name));
      }
    }
    if (onFrame) {
      onFrame(frame);
    }
  }
  furniture.close();
  if (!furniture) {
    return fail(why, furniturePath.string() + ": cannot write");
  }
  return writer.close(why);
}

}  // namespace vp::sim
