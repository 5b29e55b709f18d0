// sequence/sequence_format: the parts of the recorded-sequence format that the reader and the
// writer share (internal to vp_sequence; the public API is sequence/recorded_sequence.hpp).
//
// Contract: the file names and column names of docs/recorded_sequence.md; one parser and one
// formatter per CSV row kind; the rules between rows (SequenceRules); sequence.yaml read and
// written. The writer formats each record, parses it back with the reader's parser and applies
// the same rules before writing, so it cannot write a sequence that the reader rejects. Problems
// are thrown (start-up code only): FieldError for one field of one record (the caller adds the
// file and line), SequenceError with a complete message; the public API returns them as values.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "csv/csv_io.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::sequence::detail {

namespace fs = std::filesystem;

inline constexpr double kQuaternionNormTolerance = 1e-3;
// Fixed (not OpenCV's default, which may change between versions) so that the bytes of a
// written PNG depend on the image only.
inline constexpr int kPngCompression = 3;

inline constexpr const char* kSequenceFile = "sequence.yaml";
inline constexpr const char* kRigFile = "rig.yaml";
inline constexpr const char* kDtmFile = "dtm.tif";
inline constexpr const char* kFramesFile = "frames.csv";
inline constexpr const char* kTelemetryFile = "telemetry.csv";
inline constexpr const char* kObjectsFile = "ground_truth/objects.csv";
inline constexpr const char* kKeypointsFile = "ground_truth/keypoints.csv";
inline constexpr std::array<const char*, 3> kWorldFileExtensions{".tfw", ".tifw", ".wld"};

inline constexpr std::array<std::string_view, 3> kFrameColumns{"frame_id", "timestamp_ns", "file"};
inline constexpr std::array<std::string_view, 12> kTelemetryColumns{"timestamp_ns",
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
inline constexpr std::array<std::string_view, 3> kObjectHeadColumns{"frame_id", "track_id", "type"};
inline constexpr std::array<std::string_view, 17> kObjectTailColumns{
    "length_m",        "width_m",       "height_m",       "east_m",    "north_m",   "up_m",
    "heading_enu_rad", "speed_mps",     "yaw_rate_radps", "box_cx_px", "box_cy_px", "box_length_px",
    "box_width_px",    "box_angle_rad", "truncation",     "occlusion", "parked"};
inline constexpr std::array<std::string_view, 9> kKeypointColumns{
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

std::vector<std::string> objectColumns(int gammaCount);

template <typename Names>
std::vector<std::string> toStrings(const Names& names) {
  return std::vector<std::string>(names.begin(), names.end());
}

// Shortest text that std::from_chars reads back to the same value: exact round trips.
std::string numberText(double value);

// ---- rows (sequence_rows.cpp); parsers throw FieldError --------------------------------------

using Fields = std::span<const std::string_view>;

FrameRecord parseFrameRow(Fields f);
std::string formatFrameRow(const FrameRecord& frame);
TelemetryRecord parseTelemetryRow(Fields f);
std::string formatTelemetryRow(const TelemetryRecord& record);
// `names` is the header of the file (it has gammaCount gamma columns).
ObjectTruth parseObjectRow(Fields f, int gammaCount, const std::vector<std::string>& names);
// Precondition: 0 <= object.shape.count <= gammaCount.
std::string formatObjectRow(const ObjectTruth& object, int gammaCount);
KeypointTruth parseKeypointRow(Fields f);
std::string formatKeypointRow(const KeypointTruth& keypoint);

// ---- rules between rows and files (shared by reader and writer) ----------------------------

// ---- rules between rows and files (shared by reader and writer) ----------------------------

class SequenceRules {
  // A jump beyond kMaxTimestampGap_ns (docs/recorded_sequence.md): `later` >= `earlier`.
  static void checkGap(std::int64_t later, std::int64_t earlier, const char* what) {
    // Unsigned: the difference of any two int64 values in order fits without overflow.
    const std::uint64_t gap_ns =
        static_cast<std::uint64_t>(later) - static_cast<std::uint64_t>(earlier);
    if (gap_ns > static_cast<std::uint64_t>(kMaxTimestampGap_ns)) {
      char text[160];
      std::snprintf(text, sizeof(text),
                    "jumps %.3f s after the previous %s (%lld after %lld ns); a recording may "
                    "pause at most %lld s",
                    static_cast<double>(gap_ns) / 1e9, what, static_cast<long long>(later),
                    static_cast<long long>(earlier),
                    static_cast<long long>(kMaxTimestampGap_ns / 1'000'000'000));
      throw FieldError{"timestamp_ns", text};
    }
  }

 public:
  void checkFrame(const FrameRecord& frame) const {
    if (frameIds_.empty()) {
      return;
    }
    if (frame.frameId <= frameIds_.back()) {
      throw FieldError{"frame_id", "not increasing (" + std::to_string(frame.frameId) + " after " +
                                       std::to_string(frameIds_.back()) + ")"};
    }
    if (frame.timestamp_ns <= lastFrameNs_) {
      throw FieldError{"timestamp_ns", "not increasing (" + std::to_string(frame.timestamp_ns) +
                                           " after " + std::to_string(lastFrameNs_) + ")"};
    }
    checkGap(frame.timestamp_ns, lastFrameNs_, "frame");
  }
  void addFrame(const FrameRecord& frame) {
    checkFrame(frame);
    frameIds_.push_back(frame.frameId);
    lastFrameNs_ = frame.timestamp_ns;
  }

  void addTelemetry(const TelemetryRecord& record) {
    if (lastTelemetryNs_ && record.timestamp_ns < *lastTelemetryNs_) {
      throw FieldError{"timestamp_ns", "decreasing (" + std::to_string(record.timestamp_ns) +
                                           " after " + std::to_string(*lastTelemetryNs_) + ")"};
    }
    if (lastTelemetryNs_) {
      checkGap(record.timestamp_ns, *lastTelemetryNs_, "sample");
    }
    lastTelemetryNs_ = record.timestamp_ns;
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

// The whole file; false when it is not a readable regular file.
bool readWholeFile(const fs::path& path, std::string* text);
bool fileExists(const fs::path& path);
void setWhy(std::string* why, std::string message);

// One CSV file of the sequence, read whole at open; hands out rows as field views.
// One CSV file of the sequence, read whole at open; hands out rows as field views.
class CsvFile {
 public:
  CsvFile(const fs::path& directory, const char* relativePath)
      : name_((directory / relativePath).string()) {
    if (!readWholeFile(directory / relativePath, &text_)) {
      throw SequenceError(csv::shortened(name_) + ": missing (required)");
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
    csv::splitFields(line, fields_);
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
    throw SequenceError(csv::location(name_, line_) + ": " + problem);
  }
  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    fail(field + ": " + problem);
  }
  [[noreturn]] void fail(const FieldError& error) const { fail(error.field, error.problem); }

  [[noreturn]] void failHeader(const std::string& expected, std::string_view got,
                               const std::string& note = "") const {
    throw SequenceError(csv::location(name_, 1) + ": header: expected " + csv::quote(expected) +
                        note + ", got " +
                        (got.empty() ? std::string("an empty line or file") : csv::quote(got)));
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

void expectHeader(CsvFile& file, std::vector<std::string> names);

// ---- sequence.yaml (sequence_info.cpp) -----------------------------------------------------

// Reads sequence.yaml into *info; returns its frame_count. Throws SequenceError.
std::int64_t readInfo(const fs::path& directory, SequenceInfo* info);
std::string formatInfo(const SequenceInfo& info, std::size_t frameCount);

}  // namespace vp::sequence::detail
