// rig_config/section_reader: the shared YAML getters (see the header).
#include "rig_config/section_reader.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

namespace vp::config::detail {

namespace fs = std::filesystem;

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

double floatAsDecimal(float value) {
  char buffer[32];
  const auto written = std::to_chars(std::begin(buffer), std::end(buffer), value);
  double decimal = 0.0;
  std::from_chars(buffer, written.ptr, decimal);
  return decimal;
}

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

namespace {

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

}  // namespace

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

std::string resolvePath(const std::string& text, const std::string& baseDir) {
  fs::path path(text);
  if (path.is_relative()) {
    path = fs::path(baseDir) / path;
  }
  std::error_code error;
  const fs::path absolute = fs::absolute(path, error);
  return (error ? path : absolute).lexically_normal().string();
}

std::string readOptionalPath(MapReader& section, std::string_view key, const std::string& baseDir,
                             const std::string& fallback) {
  if (!section.has(key)) {
    return fallback.empty() ? "" : resolvePath(fallback, baseDir);
  }
  const std::string text = section.text(key, kRequired);
  return text == "none" ? "" : resolvePath(text, baseDir);
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

YAML::Node loadSections(const std::string& text, const Diagnostics& diag) {
  YAML::Node document = loadDocument(text, diag);
  if (!document.IsDefined() || document.IsNull()) {
    diag.fail("", "the configuration is empty (expected the sections origin, camera, terrain)");
  }
  if (!document.IsMap()) {
    diag.fail("", "expected a map of sections at the top level, got " + describe(document));
  }
  return document;
}

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

}  // namespace vp::config::detail
