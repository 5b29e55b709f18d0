// config/sections: one reader per loop section of the file (internal to the loader); the rig's
// sections have theirs in rig_config/rig_sections.hpp.
//
// Contract: each reads its section through a MapReader and returns (or fills) the options
// struct of the module the section configures; a key that is absent keeps that struct's own
// default, so the file and the code share one definition. Each warns about its own unknown
// keys and throws ConfigError naming the file and the key path. Start-up only.
#pragma once

#include <string>

#include "config/config.hpp"
#include "rig_config/rig_sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {

DdsConfig readDds(MapReader section, const std::string& baseDir);        // dds_section.cpp
void readPerception(MapReader section, const std::string& baseDir,       // perception_section
                    AppConfig& config);                                  // (pipeline + ASM)
telemetry::PoseBufferConfig readPose(MapReader section);                 // pose_section.cpp
tracking::TrackerConfig readTracking(MapReader section);                 // tracking_section.cpp
SourceConfig readSource(MapReader section, const std::string& baseDir);  // source_section.cpp
TelemetryLinkConfig readTelemetryLink(MapReader section);                // telemetry_section
georef::GeorefOptions readGeoref(MapReader section,                      // georef_section.cpp
                                 const std::string& baseDir);
site::SiteOptions readSite(MapReader section, const std::string& baseDir);  // site_section
traffic::TrafficAnalyzerOptions readTraffic(MapReader section);             // traffic_section
LoopConfig readLoop(MapReader section, const std::string& baseDir);         // app_section.cpp

}  // namespace vp::config::detail
