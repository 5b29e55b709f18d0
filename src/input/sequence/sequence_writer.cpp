// sequence/sequence_writer: the recorded-sequence writer (used by the simulator). It formats
// each record, parses it back with the reader's parser and applies the reader's rules before
// writing, so it cannot write a sequence that the reader rejects.
#include "sequence/recorded_sequence.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <optional>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "csv/csv_io.hpp"
#include "rig_config/rig_config.hpp"
#include "sequence/sequence_format.hpp"

namespace vp::sequence {

using namespace detail;  // this module's internals (sequence_format.hpp)
using csv::joinColumns;
using csv::quote;
using csv::splitFields;

// ---- SequenceWriter ------------------------------------------------------------------------

namespace {

// One CSV output: the stream, its display name and the line the next row goes to. At namespace
// scope, not nested in Files: inside Files' definition a nested struct with default member
// initializers is not yet default-constructible for std::optional (clang rejects emplace()).
struct Csv {
  std::ofstream stream;
  std::string name;
  int nextLine = 2;
};

}  // namespace

// A frame on disk: its row and its image's size (the disk budget of a recorder).
struct KeptFrame {
  FrameRecord record;
  std::uint64_t bytes = 0;
};

struct SequenceWriter::Files {
  fs::path directory;
  SequenceInfo info;
  bool flushRows = false;
  std::uint64_t bytesOnDisk = 0;
  std::deque<KeptFrame> kept;  // oldest first
  std::size_t removed = 0;
  EncodedFrame scratch;  // writeFrame()'s encoding buffer, reused
  int width_px = 0;
  int height_px = 0;
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
    if (flushRows) {
      csv.stream.flush();
    }
    bytesOnDisk += header.size() + 1;
    if (!csv.stream) {
      setWhy(why, csv.name + ": cannot write");
      return false;
    }
    return true;
  }

  bool appendRow(Csv& csv, const std::string& row, std::string* why) {
    // The row and its line end in one insertion: with flushRows the stream's buffer holds just
    // this row when it is flushed, so it reaches the file in one write(2).
    csv.stream << row << '\n';
    if (flushRows) {
      csv.stream.flush();
    }
    ++csv.nextLine;
    bytesOnDisk += row.size() + 1;
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
  if (!(info.frameRate_hz > 0.0) || !std::isfinite(info.frameRate_hz)) {
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
  config::RigConfig rig;
  try {
    rig = config::parseRigConfig(rigYaml, (dir / kRigFile).string(), absoluteDir.string());
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
  std::uint64_t copied = rigYaml.size() + fs::file_size(dir / kDtmFile, error);
  for (const char* extension : kWorldFileExtensions) {
    const fs::path worldFile = fs::path(dtmFile).replace_extension(extension);
    const fs::path copy = dir / (std::string("dtm") + extension);
    if (fileExists(worldFile) && !fs::copy_file(worldFile, copy, error)) {
      setWhy(why,
             "cannot copy the world file " + quote(worldFile.string()) + ": " + error.message());
      return false;
    }
    if (fileExists(copy)) {
      copied += fs::file_size(copy, error);
    }
  }

  auto files = std::make_unique<Files>();
  files->flushRows = flushRows;
  files->bytesOnDisk = copied;
  files->directory = dir;
  files->info = info;
  files->width_px = rig.camera.intrinsics.width_px;
  files->height_px = rig.camera.intrinsics.height_px;
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
  EncodedFrame& scratch = files_->scratch;
  return encodeFrame(frame, image, scratch, why) && writeEncodedFrame(scratch, why);
}

bool SequenceWriter::encodeFrame(const FrameRecord& frame, const cv::Mat& image, EncodedFrame& out,
                                 std::string* why) {
  if (!files_) {
    setWhy(why, "encodeFrame: the writer is not open");
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
    if (image.cols != files.width_px || image.rows != files.height_px) {
      throw FieldError{"image", "image is " + std::to_string(image.cols) + "x" +
                                    std::to_string(image.rows) + ", rig.yaml camera is " +
                                    std::to_string(files.width_px) + "x" +
                                    std::to_string(files.height_px)};
    }
  } catch (const FieldError& error) {
    setWhy(why, files.where(files.frames, error));
    return false;
  }
  bool encoded = false;
  try {
    encoded =
        cv::imencode(fs::path(record.file).extension().string(), image, out.bytes, parameters);
  } catch (const cv::Exception&) {
    encoded = false;  // reported below like a failed encoding
  }
  if (!encoded) {
    setWhy(why, (files.directory / record.file).string() + ": cannot encode image");
    return false;
  }
  out.record = std::move(record);
  return true;
}

bool SequenceWriter::writeEncodedFrame(const EncodedFrame& frame, std::string* why) {
  if (!files_) {
    setWhy(why, "writeEncodedFrame: the writer is not open");
    return false;
  }
  Files& files = *files_;
  const FrameRecord& record = frame.record;
  try {
    files.rules.checkFrame(record);  // frames written since it was encoded
  } catch (const FieldError& error) {
    setWhy(why, files.where(files.frames, error));
    return false;
  }
  const fs::path path = files.directory / record.file;
  fs::path temporary = path;
  temporary += ".tmp";
  std::error_code error;
  fs::create_directories(path.parent_path(), error);
  bool written = false;
  if (!error) {
    std::ofstream image(temporary, std::ios::binary | std::ios::trunc);
    image.write(reinterpret_cast<const char*>(frame.bytes.data()),
                static_cast<std::streamsize>(frame.bytes.size()));
    image.close();
    written = static_cast<bool>(image);
  }
  if (written) {
    fs::rename(temporary, path, error);
    written = !error;
  }
  if (!written) {
    fs::remove(temporary, error);
    setWhy(why, path.string() + ": cannot write image");
    return false;
  }
  files.rules.addFrame(record);
  files.bytesOnDisk += frame.bytes.size();
  files.kept.push_back({record, frame.bytes.size()});
  return files.appendRow(files.frames, formatFrameRow(record), why);
}

bool SequenceWriter::removeOldestFrame(std::string* why) {
  if (!files_) {
    setWhy(why, "removeOldestFrame: the writer is not open");
    return false;
  }
  Files& files = *files_;
  if (files.kept.empty()) {
    setWhy(why, files.frames.name + ": no frame left to remove");
    return false;
  }
  if (files.objects || files.keypoints) {
    setWhy(why, files.frames.name + ": frames cannot be removed once ground truth names them");
    return false;
  }
  const KeptFrame& oldest = files.kept.front();
  const fs::path path = files.directory / oldest.record.file;
  std::error_code error;
  if (!fs::remove(path, error) || error) {
    setWhy(why, path.string() + ": cannot remove" + (error ? ": " + error.message() : ""));
    return false;
  }
  files.bytesOnDisk -= std::min(files.bytesOnDisk, oldest.bytes);
  files.kept.pop_front();
  ++files.removed;
  return true;
}

void SequenceWriter::setNotes(const std::string& notes) {
  if (files_) {
    files_->info.notes = notes;
  }
}

std::uint64_t SequenceWriter::bytesOnDisk() const {
  return files_ ? files_->bytesOnDisk : 0;
}

std::size_t SequenceWriter::framesKept() const {
  return files_ ? files_->kept.size() : 0;
}

std::size_t SequenceWriter::framesRemoved() const {
  return files_ ? files_->removed : 0;
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
  if (ok && files->removed > 0) {
    // Frames were removed (a recorder's disk budget): frames.csv lists the kept ones only,
    // rewritten whole beside it and renamed into place.
    const fs::path framesPath = files->directory / kFramesFile;
    fs::path temporary = framesPath;
    temporary += ".tmp";
    std::ofstream rewritten(temporary, std::ios::binary | std::ios::trunc);
    rewritten << joinColumns(toStrings(kFrameColumns)) << '\n';
    for (const KeptFrame& frame : files->kept) {
      rewritten << formatFrameRow(frame.record) << '\n';
    }
    finish(rewritten, temporary.string());
    std::error_code error;
    if (ok) {
      fs::rename(temporary, framesPath, error);
    }
    if (ok && error) {
      setWhy(why, framesPath.string() + ": cannot replace: " + error.message());
      ok = false;
    }
  }
  // Written last (beside it, then renamed into place): a recording cut short has no
  // sequence.yaml, and the reader rejects it.
  const fs::path infoPath = files->directory / kSequenceFile;
  fs::path temporary = infoPath;
  temporary += ".tmp";
  std::ofstream info(temporary, std::ios::binary | std::ios::trunc);
  info << formatInfo(files->info, files->kept.size());
  info.close();
  std::error_code error;
  if (info) {
    fs::rename(temporary, infoPath, error);
  }
  if (!info || error) {
    if (ok) {
      setWhy(why, infoPath.string() + ": write error" + (error ? ": " + error.message() : ""));
    }
    ok = false;
  }
  return ok;
}

}  // namespace vp::sequence
