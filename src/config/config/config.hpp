// config/config: the application's one typed configuration, loaded once from YAML.
//
// Contract: loadConfig() reads the file, checks every key (type, unit, range) and returns
// the typed struct; any missing or malformed key throws ConfigError whose message names
// the file and the full key path (e.g. "site.yaml: camera.fx_px: must be > 0, got -3").
// Besides the rig (origin, camera, mount, terrain) it holds the loop's optional sections:
// `perception:`, `pose:` and `tracking:` as the options structs of the modules they configure
// (perception::PipelineOptions, telemetry::PoseBufferConfig, tracking::TrackerConfig: one
// definition of each knob and its default, beside the module's code), `source:`,
// `telemetry:`, `georef:` (georef::GeorefOptions), `site:`, `traffic:`
// (traffic::TrafficAnalyzerOptions), `app:` (config/loop_config.hpp) and `dds:`
// (config/dds_config.hpp). Keys the schema does not know are not fatal: they are listed in
// AppConfig::warnings
// ("site.yaml: unknown key 'camera.fxx'"). Relative paths in the file are resolved
// against the file's directory. The schema, with units, ranges and defaults, is
// documented in docs/configuration.md and config/default.yaml. The optional `dds:` section
// (config/dds_config.hpp) can also be read alone, for tools that need only the DDS settings
// (parseDdsSection: other sections are then ignored). Start-up only.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "camera/camera_model.hpp"
#include "config/dds_config.hpp"
#include "config/loop_config.hpp"
#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "georef/georeference.hpp"
#include "perception/frame_pipeline.hpp"
#include "rig_config/rig_config.hpp"
#include "site/site.hpp"
#include "telemetry/pose_buffer.hpp"
#include "terrain/terrain_model.hpp"
#include "tracking/track_manager.hpp"
#include "traffic/traffic_analyzer.hpp"

namespace vp::config {

// Default model files of `perception:`, relative to the configuration file's directory: the
// repository's (and the package's) layout with config/ beside models/.
inline constexpr const char* kDefaultDetectorModel = "../models/detector/detector_int8.onnx";
inline constexpr const char* kDefaultCropModel = "../models/detector/crop_int8.onnx";
inline constexpr const char* kDefaultAsm = "../models/asm/default_asm.yaml";

struct AppConfig {
  std::string sourcePath;           // the file it came from
  geodesy::GeodeticPoint origin{};  // world ENU origin
  CameraConfig camera{};
  MountConfig mount{};
  TerrainConfig terrain{};
  DdsConfig dds{};  // optional section: absent = the documented defaults
  // Optional sections of the loop, likewise. The model paths in perception.detection are
  // absolute after loading; an empty crop model means no second stage (`crop_model: none`).
  perception::PipelineOptions perception{};
  std::string asmPath;  // perception.asm: the Active Shape Model file, absolute
  telemetry::PoseBufferConfig pose{};
  tracking::TrackerConfig tracking{};  // the app borrows it the ASM and the detection capacity
  SourceConfig source{};
  TelemetryLinkConfig telemetry{};
  georef::GeorefOptions georef{};  // ground control points of a fixed view (telemetry off)
  site::SiteOptions site{};        // the site map and its scene prior (site.file absolute)
  traffic::TrafficAnalyzerOptions traffic{};  // the traffic analysis on the site's features
  LoopConfig app{};
  std::vector<std::string> warnings;  // unknown keys and other non-fatal remarks
};

// Throws ConfigError on a missing file, a YAML syntax error, or a bad key.
AppConfig loadConfig(const std::string& path);
// Same from text; sourceName is used in messages, baseDir to resolve relative paths.
AppConfig parseConfig(const std::string& yamlText, const std::string& sourceName,
                      const std::string& baseDir);

// Only the `dds:` section of a file (the other sections are neither read nor checked), with
// the same checks and messages as in parseConfig(). Throws ConfigError.
struct DdsSection {
  DdsConfig dds{};
  std::vector<std::string> warnings;  // unknown keys inside `dds:`
};
DdsSection parseDdsSection(const std::string& yamlText, const std::string& sourceName,
                           const std::string& baseDir);
DdsSection loadDdsSection(const std::string& path);

}  // namespace vp::config
