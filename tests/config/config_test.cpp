// Tests of config/config: the shipped default file, the documented defaults, and that every
// malformed key is reported with the file and its full key path.
#include "config/config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace vp::config {
namespace {

namespace fs = std::filesystem;

// A complete configuration with every key; the malformed cases below edit one line of it.
constexpr const char* kFullConfig = R"(origin:
  latitude_deg: 43.0731
  longitude_deg: -89.4012
  height_m: 260.0
camera:
  width_px: 2592
  height_px: 2048
  fx_px: 2900.0
  fy_px: 2910.0
  cx_px: 1295.5
  cy_px: 1023.5
  lens_model: brown_conrady
  distortion:
    k1: -0.12
    k2: 0.08
    p1: 0.0001
    p2: -0.0002
    k3: -0.01
mount:
  roll_deg: 1.0
  pitch_deg: 2.0
  yaw_deg: 3.0
  lever_arm_m: [0.0, 0.0, 0.1]
  gimbal:
    reference: body
    roll_deg: 0.0
    pitch_deg: -90.0
    yaw_deg: 0.0
terrain:
  dtm_path: dtm/site.tif
  crs: utm:16N
)";

// Only the required keys.
constexpr const char* kMinimalConfig = R"(origin:
  latitude_deg: 43.0731
  longitude_deg: -89.4012
  height_m: 260.0
camera:
  width_px: 640
  height_px: 480
  fx_px: 500.0
  fy_px: 501.0
terrain:
  dtm_path: dtm.tif
)";

constexpr const char* kSource = "site.yaml";
constexpr const char* kBaseDir = "/data/site";

AppConfig parse(const std::string& text) {
  return parseConfig(text, kSource, kBaseDir);
}

// The message of the ConfigError that parsing throws, or "" when it does not throw.
std::string errorOf(const std::string& text) {
  try {
    parse(text);
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "";
}

// kFullConfig with `from` (which must occur exactly once) replaced by `to`.
std::string edited(const std::string& from, const std::string& to) {
  std::string text = kFullConfig;
  const std::size_t at = text.find(from);
  if (at == std::string::npos || text.find(from, at + 1) != std::string::npos) {
    ADD_FAILURE() << "'" << from << "' does not occur exactly once in the base config";
    return text;
  }
  return text.replace(at, from.size(), to);
}

TEST(ConfigDefaultFile, ParsesWithoutWarningsToTheDocumentedValues) {
  const std::string path = std::string(VP_SOURCE_DIR) + "/config/default.yaml";
  const AppConfig config = loadConfig(path);
  EXPECT_TRUE(config.warnings.empty()) << config.warnings.front();
  EXPECT_EQ(config.sourcePath, path);

  EXPECT_DOUBLE_EQ(config.origin.latitudeDeg, 43.0731);
  EXPECT_DOUBLE_EQ(config.origin.longitudeDeg, -89.4012);
  EXPECT_DOUBLE_EQ(config.origin.heightM, 260.0);

  const camera::Intrinsics& in = config.camera.intrinsics;
  EXPECT_EQ(in.widthPx, 2592);
  EXPECT_EQ(in.heightPx, 2048);
  EXPECT_DOUBLE_EQ(in.fxPx, 2900.0);
  EXPECT_DOUBLE_EQ(in.fyPx, 2900.0);
  EXPECT_DOUBLE_EQ(in.cxPx, 1295.5);
  EXPECT_DOUBLE_EQ(in.cyPx, 1023.5);
  const camera::Distortion& lens = config.camera.distortion;
  EXPECT_EQ(lens.model, camera::LensModel::BrownConrady);
  EXPECT_DOUBLE_EQ(lens.k1, -0.12);
  EXPECT_DOUBLE_EQ(lens.k2, 0.08);
  EXPECT_DOUBLE_EQ(lens.p1, 0.0001);
  EXPECT_DOUBLE_EQ(lens.p2, -0.0002);
  EXPECT_DOUBLE_EQ(lens.k3, -0.01);

  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.rollDeg, 0.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.pitchDeg, 0.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.yawDeg, 0.0);
  EXPECT_EQ(config.mount.mount.leverArmM, Eigen::Vector3d(0.0, 0.0, 0.1));
  EXPECT_EQ(config.mount.gimbal.reference, geodesy::GimbalReference::Body);
  EXPECT_DOUBLE_EQ(config.mount.gimbal.angles.rollDeg, 0.0);
  EXPECT_DOUBLE_EQ(config.mount.gimbal.angles.pitchDeg, -90.0);
  EXPECT_DOUBLE_EQ(config.mount.gimbal.angles.yawDeg, 0.0);

  const fs::path dtm =
      (fs::path(VP_SOURCE_DIR) / "tests/fixtures/dtm/sloped_utm16n.tif").lexically_normal();
  EXPECT_EQ(config.terrain.dtmPath, dtm.string());
  EXPECT_FALSE(config.terrain.crs.has_value());
}

TEST(ConfigDefaults, RequiredKeysOnlyGetTheDocumentedDefaults) {
  const AppConfig config = parse(kMinimalConfig);
  EXPECT_TRUE(config.warnings.empty());
  EXPECT_EQ(config.sourcePath, kSource);

  const camera::Intrinsics& in = config.camera.intrinsics;
  EXPECT_EQ(in.widthPx, 640);
  EXPECT_EQ(in.heightPx, 480);
  EXPECT_DOUBLE_EQ(in.fxPx, 500.0);
  EXPECT_DOUBLE_EQ(in.fyPx, 501.0);
  EXPECT_DOUBLE_EQ(in.cxPx, 319.5);  // (width_px - 1) / 2
  EXPECT_DOUBLE_EQ(in.cyPx, 239.5);  // (height_px - 1) / 2
  const camera::Distortion& lens = config.camera.distortion;
  EXPECT_EQ(lens.model, camera::LensModel::Pinhole);
  EXPECT_EQ(lens.k1, 0.0);
  EXPECT_EQ(lens.k2, 0.0);
  EXPECT_EQ(lens.p1, 0.0);
  EXPECT_EQ(lens.p2, 0.0);
  EXPECT_EQ(lens.k3, 0.0);

  EXPECT_EQ(config.mount.mount.bodyToBase.rollDeg, 0.0);
  EXPECT_EQ(config.mount.mount.bodyToBase.pitchDeg, 0.0);
  EXPECT_EQ(config.mount.mount.bodyToBase.yawDeg, 0.0);
  EXPECT_EQ(config.mount.mount.leverArmM, Eigen::Vector3d::Zero());
  EXPECT_EQ(config.mount.gimbal.reference, geodesy::GimbalReference::Body);
  EXPECT_EQ(config.mount.gimbal.angles.rollDeg, 0.0);
  EXPECT_EQ(config.mount.gimbal.angles.pitchDeg, -90.0);  // nadir
  EXPECT_EQ(config.mount.gimbal.angles.yawDeg, 0.0);

  EXPECT_EQ(config.terrain.dtmPath, "/data/site/dtm.tif");
  EXPECT_FALSE(config.terrain.crs.has_value());  // auto
}

TEST(ConfigValues, FullConfigReadsEveryKey) {
  const AppConfig config = parse(kFullConfig);
  EXPECT_TRUE(config.warnings.empty());
  EXPECT_DOUBLE_EQ(config.camera.intrinsics.fyPx, 2910.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.rollDeg, 1.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.pitchDeg, 2.0);
  EXPECT_DOUBLE_EQ(config.mount.mount.bodyToBase.yawDeg, 3.0);
  ASSERT_TRUE(config.terrain.crs.has_value());
  EXPECT_EQ(config.terrain.crs->kind, terrain::HorizontalCrs::Utm);
  EXPECT_EQ(config.terrain.crs->utmZone, 16);
  EXPECT_TRUE(config.terrain.crs->utmNorth);
}

TEST(ConfigValues, OtherEnumValuesAndNumberSpellings) {
  std::string text = edited("lens_model: brown_conrady", "lens_model: equivalent_spherical");
  text.replace(text.find("distortion:"), std::string("distortion:").size(), "x_distortion:");
  const std::size_t gimbal = text.find("reference: body");
  text.replace(gimbal, std::string("reference: body").size(), "reference: earth");
  text.replace(text.find("crs: utm:16N"), std::string("crs: utm:16N").size(), "crs: WGS84");
  text.replace(text.find("fx_px: 2900.0"), std::string("fx_px: 2900.0").size(), "fx_px: +2.9e3");
  const AppConfig config = parse(text);
  EXPECT_EQ(config.camera.distortion.model, camera::LensModel::EquivalentSpherical);
  EXPECT_EQ(config.mount.gimbal.reference, geodesy::GimbalReference::Earth);
  ASSERT_TRUE(config.terrain.crs.has_value());
  EXPECT_EQ(config.terrain.crs->kind, terrain::HorizontalCrs::Wgs84Geographic);
  EXPECT_DOUBLE_EQ(config.camera.intrinsics.fxPx, 2900.0);
  ASSERT_EQ(config.warnings.size(), 1U);  // the renamed distortion section
  EXPECT_EQ(config.warnings[0], "site.yaml: unknown key 'camera.x_distortion'");
}

// The acceptance test: one malformed key per row; the error must name the source and the
// key's full path, and say what is wrong.
struct MalformedCase {
  const char* from;     // text of kFullConfig to replace (occurs once)
  const char* to;       // its replacement
  const char* path;     // full key path the message must name
  const char* problem;  // part of the message after the path
};

const MalformedCase kMalformedCases[] = {
    // origin
    {"origin:\n  latitude_deg: 43.0731\n  longitude_deg: -89.4012\n  height_m: 260.0\n", "",
     "origin", "missing (required)"},
    {"origin:\n  latitude_deg: 43.0731\n  longitude_deg: -89.4012\n  height_m: 260.0\n",
     "origin: 43.0\n", "origin", "expected a map, got '43.0'"},
    {"  latitude_deg: 43.0731\n", "", "origin.latitude_deg", "missing (required)"},
    {"latitude_deg: 43.0731", "latitude_deg: abc", "origin.latitude_deg",
     "expected a number, got 'abc'"},
    {"latitude_deg: 43.0731", "latitude_deg: 90.5", "origin.latitude_deg",
     "must be in [-90, 90], got 90.5"},
    {"latitude_deg: 43.0731", "latitude_deg: .nan", "origin.latitude_deg",
     "must be finite, got .nan"},
    {"  longitude_deg: -89.4012\n", "", "origin.longitude_deg", "missing (required)"},
    {"longitude_deg: -89.4012", "longitude_deg: -180.5", "origin.longitude_deg",
     "must be in [-180, 180], got -180.5"},
    {"longitude_deg: -89.4012", "longitude_deg: [1, 2]", "origin.longitude_deg",
     "expected a number, got a sequence of 2 element(s)"},
    {"  height_m: 260.0\n", "", "origin.height_m", "missing (required)"},
    {"height_m: 260.0", "height_m: 9001", "origin.height_m", "must be in [-500, 9000], got 9001"},
    {"height_m: 260.0", "height_m: -.inf", "origin.height_m", "must be finite, got -.inf"},
    {"height_m: 260.0", "height_m:", "origin.height_m", "expected a number, got nothing (null)"},
    // camera
    {"camera:\n  width_px", "cam:\n  width_px", "camera", "missing (required)"},
    {"camera:\n  width_px: 2592\n", "camera: [1]\nx:\n  width_px: 2592\n", "camera",
     "expected a map, got a sequence of 1 element(s)"},
    {"  width_px: 2592\n", "", "camera.width_px", "missing (required)"},
    {"width_px: 2592", "width_px: 2592.5", "camera.width_px", "expected an integer, got '2592.5'"},
    {"width_px: 2592", "width_px: 15", "camera.width_px", "must be in [16, 16384], got 15"},
    {"width_px: 2592", "width_px: wide", "camera.width_px", "expected an integer, got 'wide'"},
    {"  height_px: 2048\n", "", "camera.height_px", "missing (required)"},
    {"height_px: 2048", "height_px: 16385", "camera.height_px",
     "must be in [16, 16384], got 16385"},
    {"height_px: 2048", "height_px: .inf", "camera.height_px", "must be finite, got .inf"},
    {"  fx_px: 2900.0\n", "", "camera.fx_px", "missing (required)"},
    {"fx_px: 2900.0", "fx_px: -3", "camera.fx_px", "must be > 0, got -3"},
    {"fx_px: 2900.0", "fx_px: 0", "camera.fx_px", "must be > 0, got 0"},
    {"fx_px: 2900.0", "fx_px: {value: 2900}", "camera.fx_px", "expected a number, got a map"},
    {"fx_px: 2900.0", "fx_px: \"2900\"", "camera.fx_px",
     "expected a number, got the quoted string '2900'"},
    {"fx_px: 2900.0", "fx_px: 2900.0\n  fx_px: 2901.0", "camera.fx_px", "duplicate key"},
    {"  fy_px: 2910.0\n", "", "camera.fy_px", "missing (required)"},
    {"fy_px: 2910.0", "fy_px: .NaN", "camera.fy_px", "must be finite, got .NaN"},
    {"fy_px: 2910.0", "fy_px: 2910px", "camera.fy_px", "expected a number, got '2910px'"},
    {"cx_px: 1295.5", "cx_px: 2592", "camera.cx_px", "must be in [-0.5, 2591.5], got 2592"},
    {"cx_px: 1295.5", "cx_px: centre", "camera.cx_px", "expected a number, got 'centre'"},
    {"cy_px: 1023.5", "cy_px: -1", "camera.cy_px", "must be in [-0.5, 2047.5], got -1"},
    {"cy_px: 1023.5", "cy_px: [1, 2]", "camera.cy_px", "expected a number, got a sequence"},
    {"lens_model: brown_conrady", "lens_model: fisheye", "camera.lens_model",
     "unknown value 'fisheye' (expected pinhole, brown_conrady, equivalent_spherical)"},
    {"lens_model: brown_conrady", "lens_model: [pinhole]", "camera.lens_model",
     "expected a string, got a sequence of 1 element(s)"},
    {"lens_model: brown_conrady", "lens_model: ''", "camera.lens_model", "must not be empty"},
    {"  distortion:\n", "  distortion: 0.1\n  x:\n", "camera.distortion",
     "expected a map, got '0.1'"},
    {"k1: -0.12", "k1: abc", "camera.distortion.k1", "expected a number, got 'abc'"},
    {"k2: 0.08", "k2: .inf", "camera.distortion.k2", "must be finite, got .inf"},
    {"p1: 0.0001", "p1: 1000", "camera.distortion.p1", "must be in [-100, 100], got 1000"},
    {"p2: -0.0002", "p2: {a: 1}", "camera.distortion.p2", "expected a number, got a map"},
    {"k3: -0.01", "k3: nan", "camera.distortion.k3", "must be finite, got nan"},
    // mount
    {"mount:\n  roll_deg: 1.0\n", "mount: level\nx:\n  roll_deg: 1.0\n", "mount",
     "expected a map, got 'level'"},
    {"  roll_deg: 1.0", "  roll_deg: 181", "mount.roll_deg", "must be in [-180, 180], got 181"},
    {"  pitch_deg: 2.0", "  pitch_deg: 90.1", "mount.pitch_deg", "must be in [-90, 90], got 90.1"},
    {"  yaw_deg: 3.0", "  yaw_deg: east", "mount.yaw_deg", "expected a number, got 'east'"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0.0, 0.1]", "mount.lever_arm_m",
     "expected a sequence of 3 numbers [x, y, z], got a sequence of 2 element(s)"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0, 0, 0, 1]", "mount.lever_arm_m",
     "got a sequence of 4 element(s)"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: 0.1", "mount.lever_arm_m",
     "expected a sequence of 3 numbers [x, y, z], got '0.1'"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: {x: 0}", "mount.lever_arm_m",
     "expected a sequence of 3 numbers [x, y, z], got a map"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0.0, x, 0.1]", "mount.lever_arm_m[1]",
     "expected a number, got 'x'"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [0.0, 0.0, 11]", "mount.lever_arm_m[2]",
     "must be in [-10, 10], got 11"},
    {"lever_arm_m: [0.0, 0.0, 0.1]", "lever_arm_m: [.nan, 0.0, 0.1]", "mount.lever_arm_m[0]",
     "must be finite, got .nan"},
    {"  gimbal:\n", "  gimbal: [0, -90, 0]\n  x:\n", "mount.gimbal",
     "expected a map, got a sequence of 3 element(s)"},
    {"reference: body", "reference: world", "mount.gimbal.reference",
     "unknown value 'world' (expected body, earth)"},
    {"reference: body", "reference: {frame: body}", "mount.gimbal.reference",
     "expected a string, got a map"},
    {"    roll_deg: 0.0", "    roll_deg: 200", "mount.gimbal.roll_deg",
     "must be in [-180, 180], got 200"},
    {"    pitch_deg: -90.0", "    pitch_deg: -121", "mount.gimbal.pitch_deg",
     "must be in [-120, 30], got -121"},
    {"    pitch_deg: -90.0", "    pitch_deg: 31", "mount.gimbal.pitch_deg",
     "must be in [-120, 30], got 31"},
    {"    yaw_deg: 0.0", "    yaw_deg: abc", "mount.gimbal.yaw_deg",
     "expected a number, got 'abc'"},
    {"    yaw_deg: 0.0", "    yaw_deg: .inf", "mount.gimbal.yaw_deg", "must be finite, got .inf"},
    // terrain
    {"terrain:\n  dtm_path: dtm/site.tif\n  crs: utm:16N\n", "", "terrain", "missing (required)"},
    {"terrain:\n  dtm_path", "terrain: dtm.tif\nx:\n  dtm_path", "terrain",
     "expected a map, got 'dtm.tif'"},
    {"  dtm_path: dtm/site.tif\n", "", "terrain.dtm_path", "missing (required)"},
    {"dtm_path: dtm/site.tif", "dtm_path: \"\"", "terrain.dtm_path", "must not be empty"},
    {"dtm_path: dtm/site.tif", "dtm_path: [a.tif, b.tif]", "terrain.dtm_path",
     "expected a string, got a sequence of 2 element(s)"},
    {"dtm_path: dtm/site.tif", "dtm_path:", "terrain.dtm_path",
     "expected a string, got nothing (null)"},
    {"crs: utm:16N", "crs: utm:61N", "terrain.crs", "unknown value 'utm:61N' (expected auto"},
    {"crs: utm:16N", "crs: utm:16X", "terrain.crs", "unknown value 'utm:16X'"},
    {"crs: utm:16N", "crs: epsg:4326", "terrain.crs", "unknown value 'epsg:4326'"},
    {"crs: utm:16N", "crs: {zone: 16}", "terrain.crs", "expected a string, got a map"},
};

TEST(ConfigMalformed, EachBrokenKeyIsReportedWithSourceAndFullPath) {
  for (const MalformedCase& row : kMalformedCases) {
    SCOPED_TRACE(std::string(row.path) + " <- '" + row.to + "'");
    const std::string message = errorOf(edited(row.from, row.to));
    const std::string prefix = std::string(kSource) + ": " + row.path + ": ";
    EXPECT_EQ(message.rfind(prefix, 0), 0U) << message;
    EXPECT_NE(message.find(row.problem, prefix.size()), std::string::npos) << message;
  }
}

TEST(ConfigMalformed, TableCoversEveryKeyOfTheSchema) {
  const std::vector<std::string> schemaKeys = {"origin",
                                               "origin.latitude_deg",
                                               "origin.longitude_deg",
                                               "origin.height_m",
                                               "camera",
                                               "camera.width_px",
                                               "camera.height_px",
                                               "camera.fx_px",
                                               "camera.fy_px",
                                               "camera.cx_px",
                                               "camera.cy_px",
                                               "camera.lens_model",
                                               "camera.distortion",
                                               "camera.distortion.k1",
                                               "camera.distortion.k2",
                                               "camera.distortion.p1",
                                               "camera.distortion.p2",
                                               "camera.distortion.k3",
                                               "mount",
                                               "mount.roll_deg",
                                               "mount.pitch_deg",
                                               "mount.yaw_deg",
                                               "mount.lever_arm_m",
                                               "mount.gimbal",
                                               "mount.gimbal.reference",
                                               "mount.gimbal.roll_deg",
                                               "mount.gimbal.pitch_deg",
                                               "mount.gimbal.yaw_deg",
                                               "terrain",
                                               "terrain.dtm_path",
                                               "terrain.crs"};
  for (const std::string& key : schemaKeys) {
    bool covered = false;
    for (const MalformedCase& row : kMalformedCases) {
      covered = covered || key == row.path;
    }
    EXPECT_TRUE(covered) << key;
  }
}

TEST(ConfigMalformed, MessagesReadAsDocumented) {
  EXPECT_EQ(errorOf(edited("fx_px: 2900.0", "fx_px: -3")),
            "site.yaml: camera.fx_px: must be > 0, got -3");
  EXPECT_EQ(errorOf(edited("  width_px: 2592\n", "")),
            "site.yaml: camera.width_px: missing (required)");
  EXPECT_EQ(errorOf(edited("lens_model: brown_conrady", "lens_model: fisheye")),
            "site.yaml: camera.lens_model: unknown value 'fisheye' (expected pinhole, "
            "brown_conrady, equivalent_spherical)");
  EXPECT_EQ(errorOf(edited("latitude_deg: 43.0731", "latitude_deg: abc")),
            "site.yaml: origin.latitude_deg: expected a number, got 'abc'");
}

TEST(ConfigWarnings, UnknownKeysAtEveryLevelAreNamedButNotFatal) {
  std::string text = edited("  fx_px: 2900.0\n", "  fx_px: 2900.0\n  fxx: 1\n");
  text.replace(text.find("origin:\n"), 8, "origin:\n  datum: wgs84\n");
  text.replace(text.find("    k3: -0.01\n"), 14, "    k3: -0.01\n    k4: 0.0\n");
  text.replace(text.find("  gimbal:\n"), 10, "  gimbal:\n    mode: follow\n");
  text.replace(text.find("  crs: utm:16N\n"), 15, "  crs: utm:16N\n  geoid: egm96\n");
  text += "logging:\n  level: debug\n";
  const AppConfig config = parse(text);
  const std::vector<std::string> expected = {
      "site.yaml: unknown key 'origin.datum'",
      "site.yaml: unknown key 'camera.distortion.k4'",  // a section reports when it is read
      "site.yaml: unknown key 'camera.fxx'",
      "site.yaml: unknown key 'mount.gimbal.mode'",
      "site.yaml: unknown key 'terrain.geoid'",
      "site.yaml: unknown key 'logging'",  // a whole unknown section is one warning
  };
  EXPECT_EQ(config.warnings, expected);
  EXPECT_DOUBLE_EQ(config.camera.intrinsics.fxPx, 2900.0);
}

TEST(ConfigWarnings, DistortionWithAnotherLensModelIsIgnoredWithAWarning) {
  const AppConfig config = parse(edited("lens_model: brown_conrady", "lens_model: pinhole"));
  ASSERT_EQ(config.warnings.size(), 1U);
  EXPECT_EQ(config.warnings[0],
            "site.yaml: camera.distortion: ignored: only lens_model brown_conrady uses it");
  EXPECT_EQ(config.camera.distortion.model, camera::LensModel::Pinhole);
  EXPECT_EQ(config.camera.distortion.k1, 0.0);
  EXPECT_EQ(config.camera.distortion.k3, 0.0);
}

TEST(ConfigSyntax, YamlErrorNamesTheSourceAndLine) {
  const std::string message = errorOf("origin:\n  latitude_deg: [43.0\ncamera: {\n");
  EXPECT_EQ(message.rfind("site.yaml: YAML syntax error at line 3, column ", 0), 0U) << message;
  const std::string badIndent = errorOf("origin:\n  latitude_deg: 1\n longitude_deg: 2\n");
  EXPECT_EQ(badIndent.rfind("site.yaml: YAML syntax error at line 3, column ", 0), 0U) << badIndent;
}

TEST(ConfigSyntax, EmptyOrNonMapDocumentIsAClearError) {
  EXPECT_EQ(errorOf(""),
            "site.yaml: the configuration is empty (expected the sections origin, camera, "
            "terrain)");
  EXPECT_EQ(errorOf("# only a comment\n"), errorOf(""));
  EXPECT_EQ(errorOf("- origin\n- camera\n"),
            "site.yaml: expected a map of sections at the top level, got a sequence of 2 "
            "element(s)");
}

TEST(ConfigPaths, RelativeDtmPathIsResolvedAgainstTheBaseDirectory) {
  EXPECT_EQ(parse(kFullConfig).terrain.dtmPath, "/data/site/dtm/site.tif");
  EXPECT_FALSE(parse(edited("crs: utm:16N", "crs: Auto")).terrain.crs.has_value());
  const std::string up = edited("dtm_path: dtm/site.tif", "dtm_path: ../shared/./dtm.tif");
  EXPECT_EQ(parse(up).terrain.dtmPath, "/data/shared/dtm.tif");
  const std::string absolute = edited("dtm_path: dtm/site.tif", "dtm_path: /maps/dtm.tif");
  EXPECT_EQ(parse(absolute).terrain.dtmPath, "/maps/dtm.tif");
}

TEST(ConfigFile, LoadResolvesAgainstTheFilesDirectoryAndReportsMissingFiles) {
  const fs::path dir = fs::temp_directory_path() / "vp_config_test" / "site";
  fs::create_directories(dir);
  const fs::path file = dir / "site.yaml";
  std::ofstream(file) << kFullConfig;
  const AppConfig config = loadConfig(file.string());
  EXPECT_EQ(config.terrain.dtmPath,
            (fs::absolute(dir) / "dtm/site.tif").lexically_normal().string());
  EXPECT_EQ(config.sourcePath, file.string());

  const std::string missing = (dir / "absent.yaml").string();
  try {
    loadConfig(missing);
    ADD_FAILURE() << "no error for a missing file";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()), missing + ": cannot open configuration file");
  }
  // Errors from a file carry the path it was loaded from.
  std::ofstream(file) << "origin: 1\n";
  try {
    loadConfig(file.string());
    ADD_FAILURE() << "no error for a malformed file";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()), file.string() + ": origin: expected a map, got '1'");
  }
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace vp::config
