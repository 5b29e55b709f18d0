// rig_config/rig_config: the rig's sections of the configuration file (origin, camera, mount,
// terrain), readable without the loop's configuration.
//
// Contract: parseRigConfig() / loadRigConfig() read and check the sections origin, camera,
// mount and terrain exactly as config::parseConfig() / loadConfig() do (same keys, ranges,
// defaults and messages; ConfigError names the file and the key path) and return them in the
// types of the foundation modules. The loop's sections of the same file (dds, perception, pose,
// tracking, source, telemetry, app) are the application's: they are neither read nor reported
// as unknown here; other unknown keys are warnings. The recorded-sequence reader reads a
// recording's rig.yaml with it; config::AppConfig holds the same structs. formatRigYaml() is the
// inverse: the sections as YAML text that parseRigConfig() reads back to the same values
// (numbers in their shortest exact form), which a recorder writes as its sequence's rig.yaml.
// Start-up only.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "camera/camera_model.hpp"
#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "io/dtm_file.hpp"
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
  std::string dtmPath;  // absolute after loading
  // terrain.dsm_path: the surface model (ground + buildings, bridges, decks; the DTM's formats
  // and CRS rule), absolute after loading; empty: none (docs/field_data.md).
  std::string dsmPath;
  std::optional<terrain::CrsSpec> crs;  // required only for world-file DTMs
  io::DtmLoadOptions load{};            // terrain.max_samples
};

struct RigConfig {
  std::string sourcePath;           // the file it came from
  geodesy::GeodeticPoint origin{};  // world ENU origin
  CameraConfig camera{};
  MountConfig mount{};
  TerrainConfig terrain{};
  // site.file: the map of the site the rig serves (a sequence's site.geojson beside rig.yaml),
  // absolute; empty without one. The rest of `site:` is the application's.
  std::string sitePath;
  std::vector<std::string> warnings;  // unknown keys and other non-fatal remarks
};

// Throws ConfigError on a missing file, a YAML syntax error, or a bad key of the rig.
RigConfig loadRigConfig(const std::string& path);
// Same from text; sourceName is used in messages, baseDir to resolve relative paths.
RigConfig parseRigConfig(const std::string& yamlText, const std::string& sourceName,
                         const std::string& baseDir);

// origin:, camera:, mount: and terrain: as YAML text (a comment line `header` first when not
// empty); terrain.dtm_path is written as `dtmPath` (a recorder names its copy, dtm.tif) and
// terrain.dsm_path as `dsmPath` when that is not empty (rig.terrain.dsmPath is not written:
// a recorder names its copy, dsm.tif), the other fields from rig. parseRigConfig() of the text
// gives back rig's values exactly.
std::string formatRigYaml(const RigConfig& rig, const std::string& dtmPath,
                          const std::string& header = "", const std::string& dsmPath = "");

// The `camera:` section alone of a file (a calibration kept apart from a site's rig), with the
// same checks and messages; the file's other top-level keys are ignored. Throws ConfigError.
CameraConfig loadCameraSection(const std::string& path);

}  // namespace vp::config
