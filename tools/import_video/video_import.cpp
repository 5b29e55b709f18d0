#include "video_import.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <opencv2/core.hpp>

#include "core/frame_pool.hpp"
#include "geodesy/geodesy.hpp"
#include "io/dtm_file.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/replay/video_replay.hpp"
#include "rig_config/rig_config.hpp"
#include "sequence/recorded_sequence.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::importer {

namespace fs = std::filesystem;

namespace {

constexpr double kFlatDtmMargin_m = 1000.0;  // around the flight track: the view reaches this far
constexpr double kFlatDtmCell_m = 10.0;
constexpr int kFlatDtmMaxCells = 2000;  // per side; larger tracks get larger cells

bool fail(std::string* why, std::string message) {
  if (why != nullptr) {
    *why = std::move(message);
  }
  return false;
}

// The shortest text that reads back to the same double.
std::string num(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

// The rig of the import: the subtitles give the camera head's attitude relative to north and
// the horizon (or the nadir assumption), so an earth-referenced gimbal, no mount rotation and no
// lever arm.
config::RigConfig importRig(const geodesy::GeodeticPoint& origin, const camera::Intrinsics& k,
                            const camera::Distortion& d,
                            const std::optional<terrain::CrsSpec>& dtmCrs) {
  config::RigConfig rig;
  rig.origin = origin;
  rig.camera = {k, d};
  rig.mount.gimbal.reference = geodesy::GimbalReference::Earth;
  rig.mount.gimbal.angles = {0.0, -90.0, 0.0};
  rig.terrain.crs = dtmCrs;
  return rig;
}

// A flat DTM at height_m in the UTM zone of the track, covering it with a margin.
terrain::TerrainGrid flatDtm(const std::vector<sequence::TelemetryRecord>& records,
                             double height_m) {
  const geodesy::UtmPoint first = geodesy::toUtm(records.front().position);
  double minE = first.easting_m;
  double maxE = minE;
  double minN = first.northing_m;
  double maxN = minN;
  for (const sequence::TelemetryRecord& r : records) {
    const geodesy::UtmPoint p = geodesy::toUtm(r.position, first.zone);
    minE = std::min(minE, p.easting_m);
    maxE = std::max(maxE, p.easting_m);
    minN = std::min(minN, p.northing_m);
    maxN = std::max(maxN, p.northing_m);
  }
  const double span_m = std::max(maxE - minE, maxN - minN) + 2.0 * kFlatDtmMargin_m;
  const double cell_m = std::max(kFlatDtmCell_m, std::ceil(span_m / kFlatDtmMaxCells));
  terrain::TerrainGrid grid;
  grid.cols = static_cast<int>(std::ceil((maxE - minE + 2.0 * kFlatDtmMargin_m) / cell_m)) + 1;
  grid.rows = static_cast<int>(std::ceil((maxN - minN + 2.0 * kFlatDtmMargin_m) / cell_m)) + 1;
  grid.heights_m.assign(static_cast<std::size_t>(grid.cols) * static_cast<std::size_t>(grid.rows),
                        static_cast<float>(height_m));
  grid.transform.x0 = minE - kFlatDtmMargin_m;
  grid.transform.dxCol = cell_m;
  grid.transform.y0 = maxN + kFlatDtmMargin_m;
  grid.transform.dyRow = -cell_m;
  grid.crs.kind = terrain::HorizontalCrs::Utm;
  grid.crs.utmZone = first.zone;
  grid.crs.utmNorth = first.northp;
  return grid;
}

std::string defaultSubtitlePath(const std::string& video) {
  for (const char* ext : {".SRT", ".srt"}) {
    fs::path candidate(video);
    candidate.replace_extension(ext);
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) {
      return candidate.string();
    }
  }
  return "";
}

}  // namespace

bool loadCameraCatalogue(const std::string& path, std::vector<CatalogueCamera>& out,
                         std::string* why) {
  out.clear();
  try {
    const YAML::Node root = YAML::LoadFile(path);
    const YAML::Node cameras = root["cameras"];
    if (!cameras.IsSequence()) {
      return fail(why, path + ": cameras: expected a sequence of cameras");
    }
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const YAML::Node c = cameras[i];
      CatalogueCamera camera;
      camera.name = c["name"].as<std::string>();
      camera.model = c["model"].as<std::string>();
      camera.sensorWidth_mm = c["sensor_width_mm"].as<double>();
      camera.focalLength_mm = c["focal_length_mm"].as<double>();
      for (const YAML::Node& mode : c["video_modes"]) {
        camera.videoModes_px.emplace_back(mode[0].as<int>(), mode[1].as<int>());
      }
      if (camera.sensorWidth_mm <= 0.0 || camera.focalLength_mm <= 0.0 ||
          camera.videoModes_px.empty()) {
        return fail(why, path + ": cameras[" + std::to_string(i) +
                             "]: sensor_width_mm and focal_length_mm must be > 0, "
                             "video_modes non-empty");
      }
      out.push_back(std::move(camera));
    }
  } catch (const YAML::Exception& error) {
    return fail(why, path + ": " + error.what());
  }
  return true;
}

bool catalogueIntrinsics(const CatalogueCamera& camera, int width_px, int height_px,
                         camera::Intrinsics& out, std::string* why) {
  const bool known =
      std::any_of(camera.videoModes_px.begin(), camera.videoModes_px.end(),
                  [&](const auto& m) { return m.first == width_px && m.second == height_px; });
  if (!known) {
    std::string modes;
    for (const auto& [w, h] : camera.videoModes_px) {
      modes += (modes.empty() ? "" : ", ") + std::to_string(w) + "x" + std::to_string(h);
    }
    return fail(why, "--camera " + camera.name + ": the video is " + std::to_string(width_px) +
                         "x" + std::to_string(height_px) + ", not a video mode of the " +
                         camera.model + " (" + modes + "); give --calibration");
  }
  out.width_px = width_px;
  out.height_px = height_px;
  out.fx_px = camera.focalLength_mm / camera.sensorWidth_mm * width_px;
  out.fy_px = out.fx_px;
  out.cx_px = (width_px - 1) / 2.0;
  out.cy_px = (height_px - 1) / 2.0;
  return true;
}

bool loadCalibration(const std::string& path, camera::Intrinsics& intrinsics,
                     camera::Distortion& distortion, std::string* why) {
  std::ifstream in(path);
  if (!in) {
    return fail(why, path + ": cannot open calibration file");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().find("camera_matrix") != std::string::npos) {
    try {
      cv::FileStorage fs(path, cv::FileStorage::READ);
      cv::Mat k;
      cv::Mat d;
      int width = 0;
      int height = 0;
      fs["camera_matrix"] >> k;
      fs["distortion_coefficients"] >> d;
      fs["image_width"] >> width;
      fs["image_height"] >> height;
      if (k.rows != 3 || k.cols != 3 || width <= 0 || height <= 0) {
        return fail(why, path +
                             ": OpenCV calibration needs camera_matrix (3x3), image_width "
                             "and image_height");
      }
      k.convertTo(k, CV_64F);
      intrinsics = camera::Intrinsics{width,
                                      height,
                                      k.at<double>(0, 0),
                                      k.at<double>(1, 1),
                                      k.at<double>(0, 2),
                                      k.at<double>(1, 2)};
      distortion = camera::Distortion{};
      if (!d.empty()) {
        d.convertTo(d, CV_64F);
        const cv::Mat flat = d.reshape(1, 1);
        for (int i = 5; i < flat.cols; ++i) {
          if (flat.at<double>(0, i) != 0.0) {
            return fail(why, path +
                                 ": distortion_coefficients: only k1 k2 p1 p2 k3 are supported "
                                 "(the rational and thin-prism terms must be 0)");
          }
        }
        const auto at = [&](int i) { return i < flat.cols ? flat.at<double>(0, i) : 0.0; };
        distortion =
            camera::Distortion{camera::LensModel::BrownConrady, at(0), at(1), at(2), at(3), at(4)};
      }
      return true;
    } catch (const cv::Exception& error) {
      return fail(why, path + ": " + error.what());
    }
  }
  try {
    const config::CameraConfig camera = config::loadCameraSection(path);
    intrinsics = camera.intrinsics;
    distortion = camera.distortion;
    return true;
  } catch (const config::ConfigError& error) {
    return fail(why, error.what());
  }
}

bool importVideo(const ImportOptions& options, ImportSummary& summary, std::string* why) {
  summary = ImportSummary{};
  if (options.every < 1) {
    return fail(why, "--every: must be >= 1, got " + std::to_string(options.every));
  }
  if (options.cameraName.empty() == options.calibrationPath.empty()) {
    return fail(why, "camera: give one of --camera NAME (catalogue) or --calibration FILE");
  }
  if (options.flatDtmHeight_m.has_value() == !options.dtmPath.empty()) {
    return fail(why, "DTM: give one of --flat-dtm-height-m H or --dtm FILE");
  }

  // The video: size, frame rate, and the frames' clock.
  platform::ManualClock clock;
  platform::replay::VideoReplay video(clock);
  if (!video.open(options.videoPath, {false, false}, why)) {
    return false;
  }

  // The camera at the video's size.
  camera::Intrinsics intrinsics;
  camera::Distortion distortion;
  if (!options.cameraName.empty()) {
    std::vector<CatalogueCamera> catalogue;
    if (!loadCameraCatalogue(options.cataloguePath, catalogue, why)) {
      return false;
    }
    const auto found =
        std::find_if(catalogue.begin(), catalogue.end(),
                     [&](const CatalogueCamera& c) { return c.name == options.cameraName; });
    if (found == catalogue.end()) {
      std::string names;
      for (const CatalogueCamera& c : catalogue) {
        names += (names.empty() ? "" : ", ") + c.name;
      }
      return fail(why, "--camera: unknown camera '" + options.cameraName + "' (" +
                           options.cataloguePath + " has " + names + ")");
    }
    if (!catalogueIntrinsics(*found, video.width_px(), video.height_px(), intrinsics, why)) {
      return false;
    }
  } else {
    if (!loadCalibration(options.calibrationPath, intrinsics, distortion, why)) {
      return false;
    }
    if (intrinsics.width_px != video.width_px() || intrinsics.height_px != video.height_px()) {
      return fail(why, options.calibrationPath + ": calibrated at " +
                           std::to_string(intrinsics.width_px) + "x" +
                           std::to_string(intrinsics.height_px) + " but the video is " +
                           std::to_string(video.width_px()) + "x" +
                           std::to_string(video.height_px()) + " (calibrate at the video's size)");
    }
  }

  // The telemetry.
  const std::string srt =
      options.srtPath.empty() ? defaultSubtitlePath(options.videoPath) : options.srtPath;
  if (srt.empty()) {
    return fail(why, options.videoPath +
                         ": no subtitle file beside it (looked for the same name with .SRT and "
                         ".srt); give SRT");
  }
  subtitle::SubtitleFile subtitles;
  if (!subtitle::readSubtitleFile(srt, subtitles, why)) {
    return false;
  }
  summary.errors = subtitles.problems;
  summary.subtitleBlocks = subtitles.blocks;
  summary.subtitleSamples = subtitles.samples.size();
  subtitle::SubtitleTelemetry telemetry = subtitle::toTelemetry(subtitles, options.telemetry, srt);
  summary.errors.insert(summary.errors.end(), telemetry.problems.begin(), telemetry.problems.end());
  summary.telemetryRows = telemetry.records.size();
  summary.nadirAssumed = telemetry.nadirAssumed;
  summary.yawFromMotion = telemetry.yawFromMotion;
  if (telemetry.records.empty()) {
    return fail(why, srt + ": no usable telemetry (" + std::to_string(subtitles.blocks) +
                         " subtitles, " + std::to_string(summary.errors.size()) + " problems)");
  }

  // The DTM and the world origin (the first position, at the ground's height).
  const geodesy::GeodeticPoint& start = telemetry.records.front().position;
  geodesy::GeodeticPoint origin{start.latitude_deg, start.longitude_deg, start.height_m};
  std::string dtmFile = options.dtmPath;
  std::optional<terrain::CrsSpec> dtmCrs;  // auto
  fs::path staging;
  if (options.flatDtmHeight_m) {
    origin.height_m = *options.flatDtmHeight_m;
    staging =
        fs::temp_directory_path() / ("vp_import_video_dtm_" + std::to_string(::getpid()) + ".tif");
    if (!io::writeDtmGeoTiff(staging.string(), flatDtm(telemetry.records, origin.height_m), why)) {
      return false;
    }
    dtmFile = staging.string();
  } else {
    terrain::TerrainGrid grid;
    if (options.dtmCrs != "auto") {
      dtmCrs = terrain::crsFromString(options.dtmCrs);
      if (!dtmCrs) {
        return fail(why,
                    "--dtm-crs: expected auto, wgs84 or utm:<zone><N|S>, got " + options.dtmCrs);
      }
    }
    terrain::TerrainModel model;
    if (!io::loadDtm(options.dtmPath, dtmCrs, grid, why) ||
        !model.init(std::move(grid), geodesy::LocalFrame(origin), why)) {
      return false;
    }
    const auto ground = model.heightAt(origin.latitude_deg, origin.longitude_deg);
    origin.height_m = ground ? *ground : static_cast<double>(model.minHeight_m());
  }

  sequence::SequenceInfo info;
  info.name = fs::path(options.videoPath).stem().string();
  info.frameRate_hz = video.frameRate_hz() / options.every;
  info.source = "vp_import_video " + fs::path(options.videoPath).filename().string() + " + " +
                fs::path(srt).filename().string() + " (" + std::to_string(subtitles.bracketed) +
                " bracketed, " + std::to_string(subtitles.legacy) + " legacy subtitles)";
  std::string notes =
      options.telemetry.altitude == subtitle::AltitudeSource::Absolute
          ? "height = abs_alt + geoid separation " + num(options.telemetry.geoidSeparation_m) + " m"
          : "height = rel_alt + take-off height " + num(options.telemetry.homeHeight_m) + " m";
  notes += "; every " + std::to_string(options.every) + " frame(s) of the video";
  if (telemetry.nadirAssumed > 0) {
    const std::string assumed =
        "ATTITUDE ASSUMED: " + std::to_string(telemetry.nadirAssumed) + " of " +
        std::to_string(telemetry.records.size()) +
        " telemetry rows had no gimbal angles in the subtitles; their camera is assumed to look "
        "straight down (gimbal pitch -90 deg, earth-referenced) with yaw along the drone's "
        "motion (" +
        std::to_string(telemetry.yawFromMotion) + " rows) or 0 (the rest)";
    notes += "; " + assumed;
    summary.warnings.push_back(srt + ": " + assumed);
  }
  info.notes = notes;

  sequence::SequenceWriter writer;
  writer.imageExtension = ".jpg";
  writer.jpegQuality = options.jpegQuality;
  const bool opened = writer.open(
      options.outDir, info,
      config::formatRigYaml(importRig(origin, intrinsics, distortion, dtmCrs), "dtm.tif",
                            "Camera rig of an imported drone video "
                            "(vp_import_video), configuration schema."),
      dtmFile, why);
  if (!staging.empty()) {
    std::error_code ignored;
    fs::remove(staging, ignored);
  }
  if (!opened) {
    return false;
  }
  for (const sequence::TelemetryRecord& record : telemetry.records) {
    if (!writer.writeTelemetry(record, why)) {
      return false;
    }
  }

  Frame frame;
  frame.image.create(video.height_px(), video.width_px(), CV_8UC3);
  const std::int64_t first_ns = telemetry.records.front().timestamp_ns;
  const std::int64_t last_ns = telemetry.records.back().timestamp_ns;
  for (;;) {
    if (options.maxFrames > 0 && summary.framesWritten >= options.maxFrames) {
      break;
    }
    std::string problem;
    const platform::replay::ReplayStatus status = video.next(frame, &problem);
    if (status == platform::replay::ReplayStatus::End) {
      break;
    }
    if (status != platform::replay::ReplayStatus::Frame) {
      summary.errors.push_back(problem + "; frame skipped");
      continue;
    }
    ++summary.framesRead;
    if (frame.frameId % options.every != 0) {
      continue;
    }
    sequence::FrameRecord record;
    record.frameId = frame.frameId;
    record.timestamp_ns = frame.timestamp_ns;
    if (!writer.writeFrame(record, frame.image, why)) {
      return false;
    }
    ++summary.framesWritten;
    if (frame.timestamp_ns < first_ns || frame.timestamp_ns > last_ns) {
      ++summary.framesOutsideTelemetry;
    }
  }
  summary.indexTimestamps = video.counters().indexTimestamps;
  if (summary.framesOutsideTelemetry > 0) {
    summary.warnings.push_back(
        std::to_string(summary.framesOutsideTelemetry) + " of " +
        std::to_string(summary.framesWritten) +
        " frames lie outside the telemetry's time span (the app gives them no pose)");
  }
  return writer.close(why);
}

}  // namespace vp::importer
