// rig_config/rig_config: YAML text -> RigConfig, the rig's sections only (see the header).
#include "rig_config/rig_config.hpp"

#include <string_view>

#include "rig_config/rig_sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config {

RigConfig parseRigConfig(const std::string& yamlText, const std::string& sourceName,
                         const std::string& baseDir) {
  RigConfig rig;
  rig.sourcePath = sourceName;
  const detail::Diagnostics diag(sourceName, &rig.warnings);
  detail::MapReader root(detail::loadSections(yamlText, diag), "", diag);
  rig.origin = detail::readOrigin(root.requiredSection("origin"));
  rig.camera = detail::readCamera(root.requiredSection("camera"));
  rig.mount = detail::readMount(root.section("mount"));
  rig.terrain = detail::readTerrain(root.requiredSection("terrain"), baseDir);
  for (const std::string_view name : detail::kLoopSectionNames) {
    root.skip(name);
  }
  root.warnUnknownKeys();
  return rig;
}

CameraConfig loadCameraSection(const std::string& path) {
  const auto [text, baseDir] = detail::readConfigFile(path);
  std::vector<std::string> warnings;
  const detail::Diagnostics diag(path, &warnings);
  detail::MapReader root(detail::loadSections(text, diag), "", diag);
  return detail::readCamera(root.requiredSection("camera"));
}

RigConfig loadRigConfig(const std::string& path) {
  const auto [text, baseDir] = detail::readConfigFile(path);
  return parseRigConfig(text, path, baseDir);
}

}  // namespace vp::config
