#include "evaluate_app.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>

#include "output_files/detections_file.hpp"
#include "output_files/trajectory_file.hpp"
#include "report.hpp"
#include "sequence/recorded_sequence.hpp"
#include "shape/vehicle_model.hpp"

#ifndef VP_SOURCE_DIR
#define VP_SOURCE_DIR "."
#endif

namespace vp::evaluate {
namespace {

namespace fs = std::filesystem;

constexpr std::array<std::string_view, 6> kImageExtensions{".png", ".jpg", ".jpeg",
                                                           ".bmp", ".tif", ".tiff"};

// A message for the user; caught at the top of each entry point.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string lowerCase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

bool isImageFile(const fs::path& path) {
  const std::string ext = lowerCase(path.extension().string());
  return std::find(kImageExtensions.begin(), kImageExtensions.end(), ext) != kImageExtensions.end();
}

double parseNumber(const std::string& option, const std::string& text) {
  double value = 0.0;
  const auto [ptr, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || ptr != text.data() + text.size() ||
      !std::isfinite(value)) {
    throw InputError(option + ": not a number '" + text + "'");
  }
  return value;
}

std::int64_t parseFrameId(const std::string& option, std::string_view text) {
  std::int64_t value = 0;
  const auto [ptr, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || ptr != text.data() + text.size() || value < 0) {
    throw InputError(option + ": expected a frame id >= 0, got '" + std::string(text) + "'");
  }
  return value;
}

evaluation::PredictedObject toPrediction(const output_files::DetectionRecord& r) {
  evaluation::PredictedObject p;
  p.box = r.box;
  p.score = r.score;
  p.directionKnown = r.directionKnown;
  p.atFrameEdge = r.atFrameEdge;
  p.hasTypeProbabilities = true;
  p.typeProbabilities = r.typeProbabilities;
  p.shape = r.gamma;
  p.lifted = r.liftStatus == output_files::LiftStatus::Ok;
  p.positionEnu = r.positionEnu;
  p.headingEnu_rad = r.headingEnu_rad;
  p.dimensions_m = r.dimensions_m;
  return p;
}

// Opens a recorded sequence for evaluation: it must hold ground truth to compare with.
bool openWithGroundTruth(const std::string& sequenceDir, sequence::SequenceReader* reader,
                         std::string* why) {
  if (!reader->open(sequenceDir, why)) {
    return false;
  }
  if (!reader->hasGroundTruth()) {
    *why = sequenceDir + ": no ground_truth/objects.csv: nothing to evaluate against";
    return false;
  }
  return true;
}

// Whether --frames first:last keeps this frame.
bool inFrameRange(const EvaluateOptions& options, std::int64_t frameId) {
  return (!options.firstFrame || frameId >= *options.firstFrame) &&
         (!options.lastFrame || frameId <= *options.lastFrame);
}

}  // namespace

std::string usage() {
  return R"(vp_evaluate: the measures of seed 000 (sec. 5.1) on held-out data, with the seed's figures beside ours.

Usage:
  vp_evaluate --sequence DIR --detections FILE [--sequence DIR --detections FILE ...] --out DIR
              [--asm PATH] [--iou 0.5] [--max-occlusion 0.7] [--max-truncation 0.5]
              [--frames A:B] [--model-id TEXT]
  vp_evaluate --sequence DIR [--detections FILE] --tracks FILE [--sequence DIR ...] --out DIR
              [--track-gate 2] [--moving-speed 0.5] [--frames A:B]
  vp_evaluate --yolo DIR --detections FILE [--val-list FILE] --out DIR [--iou 0.5] [--model-id TEXT]

Inputs:
  --sequence DIR       a recorded sequence with ground_truth/ (docs/recorded_sequence.md)
  --detections FILE    the detections file run on it (docs/detections_file.md); one per
                       --sequence, in the same order (several pairs: one held-out set)
  --tracks FILE        the trajectory file of the tracker run on it (docs/tracking.md); one
                       per --sequence, in the same order: adds the tracking measures (with
                       --detections too: the detector's own heading flips and type beside)
  --yolo DIR           real images: DIR/images/*.jpg|png and DIR/labels/<stem>.txt
                       ('class cx cy w h', normalised; class 0 = car); the detections file
                       then has the 'image' key column
  --val-list FILE      evaluate only these images: one stem per line, or a JSON file with a
                       "val_stems" array (the training run's split.json)
Options:
  --out DIR            output folder: report.md, report.json, orientation_cdf.png
  --asm PATH           Active Shape Model for the shape measures (default: the source tree's
                       models/asm/default_asm.yaml); 'none' skips the shape measures
  --iou X              IoU threshold of a true positive, (0, 1] (default 0.5, seed 000)
  --max-occlusion X    references more occluded are 'ignore' (default 0.7, as in training)
  --max-truncation X   references more truncated are 'ignore' (default 0.5)
  --frames A:B         evaluate only frame ids A..B (inclusive) of every sequence
  --track-gate M       tracks (and lifted detections) match a ground-truth vehicle within
                       M metres in the world (default 2)
  --moving-speed V     a ground-truth vehicle faster than V m/s is moving (default 0.5)
  --model-id TEXT      model name for the report (default: the files' '# model:' line)
  --help               this text

Exit status: 0 report written, 1 bad input (the message names the file and line), 2 usage.
)";
}

bool parseArguments(std::span<const std::string> args, EvaluateOptions* options, std::string* why) {
  EvaluateOptions o;
  o.asmPath = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";
  std::vector<std::string> sequenceDirs;
  std::vector<std::string> detectionFiles;
  std::vector<std::string> trackFiles;
  try {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      const auto value = [&]() -> const std::string& {
        if (i + 1 >= args.size() || args[i + 1].starts_with("--")) {
          throw InputError(arg + ": missing value");
        }
        return args[++i];
      };
      if (arg == "--help" || arg == "-h") {
        o.help = true;
      } else if (arg == "--sequence") {
        sequenceDirs.push_back(value());
      } else if (arg == "--detections") {
        detectionFiles.push_back(value());
      } else if (arg == "--tracks") {
        trackFiles.push_back(value());
      } else if (arg == "--track-gate") {
        o.trackMatchDistance_m = parseNumber(arg, value());
        if (!(o.trackMatchDistance_m > 0.0)) {
          throw InputError("--track-gate: must be > 0 m");
        }
      } else if (arg == "--moving-speed") {
        o.movingSpeed_mps = parseNumber(arg, value());
        if (!(o.movingSpeed_mps >= 0.0)) {
          throw InputError("--moving-speed: must be >= 0 m/s");
        }
      } else if (arg == "--yolo") {
        o.yoloDir = value();
      } else if (arg == "--val-list") {
        o.valList = value();
      } else if (arg == "--out") {
        o.outDir = value();
      } else if (arg == "--asm") {
        const std::string path = value();
        o.asmPath = path == "none" ? std::string() : path;
      } else if (arg == "--iou") {
        o.iouThreshold = parseNumber(arg, value());
        if (!(o.iouThreshold > 0.0 && o.iouThreshold <= 1.0)) {
          throw InputError("--iou: must be in (0, 1]");
        }
      } else if (arg == "--max-occlusion") {
        o.maxOcclusion = parseNumber(arg, value());
      } else if (arg == "--max-truncation") {
        o.maxTruncation = parseNumber(arg, value());
      } else if (arg == "--frames") {
        const std::string range = value();
        const std::size_t colon = range.find(':');
        if (colon == std::string::npos) {
          throw InputError("--frames: expected A:B (first and last frame id), got '" + range + "'");
        }
        o.firstFrame = parseFrameId(arg, std::string_view(range).substr(0, colon));
        o.lastFrame = parseFrameId(arg, std::string_view(range).substr(colon + 1));
        if (*o.lastFrame < *o.firstFrame) {
          throw InputError("--frames: last frame before first in '" + range + "'");
        }
      } else if (arg == "--model-id") {
        o.modelId = value();
      } else {
        throw InputError("unknown argument '" + arg + "' (see --help)");
      }
    }
    if (o.help) {
      *options = o;
      return true;
    }
    if (o.outDir.empty()) {
      throw InputError("--out DIR is required");
    }
    if (!o.yoloDir.empty()) {
      if (!sequenceDirs.empty()) {
        throw InputError("--yolo and --sequence cannot be mixed in one report");
      }
      if (!trackFiles.empty()) {
        throw InputError("--tracks needs --sequence (ground truth in the world), not --yolo");
      }
      if (detectionFiles.size() != 1) {
        throw InputError("--yolo needs exactly one --detections FILE, got " +
                         std::to_string(detectionFiles.size()));
      }
      o.sequences.push_back({o.yoloDir, detectionFiles[0], ""});
    } else {
      if (sequenceDirs.empty()) {
        throw InputError(
            "give --sequence DIR --detections FILE and/or --tracks FILE (or --yolo DIR "
            "--detections FILE)");
      }
      if (detectionFiles.empty() && trackFiles.empty()) {
        throw InputError("each --sequence needs its --detections FILE and/or --tracks FILE");
      }
      if (!detectionFiles.empty() && sequenceDirs.size() != detectionFiles.size()) {
        throw InputError("each --sequence needs its --detections: got " +
                         std::to_string(sequenceDirs.size()) + " sequences and " +
                         std::to_string(detectionFiles.size()) + " detections files");
      }
      if (!trackFiles.empty() && sequenceDirs.size() != trackFiles.size()) {
        throw InputError("each --sequence needs its --tracks: got " +
                         std::to_string(sequenceDirs.size()) + " sequences and " +
                         std::to_string(trackFiles.size()) + " trajectory files");
      }
      if (!o.valList.empty()) {
        throw InputError("--val-list applies to --yolo only");
      }
      for (std::size_t k = 0; k < sequenceDirs.size(); ++k) {
        o.sequences.push_back({sequenceDirs[k], detectionFiles.empty() ? "" : detectionFiles[k],
                               trackFiles.empty() ? "" : trackFiles[k]});
      }
    }
  } catch (const InputError& error) {
    if (why != nullptr) {
      *why = error.what();
    }
    return false;
  }
  *options = o;
  return true;
}

bool loadSequenceImages(const SequenceInput& input, const EvaluateOptions& options,
                        LoadedInput* out, std::string* why) {
  *out = LoadedInput{};
  out->label = input.sequenceDir;
  out->detectionsFile = input.detectionsFile;
  sequence::SequenceReader reader;
  if (!openWithGroundTruth(input.sequenceDir, &reader, why)) {
    return false;
  }
  output_files::DetectionsFile detections;
  if (!output_files::readDetectionsFile(input.detectionsFile, &detections, why)) {
    return false;
  }
  if (detections.info.key != output_files::DetectionsKey::FrameId) {
    *why = input.detectionsFile +
           ": header: a sequence needs the 'frame_id' key column (this file has 'image')";
    return false;
  }
  out->model = detections.info.model;
  out->formatVersion = detections.formatVersion;
  std::map<std::int64_t, std::size_t> imageOfFrame;
  for (const sequence::FrameRecord& frame : reader.frames()) {
    if (!inFrameRange(options, frame.frameId)) {
      continue;
    }
    imageOfFrame[frame.frameId] = out->images.size();
    ImageData image;
    image.name = input.sequenceDir + ":" + std::to_string(frame.frameId);
    const auto keypoints = reader.keypoints(frame.frameId);
    for (const sequence::ObjectTruth& object : reader.objects(frame.frameId)) {
      evaluation::ReferenceObject ref;
      ref.box = object.imageBox;
      ref.box.angle = geometry::wrapTwoPi(ref.box.angle);
      ref.ignore =
          object.occlusion > options.maxOcclusion || object.truncation > options.maxTruncation;
      ref.directionKnown = true;
      ref.type = static_cast<int>(object.type);
      ref.shape = object.shape;
      ref.hasWorld = true;
      ref.positionEnu = object.positionEnu;
      ref.headingEnu_rad = object.headingEnu_rad;
      ref.dimensions_m = object.dimensions_m;
      // GSD from the wheel centres when their keypoints are given, else length / box length.
      std::array<Eigen::Vector2d, shape::kWheelCount> pixels;
      std::array<Eigen::Vector3d, shape::kWheelCount> world;
      pixels.fill(Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
      world.fill(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
      for (const sequence::KeypointTruth& k : keypoints) {
        if (k.trackId != object.trackId) {
          continue;
        }
        for (int w = 0; w < shape::kWheelCount; ++w) {
          if (shape::wheelCentreKeypoints()[static_cast<std::size_t>(w)] == k.keypoint) {
            pixels[static_cast<std::size_t>(w)] = k.pixel;
            world[static_cast<std::size_t>(w)] = k.worldEnu;
          }
        }
      }
      ref.gsd_m = evaluation::gsdFromWheelKeypoints(pixels, world);
      if (!std::isfinite(ref.gsd_m) && object.imageBox.length > 0.0) {
        ref.gsd_m = object.dimensions_m.x() / object.imageBox.length;
      }
      image.references.push_back(ref);
    }
    out->images.push_back(std::move(image));
  }
  std::set<std::int64_t> sequenceFrames;
  for (const sequence::FrameRecord& frame : reader.frames()) {
    sequenceFrames.insert(frame.frameId);
  }
  for (std::size_t i = 0; i < detections.rows.size(); ++i) {
    const output_files::DetectionRecord& row = detections.rows[i];
    if (sequenceFrames.count(row.frameId) == 0) {
      *why = input.detectionsFile + ":" + std::to_string(detections.lines[i]) +
             ": frame_id: no frame " + std::to_string(row.frameId) + " in " + input.sequenceDir +
             "/frames.csv (detections of another sequence?)";
      return false;
    }
    const auto it = imageOfFrame.find(row.frameId);
    if (it == imageOfFrame.end()) {
      ++out->skippedRows;  // outside --frames
      continue;
    }
    out->images[it->second].predictions.push_back(toPrediction(row));
  }
  return true;
}

bool loadSequenceTracking(const SequenceInput& input, const EvaluateOptions& options,
                          LoadedTracking* out, std::string* why) {
  *out = LoadedTracking{};
  out->label = input.sequenceDir;
  out->tracksFile = input.tracksFile;
  out->detectionsFile = input.detectionsFile;
  sequence::SequenceReader reader;
  if (!openWithGroundTruth(input.sequenceDir, &reader, why)) {
    return false;
  }
  output_files::TrajectoryFile tracks;
  if (!output_files::readTrajectoryFile(input.tracksFile, &tracks, why)) {
    return false;
  }
  std::map<std::int64_t, std::size_t> indexOfFrame;
  std::set<std::int64_t> sequenceFrames;
  for (const sequence::FrameRecord& frame : reader.frames()) {
    sequenceFrames.insert(frame.frameId);
    if (!inFrameRange(options, frame.frameId)) {
      continue;
    }
    indexOfFrame[frame.frameId] = out->frames.size();
    TrackingFrame data;
    data.frameId = frame.frameId;
    for (const sequence::ObjectTruth& object : reader.objects(frame.frameId)) {
      evaluation::TruthVehicle truth;
      truth.id = object.trackId;
      truth.positionEnu = object.positionEnu.head<2>();
      truth.headingEnu_rad = object.headingEnu_rad;
      truth.speed_mps = object.speed_mps;
      truth.type = static_cast<int>(object.type);
      // Hardly visible vehicles are 'ignore' here as in the detection measures.
      truth.ignore =
          object.occlusion > options.maxOcclusion || object.truncation > options.maxTruncation;
      data.truth.push_back(truth);
    }
    out->frames.push_back(std::move(data));
  }
  // Rows of frames the sequence does not have are an error (a file of another sequence?).
  const auto frameOf = [&](std::int64_t frameId, const std::string& file,
                           int line) -> TrackingFrame* {
    if (sequenceFrames.count(frameId) == 0) {
      throw InputError(file + ":" + std::to_string(line) + ": frame_id: no frame " +
                       std::to_string(frameId) + " in " + input.sequenceDir +
                       "/frames.csv (a file of another sequence?)");
    }
    const auto it = indexOfFrame.find(frameId);
    return it == indexOfFrame.end() ? nullptr : &out->frames[it->second];
  };
  try {
    for (std::size_t i = 0; i < tracks.rows.size(); ++i) {
      const output_files::TrajectoryRecord& row = tracks.rows[i];
      TrackingFrame* frame = frameOf(row.frameId, input.tracksFile, tracks.lines[i]);
      if (frame == nullptr) {
        ++out->skippedRows;  // outside --frames
        continue;
      }
      if (row.status != tracking::TrackStatus::Confirmed) {
        ++(row.status == tracking::TrackStatus::Lost ? out->lostRows : out->tentativeRows);
        continue;
      }
      ++out->confirmedRows;
      evaluation::TrackObservation track;
      track.id = row.trackId;
      track.centreEnu = row.centreEnu;
      track.headingEnu_rad = row.headingEnu_rad();
      track.speed_mps = row.speed_mps;
      track.type = static_cast<int>(row.type);
      frame->tracks.push_back(track);
    }
    if (!input.detectionsFile.empty()) {
      output_files::DetectionsFile detections;
      std::string problem;
      if (!output_files::readDetectionsFile(input.detectionsFile, &detections, &problem)) {
        throw InputError(problem);
      }
      if (detections.info.key != output_files::DetectionsKey::FrameId) {
        throw InputError(input.detectionsFile +
                         ": header: a sequence needs the 'frame_id' key column (this file has "
                         "'image')");
      }
      for (std::size_t i = 0; i < detections.rows.size(); ++i) {
        const output_files::DetectionRecord& row = detections.rows[i];
        TrackingFrame* frame = frameOf(row.frameId, input.detectionsFile, detections.lines[i]);
        if (frame == nullptr) {
          continue;
        }
        if (row.liftStatus != output_files::LiftStatus::Ok) {
          ++out->unliftedDetections;
          continue;
        }
        evaluation::DetectionObservation detection;
        detection.positionEnu = row.positionEnu.head<2>();
        detection.headingEnu_rad = row.headingEnu_rad;
        detection.headingKnown = row.directionKnown;
        detection.type = static_cast<int>(row.topType());
        frame->detections.push_back(detection);
      }
    }
  } catch (const InputError& error) {
    *why = error.what();
    return false;
  }
  return true;
}

bool readValidationList(const std::string& path, std::vector<std::string>* stems,
                        std::string* why) {
  stems->clear();
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    *why = path + ": cannot open (missing or unreadable)";
    return false;
  }
  std::ostringstream buffer;
  buffer << file.rdbuf();
  const std::string text = buffer.str();
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '{') {
    // JSON (a YAML 1.2 flow mapping, so yaml-cpp reads it).
    try {
      const YAML::Node root = YAML::Load(text);
      const YAML::Node list = root["val_stems"];
      if (!list || !list.IsSequence()) {
        *why = path +
               ": no \"val_stems\" list (tools/detector/train.py's split.json holds only "
               "counts and groups until it writes the validation stems)";
        return false;
      }
      for (const YAML::Node& item : list) {
        if (!item.IsScalar() || item.Scalar().empty()) {
          *why = path + ": \"val_stems\": every entry must be a non-empty string";
          return false;
        }
        stems->push_back(item.Scalar());
      }
    } catch (const YAML::Exception& error) {
      *why = path + ":" + std::to_string(error.mark.line + 1) + ": not valid JSON: " + error.msg;
      return false;
    }
    return true;
  }
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    const std::size_t start = line.find_first_not_of(" \t");
    if (start == std::string::npos || line[start] == '#') {
      continue;
    }
    const std::size_t end = line.find_last_not_of(" \t");
    fs::path entry(line.substr(start, end - start + 1));
    stems->push_back(isImageFile(entry) ? entry.stem().string() : entry.string());
  }
  return true;
}

bool loadYoloImages(const EvaluateOptions& options, LoadedInput* out, std::string* why) {
  *out = LoadedInput{};
  out->label = options.yoloDir;
  out->detectionsFile = options.sequences.at(0).detectionsFile;
  try {
    const fs::path root(options.yoloDir);
    const fs::path imageDir = root / "images";
    std::error_code error;
    if (!fs::is_directory(imageDir, error)) {
      throw InputError(imageDir.string() + ": missing image folder (expected DIR/images/)");
    }
    std::map<std::string, fs::path> imageOfStem;
    for (const fs::directory_entry& entry : fs::directory_iterator(imageDir)) {
      if (entry.is_regular_file() && isImageFile(entry.path())) {
        imageOfStem[entry.path().stem().string()] = entry.path();
      }
    }
    std::vector<std::string> stems;
    if (!options.valList.empty()) {
      std::string problem;
      if (!readValidationList(options.valList, &stems, &problem)) {
        throw InputError(problem);
      }
      for (const std::string& stem : stems) {
        if (imageOfStem.count(stem) == 0) {
          throw InputError(options.valList + ": validation image '" + stem + "' not in " +
                           imageDir.string());
        }
      }
    } else {
      for (const auto& [stem, path] : imageOfStem) {
        stems.push_back(stem);
      }
    }
    output_files::DetectionsFile detections;
    std::string problem;
    if (!output_files::readDetectionsFile(out->detectionsFile, &detections, &problem)) {
      throw InputError(problem);
    }
    if (detections.info.key != output_files::DetectionsKey::Image) {
      throw InputError(out->detectionsFile +
                       ": header: an image folder needs the 'image' key column (this file has "
                       "'frame_id')");
    }
    out->model = detections.info.model;
    out->formatVersion = detections.formatVersion;
    std::map<std::string, std::size_t> indexOfStem;
    for (const std::string& stem : stems) {
      indexOfStem[stem] = out->images.size();
      ImageData image;
      image.name = stem;
      const fs::path imagePath = imageOfStem.at(stem);
      const cv::Mat pixels = cv::imread(imagePath.string(), cv::IMREAD_COLOR);
      if (pixels.empty()) {
        throw InputError(imagePath.string() + ": cannot decode image (missing or corrupt)");
      }
      const fs::path labelPath = root / "labels" / (stem + ".txt");
      std::ifstream labels(labelPath);  // a missing label file: an image without vehicles
      std::string line;
      int lineNumber = 0;
      while (std::getline(labels, line)) {
        ++lineNumber;
        std::istringstream fields(line);
        std::vector<std::string> parts;
        for (std::string part; fields >> part;) {
          parts.push_back(part);
        }
        if (parts.empty()) {
          continue;
        }
        const std::string where = labelPath.string() + ":" + std::to_string(lineNumber);
        if (parts.size() != 5) {
          throw InputError(where + ": expected 'class cx cy w h', got '" + line + "'");
        }
        std::int64_t cls = 0;
        const auto [ptr, ec] =
            std::from_chars(parts[0].data(), parts[0].data() + parts[0].size(), cls);
        if (ec != std::errc() || ptr != parts[0].data() + parts[0].size()) {
          throw InputError(where + ": class: not an integer '" + parts[0] + "'");
        }
        std::array<double, 4> v{};
        constexpr std::array<const char*, 4> kNames{"cx", "cy", "w", "h"};
        for (std::size_t k = 0; k < 4; ++k) {
          v[k] = parseNumber(where + ": " + kNames[k], parts[k + 1]);
        }
        if (cls != 0) {
          continue;  // class 0 = car; others are not vehicles of this evaluation
        }
        evaluation::ReferenceObject ref;
        ref.axisAligned = true;
        ref.directionKnown = false;
        // Normalised coordinates run from the image edges; pixel centres are at integers.
        ref.box = {v[0] * pixels.cols - 0.5, v[1] * pixels.rows - 0.5, v[2] * pixels.cols,
                   v[3] * pixels.rows, 0.0};
        const double tolerance = evaluation::kImageBorderTolerance_px;
        ref.cutByImageBorder = (v[0] - v[2] / 2) * pixels.cols < tolerance ||
                               (v[1] - v[3] / 2) * pixels.rows < tolerance ||
                               (v[0] + v[2] / 2) * pixels.cols > pixels.cols - tolerance ||
                               (v[1] + v[3] / 2) * pixels.rows > pixels.rows - tolerance;
        image.references.push_back(ref);
      }
      out->images.push_back(std::move(image));
    }
    for (std::size_t i = 0; i < detections.rows.size(); ++i) {
      const output_files::DetectionRecord& row = detections.rows[i];
      const std::string stem(row.imageStem());
      if (imageOfStem.count(stem) == 0) {
        throw InputError(out->detectionsFile + ":" + std::to_string(detections.lines[i]) +
                         ": image: no image '" + stem + "' in " + imageDir.string());
      }
      const auto it = indexOfStem.find(stem);
      if (it == indexOfStem.end()) {
        ++out->skippedRows;  // a training image: not part of the held-out list
        continue;
      }
      out->images[it->second].predictions.push_back(toPrediction(row));
    }
  } catch (const InputError& error) {
    *why = error.what();
    return false;
  } catch (const fs::filesystem_error& error) {
    *why = error.what();
    return false;
  }
  return true;
}

int runEvaluate(const EvaluateOptions& options, std::ostream& out, std::ostream& err) {
  if (options.help) {
    out << usage();
    return 0;
  }
  const bool yolo = !options.yoloDir.empty();
  const bool detections =
      std::any_of(options.sequences.begin(), options.sequences.end(),
                  [](const SequenceInput& in) { return !in.detectionsFile.empty(); });
  const bool tracking = std::any_of(options.sequences.begin(), options.sequences.end(),
                                    [](const SequenceInput& in) { return !in.tracksFile.empty(); });
  shape::ActiveShapeModel asmModel;
  std::string why;
  evaluation::EvaluationOptions evalOptions;
  evalOptions.iouThreshold = options.iouThreshold;
  evalOptions.axisAligned = yolo;
  if (detections && !yolo && !options.asmPath.empty()) {
    if (!asmModel.load(options.asmPath, &why)) {
      err << "vp_evaluate: " << why << "\n";
      return 1;
    }
    evalOptions.asmModel = &asmModel;
  }
  ReportContext context;
  context.commandLine = options.commandLine;
  context.mode = yolo ? "yolo" : "sequences";
  context.asmPath = yolo || !detections ? std::string() : options.asmPath;
  context.iouThreshold = options.iouThreshold;
  context.maxOcclusion = options.maxOcclusion;
  context.maxTruncation = options.maxTruncation;
  context.valList = options.valList;
  context.hasDetections = detections;
  context.hasTracking = tracking;
  context.trackMatchDistance_m = options.trackMatchDistance_m;
  context.movingSpeed_mps = options.movingSpeed_mps;
  evaluation::Evaluator total(evalOptions);
  std::set<std::string> models;
  context.frameEdgeKnown = detections;
  for (const SequenceInput& input : options.sequences) {
    if (input.detectionsFile.empty()) {
      continue;
    }
    LoadedInput loaded;
    const bool ok = yolo ? loadYoloImages(options, &loaded, &why)
                         : loadSequenceImages(input, options, &loaded, &why);
    if (!ok) {
      err << "vp_evaluate: " << why << "\n";
      return 1;
    }
    evaluation::Evaluator own(evalOptions);
    for (const ImageData& image : loaded.images) {
      own.addImage(image.references, image.predictions);
      total.addImage(image.references, image.predictions);
    }
    if (!loaded.model.empty()) {
      models.insert(loaded.model);
    }
    context.frameEdgeKnown = context.frameEdgeKnown && loaded.formatVersion >= 2;
    context.inputs.push_back(
        {loaded.label, loaded.detectionsFile, loaded.model, loaded.skippedRows, own.summary()});
  }
  context.total = total.summary();
  evaluation::TrackingOptions trackingOptions;
  trackingOptions.matchDistance_m = options.trackMatchDistance_m;
  trackingOptions.movingSpeed_mps = options.movingSpeed_mps;
  evaluation::TrackingEvaluator trackingTotal(trackingOptions);
  for (const SequenceInput& input : options.sequences) {
    if (input.tracksFile.empty()) {
      continue;
    }
    LoadedTracking loaded;
    if (!loadSequenceTracking(input, options, &loaded, &why)) {
      err << "vp_evaluate: " << why << "\n";
      return 1;
    }
    evaluation::TrackingEvaluator own(trackingOptions);
    own.beginSequence();
    trackingTotal.beginSequence();
    for (const TrackingFrame& frame : loaded.frames) {
      own.addFrame(frame.truth, frame.tracks);
      trackingTotal.addFrame(frame.truth, frame.tracks);
      if (!loaded.detectionsFile.empty()) {
        own.addDetectorFrame(frame.truth, frame.detections);
        trackingTotal.addDetectorFrame(frame.truth, frame.detections);
      }
    }
    context.trackingInputs.push_back({loaded.label, loaded.tracksFile, loaded.detectionsFile,
                                      static_cast<int>(loaded.frames.size()), loaded.confirmedRows,
                                      loaded.tentativeRows, loaded.lostRows, loaded.skippedRows,
                                      own.summary()});
  }
  context.tracking = trackingTotal.summary();
  if (!options.modelId.empty()) {
    context.modelId = options.modelId;
  } else {
    for (const std::string& model : models) {
      context.modelId += (context.modelId.empty() ? "" : "; ") + model;
    }
    if (context.modelId.empty()) {
      context.modelId = "unknown (no '# model:' line, no --model-id)";
    }
  }
  if (!writeReport(context, options.outDir, &why)) {
    err << "vp_evaluate: " << why << "\n";
    return 1;
  }
  out << "vp_evaluate:";
  if (detections) {
    const evaluation::EvaluationSummary& s = context.total;
    out << " " << s.images << " images, " << s.references << " references, " << s.predictions
        << " predictions: P " << s.precision << " R " << s.recall << " F1 " << s.f1 << ";";
  }
  if (tracking) {
    const evaluation::TrackingSummary& t = context.tracking;
    out << " tracking: " << t.mot.frames << " frames, " << t.mot.truthObjects << " vehicle-frames, "
        << t.tracks << " confirmed tracks: MOTA " << t.mot.mota << " IDF1 " << t.mot.idf1
        << " ID switches " << t.mot.idSwitches << ";";
  }
  out << " report in " << options.outDir << "/report.md\n";
  return 0;
}

}  // namespace vp::evaluate
