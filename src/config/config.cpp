// config/config: YAML text -> AppConfig.
//
// Every key goes through MapReader, which knows the key path of the section it reads (for
// messages) and records which keys were read, so that whatever is left over becomes an
// "unknown key" warning. Reading one key is then one line that states its type, range and
// default, which is what docs/configuration.md documents; keep the two in step.
#include "config/config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace vp::config {
namespace {

namespace fs = std::filesystem;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Passed as the default of a key the file must give.
constexpr std::nullopt_t kRequired = std::nullopt;

// Shortest text that reads back as the same double ("0.1", "-90", "16384").
std::string formatNumber(double value) {
  char buffer[32];
  // Whole numbers in plain digits ("100000", not the shorter "1e+05").
  constexpr double kPlainLimit = 1e15;
  const bool whole = std::abs(value) < kPlainLimit && value == std::floor(value);
  const auto result =
      whole ? std::to_chars(std::begin(buffer), std::end(buffer), value, std::chars_format::fixed)
            : std::to_chars(std::begin(buffer), std::end(buffer), value);
  return std::string(buffer, result.ptr);
}

// Accepted interval of a numeric key; bounds are inclusive unless marked open.
struct Range {
  double lo = -kInf;
  double hi = kInf;
  bool loOpen = false;

  static Range closed(double low, double high) { return Range{low, high, false}; }
  static Range positive() { return Range{0.0, kInf, true}; }

  bool contains(double value) const { return (loOpen ? value > lo : value >= lo) && value <= hi; }
  std::string describe() const {
    if (std::isinf(hi)) {
      return (loOpen ? "must be > " : "must be >= ") + formatNumber(lo);
    }
    return std::string("must be in ") + (loOpen ? "(" : "[") + formatNumber(lo) + ", " +
           formatNumber(hi) + "]";
  }
};

// Where messages go: errors throw ConfigError, remarks are collected as warnings. Both
// start with the source name so that a log line alone says which file is meant.
class Diagnostics {
 public:
  Diagnostics(std::string sourceName, std::vector<std::string>* warnings)
      : source_(std::move(sourceName)), warnings_(warnings) {}

  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw ConfigError(source_ + ": " + (path.empty() ? problem : path + ": " + problem));
  }
  void warn(const std::string& remark) const { warnings_->push_back(source_ + ": " + remark); }

 private:
  std::string source_;
  std::vector<std::string>* warnings_;
};

// What a node is, for "expected X, got Y" messages.
std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a sequence of " + std::to_string(node.size()) + " element(s)";
    case YAML::NodeType::Scalar:
      // yaml-cpp tags quoted scalars "!": they are strings even when they look like numbers.
      return (node.Tag() == "!" ? "the quoted string '" : "'") + node.Scalar() + "'";
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      break;
  }
  return "nothing (null)";
}

// A plain YAML scalar as a number. YAML spells infinity and NaN ".inf" and ".nan"; they are
// parsed (and then rejected as not finite) rather than reported as "not a number".
std::optional<double> parseNumber(std::string_view text) {
  if (text.size() > 1 && text.front() == '+' && text[1] != '-') {
    text.remove_prefix(1);  // from_chars does not take an explicit '+'
  }
  const bool negative = !text.empty() && text.front() == '-';
  const std::string_view magnitude = negative ? text.substr(1) : text;
  for (const std::string_view inf : {".inf", ".Inf", ".INF"}) {
    if (magnitude == inf) {
      return negative ? -kInf : kInf;
    }
  }
  for (const std::string_view nan : {".nan", ".NaN", ".NAN"}) {
    if (text == nan) {
      return std::numeric_limits<double>::quiet_NaN();
    }
  }
  double value = 0.0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size()) {
    return std::nullopt;
  }
  return value;
}

// A finite number from a scalar node; `what` names the expected kind for the message.
double readFinite(const YAML::Node& node, const std::string& path, const char* what,
                  const Diagnostics& diag) {
  const std::optional<double> value =
      node.IsScalar() && node.Tag() != "!" ? parseNumber(node.Scalar()) : std::nullopt;
  if (!value) {
    diag.fail(path, std::string("expected ") + what + ", got " + describe(node));
  }
  if (!std::isfinite(*value)) {
    diag.fail(path, "must be finite, got " + node.Scalar());
  }
  return *value;
}

double readNumber(const YAML::Node& node, const std::string& path, const Range& range,
                  const Diagnostics& diag) {
  const double value = readFinite(node, path, "a number", diag);
  if (!range.contains(value)) {
    diag.fail(path, range.describe() + ", got " + node.Scalar());
  }
  return value;
}

// Any integer a double holds exactly (|value| < 2^53); the caller's range bounds it further.
std::int64_t readInteger(const YAML::Node& node, const std::string& path, const Range& range,
                         const Diagnostics& diag) {
  const double value = readFinite(node, path, "an integer", diag);
  if (value != std::floor(value)) {
    diag.fail(path, "expected an integer, got " + describe(node));
  }
  if (!range.contains(value)) {
    diag.fail(path, range.describe() + ", got " + node.Scalar());
  }
  return static_cast<std::int64_t>(value);  // in range, so it fits
}

// YAML 1.2 core booleans only: true/false in any case. yaml-cpp would also take yes/no/on/off,
// which are strings in YAML 1.2 and a classic source of surprises.
bool readBoolean(const YAML::Node& node, const std::string& path, const Diagnostics& diag) {
  if (node.IsScalar() && node.Tag() != "!") {
    std::string lower = node.Scalar();
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "true") {
      return true;
    }
    if (lower == "false") {
      return false;
    }
  }
  diag.fail(path, "expected true or false, got " + describe(node));
}

// A non-empty string; no key of the schema has a meaningful empty value.
std::string readText(const YAML::Node& node, const std::string& path, const Diagnostics& diag) {
  if (!node.IsScalar()) {
    diag.fail(path, "expected a string, got " + describe(node));
  }
  if (node.Scalar().empty()) {
    diag.fail(path, "must not be empty");
  }
  return node.Scalar();
}

// One YAML map of the file: typed getters by key, each marking the key as read.
class MapReader {
 public:
  // A missing or null node reads as an empty map, so that an optional section that is
  // absent, or present with all its keys commented out, gives the defaults.
  MapReader(const YAML::Node& node, std::string path, const Diagnostics& diag)
      : path_(std::move(path)), diag_(diag) {
    if (!node.IsDefined() || node.IsNull()) {
      return;
    }
    if (!node.IsMap()) {
      diag_.fail(path_, "expected a map, got " + describe(node));
    }
    for (const auto& item : node) {
      std::string key = item.first.Scalar();
      // yaml-cpp keeps duplicate keys and returns the first; the author meant one of them.
      if (find(key) != nullptr) {
        diag_.fail(childPath(key), "duplicate key");
      }
      entries_.push_back(Entry{std::move(key), item.second, false});
    }
  }

  // The getters take the default as their last argument; kRequired makes the key required.
  double number(std::string_view key, const Range& range, std::optional<double> fallback) {
    const YAML::Node* node = take(key, !fallback);
    return node ? readNumber(*node, childPath(key), range, diag_) : *fallback;
  }
  int integer(std::string_view key, const Range& range, std::optional<int> fallback) {
    const YAML::Node* node = take(key, !fallback);
    // The ranges of int keys lie within int.
    return node ? static_cast<int>(readInteger(*node, childPath(key), range, diag_)) : *fallback;
  }
  // An unsigned 32-bit integer (DDS ids); the range must lie within [0, 2^32 - 1].
  std::uint32_t uint32(std::string_view key, const Range& range,
                       std::optional<std::uint32_t> fallback) {
    const YAML::Node* node = take(key, !fallback);
    return node ? static_cast<std::uint32_t>(readInteger(*node, childPath(key), range, diag_))
                : *fallback;
  }
  bool boolean(std::string_view key, std::optional<bool> fallback) {
    const YAML::Node* node = take(key, !fallback);
    return node ? readBoolean(*node, childPath(key), diag_) : *fallback;
  }
  std::string text(std::string_view key, std::optional<std::string> fallback) {
    const YAML::Node* node = take(key, !fallback);
    return node ? readText(*node, childPath(key), diag_) : *fallback;
  }
  // A string mapped through parse (string -> std::optional<T>); `expected` lists the
  // accepted spellings for the message when parse rejects the value.
  template <class T, class Parse>
  T choice(std::string_view key, Parse parse, std::string_view expected,
           std::optional<T> fallback) {
    const YAML::Node* node = take(key, !fallback);
    if (node == nullptr) {
      return *fallback;
    }
    const std::string value = readText(*node, childPath(key), diag_);
    std::optional<T> parsed = parse(value);
    if (!parsed) {
      diag_.fail(childPath(key),
                 "unknown value '" + value + "' (expected " + std::string(expected) + ")");
    }
    return *std::move(parsed);
  }
  // A sequence of exactly three numbers [x, y, z], each in range.
  Eigen::Vector3d vector3(std::string_view key, const Range& range,
                          std::optional<Eigen::Vector3d> fallback) {
    const YAML::Node* node = take(key, !fallback);
    if (node == nullptr) {
      return *fallback;
    }
    const std::string path = childPath(key);
    if (!node->IsSequence() || node->size() != 3) {
      diag_.fail(path, "expected a sequence of 3 numbers [x, y, z], got " + describe(*node));
    }
    Eigen::Vector3d vector;
    for (int i = 0; i < 3; ++i) {
      vector[i] = readNumber((*node)[i], path + "[" + std::to_string(i) + "]", range, diag_);
    }
    return vector;
  }
  // A sequence of integers, each in range: exactly `count` of them, or any number (also
  // none) when count < 0. The key must be present (callers test has() first).
  std::vector<int> integers(std::string_view key, const Range& range, int count) {
    const YAML::Node* node = take(key, true);
    const std::string path = childPath(key);
    if (!node->IsSequence() || (count >= 0 && node->size() != static_cast<std::size_t>(count))) {
      const std::string what = count >= 0 ? "a sequence of " + std::to_string(count) + " integers"
                                          : std::string("a sequence of integers");
      diag_.fail(path, "expected " + what + ", got " + describe(*node));
    }
    std::vector<int> values;
    for (std::size_t i = 0; i < node->size(); ++i) {
      values.push_back(static_cast<int>(
          readInteger((*node)[i], path + "[" + std::to_string(i) + "]", range, diag_)));
    }
    return values;
  }
  // A non-empty sequence of strings, each mapped through parse (see choice()).
  template <class T, class Parse>
  std::vector<T> choices(std::string_view key, Parse parse, std::string_view expected) {
    const YAML::Node* node = take(key, true);
    const std::string path = childPath(key);
    if (!node->IsSequence() || node->size() == 0) {
      diag_.fail(path, "expected a non-empty sequence of " + std::string(expected) + ", got " +
                           describe(*node));
    }
    std::vector<T> values;
    for (std::size_t i = 0; i < node->size(); ++i) {
      const std::string itemPath = path + "[" + std::to_string(i) + "]";
      const std::string value = readText((*node)[i], itemPath, diag_);
      std::optional<T> parsed = parse(value);
      if (!parsed) {
        diag_.fail(itemPath,
                   "unknown value '" + value + "' (expected " + std::string(expected) + ")");
      }
      values.push_back(*std::move(parsed));
    }
    return values;
  }
  // A nested section; an optional one that is absent reads as empty (all defaults).
  MapReader section(std::string_view key) { return sectionOf(key, take(key, false)); }
  MapReader requiredSection(std::string_view key) { return sectionOf(key, take(key, true)); }

  bool has(std::string_view key) const { return find(key) != nullptr; }
  [[noreturn]] void fail(std::string_view key, const std::string& problem) const {
    diag_.fail(childPath(key), problem);
  }
  void warn(std::string_view key, const std::string& remark) const {
    diag_.warn(childPath(key) + ": " + remark);
  }
  // Call once all keys of the section were read: the rest are unknown to the schema.
  void warnUnknownKeys() const {
    for (const Entry& entry : entries_) {
      if (!entry.used) {
        diag_.warn("unknown key '" + childPath(entry.key) + "'");
      }
    }
  }

 private:
  struct Entry {
    std::string key;
    YAML::Node value;
    bool used = false;
  };

  const Entry* find(std::string_view key) const {
    for (const Entry& entry : entries_) {
      if (entry.key == key) {
        return &entry;
      }
    }
    return nullptr;
  }
  // The value of key, marked as read; nullptr when absent (an error when required).
  const YAML::Node* take(std::string_view key, bool required) {
    for (Entry& entry : entries_) {
      if (entry.key == key) {
        entry.used = true;
        return &entry.value;
      }
    }
    if (required) {
      diag_.fail(childPath(key), "missing (required)");
    }
    return nullptr;
  }
  MapReader sectionOf(std::string_view key, const YAML::Node* node) const {
    return MapReader(node ? *node : YAML::Node(), childPath(key), diag_);
  }
  std::string childPath(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }

  std::string path_;
  const Diagnostics& diag_;
  std::vector<Entry> entries_;
};

// --- the schema (docs/configuration.md) ----------------------------------------------------

const Range kLatitudeRangeDeg = Range::closed(-90.0, 90.0);
const Range kLongitudeRangeDeg = Range::closed(-180.0, 180.0);
// Ellipsoidal height of the ENU origin: below the Dead Sea shore to above any launch site.
const Range kOriginHeightRangeM = Range::closed(-500.0, 9000.0);
const Range kImageSizeRangePx = Range::closed(16.0, 16384.0);
// Not a physical limit: |coefficient| > 100 means a unit or copy mistake, not a lens.
const Range kDistortionRange = Range::closed(-100.0, 100.0);
const Range kRollYawRangeDeg = Range::closed(-180.0, 180.0);
const Range kMountPitchRangeDeg = Range::closed(-90.0, 90.0);
// Gimbal heads reach a little past nadir (-90) and somewhat above the horizon.
const Range kGimbalPitchRangeDeg = Range::closed(-120.0, 30.0);
// The camera sits on the airframe: a lever arm of metres more means a unit mistake.
const Range kLeverArmRangeM = Range::closed(-10.0, 10.0);

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

geodesy::GeodeticPoint readOrigin(MapReader section) {
  geodesy::GeodeticPoint origin;
  origin.latitudeDeg = section.number("latitude_deg", kLatitudeRangeDeg, kRequired);
  origin.longitudeDeg = section.number("longitude_deg", kLongitudeRangeDeg, kRequired);
  origin.heightM = section.number("height_m", kOriginHeightRangeM, kRequired);
  section.warnUnknownKeys();
  return origin;
}

CameraConfig readCamera(MapReader section) {
  CameraConfig config;
  camera::Intrinsics& in = config.intrinsics;
  in.widthPx = section.integer("width_px", kImageSizeRangePx, kRequired);
  in.heightPx = section.integer("height_px", kImageSizeRangePx, kRequired);
  in.fxPx = section.number("fx_px", Range::positive(), kRequired);
  in.fyPx = section.number("fy_px", Range::positive(), kRequired);
  // Pixel centres are integers, so the image spans [-0.5, size - 0.5] and its centre is
  // (size - 1) / 2; a principal point outside the image is a calibration error.
  in.cxPx = section.number("cx_px", Range::closed(-0.5, in.widthPx - 0.5), (in.widthPx - 1) / 2.0);
  in.cyPx =
      section.number("cy_px", Range::closed(-0.5, in.heightPx - 0.5), (in.heightPx - 1) / 2.0);

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
  section.warnUnknownKeys();
  return config;
}

geodesy::EulerAnglesDeg readAngles(MapReader& section, const Range& pitchRangeDeg,
                                   const geodesy::EulerAnglesDeg& fallback) {
  geodesy::EulerAnglesDeg angles;
  angles.rollDeg = section.number("roll_deg", kRollYawRangeDeg, fallback.rollDeg);
  angles.pitchDeg = section.number("pitch_deg", pitchRangeDeg, fallback.pitchDeg);
  angles.yawDeg = section.number("yaw_deg", kRollYawRangeDeg, fallback.yawDeg);
  return angles;
}

MountConfig readMount(MapReader section) {
  // The defaults are those of the structs, so code and file agree on "nothing configured".
  const MountConfig defaults;
  MountConfig config;
  config.mount.bodyToBase = readAngles(section, kMountPitchRangeDeg, defaults.mount.bodyToBase);
  config.mount.leverArmM =
      section.vector3("lever_arm_m", kLeverArmRangeM, defaults.mount.leverArmM);
  MapReader gimbal = section.section("gimbal");
  config.gimbal.reference = gimbal.choice<geodesy::GimbalReference>(
      "reference", gimbalReferenceFromString, kGimbalReferenceNames, defaults.gimbal.reference);
  config.gimbal.angles = readAngles(gimbal, kGimbalPitchRangeDeg, defaults.gimbal.angles);
  gimbal.warnUnknownKeys();
  section.warnUnknownKeys();
  return config;
}

// Relative paths are relative to the configuration file, not to the working directory, so
// that a file and its DTM can be moved together. Lexical: existence is the loader's check.
std::string resolvePath(const std::string& text, const std::string& baseDir) {
  fs::path path(text);
  if (path.is_relative()) {
    path = fs::path(baseDir) / path;
  }
  std::error_code error;
  const fs::path absolute = fs::absolute(path, error);
  return (error ? path : absolute).lexically_normal().string();
}

TerrainConfig readTerrain(MapReader section, const std::string& baseDir) {
  TerrainConfig config;
  config.dtmPath = resolvePath(section.text("dtm_path", kRequired), baseDir);
  config.crs = section.choice<std::optional<terrain::CrsSpec>>(
      "crs", crsSettingFromString, kCrsForms, std::optional<terrain::CrsSpec>());
  section.warnUnknownKeys();
  return config;
}

// --- dds: (docs/configuration.md, docs/dds.md) ----------------------------------------------

// DDS domain ids: Cyclone accepts 0..232 (the RTPS port formula with the default port mapping).
const Range kDomainIdRange = Range::closed(0.0, 232.0);
const Range kDroneIdRange = Range::closed(0.0, 4294967295.0);
// How long a reliable write may block when the writer's history is full: beyond 10 s the loop
// would miss many frames, which is never wanted.
const Range kMaxBlockingRangeS = Range::closed(0.0, 10.0);
const Range kHistoryDepthRange = Range::closed(1.0, 1000.0);
// Deadline, lifespan, liveliness lease: 0 = off; an hour is far beyond any useful setting.
const Range kQosDurationRangeS = Range::closed(0.0, 3600.0);
const Range kStatusRateRangeHz = Range::closed(0.01, 100.0);
const Range kOccupancyRateRangeHz = Range::closed(0.0, 100.0);
const Range kGridOriginRangeM = Range::closed(-1e5, 1e5);
const Range kGridResolutionRangeM = Range::closed(0.05, 10.0);
// 2048 x 2048 cells is the IDL's bound on the grid (kMaxOccupancyCells).
const Range kGridCellsRange = Range::closed(1.0, 2048.0);
// Geoid undulation is within about +-110 m on Earth; more means a unit mistake.
const Range kAltitudeOffsetRangeM = Range::closed(-200.0, 200.0);

constexpr std::string_view kReliabilityNames = "reliable, best_effort";
constexpr std::string_view kDurabilityNames = "volatile, transient_local";
constexpr std::string_view kTelemetrySourceNames = "none, ardupilot, px4";

std::optional<Reliability> reliabilityFromString(const std::string& text) {
  if (text == "reliable") {
    return Reliability::Reliable;
  }
  if (text == "best_effort") {
    return Reliability::BestEffort;
  }
  return std::nullopt;
}

std::optional<Durability> durabilityFromString(const std::string& text) {
  if (text == "volatile") {
    return Durability::Volatile;
  }
  if (text == "transient_local") {
    return Durability::TransientLocal;
  }
  return std::nullopt;
}

std::optional<TelemetrySource> telemetrySourceFromString(const std::string& text) {
  for (const TelemetrySource source :
       {TelemetrySource::None, TelemetrySource::ArduPilot, TelemetrySource::Px4}) {
    if (text == toString(source)) {
      return source;
    }
  }
  return std::nullopt;
}

QosProfile readQos(MapReader section, const QosProfile& defaults) {
  QosProfile qos;
  qos.reliability = section.choice<Reliability>("reliability", reliabilityFromString,
                                                kReliabilityNames, defaults.reliability);
  qos.maxBlocking_s = section.number("max_blocking_s", kMaxBlockingRangeS, defaults.maxBlocking_s);
  qos.durability = section.choice<Durability>("durability", durabilityFromString, kDurabilityNames,
                                              defaults.durability);
  qos.historyDepth = section.integer("history_depth", kHistoryDepthRange, defaults.historyDepth);
  qos.deadline_s = section.number("deadline_s", kQosDurationRangeS, defaults.deadline_s);
  qos.lifespan_s = section.number("lifespan_s", kQosDurationRangeS, defaults.lifespan_s);
  qos.livelinessLease_s =
      section.number("liveliness_lease_s", kQosDurationRangeS, defaults.livelinessLease_s);
  section.warnUnknownKeys();
  return qos;
}

// A security document: required and checked to exist when security is enabled (Cyclone would
// only say "dds_create_participant: Error"), read for its type and resolved otherwise.
std::string readSecurityFile(MapReader& section, std::string_view key, bool enabled,
                             const std::string& baseDir) {
  if (!section.has(key)) {
    if (enabled) {
      section.fail(key, "missing (required when dds.security.enabled is true)");
    }
    return "";
  }
  const std::string path = resolvePath(section.text(key, kRequired), baseDir);
  std::error_code error;
  if (enabled && !fs::is_regular_file(path, error)) {
    section.fail(key, "file not found: " + path);
  }
  return path;
}

SecurityConfig readSecurity(MapReader section, const std::string& baseDir) {
  const SecurityConfig defaults;
  SecurityConfig security;
  security.enabled = section.boolean("enabled", defaults.enabled);
  security.pluginDir = section.text("plugin_dir", defaults.pluginDir);
  std::error_code error;
  if (security.enabled &&
      !fs::is_regular_file(fs::path(security.pluginDir) / "libdds_security_auth.so", error)) {
    section.fail("plugin_dir",
                 "no DDS Security plugins (libdds_security_auth.so) in " + security.pluginDir);
  }
  security.identityCa = readSecurityFile(section, "identity_ca", security.enabled, baseDir);
  security.identityCertificate =
      readSecurityFile(section, "identity_certificate", security.enabled, baseDir);
  security.privateKey = readSecurityFile(section, "private_key", security.enabled, baseDir);
  security.permissionsCa = readSecurityFile(section, "permissions_ca", security.enabled, baseDir);
  security.governance = readSecurityFile(section, "governance", security.enabled, baseDir);
  security.permissions = readSecurityFile(section, "permissions", security.enabled, baseDir);
  section.warnUnknownKeys();
  return security;
}

TelemetryConfig readTelemetry(MapReader section) {
  const TelemetryConfig defaults;
  TelemetryConfig telemetry;
  telemetry.source = section.choice<TelemetrySource>("source", telemetrySourceFromString,
                                                     kTelemetrySourceNames, defaults.source);
  telemetry.domainId = section.uint32("domain_id", kDomainIdRange, defaults.domainId);
  telemetry.ardupilotGeoPoseTopic =
      section.text("ardupilot_geopose_topic", defaults.ardupilotGeoPoseTopic);
  telemetry.px4AttitudeTopic = section.text("px4_attitude_topic", defaults.px4AttitudeTopic);
  telemetry.px4GlobalPositionTopic =
      section.text("px4_global_position_topic", defaults.px4GlobalPositionTopic);
  telemetry.ardupilotAltitudeOffset_m = section.number(
      "ardupilot_altitude_offset_m", kAltitudeOffsetRangeM, defaults.ardupilotAltitudeOffset_m);
  telemetry.historyDepth =
      section.integer("history_depth", kHistoryDepthRange, defaults.historyDepth);
  section.warnUnknownKeys();
  return telemetry;
}

DdsConfig readDds(MapReader section, const std::string& baseDir) {
  const DdsConfig defaults;
  DdsConfig dds;
  dds.enabled = section.boolean("enabled", defaults.enabled);
  dds.domainId = section.uint32("domain_id", kDomainIdRange, defaults.domainId);
  dds.partition = section.text("partition", defaults.partition);
  dds.droneId = section.uint32("drone_id", kDroneIdRange, defaults.droneId);
  dds.topicPrefix = section.text("topic_prefix", defaults.topicPrefix);
  dds.statusRate_hz = section.number("status_rate_hz", kStatusRateRangeHz, defaults.statusRate_hz);
  dds.occupancyRate_hz =
      section.number("occupancy_rate_hz", kOccupancyRateRangeHz, defaults.occupancyRate_hz);
  {
    MapReader qos = section.section("qos");
    dds.vehicleState = readQos(qos.section("vehicle_state"), defaults.vehicleState);
    dds.droneStatus = readQos(qos.section("drone_status"), defaults.droneStatus);
    dds.occupancy = readQos(qos.section("occupancy"), defaults.occupancy);
    qos.warnUnknownKeys();
  }
  {
    MapReader grid = section.section("occupancy_grid");
    dds.grid.originEast_m =
        grid.number("origin_east_m", kGridOriginRangeM, defaults.grid.originEast_m);
    dds.grid.originNorth_m =
        grid.number("origin_north_m", kGridOriginRangeM, defaults.grid.originNorth_m);
    dds.grid.resolution_m =
        grid.number("resolution_m", kGridResolutionRangeM, defaults.grid.resolution_m);
    dds.grid.rows = grid.uint32("rows", kGridCellsRange, defaults.grid.rows);
    dds.grid.cols = grid.uint32("cols", kGridCellsRange, defaults.grid.cols);
    grid.warnUnknownKeys();
  }
  dds.security = readSecurity(section.section("security"), baseDir);
  dds.telemetry = readTelemetry(section.section("telemetry"));
  section.warnUnknownKeys();
  return dds;
}

// --- the loop's sections: perception, pose, tracking, source, telemetry, app ----------------

const Range kThreadsRange = Range::closed(1.0, 16.0);
const Range kShareRange = Range{0.0, 1.0, true};  // (0, 1]
const Range kProbabilityRange = Range::closed(0.0, 1.0);
const Range kWorkingScaleRange = Range{0.0, 1.0, true};
const Range kTileOverlapRangePx = Range::closed(0.0, 1024.0);
const Range kTopKRange = Range::closed(1.0, 512.0);
const Range kMaxCropsRange = Range::closed(0.0, 512.0);
const Range kCutMarginRangePx = Range::closed(0.0, 64.0);
const Range kFixedGsdRangeM = Range::closed(0.0, 1.0);
const Range kCarLengthRangeM = Range{0.0, 30.0, true};
const Range kWhiteBalanceGridRange = Range::closed(1.0, 8.0);  // rows x cols <= 64 regions
const Range kSampleStrideRangePx = Range::closed(1.0, 64.0);
const Range kMaxGainRange = Range::closed(1.0, 16.0);
// A pose further than 10 s from the frame is useless for a moving drone.
const Range kPoseMaxAgeRangeS = Range{0.0, 10.0, true};
const Range kPoseCapacityRange = Range::closed(2.0, 100000.0);
// The publisher's table of published tracks holds 1024 (VehicleStatePublisher::kMaxTracks).
const Range kMaxTracksRange = Range::closed(1.0, 1024.0);
const Range kConfirmHitsRange = Range::closed(1.0, 100.0);
const Range kConfirmWholeHitsRange = Range::closed(0.0, 100.0);
const Range kTrackTimeRangeS = Range::closed(0.0, 60.0);
const Range kSpeedRangeMps = Range::closed(0.0, 50.0);
const Range kFlipVotesRange = Range::closed(1.0, 100.0);
const Range kEvidenceWeightRange = Range{0.0, 1.0, true};
const Range kShapeWeightRange = Range{0.0, 1e6, true};
const Range kGateDistanceRangeM = Range{0.0, 100.0, true};
const Range kMeasurementPositionRangeM = Range{0.0, 10.0, true};   // (0, 10] m
const Range kMeasurementHeadingRangeDeg = Range{0.0, 90.0, true};  // (0, 90] deg
const Range kNoiseFactorRange = Range::closed(1.0, 1000.0);
const Range kCameraBuffersRange = Range::closed(2.0, 16.0);
const Range kDequeueTimeoutRangeMs = Range::closed(1.0, 60000.0);
const Range kPortRange = Range::closed(0.0, 65535.0);
const Range kSystemIdRange = Range::closed(0.0, 255.0);
const Range kLinkLatencyRangeS = Range::closed(0.0, 1.0);
const Range kLookaheadRangeS = Range::closed(0.0, 10.0);
const Range kQueueDepthRange = Range::closed(1.0, 8.0);
const Range kPoolSizeRange = Range::closed(0.0, 64.0);  // FramePool::kMaxFrames
const Range kPriorityRange = Range::closed(0.0, 99.0);
const Range kCpuRange = Range::closed(0.0, 1023.0);
const Range kStatsPeriodRangeS = Range::closed(0.1, 3600.0);
const Range kVideoFpsRange = Range{0.0, 1000.0, true};

constexpr std::string_view kBackendNames = "int8, fp32, opencv";
constexpr std::string_view kSourceKindNames = "replay, v4l2";
constexpr std::string_view kPixelFormatNames = "yuyv, nv12, mjpeg";
constexpr std::string_view kTelemetryKindNames =
    "recording, mavlink_udp, mavlink_serial, dds, none";
constexpr std::string_view kBaudNames =
    "9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600, 1000000, 1500000, "
    "2000000, 3000000";

// Looks a spelling up among the values of an enumeration by their toString().
template <class E, std::size_t N>
std::optional<E> enumFromString(const std::string& text, const std::array<E, N>& values) {
  for (const E value : values) {
    if (text == toString(value)) {
      return value;
    }
  }
  return std::nullopt;
}

std::optional<InferenceBackend> backendFromString(const std::string& text) {
  return enumFromString(
      text, std::array{InferenceBackend::Int8, InferenceBackend::Fp32, InferenceBackend::OpenCv});
}
std::optional<FrameSourceKind> sourceKindFromString(const std::string& text) {
  return enumFromString(text, std::array{FrameSourceKind::Replay, FrameSourceKind::V4l2});
}
std::optional<CameraPixelFormat> pixelFormatFromString(const std::string& text) {
  return enumFromString(
      text, std::array{CameraPixelFormat::Yuyv, CameraPixelFormat::Nv12, CameraPixelFormat::Mjpeg});
}
std::optional<TelemetrySourceKind> telemetryKindFromString(const std::string& text) {
  return enumFromString(text,
                        std::array{TelemetrySourceKind::Recording, TelemetrySourceKind::MavlinkUdp,
                                   TelemetrySourceKind::MavlinkSerial, TelemetrySourceKind::Dds,
                                   TelemetrySourceKind::None});
}
std::optional<int> baudFromString(const std::string& text) {
  for (const int baud : {9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600, 1000000,
                         1500000, 2000000, 3000000}) {
    if (text == std::to_string(baud)) {
      return baud;
    }
  }
  return std::nullopt;
}

// An optional output or input path; `none` (or absence) means "not used".
std::string readOptionalPath(MapReader& section, std::string_view key, const std::string& baseDir,
                             const std::string& fallback) {
  if (!section.has(key)) {
    return fallback.empty() ? "" : resolvePath(fallback, baseDir);
  }
  const std::string text = section.text(key, kRequired);
  return text == "none" ? "" : resolvePath(text, baseDir);
}

PerceptionConfig readPerception(MapReader section, const std::string& baseDir) {
  const PerceptionConfig d;
  PerceptionConfig p;
  p.detectorModel = resolvePath(
      section.text("detector_model", std::string(PerceptionConfig::kDefaultDetectorModel)),
      baseDir);
  p.cropModel =
      readOptionalPath(section, "crop_model", baseDir, PerceptionConfig::kDefaultCropModel);
  p.asmPath = resolvePath(section.text("asm", std::string(PerceptionConfig::kDefaultAsm)), baseDir);
  p.backend =
      section.choice<InferenceBackend>("backend", backendFromString, kBackendNames, d.backend);
  p.threads = section.integer("threads", kThreadsRange, d.threads);
  p.cropThreads = section.integer("crop_threads", kThreadsRange, d.cropThreads);
  p.undistort = section.boolean("undistort", d.undistort);
  p.whiteBalance = section.boolean("white_balance", d.whiteBalance);
  if (section.has("white_balance_regions")) {
    const std::vector<int> regions =
        section.integers("white_balance_regions", kWhiteBalanceGridRange, 2);
    p.whiteBalanceRegionRows = regions[0];
    p.whiteBalanceRegionCols = regions[1];
  }
  p.whiteBalanceSampleStridePx = section.integer(
      "white_balance_sample_stride_px", kSampleStrideRangePx, d.whiteBalanceSampleStridePx);
  p.whiteBalanceWhiteShare =
      section.number("white_balance_white_share", kShareRange, d.whiteBalanceWhiteShare);
  p.whiteBalanceMaxGain =
      section.number("white_balance_max_gain", kMaxGainRange, d.whiteBalanceMaxGain);
  p.workingScale = section.number("working_scale", kWorkingScaleRange, d.workingScale);
  p.tileOverlapPx = section.integer("tile_overlap_px", kTileOverlapRangePx, d.tileOverlapPx);
  p.scoreThreshold = section.number("score_threshold", kProbabilityRange, d.scoreThreshold);
  p.topKPerTile = section.integer("top_k_per_tile", kTopKRange, d.topKPerTile);
  p.nmsIou = section.number("nms_iou", kShareRange, d.nmsIou);
  p.duplicateOverlap = section.number("duplicate_overlap", kShareRange, d.duplicateOverlap);
  p.cutEdgeMarginPx = section.number("cut_edge_margin_px", kCutMarginRangePx, d.cutEdgeMarginPx);
  p.maxCrops = section.integer("max_crops", kMaxCropsRange, d.maxCrops);
  p.applyFlip = section.boolean("apply_flip", d.applyFlip);
  p.applyRefine = section.boolean("apply_refine", d.applyRefine);
  p.cropMirrorAverage = section.boolean("crop_mirror_average", d.cropMirrorAverage);
  p.cropMirrorRefine = section.boolean("crop_mirror_refine", d.cropMirrorRefine);
  p.cropLargeVehicleEnds = section.boolean("crop_large_vehicle_ends", d.cropLargeVehicleEnds);
  p.cropMinVehicleProbability = section.number("crop_min_vehicle_probability", kProbabilityRange,
                                               d.cropMinVehicleProbability);
  p.fixedGsd_m = section.number("fixed_gsd_m", kFixedGsdRangeM, d.fixedGsd_m);
  p.nominalCarLength_m =
      section.number("nominal_car_length_m", kCarLengthRangeM, d.nominalCarLength_m);
  p.liftHeightShare = section.number("lift_height_share", kProbabilityRange, d.liftHeightShare);
  section.warnUnknownKeys();
  return p;
}

PoseConfig readPose(MapReader section) {
  const PoseConfig d;
  PoseConfig p;
  p.maxAge_s = section.number("max_age_s", kPoseMaxAgeRangeS, d.maxAge_s);
  p.bufferCapacity = section.integer("buffer_capacity", kPoseCapacityRange, d.bufferCapacity);
  section.warnUnknownKeys();
  return p;
}

TrackingConfig readTracking(MapReader section) {
  const TrackingConfig d;
  TrackingConfig t;
  t.maxTracks = section.integer("max_tracks", kMaxTracksRange, d.maxTracks);
  t.confirmHits = section.integer("confirm_hits", kConfirmHitsRange, d.confirmHits);
  t.maxTentativeGap_s =
      section.number("max_tentative_gap_s", kTrackTimeRangeS, d.maxTentativeGap_s);
  t.maxLost_s = section.number("max_lost_s", kTrackTimeRangeS, d.maxLost_s);
  t.maxLostAtEdge_s = section.number("max_lost_at_edge_s", kTrackTimeRangeS, d.maxLostAtEdge_s);
  t.coast_s = section.number("coast_s", kTrackTimeRangeS, d.coast_s);
  t.movingSpeed_mps = section.number("moving_speed_mps", kSpeedRangeMps, d.movingSpeed_mps);
  t.flipVotes = section.integer("flip_votes", kFlipVotesRange, d.flipVotes);
  t.typeEvidenceWeight =
      section.number("type_evidence_weight", kEvidenceWeightRange, d.typeEvidenceWeight);
  t.shapeMaxWeight = section.number("shape_max_weight", kShapeWeightRange, d.shapeMaxWeight);
  t.maxDistance_m = section.number("max_distance_m", kGateDistanceRangeM, d.maxDistance_m);
  t.highScore = section.number("high_score", kProbabilityRange, d.highScore);
  t.lowScore = section.number("low_score", Range::closed(0.0, t.highScore), d.lowScore);
  t.measurementPosition_m =
      section.number("measurement_position_m", kMeasurementPositionRangeM, d.measurementPosition_m);
  t.measurementHeading_deg = section.number("measurement_heading_deg", kMeasurementHeadingRangeDeg,
                                            d.measurementHeading_deg);
  t.steeringDecay_s = section.number("steering_decay_s", kTrackTimeRangeS, d.steeringDecay_s);
  t.confirmWholeHits =
      section.integer("confirm_whole_hits", kConfirmWholeHitsRange, d.confirmWholeHits);
  t.confirmHitsAnyway =
      section.integer("confirm_hits_anyway", kConfirmHitsRange, d.confirmHitsAnyway);
  t.confirmHitsStanding =
      section.integer("confirm_hits_standing", kConfirmHitsRange, d.confirmHitsStanding);
  t.confirmHitsLarge = section.integer("confirm_hits_large", kConfirmHitsRange, d.confirmHitsLarge);
  t.confirmMinScore = section.number("confirm_min_score", kProbabilityRange, d.confirmMinScore);
  t.partialInsideShare =
      section.number("partial_inside_share", kProbabilityRange, d.partialInsideShare);
  t.partialAlongNoiseFactor =
      section.number("partial_along_noise_factor", kNoiseFactorRange, d.partialAlongNoiseFactor);
  section.warnUnknownKeys();
  return t;
}

V4l2SourceConfig readV4l2(MapReader section) {
  const V4l2SourceConfig d;
  V4l2SourceConfig v;
  v.device = section.text("device", d.device);
  v.busInfo = section.text("bus_info", d.busInfo);
  v.widthPx = section.integer("width_px", kImageSizeRangePx, d.widthPx);
  v.heightPx = section.integer("height_px", kImageSizeRangePx, d.heightPx);
  if (section.has("formats")) {
    v.formats =
        section.choices<CameraPixelFormat>("formats", pixelFormatFromString, kPixelFormatNames);
  }
  v.buffers = section.integer("buffers", kCameraBuffersRange, d.buffers);
  v.dequeueTimeoutMs =
      section.integer("dequeue_timeout_ms", kDequeueTimeoutRangeMs, d.dequeueTimeoutMs);
  section.warnUnknownKeys();
  return v;
}

SourceConfig readSource(MapReader section, const std::string& baseDir) {
  const SourceConfig d;
  SourceConfig s;
  s.kind = section.choice<FrameSourceKind>("kind", sourceKindFromString, kSourceKindNames, d.kind);
  s.sequenceDir = readOptionalPath(section, "sequence_dir", baseDir, "");
  s.paced = section.boolean("paced", d.paced);
  s.loop = section.boolean("loop", d.loop);
  s.v4l2 = readV4l2(section.section("v4l2"));
  section.warnUnknownKeys();
  return s;
}

TelemetryLinkConfig readTelemetryLink(MapReader section) {
  const TelemetryLinkConfig d;
  TelemetryLinkConfig t;
  t.source = section.choice<TelemetrySourceKind>("source", telemetryKindFromString,
                                                 kTelemetryKindNames, d.source);
  t.udpBindAddress = section.text("udp_bind_address", d.udpBindAddress);
  t.udpPort = section.integer("udp_port", kPortRange, d.udpPort);
  t.serialDevice = section.text("serial_device", d.serialDevice);
  t.serialBaud = section.choice<int>("serial_baud", baudFromString, kBaudNames, d.serialBaud);
  t.systemId = section.integer("system_id", kSystemIdRange, d.systemId);
  t.geoidSeparation_m =
      section.number("geoid_separation_m", kAltitudeOffsetRangeM, d.geoidSeparation_m);
  t.linkLatency_s = section.number("link_latency_s", kLinkLatencyRangeS, d.linkLatency_s);
  t.replayLookahead_s = section.number("replay_lookahead_s", kLookaheadRangeS, d.replayLookahead_s);
  section.warnUnknownKeys();
  return t;
}

LoopConfig readLoop(MapReader section, const std::string& baseDir) {
  const LoopConfig d;
  LoopConfig a;
  a.queueDepth = section.integer("queue_depth", kQueueDepthRange, d.queueDepth);
  a.framePoolSize = section.integer("frame_pool_size", kPoolSizeRange, d.framePoolSize);
  if (a.framePoolSize != 0 && a.framePoolSize < a.queueDepth + 2) {
    section.fail("frame_pool_size", "must be 0 (automatic) or >= queue_depth + 2 = " +
                                        std::to_string(a.queueDepth + 2) + ", got " +
                                        std::to_string(a.framePoolSize));
  }
  a.lockMemory = section.boolean("lock_memory", d.lockMemory);
  a.realtimePriority = section.integer("realtime_priority", kPriorityRange, d.realtimePriority);
  if (section.has("capture_cpus")) {
    a.captureCpus = section.integers("capture_cpus", kCpuRange, -1);
  }
  if (section.has("processing_cpus")) {
    a.processingCpus = section.integers("processing_cpus", kCpuRange, -1);
  }
  a.statsPeriod_s = section.number("stats_period_s", kStatsPeriodRangeS, d.statsPeriod_s);
  a.trajectoryCsv = readOptionalPath(section, "trajectory_csv", baseDir, "");
  a.detectionsCsv = readOptionalPath(section, "detections_csv", baseDir, "");
  a.annotatedVideo = readOptionalPath(section, "annotated_video", baseDir, "");
  a.annotatedVideoFps = section.number("annotated_video_fps", kVideoFpsRange, d.annotatedVideoFps);
  section.warnUnknownKeys();
  return a;
}

YAML::Node loadDocument(const std::string& text, const Diagnostics& diag) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& error) {
    if (error.mark.is_null()) {
      diag.fail("", "YAML error: " + error.msg);
    }
    diag.fail("", "YAML syntax error at line " + std::to_string(error.mark.line + 1) + ", column " +
                      std::to_string(error.mark.column + 1) + ": " + error.msg);
  }
}

}  // namespace

AppConfig parseConfig(const std::string& yamlText, const std::string& sourceName,
                      const std::string& baseDir) {
  AppConfig config;
  config.sourcePath = sourceName;
  const Diagnostics diag(sourceName, &config.warnings);

  const YAML::Node document = loadDocument(yamlText, diag);
  if (!document.IsDefined() || document.IsNull()) {
    diag.fail("", "the configuration is empty (expected the sections origin, camera, terrain)");
  }
  if (!document.IsMap()) {
    diag.fail("", "expected a map of sections at the top level, got " + describe(document));
  }
  MapReader root(document, "", diag);
  config.origin = readOrigin(root.requiredSection("origin"));
  config.camera = readCamera(root.requiredSection("camera"));
  config.mount = readMount(root.section("mount"));
  config.terrain = readTerrain(root.requiredSection("terrain"), baseDir);
  config.dds = readDds(root.section("dds"), baseDir);
  config.perception = readPerception(root.section("perception"), baseDir);
  config.pose = readPose(root.section("pose"));
  config.tracking = readTracking(root.section("tracking"));
  config.source = readSource(root.section("source"), baseDir);
  config.telemetry = readTelemetryLink(root.section("telemetry"));
  config.app = readLoop(root.section("app"), baseDir);
  if (config.telemetry.source == TelemetrySourceKind::Dds &&
      config.dds.telemetry.source == TelemetrySource::None) {
    diag.fail("telemetry.source", "dds needs dds.telemetry.source ardupilot or px4 (it is none)");
  }
  root.warnUnknownKeys();
  return config;
}

DdsSection parseDdsSection(const std::string& yamlText, const std::string& sourceName,
                           const std::string& baseDir) {
  DdsSection result;
  const Diagnostics diag(sourceName, &result.warnings);
  const YAML::Node document = loadDocument(yamlText, diag);
  if (document.IsDefined() && !document.IsNull() && !document.IsMap()) {
    diag.fail("", "expected a map of sections at the top level, got " + describe(document));
  }
  // The other sections belong to other readers: they are not reported as unknown here.
  MapReader root(document, "", diag);
  result.dds = readDds(root.section("dds"), baseDir);
  return result;
}

namespace {

// The file's text and its directory (against which relative paths are resolved).
std::pair<std::string, std::string> readConfigFile(const std::string& path) {
  std::error_code error;
  if (fs::is_directory(path, error)) {
    throw ConfigError(path + ": cannot open configuration file (it is a directory)");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    throw ConfigError(path + ": cannot open configuration file");
  }
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) {
    throw ConfigError(path + ": cannot read configuration file");
  }
  const fs::path absolute = fs::absolute(path, error);
  const fs::path baseDir = (error ? fs::path(path) : absolute).parent_path();
  return {text.str(), baseDir.string()};
}

}  // namespace

AppConfig loadConfig(const std::string& path) {
  const auto [text, baseDir] = readConfigFile(path);
  return parseConfig(text, path, baseDir);
}

DdsSection loadDdsSection(const std::string& path) {
  const auto [text, baseDir] = readConfigFile(path);
  return parseDdsSection(text, path, baseDir);
}

const char* toString(InferenceBackend backend) {
  switch (backend) {
    case InferenceBackend::Int8:
      return "int8";
    case InferenceBackend::Fp32:
      return "fp32";
    case InferenceBackend::OpenCv:
      return "opencv";
  }
  return "unknown";
}

const char* toString(FrameSourceKind kind) {
  switch (kind) {
    case FrameSourceKind::Replay:
      return "replay";
    case FrameSourceKind::V4l2:
      return "v4l2";
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
