// rig_config/rig_sections: the readers of the rig's sections (internal to the rig reader and
// the configuration library, see config/sections.hpp for the loop's).
//
// Contract: each reads its section through a MapReader and returns the struct it fills; a key
// that is absent keeps that struct's own default. Each warns about its own unknown keys and
// throws ConfigError naming the file and the key path. Start-up only.
#pragma once

#include <array>
#include <string>
#include <string_view>

#include "rig_config/rig_config.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {

geodesy::GeodeticPoint readOrigin(MapReader section);
CameraConfig readCamera(MapReader section);
MountConfig readMount(MapReader section);
TerrainConfig readTerrain(MapReader section, const std::string& baseDir);

// The top-level sections config::parseConfig() reads besides the rig's (config/sections.hpp):
// parseRigConfig() leaves them to it instead of reporting them as unknown keys.
inline constexpr std::array<std::string_view, 10> kLoopSectionNames = {
    "dds",       "perception", "pose", "tracking", "source",
    "telemetry", "georef",     "site", "traffic",  "app"};

}  // namespace vp::config::detail
