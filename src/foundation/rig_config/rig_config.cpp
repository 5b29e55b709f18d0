// rig_config/rig_config: YAML text -> RigConfig, the rig's sections only (see the header).
#include "rig_config/rig_config.hpp"

#include <array>
#include <charconv>
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
  if (root.has("site")) {
    detail::MapReader site = root.section("site");
    rig.sitePath = detail::readOptionalPath(site, "file", baseDir, "");
    site.skip("off_road");
    site.warnUnknownKeys();
  }
  for (const std::string_view name : detail::kLoopSectionNames) {
    root.skip(name);
  }
  root.warnUnknownKeys();
  return rig;
}

namespace {

// The shortest text that reads back to the same double (yaml-cpp reads it with strtod).
std::string number(double value) {
  std::array<char, 32> text{};
  const auto result = std::to_chars(text.data(), text.data() + text.size(), value);
  return std::string(text.data(), result.ptr);
}

void appendAngles(std::string& y, const char* indent, const geodesy::EulerAnglesDeg& angles) {
  y += std::string(indent) + "roll_deg: " + number(angles.roll_deg) + "\n";
  y += std::string(indent) + "pitch_deg: " + number(angles.pitch_deg) + "\n";
  y += std::string(indent) + "yaw_deg: " + number(angles.yaw_deg) + "\n";
}

}  // namespace

std::string formatRigYaml(const RigConfig& rig, const std::string& dtmPath,
                          const std::string& header, const std::string& dsmPath) {
  std::string y;
  if (!header.empty()) {
    y += "# " + header + "\n";
  }
  y += "origin:\n";
  y += "  latitude_deg: " + number(rig.origin.latitude_deg) + "\n";
  y += "  longitude_deg: " + number(rig.origin.longitude_deg) + "\n";
  y += "  height_m: " + number(rig.origin.height_m) + "\n";
  const camera::Intrinsics& k = rig.camera.intrinsics;
  const camera::Distortion& d = rig.camera.distortion;
  y += "camera:\n";
  y += "  width_px: " + std::to_string(k.width_px) + "\n";
  y += "  height_px: " + std::to_string(k.height_px) + "\n";
  y += "  fx_px: " + number(k.fx_px) + "\n";
  y += "  fy_px: " + number(k.fy_px) + "\n";
  y += "  cx_px: " + number(k.cx_px) + "\n";
  y += "  cy_px: " + number(k.cy_px) + "\n";
  y += std::string("  lens_model: ") + camera::toString(d.model) + "\n";
  if (d.model == camera::LensModel::BrownConrady) {
    y += "  distortion:\n";
    y += "    k1: " + number(d.k1) + "\n";
    y += "    k2: " + number(d.k2) + "\n";
    y += "    p1: " + number(d.p1) + "\n";
    y += "    p2: " + number(d.p2) + "\n";
    y += "    k3: " + number(d.k3) + "\n";
  }
  const geodesy::CameraMount& mount = rig.mount.mount;
  y += "mount:\n";
  appendAngles(y, "  ", mount.bodyToBase);
  y += "  lever_arm_m: [" + number(mount.leverArm_m.x()) + ", " + number(mount.leverArm_m.y()) +
       ", " + number(mount.leverArm_m.z()) + "]\n";
  y += "  gimbal:\n";
  y += std::string("    reference: ") +
       (rig.mount.gimbal.reference == geodesy::GimbalReference::Earth ? "earth" : "body") + "\n";
  appendAngles(y, "    ", rig.mount.gimbal.angles);
  y += "terrain:\n";
  y += "  dtm_path: " + dtmPath + "\n";
  if (!dsmPath.empty()) {
    y += "  dsm_path: " + dsmPath + "\n";
  }
  y += "  crs: " + (rig.terrain.crs ? terrain::toString(*rig.terrain.crs) : std::string("auto")) +
       "\n";
  y += "  max_samples: " + std::to_string(rig.terrain.load.maxSamples) + "\n";
  return y;
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
