// vp_detect_images: runs the image side of the perception pipeline (preprocess -> detector ->
// second stage) on a folder of still images and writes a detections file keyed by image stem
// (docs/detections_file.md), for evaluation on labelled photo sets such as the real held-out
// split (vp_evaluate --yolo). No pose, no DTM: nothing is lifted (lift_status not_lifted).
//
// Images may have any size; each gets its own pinhole camera of that size (no undistortion).
// The working scale maps image pixels to the detector's training resolution (~12 cm/px): with
// --gsd-m G it is G / 0.12 (detection::workingScaleForGsd), unless --working-scale is given.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "camera/camera_model.hpp"
#include "detection/detection.hpp"
#include "detection/detection_stage.hpp"
#include "detection/ground_sample_distance.hpp"
#include "inference/engine.hpp"
#include "output_files/detections_file.hpp"
#include "preprocess/preprocessor.hpp"
#include "sequence/recorded_sequence.hpp"

namespace fs = std::filesystem;

namespace {

constexpr const char* kUsage = R"(usage: vp_detect_images --images DIR --out FILE [options]

Runs the detector (+ second stage) on every image of DIR (.jpg .jpeg .png .bmp) and writes a
detections file with one row per detection, keyed by the image's file stem.

options:
  --images DIR          folder of images (a YOLO set's images/ folder, or the set's root)
  --sequence DIR        instead: the frames of a recorded sequence (docs/recorded_sequence.md),
                        rows keyed by frame_id, boxes in the raw frame's pixels (no undistortion:
                        the detector is trained on raw frames), GSD for the crops from the rig's
                        camera height and focal length unless --gsd-m is given
  --out FILE            detections file to write (docs/detections_file.md)
  --list FILE           only the images named in FILE: a text file with one stem per line, or
                        the split.json of tools/detector/split_real.py (its "val_stems")
  --detector PATH       detector ONNX (default: models/detector/detector_int8.onnx)
  --crop PATH           second-stage ONNX (default: models/detector/crop_int8.onnx; "" = none)
  --backend B           int8 | fp32 | opencv | int8-dnnl | auto (default int8, the reference
                        of the model card; the app's default is auto)
  --crop-backend B      the second stage's backend when it should differ from --backend
                        (e.g. int8 detector + fp32 crops: which stage carries the int8 error)
  --working-scale S     working px per image px, (0, 1] (default for images: G / 0.12 with
                        --gsd-m G, which brings them to the detector's ~12 cm/px, else 0.4 for
                        ~4.8 cm/px photos; with --sequence: 648 / frame width, the training
                        resolution)
  --gsd-m G             metres per image pixel: the second stage's crops, and for images the
                        working scale (default: the image's median box length taken as a 4.5 m
                        car, working scale 0.4)
  --score-threshold T   detection score threshold, [0, 1] (default 0.4)
  --threads N           detector threads (default 1)
  --no-flip             keep the detector's front/back (the second stage's flip is not applied)
  --no-refine           keep the detector's box (the second stage's refinement is not applied)
  --no-refine-size      refine centre and axis but keep the detector's length and width
  --no-mirror           one crop-network run per vehicle (default: also the mirrored crop, type
                        averaged, as the app's perception.crop_mirror_average)
  --no-mirror-refine    average only the type over the crop and its mirror image, not the box
                        refinement (default: both, as the app's perception.crop_mirror_refine)
  --no-turn             front/back from the crop as cut only (default: from a crop at the
                        refined box and its 180 deg turn, as the app's
                        perception.crop_turn_average)
  --no-turn-type        type from the first look only (default: also from those two runs at
                        the refined box, averaged with the first look's, as the app's
                        perception.crop_turn_type_average)
  --turn-type-weight W  the second look's weight in that type average, [0, 1] (default 0.8,
                        as the app's perception.crop_turn_type_weight)
  --no-large-merge      keep the parts of a bus or truck the first stage boxed twice (default:
                        merged into one box, as the app's perception.large_vehicle_merge)
  --min-vehicle-probability P
                        drop detections the crop network's verifier gives a lower vehicle
                        probability, [0, 1] (default 0.5, as the app's
                        perception.crop_min_vehicle_probability; 0 keeps all; no effect
                        without a verifier)
  --no-edge-keep-box    refine the box of a vehicle cut by the frame's border too (default: it
                        keeps the detector's box, as the app's
                        perception.crop_frame_edge_keep_box)
  --edge-min-vehicle-probability P
                        the verifier's threshold for vehicles cut by the frame's border, lower
                        or higher than --min-vehicle-probability, [0, 1] (default 0.3, as the
                        app's perception.crop_frame_edge_min_vehicle_probability; with the kept
                        box only)
  --edge-inside-verifier
                        decide vehicles cut by the frame's border with the verifier used inside
                        the frame, not the crop network's border verifier (vehicle_logit_edge,
                        v14's; as the app's perception.crop_frame_edge_own_verifier: false)
  --refine-large-length apply the second stage's length to vehicles most likely large too
                        (default: they keep the first stage's length; the crop shows a part)
  --no-large-vehicle-ends
                        front/back of vehicles most likely large from the crop at the box's
                        middle (default: from crops at its two ends, as the app's
                        perception.crop_large_vehicle_ends)
  --no-exposure         no gain for under-exposed images (default: images darker than a mean
                        luminance of 40 are brightened to 100, as the app's
                        perception.exposure)
  --help                this text
)";

// The detection stage's own options (the defaults the app's perception: section has too); the
// switches override their fields.
struct Options {
  std::string images;
  std::string sequence;
  std::string out;
  std::string list;
  std::string backend = "int8";  // as given, for the detections file's model line
  std::string cropBackend;       // empty: backend
  vp::detection::DetectionStageOptions stage{};
  // Photos, unlike the app's camera frames (perception.working_scale 0.25 of a 2592 px
  // frame), are ~4.8 cm/px: 0.4 brings them to the detector's ~12 cm/px.
  double workingScale = 0.4;
  bool workingScaleGiven = false;
  bool exposure = true;  // the preprocessor's gain for under-exposed images
};

[[noreturn]] void usageError(const std::string& message) {
  std::fprintf(stderr, "vp_detect_images: %s\n(see --help)\n", message.c_str());
  std::exit(2);
}

double parseDouble(const std::string& option, const std::string& text, double lo, double hi) {
  double value = 0.0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size() || !(value >= lo) ||
      !(value <= hi)) {
    usageError(option + ": expected a number in [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "], got '" + text + "'");
  }
  return value;
}

vp::inference::Backend parseBackend(const std::string& option, const std::string& text) {
  const auto backend = vp::inference::backendFromString(text);
  if (!backend)
    usageError(option + ": expected int8, fp32 or opencv, got '" + text + "'");
  return *backend;
}

std::string repoPath(const char* relative) {
  return std::string(VP_SOURCE_DIR) + "/" + relative;
}

Options parseArguments(int argc, char** argv) {
  Options o;
  vp::detection::DetectionStageOptions& stage = o.stage;
  vp::detection::SecondStageOptions& second = stage.secondStage;
  stage.detectorModelPath = repoPath("models/detector/detector_int8.onnx");
  stage.cropModelPath = repoPath("models/detector/crop_int8.onnx");
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    }
    // Switches without a value: each sets one flag.
    const struct {
      const char* name;
      bool* flag;
      bool value;
    } switches[] = {{"--no-flip", &second.applyFlip, false},
                    {"--no-refine", &second.applyRefine, false},
                    {"--no-refine-size", &second.refineSize, false},
                    {"--no-edge-keep-box", &second.frameEdgeKeepBox, false},
                    {"--edge-inside-verifier", &second.frameEdgeOwnVerifier, false},
                    {"--no-mirror", &second.mirrorAverage, false},
                    {"--no-mirror-refine", &second.mirrorRefine, false},
                    {"--no-turn", &second.turnAverage, false},
                    {"--no-turn-type", &second.turnTypeAverage, false},
                    {"--refine-large-length", &second.refineLargeVehicleLength, true},
                    {"--no-large-vehicle-ends", &second.largeVehicleEnds, false},
                    {"--no-large-merge", &stage.largeMerge.enabled, false},
                    {"--no-exposure", &o.exposure, false}};
    bool isSwitch = false;
    for (const auto& s : switches) {
      if (arg == s.name) {
        *s.flag = s.value;
        isSwitch = true;
      }
    }
    if (isSwitch) {
      continue;
    }
    if (i + 1 >= argc)
      usageError(arg + ": missing value");
    const std::string value = argv[++i];
    if (arg == "--images")
      o.images = value;
    else if (arg == "--sequence")
      o.sequence = value;
    else if (arg == "--out")
      o.out = value;
    else if (arg == "--list")
      o.list = value;
    else if (arg == "--detector")
      stage.detectorModelPath = value;
    else if (arg == "--crop")
      stage.cropModelPath = value;
    else if (arg == "--backend")
      o.backend = value;
    else if (arg == "--crop-backend")
      o.cropBackend = value;
    else if (arg == "--working-scale") {
      o.workingScale = parseDouble(arg, value, 1e-3, 1.0);
      o.workingScaleGiven = true;
    } else if (arg == "--gsd-m")
      stage.gsd.fixedGsd_m = parseDouble(arg, value, 1e-4, 10.0);
    else if (arg == "--score-threshold")
      stage.decoder.scoreThreshold = static_cast<float>(parseDouble(arg, value, 0.0, 1.0));
    else if (arg == "--min-vehicle-probability")
      second.minVehicleProbability = static_cast<float>(parseDouble(arg, value, 0.0, 1.0));
    else if (arg == "--turn-type-weight")
      second.turnTypeWeight = static_cast<float>(parseDouble(arg, value, 0.0, 1.0));
    else if (arg == "--edge-min-vehicle-probability")
      second.frameEdgeMinVehicleProbability = static_cast<float>(parseDouble(arg, value, 0.0, 1.0));
    else if (arg == "--threads")
      stage.engine.threads = static_cast<int>(parseDouble(arg, value, 1, 64));
    else
      usageError("unknown option '" + arg + "'");
  }
  if (o.images.empty() == o.sequence.empty())
    usageError("give one of --images and --sequence");
  if (o.out.empty())
    usageError("--out is required");
  // The refinement is averaged only over crops that were mirrored.
  second.mirrorRefine = second.mirrorRefine && second.mirrorAverage;
  // A photo set's GSD says how far to shrink it for the detector: nobody should have to
  // compute gsd / 0.12 by hand.
  if (!o.images.empty() && !o.workingScaleGiven && stage.gsd.fixedGsd_m > 0.0)
    o.workingScale = vp::detection::workingScaleForGsd(stage.gsd.fixedGsd_m);
  return o;
}

// Stems named by a list file: plain text (one per line) or split.json's "val_stems".
std::set<std::string> readList(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    usageError("--list " + path + ": cannot open");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  std::set<std::string> stems;
  const std::size_t key = text.find("\"val_stems\"");
  if (key != std::string::npos) {
    const std::size_t open = text.find('[', key);
    const std::size_t close = text.find(']', open);
    if (open == std::string::npos || close == std::string::npos)
      usageError("--list " + path + ": \"val_stems\" is not a list");
    std::size_t pos = open;
    while ((pos = text.find('"', pos + 1)) != std::string::npos && pos < close) {
      const std::size_t end = text.find('"', pos + 1);
      stems.insert(text.substr(pos + 1, end - pos - 1));
      pos = end;
    }
  } else {
    std::string line;
    std::istringstream lines(text);
    while (std::getline(lines, line)) {
      line.erase(line.find_last_not_of(" \r\t") + 1);
      if (!line.empty() && line[0] != '#')
        stems.insert(line);
    }
  }
  if (stems.empty())
    usageError("--list " + path + ": names no image");
  return stems;
}

// The detection stage of both modes (models, thresholds from the options; the backends are
// checked here, after the arguments, as before).
bool initStage(const Options& options, vp::detection::DetectionStage& stage, std::string* why) {
  vp::detection::DetectionStageOptions stageOptions = options.stage;
  stageOptions.engine.backend = parseBackend("--backend", options.backend);
  if (!options.cropBackend.empty())
    stageOptions.cropBackend = parseBackend("--crop-backend", options.cropBackend);
  return stage.init(stageOptions, vp::preprocess::kMaxTiles, why);
}

// The preprocessing of both modes: the module's defaults but for the image geometry.
vp::preprocess::PreprocessOptions preprocessOptions(const vp::detection::DetectionStage& stage,
                                                    double workingScale, bool exposure) {
  vp::preprocess::PreprocessOptions pre;
  pre.exposure.enabled = exposure;
  // The detector is trained on raw frames and the labels are raw pixels (also the module's
  // default; stated because the tool's boxes must be in the images' own pixels).
  pre.undistort = false;
  pre.workingScale = workingScale;
  pre.workingGsd_m = 0.0;  // one scale per run: the option's, or --gsd-m's
  pre.networkWidth_px = stage.detectorInputWidth();
  pre.networkHeight_px = stage.detectorInputHeight();
  return pre;
}

std::string modelId(const Options& options) {
  const std::string& crop = options.stage.cropModelPath;
  return fs::path(options.stage.detectorModelPath).filename().string() + " + " +
         (crop.empty() ? std::string("no second stage") : fs::path(crop).filename().string()) +
         " (" + options.backend +
         (options.cropBackend.empty() ? std::string() : ", crops " + options.cropBackend) + ")";
}

// Image-space row of one detection (never lifted here).
vp::output_files::DetectionRecord toRecord(const vp::detection::Detection& d, int id) {
  vp::output_files::DetectionRecord row;
  row.detId = id;
  row.score = d.score;
  row.box = d.box;
  row.directionKnown = d.directionKnown;
  row.atFrameEdge = d.atFrameEdge;
  row.vehicleProbability = d.vehicleProbability;
  row.typeProbabilities = d.typeProbabilities;
  row.gamma = d.gamma;
  row.liftStatus = vp::output_files::LiftStatus::NotLifted;
  return row;
}

int fail(const std::string& message) {
  std::fprintf(stderr, "vp_detect_images: %s\n", message.c_str());
  return 1;
}

int runSequence(const Options& options) {
  vp::sequence::SequenceReader reader;
  std::string why;
  if (!reader.open(options.sequence, &why))
    return fail(why);
  const vp::sequence::Rig& rig = reader.rig();
  vp::camera::CameraModel camera;
  if (!camera.init(rig.intrinsics, rig.distortion, &why))
    return fail(options.sequence + "/rig.yaml: camera: " + why);
  vp::detection::DetectionStage stage;
  if (!initStage(options, stage, &why))
    return fail(why);
  // A recording's frames are the app's: the training resolution unless told otherwise.
  const vp::preprocess::PreprocessOptions pre = preprocessOptions(
      stage, options.workingScaleGiven ? options.workingScale : 648.0 / rig.intrinsics.width_px,
      options.exposure);
  vp::preprocess::Preprocessor preprocessor;
  const cv::Size size(rig.intrinsics.width_px, rig.intrinsics.height_px);
  if (!preprocessor.init(pre, camera, size, &why))
    return fail(why);

  vp::output_files::DetectionsFileInfo info;
  info.key = vp::output_files::DetectionsKey::FrameId;
  info.gammaColumns = 3;
  info.model = modelId(options);
  info.source = "vp_detect_images --sequence " + options.sequence;
  vp::output_files::DetectionsFileWriter writer;
  if (!writer.open(options.out, info, &why))
    return fail(why);

  std::vector<vp::detection::Detection> detections(vp::detection::kMaxDetectionsPerFrame);
  cv::Mat image;
  std::size_t total = 0;
  int failed = 0;
  for (std::size_t f = 0; f < reader.frames().size(); ++f) {
    const long long frameId = static_cast<long long>(reader.frames()[f].frameId);
    why.clear();
    if (!reader.loadFrame(f, image, &why) ||
        preprocessor.process(image) != vp::preprocess::PreprocessStatus::Ok) {
      std::fprintf(stderr, "vp_detect_images: frame %lld: %s, skipped\n", frameId,
                   why.empty() ? preprocessor.lastError() : why.c_str());
      ++failed;
      continue;
    }
    std::size_t count = 0;
    const auto status = stage.run(preprocessor.output(), detections, &count);
    if (status != vp::detection::DetectionStatus::Ok) {
      std::fprintf(stderr, "vp_detect_images: frame %lld: detection: %s, skipped\n", frameId,
                   vp::detection::toString(status));
      ++failed;
      continue;
    }
    for (std::size_t i = 0; i < count; ++i) {
      vp::output_files::DetectionRecord row = toRecord(detections[i], static_cast<int>(i));
      row.frameId = frameId;
      if (!writer.writeRow(row, &why))
        return fail(why);
    }
    total += count;
  }
  if (!writer.close(&why))
    return fail(why);
  std::printf("vp_detect_images: %zu detections in %zu frames (%d skipped) -> %s\n", total,
              reader.frames().size(), failed, options.out.c_str());
  return 0;
}

// One preprocessor per image size (each size has its own camera); built on first use.
struct SizedPreprocessor {
  vp::preprocess::Preprocessor preprocessor;
};

int runImages(const Options& options) {
  fs::path folder(options.images);
  if (fs::is_directory(folder / "images"))
    folder /= "images";
  if (!fs::is_directory(folder))
    usageError("--images " + options.images + ": not a directory");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".jpg" || ext == ".jpeg" || ext == ".png" || ext == ".bmp")
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (!options.list.empty()) {
    const std::set<std::string> wanted = readList(options.list);
    std::erase_if(files, [&](const fs::path& p) { return !wanted.count(p.stem().string()); });
    if (files.size() != wanted.size())
      std::fprintf(stderr, "vp_detect_images: warning: %zu of %zu listed images found in %s\n",
                   files.size(), wanted.size(), folder.c_str());
  }
  if (files.empty())
    usageError("no images in " + folder.string());

  vp::detection::DetectionStage stage;
  std::string why;
  if (!initStage(options, stage, &why))
    return fail(why);
  vp::output_files::DetectionsFileInfo info;
  info.key = vp::output_files::DetectionsKey::Image;
  info.gammaColumns = 3;
  info.model = modelId(options);
  info.source = "vp_detect_images " + folder.string() + " working_scale " +
                std::to_string(options.workingScale);
  vp::output_files::DetectionsFileWriter writer;
  if (!writer.open(options.out, info, &why))
    return fail(why);

  std::map<std::pair<int, int>, std::unique_ptr<SizedPreprocessor>> preprocessors;
  std::vector<vp::detection::Detection> detections(vp::detection::kMaxDetectionsPerFrame);
  std::size_t total = 0;
  int failed = 0;
  for (const fs::path& file : files) {
    const cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (image.empty()) {
      std::fprintf(stderr, "vp_detect_images: %s: cannot decode, skipped\n", file.c_str());
      ++failed;
      continue;
    }
    auto& slot = preprocessors[{image.cols, image.rows}];
    if (!slot) {
      slot = std::make_unique<SizedPreprocessor>();
      const vp::camera::Intrinsics k{image.cols,
                                     image.rows,
                                     double(image.cols),
                                     double(image.cols),
                                     (image.cols - 1) / 2.0,
                                     (image.rows - 1) / 2.0};
      vp::camera::CameraModel camera;
      if (!camera.init(k, vp::camera::Distortion{}, &why))
        return fail(file.string() + ": " + why);
      const vp::preprocess::PreprocessOptions pre =
          preprocessOptions(stage, options.workingScale, options.exposure);
      if (!slot->preprocessor.init(pre, camera, image.size(), &why))
        return fail(file.string() + ": " + why);
    }
    if (slot->preprocessor.process(image) != vp::preprocess::PreprocessStatus::Ok) {
      std::fprintf(stderr, "vp_detect_images: %s: %s, skipped\n", file.c_str(),
                   slot->preprocessor.lastError());
      ++failed;
      continue;
    }
    std::size_t count = 0;
    const auto status = stage.run(slot->preprocessor.output(), detections, &count);
    if (status != vp::detection::DetectionStatus::Ok) {
      std::fprintf(stderr, "vp_detect_images: %s: detection: %s, skipped\n", file.c_str(),
                   vp::detection::toString(status));
      ++failed;
      continue;
    }
    for (std::size_t i = 0; i < count; ++i) {
      vp::output_files::DetectionRecord row = toRecord(detections[i], static_cast<int>(i));
      if (!row.setImageStem(file.stem().string()))
        return fail(file.string() + ": file stem longer than " +
                    std::to_string(vp::output_files::kMaxImageStemChars) + " characters");
      if (!writer.writeRow(row, &why))
        return fail(why);
    }
    total += count;
  }
  if (!writer.close(&why))
    return fail(why);
  std::printf("vp_detect_images: %zu detections in %zu images (%d skipped) -> %s\n", total,
              files.size() - static_cast<std::size_t>(failed), failed, options.out.c_str());
  return failed == static_cast<int>(files.size()) ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parseArguments(argc, argv);
  return options.sequence.empty() ? runImages(options) : runSequence(options);
}
