// config/config: the application's one typed configuration, loaded once from YAML.
//
// Contract: loadConfig() reads the file, checks every key (type, unit, range) and returns
// the typed struct; any missing or malformed key throws ConfigError whose message names
// the file and the full key path (e.g. "site.yaml: camera.fx_px: must be > 0, got -3").
// Besides the rig (origin, camera, mount, terrain) it holds the loop's optional sections
// (config/runtime_config.hpp: perception, pose, tracking, source, telemetry, app) and `dds:`.
// Keys the schema does not know are not fatal: they are listed in AppConfig::warnings
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
#include "config/runtime_config.hpp"
#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::config {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CameraConfig {
  camera::Intrinsics intrinsics{};
  camera::Distortion distortion{};
};

struct MountConfig {
  geodesy::CameraMount mount{};
  geodesy::GimbalState gimbal{};  // default gimbal state when telemetry has none
};

struct TerrainConfig {
  std::string dtmPath;                  // absolute after loading
  std::optional<terrain::CrsSpec> crs;  // required only for world-file DTMs
};

struct AppConfig {
  std::string sourcePath;           // the file it came from
  geodesy::GeodeticPoint origin{};  // world ENU origin
  CameraConfig camera{};
  MountConfig mount{};
  TerrainConfig terrain{};
  DdsConfig dds{};                // optional section: absent = the documented defaults
  PerceptionConfig perception{};  // optional sections of the loop, likewise
  PoseConfig pose{};
  TrackingConfig tracking{};
  SourceConfig source{};
  TelemetryLinkConfig telemetry{};
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
