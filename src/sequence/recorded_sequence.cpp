// sequence/recorded_sequence: reader and writer of the recorded-sequence directory format.
// The format, its rules and its error messages are documented in docs/recorded_sequence.md;
// this file implements exactly that document.
//
// The reader and the writer share the row parsers and the cross-row rules (SequenceRules):
// the writer formats each record, parses it back with the reader's parser and applies the same
// rules before writing, so it cannot write a sequence that the reader rejects.
#include "sequence/recorded_sequence.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>

#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>

namespace vp::sequence {
namespace {

namespace fs = std::filesystem;

constexpr double kQuaternionNormTolerance = 1e-3;
// Fixed (not OpenCV's default, which may change between versions) so that the bytes of a
// written PNG depend on the image only.
constexpr int kPngCompression = 3;

constexpr const char* kSequenceFile = "sequence.yaml";
constexpr const char* kRigFile = "rig.yaml";
constexpr const char* kDtmFile = "dtm.tif";
constexpr const char* kFramesFile = "frames.csv";
constexpr const char* kTelemetryFile = "telemetry.csv";
constexpr const char* kObjectsFile = "ground_truth/objects.csv";
constexpr const char* kKeypointsFile = "ground_truth/keypoints.csv";
constexpr std::array<const char*, 3> kWorldFileExtensions{".tfw", ".tifw", ".wld"};

constexpr std::array<std::string_view, 3> kFrameColumns{"frame_id", "timestamp_ns", "file"};
constexpr std::array<std::string_view, 12> kTelemetryColumns{"timestamp_ns",
                                                             "latitude_deg",
                                                             "longitude_deg",
                                                             "height_m",
                                                             "qw",
                                                             "qx",
                                                             "qy",
                                                             "qz",
                                                             "gimbal_roll_deg",
                                                             "gimbal_pitch_deg",
                                                             "gimbal_yaw_deg",
                                                             "gimbal_reference"};
constexpr std::array<std::string_view, 3> kObjectHeadColumns{"frame_id", "track_id", "type"};
constexpr std::array<std::string_view, 17> kObjectTailColumns{
    "length_m",        "width_m",       "height_m",       "east_m",    "north_m",   "up_m",
    "heading_enu_rad", "speed_mps",     "yaw_rate_radps", "box_cx_px", "box_cy_px", "box_length_px",
    "box_width_px",    "box_angle_rad", "truncation",     "occlusion", "parked"};
constexpr std::array<std::string_view, 9> kKeypointColumns{
    "frame_id", "track_id", "keypoint", "u_px", "v_px", "visible", "east_m", "north_m", "up_m"};

// A complete message ("<file>:<line>: <field>: <problem>"); caught by open() and returned.
class SequenceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A problem with one field of one record; the caller adds the file and line.
struct FieldError {
  std::string field;
  std::string problem;
};

std::string quote(std::string_view text) {
  return "'" + std::string(text) + "'";
}

std::vector<std::string> objectColumns(int gammaCount) {
  std::vector<std::string> names(kObjectHeadColumns.begin(), kObjectHeadColumns.end());
  for (int i = 0; i < gammaCount; ++i) {
    names.push_back("gamma_" + std::to_string(i));
  }
  names.insert(names.end(), kObjectTailColumns.begin(), kObjectTailColumns.end());
  return names;
}

template <typename Names>
std::vector<std::string> toStrings(const Names& names) {
  return std::vector<std::string>(names.begin(), names.end());
}

std::string joinColumns(const std::vector<std::string>& names) {
  std::string line;
  for (const std::string& name : names) {
    line += (line.empty() ? "" : ",") + name;
  }
  return line;
}

// ---- numbers -------------------------------------------------------------------------------

// Shortest text that std::from_chars reads back to the same value: exact round trips.
template <typename T>
void appendNumber(std::string& out, T value) {
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  out.append(buffer.data(), result.ptr);
}

template <typename T>
std::string numberText(T value) {
  std::string text;
  appendNumber(text, value);
  return text;
}

std::int64_t parseInteger(std::string_view text, std::string_view field, std::int64_t low,
                          std::int64_t high) {
  std::int64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, value);
  if (error == std::errc::result_out_of_range) {
    throw FieldError{std::string(field), "integer out of range " + quote(text)};
  }
  if (text.empty() || error != std::errc() || ptr != end) {
    throw FieldError{std::string(field), "not an integer " + quote(text)};
  }
  if (value < low || value > high) {
    throw FieldError{std::string(field),
                     low == 0 && high == std::numeric_limits<std::int64_t>::max()
                         ? "must be >= 0, got " + std::string(text)
                         : "must be in [" + std::to_string(low) + ", " + std::to_string(high) +
                               "], got " + std::string(text)};
  }
  return value;
}

template <typename T>
T parseReal(std::string_view text, std::string_view field) {
  T value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, value);
  if (text.empty() || error != std::errc() || ptr != end) {
    throw FieldError{std::string(field), "not a number " + quote(text)};
  }
  if (!std::isfinite(value)) {
    throw FieldError{std::string(field),
                     "not finite " + quote(text) + " (there are no missing values: omit the row)"};
  }
  return value;
}

double parseReal(std::string_view text, std::string_view field, double low, double high) {
  const double value = parseReal<double>(text, field);
  if (value < low || value > high) {
    throw FieldError{std::string(field), "must be in [" + numberText(low) + ", " +
                                             numberText(high) + "], got " + std::string(text)};
  }
  return value;
}

bool parseFlag(std::string_view text, std::string_view field) {
  if (text != "0" && text != "1") {
    throw FieldError{std::string(field), "expected 0 or 1, got " + quote(text)};
  }
  return text == "1";
}

// ---- rows ----------------------------------------------------------------------------------

void checkRelativeFile(std::string_view file) {
  if (file.empty()) {
    throw FieldError{"file", "empty"};
  }
  const fs::path path{std::string(file)};
  if (path.has_root_path()) {
    throw FieldError{"file", "must be relative to the sequence directory, got " + quote(file)};
  }
  for (const fs::path& part : path) {
    if (part == "..") {
      throw FieldError{"file", "must stay inside the sequence directory, got " + quote(file)};
    }
  }
}

using Fields = std::span<const std::string_view>;

FrameRecord parseFrameRow(Fields f) {
  FrameRecord frame;
  frame.frameId = parseInteger(f[0], kFrameColumns[0], 0, std::numeric_limits<std::int64_t>::max());
  frame.timestampNs = parseInteger(f[1], kFrameColumns[1], std::numeric_limits<std::int64_t>::min(),
                                   std::numeric_limits<std::int64_t>::max());
  checkRelativeFile(f[2]);
  frame.file = std::string(f[2]);
  return frame;
}

std::string formatFrameRow(const FrameRecord& frame) {
  std::string row;
  appendNumber(row, frame.frameId);
  row += ',';
  appendNumber(row, frame.timestampNs);
  row += ',';
  row += frame.file;
  return row;
}

TelemetryRecord parseTelemetryRow(Fields f) {
  const auto& c = kTelemetryColumns;
  TelemetryRecord record;
  record.timestampNs = parseInteger(f[0], c[0], std::numeric_limits<std::int64_t>::min(),
                                    std::numeric_limits<std::int64_t>::max());
  record.position.latitudeDeg = parseReal(f[1], c[1], -90.0, 90.0);
  record.position.longitudeDeg = parseReal(f[2], c[2], -180.0, 180.0);
  record.position.heightM = parseReal<double>(f[3], c[3]);
  const double qw = parseReal<double>(f[4], c[4]);
  const double qx = parseReal<double>(f[5], c[5]);
  const double qy = parseReal<double>(f[6], c[6]);
  const double qz = parseReal<double>(f[7], c[7]);
  // Kept as written (no renormalisation) so that a round trip is exact; the tolerance catches
  // wrong units or a wrong component order, not rounding.
  const double norm = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz);
  if (!(std::abs(norm - 1.0) <= kQuaternionNormTolerance)) {
    throw FieldError{"qw,qx,qy,qz", "quaternion norm " + numberText(norm) +
                                        " is not 1 (tolerance " +
                                        numberText(kQuaternionNormTolerance) + ")"};
  }
  record.bodyToNed = Eigen::Quaterniond(qw, qx, qy, qz);
  record.gimbal.angles.rollDeg = parseReal<double>(f[8], c[8]);
  record.gimbal.angles.pitchDeg = parseReal<double>(f[9], c[9]);
  record.gimbal.angles.yawDeg = parseReal<double>(f[10], c[10]);
  if (f[11] == "body") {
    record.gimbal.reference = geodesy::GimbalReference::Body;
  } else if (f[11] == "earth") {
    record.gimbal.reference = geodesy::GimbalReference::Earth;
  } else {
    throw FieldError{std::string(c[11]), "expected body or earth, got " + quote(f[11])};
  }
  return record;
}

std::string formatTelemetryRow(const TelemetryRecord& record) {
  std::string row;
  appendNumber(row, record.timestampNs);
  for (const double value :
       {record.position.latitudeDeg, record.position.longitudeDeg, record.position.heightM,
        record.bodyToNed.w(), record.bodyToNed.x(), record.bodyToNed.y(), record.bodyToNed.z(),
        record.gimbal.angles.rollDeg, record.gimbal.angles.pitchDeg, record.gimbal.angles.yawDeg}) {
    row += ',';
    appendNumber(row, value);
  }
  row += record.gimbal.reference == geodesy::GimbalReference::Earth ? ",earth" : ",body";
  return row;
}

// `names` is the header of the file (it has gammaCount gamma columns).
ObjectTruth parseObjectRow(Fields f, int gammaCount, const std::vector<std::string>& names) {
  ObjectTruth object;
  object.frameId = parseInteger(f[0], names[0], 0, std::numeric_limits<std::int64_t>::max());
  object.trackId =
      static_cast<int>(parseInteger(f[1], names[1], 0, std::numeric_limits<int>::max()));
  const std::optional<shape::VehicleType> type = shape::vehicleTypeFromString(f[2]);
  if (!type) {
    throw FieldError{names[2], "unknown vehicle type " + quote(f[2]) +
                                   " (expected estate, compact, sports, sedan, suv, van, large)"};
  }
  object.type = *type;
  // The shape has as many components as there are leading non-empty gamma fields.
  int count = 0;
  for (int i = 0; i < gammaCount; ++i) {
    const std::size_t column = 3 + static_cast<std::size_t>(i);
    if (f[column].empty()) {
      continue;
    }
    if (count != i) {
      throw FieldError{names[column], "value after an empty gamma field"};
    }
    if (object.type == shape::VehicleType::Large) {
      throw FieldError{names[column], "large vehicles have no shape (leave gamma empty)"};
    }
    object.shape.gamma[static_cast<std::size_t>(i)] = parseReal<float>(f[column], names[column]);
    count = i + 1;
  }
  object.shape.count = count;

  const std::size_t t = 3 + static_cast<std::size_t>(gammaCount);  // first tail column
  const auto real = [&](std::size_t k) { return parseReal<double>(f[t + k], names[t + k]); };
  const auto nonNegative = [&](std::size_t k) {
    return parseReal(f[t + k], names[t + k], 0.0, std::numeric_limits<double>::max());
  };
  object.dimensionsM = {nonNegative(0), nonNegative(1), nonNegative(2)};
  object.positionEnu = {real(3), real(4), real(5)};
  object.headingEnuRad = real(6);
  object.speedMps = real(7);
  object.yawRateRadps = real(8);
  object.imageBox.cx = real(9);
  object.imageBox.cy = real(10);
  object.imageBox.length = nonNegative(11);
  object.imageBox.width = nonNegative(12);
  object.imageBox.angle = real(13);
  object.truncation = parseReal(f[t + 14], names[t + 14], 0.0, 1.0);
  object.occlusion = parseReal(f[t + 15], names[t + 15], 0.0, 1.0);
  object.parked = parseFlag(f[t + 16], names[t + 16]);
  return object;
}

// Precondition: 0 <= object.shape.count <= gammaCount.
std::string formatObjectRow(const ObjectTruth& object, int gammaCount) {
  std::string row;
  appendNumber(row, object.frameId);
  row += ',';
  appendNumber(row, object.trackId);
  row += ',';
  row += shape::toString(object.type);
  for (int i = 0; i < gammaCount; ++i) {
    row += ',';
    if (i < object.shape.count) {
      appendNumber(row, object.shape.gamma[static_cast<std::size_t>(i)]);
    }
  }
  for (const double value :
       {object.dimensionsM.x(), object.dimensionsM.y(), object.dimensionsM.z(),
        object.positionEnu.x(), object.positionEnu.y(), object.positionEnu.z(),
        object.headingEnuRad, object.speedMps, object.yawRateRadps, object.imageBox.cx,
        object.imageBox.cy, object.imageBox.length, object.imageBox.width, object.imageBox.angle,
        object.truncation, object.occlusion}) {
    row += ',';
    appendNumber(row, value);
  }
  row += object.parked ? ",1" : ",0";
  return row;
}

KeypointTruth parseKeypointRow(Fields f) {
  const auto& c = kKeypointColumns;
  KeypointTruth keypoint;
  keypoint.frameId = parseInteger(f[0], c[0], 0, std::numeric_limits<std::int64_t>::max());
  keypoint.trackId = static_cast<int>(parseInteger(f[1], c[1], 0, std::numeric_limits<int>::max()));
  keypoint.keypoint = static_cast<int>(parseInteger(f[2], c[2], 0, shape::kKeypointCount - 1));
  keypoint.pixel = {parseReal<double>(f[3], c[3]), parseReal<double>(f[4], c[4])};
  keypoint.visible = parseFlag(f[5], c[5]);
  keypoint.worldEnu = {parseReal<double>(f[6], c[6]), parseReal<double>(f[7], c[7]),
                       parseReal<double>(f[8], c[8])};
  return keypoint;
}

std::string formatKeypointRow(const KeypointTruth& keypoint) {
  std::string row;
  appendNumber(row, keypoint.frameId);
  row += ',';
  appendNumber(row, keypoint.trackId);
  row += ',';
  appendNumber(row, keypoint.keypoint);
  for (const double value : {keypoint.pixel.x(), keypoint.pixel.y()}) {
    row += ',';
    appendNumber(row, value);
  }
  row += keypoint.visible ? ",1" : ",0";
  for (const double value : {keypoint.worldEnu.x(), keypoint.worldEnu.y(), keypoint.worldEnu.z()}) {
    row += ',';
    appendNumber(row, value);
  }
  return row;
}

// ---- rules between rows and files (shared by reader and writer) ----------------------------

class SequenceRules {
 public:
  void checkFrame(const FrameRecord& frame) const {
    if (frameIds_.empty()) {
      return;
    }
    if (frame.frameId <= frameIds_.back()) {
      throw FieldError{"frame_id", "not increasing (" + std::to_string(frame.frameId) + " after " +
                                       std::to_string(frameIds_.back()) + ")"};
    }
    if (frame.timestampNs <= lastFrameNs_) {
      throw FieldError{"timestamp_ns", "not increasing (" + std::to_string(frame.timestampNs) +
                                           " after " + std::to_string(lastFrameNs_) + ")"};
    }
  }
  void addFrame(const FrameRecord& frame) {
    checkFrame(frame);
    frameIds_.push_back(frame.frameId);
    lastFrameNs_ = frame.timestampNs;
  }

  void addTelemetry(const TelemetryRecord& record) {
    if (lastTelemetryNs_ && record.timestampNs < *lastTelemetryNs_) {
      throw FieldError{"timestamp_ns", "decreasing (" + std::to_string(record.timestampNs) +
                                           " after " + std::to_string(*lastTelemetryNs_) + ")"};
    }
    lastTelemetryNs_ = record.timestampNs;
  }

  void addObject(const ObjectTruth& object) {
    checkFrameOrder(object.frameId, lastObjectFrame_);
    if (!std::binary_search(frameIds_.begin(), frameIds_.end(), object.frameId)) {
      throw FieldError{"frame_id", "no frame " + std::to_string(object.frameId) + " in frames.csv"};
    }
    if (!objectKeys_.emplace(object.frameId, object.trackId).second) {
      throw FieldError{"track_id", "track " + std::to_string(object.trackId) +
                                       " appears twice in frame " + std::to_string(object.frameId)};
    }
    lastObjectFrame_ = object.frameId;
  }

  void addKeypoint(const KeypointTruth& keypoint) {
    checkFrameOrder(keypoint.frameId, lastKeypointFrame_);
    if (!objectKeys_.contains({keypoint.frameId, keypoint.trackId})) {
      throw FieldError{"track_id", "no object " + std::to_string(keypoint.trackId) + " in frame " +
                                       std::to_string(keypoint.frameId) + " of objects.csv"};
    }
    if (keypoint.frameId != lastKeypointFrame_) {
      frameKeypoints_.clear();
    }
    if (!frameKeypoints_.emplace(keypoint.trackId, keypoint.keypoint).second) {
      throw FieldError{"keypoint", "keypoint " + std::to_string(keypoint.keypoint) + " of track " +
                                       std::to_string(keypoint.trackId) +
                                       " appears twice in frame " +
                                       std::to_string(keypoint.frameId)};
    }
    lastKeypointFrame_ = keypoint.frameId;
  }

  std::size_t frameCount() const { return frameIds_.size(); }

 private:
  static void checkFrameOrder(std::int64_t frameId, const std::optional<std::int64_t>& last) {
    if (last && frameId < *last) {
      throw FieldError{"frame_id", "not in frame order (" + std::to_string(frameId) + " after " +
                                       std::to_string(*last) + ")"};
    }
  }

  std::vector<std::int64_t> frameIds_;  // increasing
  std::int64_t lastFrameNs_ = 0;
  std::optional<std::int64_t> lastTelemetryNs_;
  std::set<std::pair<std::int64_t, int>> objectKeys_;  // (frame, track)
  std::optional<std::int64_t> lastObjectFrame_;
  std::optional<std::int64_t> lastKeypointFrame_;
  std::set<std::pair<int, int>> frameKeypoints_;  // (track, keypoint) in lastKeypointFrame_
};

// ---- files ---------------------------------------------------------------------------------

bool readWholeFile(const fs::path& path, std::string* text) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    return false;
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    return false;
  }
  std::ostringstream buffer;
  buffer << file.rdbuf();
  *text = buffer.str();
  return !file.bad();
}

// Splits `line` at commas into `fields` (views into `line`).
void splitFields(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(line.substr(start));
      return;
    }
    fields.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
}

// One CSV file of the sequence, read whole at open; hands out rows as field views.
class CsvFile {
 public:
  CsvFile(const fs::path& directory, const char* relativePath)
      : name_((directory / relativePath).string()) {
    if (!readWholeFile(directory / relativePath, &text_)) {
      throw SequenceError(name_ + ": missing (required)");
    }
  }

  // The header line, checked against the expected column names by the caller.
  std::string_view header() {
    std::string_view line;
    if (!nextLine(line)) {
      line_ = 1;
      return {};
    }
    return line;
  }

  void setColumns(std::vector<std::string> names) { names_ = std::move(names); }
  const std::vector<std::string>& columns() const { return names_; }

  // Next data row; false at the end of the file.
  bool nextRow() {
    std::string_view line;
    if (!nextLine(line)) {
      return false;
    }
    if (line.empty()) {
      fail("empty line");
    }
    splitFields(line, fields_);
    for (std::size_t i = 0; i < fields_.size(); ++i) {
      if (fields_[i].find('"') != std::string_view::npos) {
        fail(columnName(i), "quoted fields are not supported (fields never contain commas)");
      }
    }
    if (fields_.size() != names_.size()) {
      fail("expected " + std::to_string(names_.size()) + " fields, got " +
           std::to_string(fields_.size()));
    }
    return true;
  }

  Fields fields() const { return fields_; }
  const std::string& name() const { return name_; }

  [[noreturn]] void fail(const std::string& problem) const {
    throw SequenceError(name_ + ":" + std::to_string(line_) + ": " + problem);
  }
  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    fail(field + ": " + problem);
  }
  [[noreturn]] void fail(const FieldError& error) const { fail(error.field, error.problem); }

  [[noreturn]] void failHeader(const std::string& expected, std::string_view got,
                               const std::string& note = "") const {
    throw SequenceError(name_ + ":1: header: expected " + quote(expected) + note + ", got " +
                        (got.empty() ? std::string("an empty line or file") : quote(got)));
  }

 private:
  bool nextLine(std::string_view& line) {
    if (position_ >= text_.size()) {
      return false;
    }
    const std::size_t end = std::min(text_.find('\n', position_), text_.size());
    line = std::string_view(text_).substr(position_, end - position_);
    position_ = end + 1;
    ++line_;
    if (!line.empty() && line.back() == '\r') {
      line.remove_suffix(1);  // CRLF files from Windows tools read the same
    }
    return true;
  }

  std::string columnName(std::size_t i) const {
    return i < names_.size() ? names_[i] : "field " + std::to_string(i + 1);
  }

  std::string name_;
  std::string text_;
  std::size_t position_ = 0;
  int line_ = 0;
  std::vector<std::string> names_;
  std::vector<std::string_view> fields_;
};

void expectHeader(CsvFile& file, std::vector<std::string> names) {
  const std::string expected = joinColumns(names);
  const std::string_view got = file.header();
  if (got != expected) {
    file.failHeader(expected, got);
  }
  file.setColumns(std::move(names));
}

// ---- sequence.yaml -------------------------------------------------------------------------

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
    throw SequenceError(name_ + ": " + (key.empty() ? "" : key + ": ") + problem);
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
  info->frameRateHz = reader.number(required("frame_rate_hz"), "frame_rate_hz");
  if (!(info->frameRateHz > 0.0)) {
    reader.fail("frame_rate_hz", "must be > 0, got " + numberText(info->frameRateHz));
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

std::string formatInfo(const SequenceInfo& info, std::size_t frameCount) {
  std::string text = "format_version: " + std::to_string(info.formatVersion) + "\n";
  text += "name: " + yamlQuoted(info.name) + "\n";
  text += "frame_rate_hz: " + numberText(info.frameRateHz) + "\n";
  text += "source: " + yamlQuoted(info.source) + "\n";
  text += "frame_count: " + std::to_string(frameCount) + "\n";
  if (!info.notes.empty()) {
    text += "notes: " + yamlQuoted(info.notes) + "\n";
  }
  return text;
}

// ---- reading the parts ---------------------------------------------------------------------

config::AppConfig readRig(const fs::path& directory) {
  const fs::path path = directory / kRigFile;
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    throw SequenceError(path.string() + ": missing (required)");
  }
  config::AppConfig rig;
  try {
    rig = config::loadConfig(path.string());
  } catch (const config::ConfigError& problem) {
    throw SequenceError(problem.what());
  }
  if (!fs::is_regular_file(rig.terrain.dtmPath, error)) {
    throw SequenceError(path.string() + ": terrain.dtm_path: no such file " +
                        quote(rig.terrain.dtmPath));
  }
  return rig;
}

std::vector<FrameRecord> readFrames(const fs::path& directory, SequenceRules& rules) {
  CsvFile file(directory, kFramesFile);
  expectHeader(file, toStrings(kFrameColumns));
  std::vector<FrameRecord> frames;
  while (file.nextRow()) {
    try {
      FrameRecord frame = parseFrameRow(file.fields());
      rules.addFrame(frame);
      frames.push_back(std::move(frame));
    } catch (const FieldError& error) {
      file.fail(error);
    }
  }
  return frames;
}

std::vector<TelemetryRecord> readTelemetry(const fs::path& directory, SequenceRules& rules) {
  CsvFile file(directory, kTelemetryFile);
  expectHeader(file, toStrings(kTelemetryColumns));
  std::vector<TelemetryRecord> records;
  while (file.nextRow()) {
    try {
      records.push_back(parseTelemetryRow(file.fields()));
      rules.addTelemetry(records.back());
    } catch (const FieldError& error) {
      file.fail(error);
    }
  }
  return records;
}

// The gamma column count of an objects.csv header, or -1 when it is not a valid header.
int objectsGammaCount(std::string_view header) {
  std::vector<std::string_view> fields;
  splitFields(header, fields);
  const int count = static_cast<int>(fields.size()) -
                    static_cast<int>(kObjectHeadColumns.size() + kObjectTailColumns.size());
  if (count < 0 || count > shape::kMaxShapeComponents) {
    return -1;
  }
  return header == joinColumns(objectColumns(count)) ? count : -1;
}

std::vector<ObjectTruth> readObjects(const fs::path& directory, SequenceRules& rules) {
  CsvFile file(directory, kObjectsFile);
  const std::string_view header = file.header();
  const int gammaCount = objectsGammaCount(header);
  if (gammaCount < 0) {
    file.failHeader(
        "frame_id,track_id,type,gamma_0,...,gamma_{n-1},length_m,width_m,height_m,east_m,"
        "north_m,up_m,heading_enu_rad,speed_mps,yaw_rate_radps,box_cx_px,box_cy_px,"
        "box_length_px,box_width_px,box_angle_rad,truncation,occlusion,parked",
        header, " (n = 0.." + std::to_string(shape::kMaxShapeComponents) + ")");
  }
  file.setColumns(objectColumns(gammaCount));
  std::vector<ObjectTruth> objects;
  while (file.nextRow()) {
    try {
      objects.push_back(parseObjectRow(file.fields(), gammaCount, file.columns()));
      rules.addObject(objects.back());
    } catch (const FieldError& error) {
      file.fail(error);
    }
  }
  return objects;
}

std::vector<KeypointTruth> readKeypoints(const fs::path& directory, SequenceRules& rules) {
  CsvFile file(directory, kKeypointsFile);
  expectHeader(file, toStrings(kKeypointColumns));
  std::vector<KeypointTruth> keypoints;
  while (file.nextRow()) {
    try {
      keypoints.push_back(parseKeypointRow(file.fields()));
      rules.addKeypoint(keypoints.back());
    } catch (const FieldError& error) {
      file.fail(error);
    }
  }
  return keypoints;
}

bool fileExists(const fs::path& path) {
  std::error_code error;
  return fs::exists(path, error);
}

void setWhy(std::string* why, std::string message) {
  if (why != nullptr) {
    *why = std::move(message);
  }
}

// Storage is in non-decreasing frame order (the files must be); spans are found by bisection.
struct ByFrame {
  template <typename T>
  bool operator()(const T& record, std::int64_t frameId) const {
    return record.frameId < frameId;
  }
  template <typename T>
  bool operator()(std::int64_t frameId, const T& record) const {
    return frameId < record.frameId;
  }
};

template <typename T>
std::span<const T> framesSpan(const std::vector<T>& records, std::int64_t frameId) {
  const auto [first, last] = std::equal_range(records.begin(), records.end(), frameId, ByFrame{});
  return std::span<const T>(first, last);
}

}  // namespace

// ---- SequenceReader ------------------------------------------------------------------------

bool SequenceReader::open(const std::string& directory, std::string* why) {
  *this = SequenceReader{};
  try {
    const fs::path dir(directory);
    SequenceReader reader;
    reader.directory_ = directory;
    const std::int64_t frameCount = readInfo(dir, &reader.info_);
    reader.rig_ = readRig(dir);
    SequenceRules rules;
    reader.frames_ = readFrames(dir, rules);
    if (static_cast<std::size_t>(frameCount) != reader.frames_.size()) {
      throw SequenceError((dir / kSequenceFile).string() +
                          ": frame_count: " + std::to_string(frameCount) + " but frames.csv has " +
                          std::to_string(reader.frames_.size()) + " frames");
    }
    reader.telemetry_ = readTelemetry(dir, rules);
    const bool hasObjects = fileExists(dir / kObjectsFile);
    if (hasObjects) {
      reader.hasGroundTruth_ = true;
      reader.objects_ = readObjects(dir, rules);
    }
    if (fileExists(dir / kKeypointsFile)) {
      if (!hasObjects) {
        throw SequenceError((dir / kKeypointsFile).string() + ": present without " +
                            (dir / kObjectsFile).string());
      }
      reader.keypoints_ = readKeypoints(dir, rules);
    }
    *this = std::move(reader);
    return true;
  } catch (const SequenceError& error) {
    setWhy(why, error.what());
    return false;
  }
}

std::span<const ObjectTruth> SequenceReader::objects(std::int64_t frameId) const {
  return framesSpan(objects_, frameId);
}

std::span<const KeypointTruth> SequenceReader::keypoints(std::int64_t frameId) const {
  return framesSpan(keypoints_, frameId);
}

bool SequenceReader::loadFrame(std::size_t index, cv::Mat& image, std::string* why) const {
  if (index >= frames_.size()) {
    setWhy(why, directory_ + ": frame index " + std::to_string(index) + " out of range (" +
                    std::to_string(frames_.size()) + " frames)");
    return false;
  }
  const std::string path = (fs::path(directory_) / frames_[index].file).string();
  cv::Mat decoded;
  try {
    decoded = cv::imread(path, cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    decoded.release();  // a decoder that throws on a corrupt file: same report as one that fails
  }
  if (decoded.empty()) {
    setWhy(why, path + ": cannot decode image (missing or corrupt)");
    return false;
  }
  const camera::Intrinsics& camera = rig_.camera.intrinsics;
  if (decoded.cols != camera.widthPx || decoded.rows != camera.heightPx) {
    setWhy(why, path + ": image is " + std::to_string(decoded.cols) + "x" +
                    std::to_string(decoded.rows) + ", rig.yaml camera is " +
                    std::to_string(camera.widthPx) + "x" + std::to_string(camera.heightPx));
    return false;
  }
  if (image.size() == decoded.size() && image.type() == decoded.type()) {
    decoded.copyTo(image);  // keeps the caller's buffer (it may be shared or pinned)
  } else {
    image = decoded;
  }
  return true;
}

// ---- SequenceWriter ------------------------------------------------------------------------

struct SequenceWriter::Files {
  // One CSV output: the stream, its display name and the line the next row goes to.
  struct Csv {
    std::ofstream stream;
    std::string name;
    int nextLine = 2;
  };

  fs::path directory;
  SequenceInfo info;
  int widthPx = 0;
  int heightPx = 0;
  int gammaColumns = 0;
  std::vector<std::string> objectNames;
  Csv frames;
  Csv telemetry;
  std::optional<Csv> objects;
  std::optional<Csv> keypoints;
  SequenceRules rules;
  std::vector<std::string_view> fields;  // scratch

  bool openCsv(Csv& csv, const char* relativePath, const std::string& header, std::string* why) {
    csv.name = (directory / relativePath).string();
    csv.stream.open(directory / relativePath, std::ios::binary | std::ios::trunc);
    csv.stream << header << '\n';
    if (!csv.stream) {
      setWhy(why, csv.name + ": cannot write");
      return false;
    }
    return true;
  }

  bool appendRow(Csv& csv, const std::string& row, std::string* why) {
    csv.stream << row << '\n';
    ++csv.nextLine;
    if (!csv.stream) {
      setWhy(why, csv.name + ": write error");
      return false;
    }
    return true;
  }

  std::string where(const Csv& csv, const FieldError& error) const {
    return csv.name + ":" + std::to_string(csv.nextLine) + ": " + error.field + ": " +
           error.problem;
  }
};

SequenceWriter::SequenceWriter() = default;

SequenceWriter::~SequenceWriter() {
  if (files_) {
    close(nullptr);
  }
}

bool SequenceWriter::open(const std::string& directory, const SequenceInfo& info,
                          const std::string& rigYaml, const std::string& dtmFile,
                          std::string* why) {
  if (files_) {
    setWhy(why, directory_ + ": writer already open");
    return false;
  }
  const fs::path dir(directory);
  const std::string infoName = (dir / kSequenceFile).string();
  if (info.formatVersion != kFormatVersion) {
    setWhy(why, infoName + ": format_version: " + std::to_string(info.formatVersion) +
                    " not supported (this writer writes " + std::to_string(kFormatVersion) + ")");
    return false;
  }
  if (info.name.empty()) {
    setWhy(why, infoName + ": name: must not be empty");
    return false;
  }
  if (!(info.frameRateHz > 0.0) || !std::isfinite(info.frameRateHz)) {
    setWhy(why, infoName + ": frame_rate_hz: must be a finite number > 0");
    return false;
  }

  std::error_code error;
  // Never mix two recordings: stale frames of an earlier run would be silently kept.
  if (fs::exists(dir, error) && !(fs::is_directory(dir, error) && fs::is_empty(dir, error))) {
    setWhy(why, directory + ": exists and is not an empty directory");
    return false;
  }
  fs::create_directories(dir / "frames", error);
  if (!error) {
    fs::create_directories(dir / "ground_truth", error);
  }
  if (error) {
    setWhy(why, directory + ": cannot create the directory: " + error.message());
    return false;
  }

  // Checked now so that a sequence is never written with a rig the reader rejects.
  const fs::path absoluteDir = fs::absolute(dir, error).lexically_normal();
  config::AppConfig rig;
  try {
    rig = config::parseConfig(rigYaml, (dir / kRigFile).string(), absoluteDir.string());
  } catch (const config::ConfigError& problem) {
    setWhy(why, problem.what());
    return false;
  }
  if (fs::path(rig.terrain.dtmPath) != (absoluteDir / kDtmFile).lexically_normal()) {
    setWhy(why, (dir / kRigFile).string() + ": terrain.dtm_path: must be " + kDtmFile +
                    " (the writer copies the DTM there)");
    return false;
  }
  {
    std::ofstream rigFile(dir / kRigFile, std::ios::binary | std::ios::trunc);
    rigFile << rigYaml;
    rigFile.close();
    if (!rigFile) {
      setWhy(why, (dir / kRigFile).string() + ": cannot write");
      return false;
    }
  }
  if (!fs::copy_file(dtmFile, dir / kDtmFile, error)) {
    setWhy(why, "cannot copy the DTM " + quote(dtmFile) + " to " +
                    quote((dir / kDtmFile).string()) + ": " + error.message());
    return false;
  }
  for (const char* extension : kWorldFileExtensions) {
    const fs::path worldFile = fs::path(dtmFile).replace_extension(extension);
    if (fileExists(worldFile) &&
        !fs::copy_file(worldFile, dir / (std::string("dtm") + extension), error)) {
      setWhy(why,
             "cannot copy the world file " + quote(worldFile.string()) + ": " + error.message());
      return false;
    }
  }

  auto files = std::make_unique<Files>();
  files->directory = dir;
  files->info = info;
  files->widthPx = rig.camera.intrinsics.widthPx;
  files->heightPx = rig.camera.intrinsics.heightPx;
  if (!files->openCsv(files->frames, kFramesFile, joinColumns(toStrings(kFrameColumns)), why) ||
      !files->openCsv(files->telemetry, kTelemetryFile, joinColumns(toStrings(kTelemetryColumns)),
                      why)) {
    return false;
  }
  files_ = std::move(files);
  directory_ = directory;
  return true;
}

bool SequenceWriter::writeFrame(const FrameRecord& frame, const cv::Mat& image, std::string* why) {
  if (!files_) {
    setWhy(why, "writeFrame: the writer is not open");
    return false;
  }
  Files& files = *files_;
  FrameRecord record = frame;
  if (record.file.empty()) {
    std::array<char, 32> name{};
    std::snprintf(name.data(), name.size(), "%06lld", static_cast<long long>(record.frameId));
    record.file = "frames/" + std::string(name.data()) + imageExtension;
  }
  std::vector<int> parameters;
  try {
    if (record.file.find_first_of(",\"\r\n") != std::string::npos) {
      throw FieldError{"file",
                       "must not contain ',', '\"' or line breaks, got " + quote(record.file)};
    }
    const std::string row = formatFrameRow(record);
    splitFields(row, files.fields);
    record = parseFrameRow(files.fields);
    files.rules.checkFrame(record);
    const std::string extension = fs::path(record.file).extension().string();
    if (extension == ".png") {
      parameters = {cv::IMWRITE_PNG_COMPRESSION, kPngCompression};
    } else if (extension == ".jpg" || extension == ".jpeg") {
      if (jpegQuality < 1 || jpegQuality > 100) {
        throw FieldError{"file",
                         "jpegQuality must be in [1, 100], got " + std::to_string(jpegQuality)};
      }
      parameters = {cv::IMWRITE_JPEG_QUALITY, jpegQuality};
    } else {
      throw FieldError{
          "file", "unsupported image extension " + quote(extension) + " (expected .png, .jpg)"};
    }
    if (image.type() != CV_8UC3 && image.type() != CV_8UC1) {
      throw FieldError{"image", "expected an 8-bit BGR or grey image, got OpenCV type " +
                                    std::to_string(image.type())};
    }
    if (image.cols != files.widthPx || image.rows != files.heightPx) {
      throw FieldError{"image", "image is " + std::to_string(image.cols) + "x" +
                                    std::to_string(image.rows) + ", rig.yaml camera is " +
                                    std::to_string(files.widthPx) + "x" +
                                    std::to_string(files.heightPx)};
    }
  } catch (const FieldError& error) {
    setWhy(why, files.where(files.frames, error));
    return false;
  }

  const fs::path path = files.directory / record.file;
  std::error_code error;
  fs::create_directories(path.parent_path(), error);
  bool written = false;
  try {
    written = !error && cv::imwrite(path.string(), image, parameters);
  } catch (const cv::Exception&) {
    written = false;  // reported below like a failed write
  }
  if (!written) {
    setWhy(why, path.string() + ": cannot write image");
    return false;
  }
  files.rules.addFrame(record);
  return files.appendRow(files.frames, formatFrameRow(record), why);
}

bool SequenceWriter::writeTelemetry(const TelemetryRecord& record, std::string* why) {
  if (!files_) {
    setWhy(why, "writeTelemetry: the writer is not open");
    return false;
  }
  Files& files = *files_;
  const std::string row = formatTelemetryRow(record);
  try {
    splitFields(row, files.fields);
    files.rules.addTelemetry(parseTelemetryRow(files.fields));
  } catch (const FieldError& error) {
    setWhy(why, files.where(files.telemetry, error));
    return false;
  }
  return files.appendRow(files.telemetry, row, why);
}

bool SequenceWriter::writeObjects(std::span<const ObjectTruth> objects, std::string* why) {
  if (!files_) {
    setWhy(why, "writeObjects: the writer is not open");
    return false;
  }
  Files& files = *files_;
  if (!files.objects) {
    int columns = gammaColumns;
    if (columns < 0) {
      columns = 0;
      for (const ObjectTruth& object : objects) {
        columns = std::max(columns, object.shape.count);
      }
      columns = columns > 0 ? columns : shape::kMaxShapeComponents;
    }
    if (columns > shape::kMaxShapeComponents) {
      setWhy(why, "writeObjects: gammaColumns must be in [-1, " +
                      std::to_string(shape::kMaxShapeComponents) + "], got " +
                      std::to_string(columns));
      return false;
    }
    files.gammaColumns = columns;
    files.objectNames = objectColumns(columns);
    files.objects.emplace();
    if (!files.openCsv(*files.objects, kObjectsFile, joinColumns(files.objectNames), why)) {
      return false;
    }
  }
  for (const ObjectTruth& object : objects) {
    try {
      if (object.shape.count < 0 || object.shape.count > files.gammaColumns) {
        throw FieldError{"gamma", "shape has " + std::to_string(object.shape.count) +
                                      " components, objects.csv has " +
                                      std::to_string(files.gammaColumns) + " gamma columns"};
      }
      const std::string row = formatObjectRow(object, files.gammaColumns);
      splitFields(row, files.fields);
      files.rules.addObject(parseObjectRow(files.fields, files.gammaColumns, files.objectNames));
      if (!files.appendRow(*files.objects, row, why)) {
        return false;
      }
    } catch (const FieldError& error) {
      setWhy(why, files.where(*files.objects, error));
      return false;
    }
  }
  return true;
}

bool SequenceWriter::writeKeypoints(std::span<const KeypointTruth> keypoints, std::string* why) {
  if (!files_) {
    setWhy(why, "writeKeypoints: the writer is not open");
    return false;
  }
  Files& files = *files_;
  if (!files.keypoints) {
    files.keypoints.emplace();
    if (!files.openCsv(*files.keypoints, kKeypointsFile, joinColumns(toStrings(kKeypointColumns)),
                       why)) {
      return false;
    }
  }
  for (const KeypointTruth& keypoint : keypoints) {
    try {
      const std::string row = formatKeypointRow(keypoint);
      splitFields(row, files.fields);
      files.rules.addKeypoint(parseKeypointRow(files.fields));
      if (!files.appendRow(*files.keypoints, row, why)) {
        return false;
      }
    } catch (const FieldError& error) {
      setWhy(why, files.where(*files.keypoints, error));
      return false;
    }
  }
  return true;
}

bool SequenceWriter::close(std::string* why) {
  if (!files_) {
    return true;  // closing twice is harmless
  }
  const std::unique_ptr<Files> files = std::move(files_);
  bool ok = true;
  const auto finish = [&](std::ofstream& stream, const std::string& name) {
    stream.close();
    if (ok && !stream) {
      setWhy(why, name + ": write error");
      ok = false;
    }
  };
  finish(files->frames.stream, files->frames.name);
  finish(files->telemetry.stream, files->telemetry.name);
  if (files->objects) {
    finish(files->objects->stream, files->objects->name);
  }
  if (files->keypoints) {
    finish(files->keypoints->stream, files->keypoints->name);
  }
  // Written last: a recording cut short has no sequence.yaml, and the reader rejects it.
  const fs::path infoPath = files->directory / kSequenceFile;
  std::ofstream info(infoPath, std::ios::binary | std::ios::trunc);
  info << formatInfo(files->info, files->rules.frameCount());
  finish(info, infoPath.string());
  return ok;
}

}  // namespace vp::sequence
