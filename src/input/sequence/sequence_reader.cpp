// sequence/sequence_reader: SequenceReader, the recorded-sequence reader. The format, its rules
// and its error messages are documented in docs/recorded_sequence.md; this file and the parts it
// shares with the writer (sequence_format.hpp) implement exactly that document.
#include "sequence/recorded_sequence.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string_view>
#include <system_error>
#include <utility>

#include <opencv2/imgcodecs.hpp>

#include "csv/csv_io.hpp"
#include "rig_config/rig_config.hpp"
#include "sequence/sequence_format.hpp"

namespace vp::sequence {

using namespace detail;  // this module's internals (sequence_format.hpp)
using csv::joinColumns;
using csv::quote;
using csv::shortened;
using csv::splitFields;

namespace {

// ---- reading the parts ---------------------------------------------------------------------

Rig readRig(const fs::path& directory) {
  const fs::path path = directory / kRigFile;
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    throw SequenceError(shortened(path.string()) + ": missing (required)");
  }
  config::RigConfig config;
  try {
    config = config::loadRigConfig(path.string());
  } catch (const config::ConfigError& problem) {
    throw SequenceError(problem.what());
  }
  if (!fs::is_regular_file(config.terrain.dtmPath, error)) {
    throw SequenceError(shortened(path.string()) + ": terrain.dtm_path: no such file " +
                        quote(config.terrain.dtmPath));
  }
  if (!config.terrain.dsmPath.empty() && !fs::is_regular_file(config.terrain.dsmPath, error)) {
    throw SequenceError(shortened(path.string()) + ": terrain.dsm_path: no such file " +
                        quote(config.terrain.dsmPath));
  }
  // Only the rig sections: the loop's sections of a rig.yaml are the application's, not recorded.
  Rig rig;
  rig.sourcePath = config.sourcePath;
  rig.origin = config.origin;
  rig.intrinsics = config.camera.intrinsics;
  rig.distortion = config.camera.distortion;
  rig.mount = config.mount.mount;
  rig.gimbal = config.mount.gimbal;
  rig.dtmPath = config.terrain.dtmPath;
  rig.crs = config.terrain.crs;
  rig.sitePath = config.sitePath;
  rig.dsmPath = config.terrain.dsmPath;
  rig.warnings = std::move(config.warnings);
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

std::vector<TelemetryRecord> readTelemetry(const fs::path& directory, SequenceRules& rules,
                                           const char* fileName = kTelemetryFile) {
  CsvFile file(directory, fileName);
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

// The whole file into bytes (reused by the caller's vector); false when it cannot be read.
bool readFileBytes(const std::string& path, std::vector<unsigned char>& bytes) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    return false;
  }
  bytes.clear();
  std::array<unsigned char, 64 * 1024> chunk{};
  bool ok = true;
  for (;;) {
    const std::size_t n = std::fread(chunk.data(), 1, chunk.size(), file);
    bytes.insert(bytes.end(), chunk.data(), chunk.data() + n);
    if (n < chunk.size()) {
      ok = std::ferror(file) == 0;
      break;
    }
  }
  std::fclose(file);
  return ok;
}

// Why an image file is cut short, or nullptr when it ends as its format requires (formats
// other than JPEG and PNG are left to the decoder).
const char* imageEndProblem(std::span<const unsigned char> bytes) {
  constexpr std::array<unsigned char, 2> kJpegStart{0xFF, 0xD8};
  constexpr std::array<unsigned char, 8> kPngSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  // The IEND chunk: length 0, type, CRC of the type.
  constexpr std::array<unsigned char, 12> kPngEnd{0,   0,   0,    0,    'I',  'E',
                                                  'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  const auto startsWith = [&](std::span<const unsigned char> prefix) {
    return bytes.size() >= prefix.size() && std::equal(prefix.begin(), prefix.end(), bytes.begin());
  };
  if (startsWith(kJpegStart)) {
    // The end-of-image marker FF D9, after which some writers pad with zero bytes.
    std::size_t end = bytes.size();
    while (end > 0 && bytes[end - 1] == 0x00) {
      --end;
    }
    if (end < 4 || bytes[end - 2] != 0xFF || bytes[end - 1] != 0xD9) {
      return "truncated JPEG: partial decode refused (the file does not end with the "
             "end-of-image marker FF D9)";
    }
    return nullptr;
  }
  if (startsWith(kPngSignature)) {
    if (bytes.size() < kPngSignature.size() + kPngEnd.size() ||
        !std::equal(kPngEnd.begin(), kPngEnd.end(), bytes.end() - kPngEnd.size())) {
      return "truncated PNG: partial decode refused (the file does not end with the IEND "
             "chunk)";
    }
    return nullptr;
  }
  return nullptr;
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

bool readTelemetryFile(const std::string& path, std::vector<TelemetryRecord>& out,
                       std::string* why) {
  try {
    const fs::path file(path);
    SequenceRules rules;
    out = readTelemetry(file.parent_path(), rules, file.filename().c_str());
    return true;
  } catch (const SequenceError& error) {
    setWhy(why, error.what());
    return false;
  }
}

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
      throw SequenceError(shortened((dir / kSequenceFile).string()) +
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
        throw SequenceError(shortened((dir / kKeypointsFile).string()) + ": present without " +
                            kObjectsFile);
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
    setWhy(why, shortened(directory_) + ": frame index " + std::to_string(index) +
                    " out of range (" + std::to_string(frames_.size()) + " frames)");
    return false;
  }
  const std::string path = (fs::path(directory_) / frames_[index].file).string();
  // The file's bytes, decoded from memory: the decoder and the end check below see the same
  // bytes (allocates; loadFrame runs on the replay thread, see the contract).
  std::vector<unsigned char> bytes;
  cv::Mat decoded;
  if (readFileBytes(path, bytes) && !bytes.empty()) {
    try {
      decoded = cv::imdecode(bytes, cv::IMREAD_COLOR);
    } catch (const cv::Exception&) {
      decoded.release();  // a decoder that throws on a corrupt file: same as one that fails
    }
  }
  if (decoded.empty()) {
    setWhy(why, shortened(path) + ": cannot decode image (missing or corrupt)");
    return false;
  }
  // A truncated JPEG decodes "successfully" (libjpeg fills the missing rows with grey and only
  // prints a warning): the file must end where its format says it ends.
  if (const char* problem = imageEndProblem(bytes)) {
    setWhy(why, shortened(path) + ": " + problem);
    return false;
  }
  const camera::Intrinsics& camera = rig_.intrinsics;
  if (decoded.cols != camera.width_px || decoded.rows != camera.height_px) {
    setWhy(why, shortened(path) + ": image is " + std::to_string(decoded.cols) + "x" +
                    std::to_string(decoded.rows) + ", rig.yaml camera is " +
                    std::to_string(camera.width_px) + "x" + std::to_string(camera.height_px));
    return false;
  }
  if (image.size() == decoded.size() && image.type() == decoded.type()) {
    decoded.copyTo(image);  // keeps the caller's buffer (it may be shared or pinned)
  } else {
    image = decoded;
  }
  return true;
}

}  // namespace vp::sequence
