// sequence/sequence_rows: the CSV rows of a recorded sequence (frames, telemetry, ground
// truth), parsed and formatted, and the CSV file reader of the recording.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>

#include "csv/csv_io.hpp"
#include "sequence/sequence_format.hpp"

namespace vp::sequence::detail {
namespace {

using csv::joinColumns;
using csv::quote;

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

}  // namespace

std::string numberText(double value) {
  return numberText<double>(value);
}

std::vector<std::string> objectColumns(int gammaCount) {
  std::vector<std::string> names(kObjectHeadColumns.begin(), kObjectHeadColumns.end());
  for (int i = 0; i < gammaCount; ++i) {
    names.push_back("gamma_" + std::to_string(i));
  }
  names.insert(names.end(), kObjectTailColumns.begin(), kObjectTailColumns.end());
  return names;
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

FrameRecord parseFrameRow(Fields f) {
  FrameRecord frame;
  frame.frameId = parseInteger(f[0], kFrameColumns[0], 0, std::numeric_limits<std::int64_t>::max());
  frame.timestamp_ns =
      parseInteger(f[1], kFrameColumns[1], std::numeric_limits<std::int64_t>::min(),
                   std::numeric_limits<std::int64_t>::max());
  checkRelativeFile(f[2]);
  frame.file = std::string(f[2]);
  return frame;
}

std::string formatFrameRow(const FrameRecord& frame) {
  std::string row;
  appendNumber(row, frame.frameId);
  row += ',';
  appendNumber(row, frame.timestamp_ns);
  row += ',';
  row += frame.file;
  return row;
}

TelemetryRecord parseTelemetryRow(Fields f) {
  const auto& c = kTelemetryColumns;
  TelemetryRecord record;
  record.timestamp_ns = parseInteger(f[0], c[0], std::numeric_limits<std::int64_t>::min(),
                                     std::numeric_limits<std::int64_t>::max());
  record.position.latitude_deg = parseReal(f[1], c[1], -90.0, 90.0);
  record.position.longitude_deg = parseReal(f[2], c[2], -180.0, 180.0);
  record.position.height_m = parseReal<double>(f[3], c[3]);
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
  record.gimbal.angles.roll_deg = parseReal<double>(f[8], c[8]);
  record.gimbal.angles.pitch_deg = parseReal<double>(f[9], c[9]);
  record.gimbal.angles.yaw_deg = parseReal<double>(f[10], c[10]);
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
  appendNumber(row, record.timestamp_ns);
  for (const double value :
       {record.position.latitude_deg, record.position.longitude_deg, record.position.height_m,
        record.bodyToNed.w(), record.bodyToNed.x(), record.bodyToNed.y(), record.bodyToNed.z(),
        record.gimbal.angles.roll_deg, record.gimbal.angles.pitch_deg,
        record.gimbal.angles.yaw_deg}) {
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
  object.dimensions_m = {nonNegative(0), nonNegative(1), nonNegative(2)};
  object.positionEnu = {real(3), real(4), real(5)};
  object.headingEnu_rad = real(6);
  object.speed_mps = real(7);
  object.yawRate_radps = real(8);
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
       {object.dimensions_m.x(), object.dimensions_m.y(), object.dimensions_m.z(),
        object.positionEnu.x(), object.positionEnu.y(), object.positionEnu.z(),
        object.headingEnu_rad, object.speed_mps, object.yawRate_radps, object.imageBox.cx,
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

bool fileExists(const fs::path& path) {
  std::error_code error;
  return fs::exists(path, error);
}

void setWhy(std::string* why, std::string message) {
  if (why != nullptr) {
    *why = std::move(message);
  }
}

void expectHeader(CsvFile& file, std::vector<std::string> names) {
  const std::string expected = joinColumns(names);
  const std::string_view got = file.header();
  if (got != expected) {
    file.failHeader(expected, got);
  }
  file.setColumns(std::move(names));
}

}  // namespace vp::sequence::detail
