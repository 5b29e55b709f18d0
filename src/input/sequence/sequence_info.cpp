// sequence/sequence_info: sequence.yaml, read strictly (unknown keys, duplicates and quoted
// numbers are errors) and written so that any name or free text reads back unchanged.
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>

#include <yaml-cpp/yaml.h>

#include "csv/csv_io.hpp"
#include "sequence/sequence_format.hpp"

namespace vp::sequence::detail {
namespace {

using csv::quote;

std::string describe(const YAML::Node& node) {
  if (node.IsScalar()) {
    return (node.Tag() == "!" ? "the quoted string " : "") + quote(node.Scalar());
  }
  if (node.IsMap()) {
    return "a map";
  }
  if (node.IsSequence()) {
    return "a sequence";
  }
  return "nothing";
}

class InfoReader {
 public:
  explicit InfoReader(std::string name) : name_(std::move(name)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw SequenceError(csv::shortened(name_) + ": " + (key.empty() ? "" : key + ": ") + problem);
  }

  std::int64_t integer(const YAML::Node& node, const std::string& key) const {
    std::int64_t value = 0;
    const std::string& text = node.Scalar();
    const auto [ptr, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (!node.IsScalar() || node.Tag() == "!" || text.empty() || error != std::errc() ||
        ptr != text.data() + text.size()) {
      fail(key, "expected an integer, got " + describe(node));
    }
    return value;
  }

  double number(const YAML::Node& node, const std::string& key) const {
    double value = 0;
    const std::string& text = node.Scalar();
    const auto [ptr, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (!node.IsScalar() || node.Tag() == "!" || text.empty() || error != std::errc() ||
        ptr != text.data() + text.size() || !std::isfinite(value)) {
      fail(key, "expected a finite number, got " + describe(node));
    }
    return value;
  }

  std::string text(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) {
      fail(key, "expected a string, got " + describe(node));
    }
    return node.Scalar();
  }

 private:
  std::string name_;
};

std::string yamlQuoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (byte < 0x20 || byte == 0x7f) {
      std::array<char, 8> escaped{};
      std::snprintf(escaped.data(), escaped.size(), "\\x%02x", static_cast<unsigned>(byte));
      out += escaped.data();
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

// Reads sequence.yaml into *info; returns its frame_count.
std::int64_t readInfo(const fs::path& directory, SequenceInfo* info) {
  const fs::path path = directory / kSequenceFile;
  const InfoReader reader(path.string());
  std::string text;
  if (!readWholeFile(path, &text)) {
    reader.fail("", "missing (required)");
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& error) {
    reader.fail("", "YAML syntax error at line " + std::to_string(error.mark.line + 1) +
                        ", column " + std::to_string(error.mark.column + 1) + ": " + error.msg);
  }
  if (!root.IsMap()) {
    reader.fail("", "expected a map of keys, got " + describe(root));
  }
  std::map<std::string, YAML::Node> keys;
  for (const auto& entry : root) {
    // yaml-cpp keeps duplicate keys; the author meant one of them, so neither is guessed.
    if (!keys.emplace(entry.first.Scalar(), entry.second).second) {
      reader.fail(entry.first.Scalar(), "duplicate key");
    }
  }
  const auto required = [&](const std::string& key) -> const YAML::Node& {
    const auto found = keys.find(key);
    if (found == keys.end()) {
      reader.fail(key, "missing (required)");
    }
    return found->second;
  };

  // First, so that a newer sequence is reported as such and not as a list of unknown keys.
  const std::int64_t version = reader.integer(required("format_version"), "format_version");
  if (version != kFormatVersion) {
    reader.fail("format_version", std::to_string(version) + " not supported (this reader reads " +
                                      std::to_string(kFormatVersion) + ")");
  }
  for (const auto& [key, node] : keys) {
    if (key != "format_version" && key != "name" && key != "frame_rate_hz" && key != "source" &&
        key != "frame_count" && key != "notes") {
      reader.fail("", "unknown key " + quote(key));
    }
  }
  info->formatVersion = static_cast<int>(version);
  info->name = reader.text(required("name"), "name");
  if (info->name.empty()) {
    reader.fail("name", "must not be empty");
  }
  info->frameRate_hz = reader.number(required("frame_rate_hz"), "frame_rate_hz");
  if (!(info->frameRate_hz > 0.0)) {
    reader.fail("frame_rate_hz", "must be > 0, got " + numberText(info->frameRate_hz));
  }
  info->source = reader.text(required("source"), "source");
  if (keys.contains("notes")) {
    info->notes = reader.text(keys.at("notes"), "notes");
  }
  const std::int64_t frameCount = reader.integer(required("frame_count"), "frame_count");
  if (frameCount < 0) {
    reader.fail("frame_count", "must be >= 0, got " + std::to_string(frameCount));
  }
  return frameCount;
}

// A YAML double-quoted scalar: any name or free text reads back unchanged.
std::string formatInfo(const SequenceInfo& info, std::size_t frameCount) {
  std::string text = "format_version: " + std::to_string(info.formatVersion) + "\n";
  text += "name: " + yamlQuoted(info.name) + "\n";
  text += "frame_rate_hz: " + numberText(info.frameRate_hz) + "\n";
  text += "source: " + yamlQuoted(info.source) + "\n";
  text += "frame_count: " + std::to_string(frameCount) + "\n";
  if (!info.notes.empty()) {
    text += "notes: " + yamlQuoted(info.notes) + "\n";
  }
  return text;
}

}  // namespace vp::sequence::detail
