// config/config: YAML text -> AppConfig. Each top-level section has its own reader
// (config/sections.hpp, one file per section), which fills the options struct of the module
// it configures; this file puts them together and reads the file.
#include "config/config.hpp"

#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>
#include <vector>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config {

AppConfig parseConfig(const std::string& yamlText, const std::string& sourceName,
                      const std::string& baseDir) {
  AppConfig config;
  config.sourcePath = sourceName;
  const detail::Diagnostics diag(sourceName, &config.warnings);

  detail::MapReader root(detail::loadSections(yamlText, diag), "", diag);
  config.origin = detail::readOrigin(root.requiredSection("origin"));
  config.camera = detail::readCamera(root.requiredSection("camera"));
  config.mount = detail::readMount(root.section("mount"));
  config.terrain = detail::readTerrain(root.requiredSection("terrain"), baseDir);
  // The loop's sections, in the order of detail::kLoopSectionNames (which the rig reader skips).
  config.dds = detail::readDds(root.section("dds"), baseDir);
  detail::readPerception(root.section("perception"), baseDir, config);
  config.pose = detail::readPose(root.section("pose"));
  config.tracking = detail::readTracking(root.section("tracking"));
  config.source = detail::readSource(root.section("source"), baseDir);
  config.telemetry = detail::readTelemetryLink(root.section("telemetry"));
  config.georef = detail::readGeoref(root.section("georef"), baseDir);
  config.site = detail::readSite(root.section("site"), baseDir);
  config.traffic = detail::readTraffic(root.section("traffic"));
  config.app = detail::readLoop(root.section("app"), baseDir);
  if (config.telemetry.source == TelemetrySourceKind::Dds &&
      config.dds.telemetry.source == TelemetrySource::None) {
    diag.fail("telemetry.source", "dds needs dds.telemetry.source ardupilot or px4 (it is none)");
  }
  if (!config.georef.gcpFile.empty() && config.telemetry.source != TelemetrySourceKind::None) {
    diag.fail("georef.gcp_file",
              std::string("ground control points place a fixed view without telemetry: set "
                          "telemetry.source: none (it is ") +
                  toString(config.telemetry.source) + ")");
  }
  root.warnUnknownKeys();
  return config;
}

DdsSection parseDdsSection(const std::string& yamlText, const std::string& sourceName,
                           const std::string& baseDir) {
  DdsSection result;
  const detail::Diagnostics diag(sourceName, &result.warnings);
  const YAML::Node document = detail::loadDocument(yamlText, diag);
  if (document.IsDefined() && !document.IsNull() && !document.IsMap()) {
    diag.fail("", "expected a map of sections at the top level, got " + detail::describe(document));
  }
  // The other sections belong to other readers: they are not reported as unknown here.
  detail::MapReader root(document, "", diag);
  result.dds = detail::readDds(root.section("dds"), baseDir);
  return result;
}

AppConfig loadConfig(const std::string& path) {
  const auto [text, baseDir] = detail::readConfigFile(path);
  return parseConfig(text, path, baseDir);
}

DdsSection loadDdsSection(const std::string& path) {
  const auto [text, baseDir] = detail::readConfigFile(path);
  return parseDdsSection(text, path, baseDir);
}

const char* toString(FrameSourceKind kind) {
  switch (kind) {
    case FrameSourceKind::Replay:
      return "replay";
    case FrameSourceKind::V4l2:
      return "v4l2";
    case FrameSourceKind::Video:
      return "video";
  }
  return "unknown";
}

const char* toString(PipelineMode mode) {
  switch (mode) {
    case PipelineMode::Off:
      return "off";
    case PipelineMode::On:
      return "on";
  }
  return "unknown";
}

const char* toString(RecordFullPolicy policy) {
  switch (policy) {
    case RecordFullPolicy::Stop:
      return "stop";
    case RecordFullPolicy::Ring:
      return "ring";
  }
  return "unknown";
}

const char* toString(CameraPixelFormat format) {
  switch (format) {
    case CameraPixelFormat::Yuyv:
      return "yuyv";
    case CameraPixelFormat::Nv12:
      return "nv12";
    case CameraPixelFormat::Mjpeg:
      return "mjpeg";
  }
  return "unknown";
}

std::vector<CameraPixelFormat> defaultCameraFormats() {
  // Built element by element: g++ 12 warns (wrongly) on an initializer list of 1-byte enums.
  std::vector<CameraPixelFormat> formats;
  for (const CameraPixelFormat format :
       {CameraPixelFormat::Yuyv, CameraPixelFormat::Nv12, CameraPixelFormat::Mjpeg}) {
    formats.push_back(format);
  }
  return formats;
}

const char* toString(TelemetrySourceKind kind) {
  switch (kind) {
    case TelemetrySourceKind::Recording:
      return "recording";
    case TelemetrySourceKind::MavlinkUdp:
      return "mavlink_udp";
    case TelemetrySourceKind::MavlinkSerial:
      return "mavlink_serial";
    case TelemetrySourceKind::Dds:
      return "dds";
    case TelemetrySourceKind::None:
      return "none";
  }
  return "unknown";
}

}  // namespace vp::config
