// rig_config/rig_sections: the rig's sections origin:, camera:, mount:, terrain: (the camera,
// lens and mount structs of camera/ and geodesy/ are filled directly).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "rig_config/rig_sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kLatitudeRange_deg = Range::closed(-90.0, 90.0);
const Range kLongitudeRange_deg = Range::closed(-180.0, 180.0);
// Ellipsoidal height of the ENU origin: below the Dead Sea shore to above any launch site.
const Range kOriginHeightRange_m = Range::closed(-500.0, 9000.0);
// Not a physical limit: |coefficient| > 100 means a unit or copy mistake, not a lens.
const Range kDistortionRange = Range::closed(-100.0, 100.0);
const Range kRollYawRange_deg = Range::closed(-180.0, 180.0);
const Range kMountPitchRange_deg = Range::closed(-90.0, 90.0);
// Gimbal heads reach a little past nadir (-90) and somewhat above the horizon.
const Range kGimbalPitchRange_deg = Range::closed(-120.0, 30.0);
// The camera sits on the airframe: a lever arm of metres more means a unit mistake.
const Range kLeverArmRange_m = Range::closed(-10.0, 10.0);

constexpr std::string_view kLensModelNames = "pinhole, brown_conrady, equivalent_spherical";
constexpr std::string_view kGimbalReferenceNames = "body, earth";
constexpr std::string_view kCrsForms = "auto, wgs84, or utm:<zone 1-60><N|S> such as utm:16N";

std::optional<geodesy::GimbalReference> gimbalReferenceFromString(const std::string& text) {
  if (text == "body") {
    return geodesy::GimbalReference::Body;
  }
  if (text == "earth") {
    return geodesy::GimbalReference::Earth;
  }
  return std::nullopt;
}

// "auto" -> an engaged empty CRS (let the DTM say); nullopt only when malformed. Case-blind,
// as terrain::crsFromString is for the other spellings.
std::optional<std::optional<terrain::CrsSpec>> crsSettingFromString(const std::string& text) {
  const auto lower = [](unsigned char c) { return std::tolower(c); };
  constexpr std::string_view kAuto = "auto";
  if (std::equal(text.begin(), text.end(), kAuto.begin(), kAuto.end(),
                 [&](char a, char b) { return lower(a) == lower(b); })) {
    return std::optional<terrain::CrsSpec>();
  }
  const std::optional<terrain::CrsSpec> crs = terrain::crsFromString(text);
  if (!crs) {
    return std::nullopt;
  }
  return crs;
}

// Largest radial displacement |r_d / r - 1| of a Brown-Conrady lens a mapping camera is
// expected to have within its image; beyond it the coefficients are more likely in the wrong
// units or order than a real lens (a strong wide-angle lens stays near 0.3).
constexpr double kUnusualRadialDistortion = 0.5;
// Largest |p1|, |p2| of a real lens: decentring is a small effect (typically 1e-4 .. 1e-3).
constexpr double kUnusualTangentialDistortion = 0.05;

// Checks the Brown-Conrady coefficients against the image they apply to: in normalised
// coordinates r = |(u - cx) / fx, (v - cy) / fy| the image reaches out to its farthest corner;
// over [0, that radius] the radial model r_d = r (1 + k1 r^2 + k2 r^4 + k3 r^6) must keep
// increasing (else two directions map to one pixel: surely wrong coefficients, an error), and a
// displacement beyond kUnusualRadialDistortion is worth a warning.
void checkDistortion(MapReader& section, const camera::Intrinsics& in,
                     const camera::Distortion& lens) {
  if (lens.model != camera::LensModel::BrownConrady) {
    return;
  }
  const double du = std::max(in.cx_px + 0.5, in.width_px - 0.5 - in.cx_px) / in.fx_px;
  const double dv = std::max(in.cy_px + 0.5, in.height_px - 0.5 - in.cy_px) / in.fy_px;
  const double corner = std::hypot(du, dv);
  constexpr int kSteps = 200;
  double worst = 0.0;
  double worstRadius = 0.0;
  for (int i = 1; i <= kSteps; ++i) {
    const double r = corner * i / kSteps;
    const double r2 = r * r;
    const double factor = 1.0 + r2 * (lens.k1 + r2 * (lens.k2 + r2 * lens.k3));
    const double slope = 1.0 + r2 * (3.0 * lens.k1 + r2 * (5.0 * lens.k2 + r2 * 7.0 * lens.k3));
    if (slope <= 0.0) {
      section.fail("distortion",
                   "k1, k2, k3 fold the image over at normalised radius " +
                       formatNumber(std::round(r * 1000.0) / 1000.0) + " (the corner is at " +
                       formatNumber(std::round(corner * 1000.0) / 1000.0) +
                       "): not a lens; check the coefficients' units and order (OpenCV k1 k2 p1 "
                       "p2 k3)");
    }
    if (std::abs(factor - 1.0) > worst) {
      worst = std::abs(factor - 1.0);
      worstRadius = r;
    }
  }
  if (worst > kUnusualRadialDistortion) {
    section.warn("distortion",
                 "unusual: k1, k2, k3 move image points radially by " +
                     formatNumber(std::round(worst * 100.0)) + " % at normalised radius " +
                     formatNumber(std::round(worstRadius * 1000.0) / 1000.0) +
                     " (within the image); check the coefficients' units and order (OpenCV k1 k2 "
                     "p1 p2 k3)");
  }
  for (const auto& [name, value] : {std::pair{"p1", lens.p1}, std::pair{"p2", lens.p2}}) {
    if (std::abs(value) > kUnusualTangentialDistortion) {
      section.warn(std::string("distortion.") + name,
                   "unusual: " + formatNumber(value) + " (real lenses: |p| below " +
                       formatNumber(kUnusualTangentialDistortion) + ")");
    }
  }
}

geodesy::EulerAnglesDeg readAngles(MapReader& section, const Range& pitchRange_deg,
                                   const geodesy::EulerAnglesDeg& fallback) {
  geodesy::EulerAnglesDeg angles;
  angles.roll_deg = section.number("roll_deg", kRollYawRange_deg, fallback.roll_deg);
  angles.pitch_deg = section.number("pitch_deg", pitchRange_deg, fallback.pitch_deg);
  angles.yaw_deg = section.number("yaw_deg", kRollYawRange_deg, fallback.yaw_deg);
  return angles;
}

}  // namespace

geodesy::GeodeticPoint readOrigin(MapReader section) {
  geodesy::GeodeticPoint origin;
  origin.latitude_deg = section.number("latitude_deg", kLatitudeRange_deg, kRequired);
  origin.longitude_deg = section.number("longitude_deg", kLongitudeRange_deg, kRequired);
  origin.height_m = section.number("height_m", kOriginHeightRange_m, kRequired);
  section.warnUnknownKeys();
  return origin;
}

CameraConfig readCamera(MapReader section) {
  CameraConfig config;
  camera::Intrinsics& in = config.intrinsics;
  in.width_px = section.integer("width_px", kImageSizeRange_px, kRequired);
  in.height_px = section.integer("height_px", kImageSizeRange_px, kRequired);
  in.fx_px = section.number("fx_px", Range::positive(), kRequired);
  in.fy_px = section.number("fy_px", Range::positive(), kRequired);
  // Pixel centres are integers, so the image spans [-0.5, size - 0.5] and its centre is
  // (size - 1) / 2; a principal point outside the image is a calibration error.
  in.cx_px =
      section.number("cx_px", Range::closed(-0.5, in.width_px - 0.5), (in.width_px - 1) / 2.0);
  in.cy_px =
      section.number("cy_px", Range::closed(-0.5, in.height_px - 0.5), (in.height_px - 1) / 2.0);

  camera::Distortion& lens = config.distortion;
  lens.model = section.choice<camera::LensModel>("lens_model", camera::lensModelFromString,
                                                 kLensModelNames, camera::LensModel::Pinhole);
  MapReader coefficients = section.section("distortion");
  lens.k1 = coefficients.number("k1", kDistortionRange, 0.0);
  lens.k2 = coefficients.number("k2", kDistortionRange, 0.0);
  lens.p1 = coefficients.number("p1", kDistortionRange, 0.0);
  lens.p2 = coefficients.number("p2", kDistortionRange, 0.0);
  lens.k3 = coefficients.number("k3", kDistortionRange, 0.0);
  coefficients.warnUnknownKeys();
  if (lens.model != camera::LensModel::BrownConrady && section.has("distortion")) {
    // Probably a lens_model left at its default: say so instead of silently dropping them.
    section.warn("distortion", "ignored: only lens_model brown_conrady uses it");
    lens = camera::Distortion{lens.model};
  }
  checkDistortion(section, in, lens);
  section.warnUnknownKeys();
  return config;
}

MountConfig readMount(MapReader section) {
  // The defaults are those of the structs, so code and file agree on "nothing configured".
  const MountConfig defaults;
  MountConfig config;
  config.mount.bodyToBase = readAngles(section, kMountPitchRange_deg, defaults.mount.bodyToBase);
  config.mount.leverArm_m =
      section.vector3("lever_arm_m", kLeverArmRange_m, defaults.mount.leverArm_m);
  MapReader gimbal = section.section("gimbal");
  config.gimbal.reference = gimbal.choice<geodesy::GimbalReference>(
      "reference", gimbalReferenceFromString, kGimbalReferenceNames, defaults.gimbal.reference);
  config.gimbal.angles = readAngles(gimbal, kGimbalPitchRange_deg, defaults.gimbal.angles);
  gimbal.warnUnknownKeys();
  section.warnUnknownKeys();
  return config;
}

TerrainConfig readTerrain(MapReader section, const std::string& baseDir) {
  TerrainConfig config;
  config.dtmPath = resolvePath(section.text("dtm_path", kRequired), baseDir);
  config.dsmPath = readOptionalPath(section, "dsm_path", baseDir, "");
  config.crs = section.choice<std::optional<terrain::CrsSpec>>(
      "crs", crsSettingFromString, kCrsForms, std::optional<terrain::CrsSpec>());
  config.load.maxSamples = section.uint32(
      "max_samples", Range::closed(4.0, static_cast<double>(io::kDtmMaxSamplesLimit)),
      static_cast<std::uint32_t>(io::DtmLoadOptions{}.maxSamples));
  section.warnUnknownKeys();
  return config;
}

}  // namespace vp::config::detail
