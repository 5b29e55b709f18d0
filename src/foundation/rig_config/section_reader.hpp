// rig_config/section_reader: the typed YAML getters every section reader of the loader shares.
//
// Contract (internal to the rig reader and the configuration library): MapReader wraps one YAML map
// of the file, knows the full key path of the section it reads (for messages) and records which
// keys were read, so that whatever is left over becomes an "unknown key" warning. Reading one key
// is one line that states its type, range and default; the default is the module's own (its options
// struct), so the file and the code share one definition. Every failure throws ConfigError
// whose message names the file and the full key path. Start-up only.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rig_config/rig_config.hpp"

namespace vp::config::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Passed as the default of a key the file must give.
constexpr std::nullopt_t kRequired = std::nullopt;

// Shortest text that reads back as the same double ("0.1", "-90", "16384").
std::string formatNumber(double value);

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

// Ranges more than one section uses.
inline const Range kProbabilityRange = Range::closed(0.0, 1.0);
inline const Range kShareRange = Range{0.0, 1.0, true};  // (0, 1]
inline const Range kImageSizeRange_px = Range::closed(16.0, 16384.0);
// Geoid undulation is within about +-110 m on Earth; more means a unit mistake.
inline const Range kAltitudeOffsetRange_m = Range::closed(-200.0, 200.0);

// A float default as the decimal it was written as (0.45F -> 0.45, not 0.449999988...), so
// that a range derived from it and its message read as in the header.
double floatAsDecimal(float value);

// What a node is, for "expected X, got Y" messages.
std::string describe(const YAML::Node& node);

// Scalar readers: each checks the node's type (and range) and fails naming path otherwise.
double readNumber(const YAML::Node& node, const std::string& path, const Range& range,
                  const Diagnostics& diag);
std::int64_t readInteger(const YAML::Node& node, const std::string& path, const Range& range,
                         const Diagnostics& diag);
bool readBoolean(const YAML::Node& node, const std::string& path, const Diagnostics& diag);
std::string readText(const YAML::Node& node, const std::string& path, const Diagnostics& diag);

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
  // Marks a key as read without reading it: a section another reader checks.
  void skip(std::string_view key) { take(key, false); }
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

// Relative paths are relative to the configuration file, not to the working directory, so
// that a file and its DTM can be moved together. Lexical: existence is the loader's check.
std::string resolvePath(const std::string& text, const std::string& baseDir);

// An optional output or input path; `none` (or absence) means "not used".
std::string readOptionalPath(MapReader& section, std::string_view key, const std::string& baseDir,
                             const std::string& fallback);

// Looks a spelling up among the values of an enumeration by their toString().
template <class E, std::size_t N, class ToString>
std::optional<E> enumFromString(const std::string& text, const std::array<E, N>& values,
                                ToString toString) {
  for (const E value : values) {
    if (text == toString(value)) {
      return value;
    }
  }
  return std::nullopt;
}

// The parsed document; a syntax error throws ConfigError naming the line and column.
YAML::Node loadDocument(const std::string& text, const Diagnostics& diag);
// The parsed document of a whole configuration file, which must be a map of sections: an empty
// document or one that is not a map throws ConfigError.
YAML::Node loadSections(const std::string& text, const Diagnostics& diag);

// A configuration file's text and its directory (against which relative paths are resolved);
// throws ConfigError when it cannot be read.
std::pair<std::string, std::string> readConfigFile(const std::string& path);

}  // namespace vp::config::detail
