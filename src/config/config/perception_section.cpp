// config/perception_section: `perception:` into the pipeline's own options
// (perception::PipelineOptions: preprocess, detection stage, lifter) and the ASM file. An
// absent key keeps the module's default.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "config/sections.hpp"
#include "inference/engine.hpp"
#include "inference/model_checksum.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kThreadsRange = Range::closed(1.0, 16.0);
const Range kWorkingScaleRange = Range{0.0, 1.0, true};
const Range kTileOverlapRange_px = Range::closed(0.0, 1024.0);
const Range kTopKRange = Range::closed(1.0, 512.0);
const Range kMaxCropsRange = Range::closed(0.0, 512.0);
const Range kCutMarginRange_px = Range::closed(0.0, 64.0);
const Range kFixedGsdRange_m = Range::closed(0.0, 1.0);
const Range kCarLengthRange_m = Range{0.0, 30.0, true};
const Range kLargeVehicleLengthRange_m = Range{0.0, 60.0, true};
const Range kWhiteBalanceGridRange = Range::closed(1.0, 8.0);  // rows x cols <= 64 regions
const Range kSampleStrideRange_px = Range::closed(1.0, 64.0);
const Range kMaxGainRange = Range::closed(1.0, 16.0);
const Range kLumaRange = Range::closed(0.0, 255.0);  // 8-bit mean luminance

constexpr std::string_view kBackendNames = "int8, fp32, opencv, int8-dnnl, auto";

// The working frame must still be an image: at least as many pixels as the smallest camera.
constexpr int kMinWorkingSide_px = 16;
// Below this a vehicle shrinks to a few working pixels at the flying heights the detector was
// trained for (0.25 of a 2592 px frame; 1 for small frames): legal, but worth a warning.
constexpr double kUnusualWorkingScale = 0.1;

// Python's round-half-even, as the preprocessing sizes the working frame.
int workingSize(int size_px, double scale) {
  return static_cast<int>(std::nearbyint(size_px * scale));
}

void checkWorkingScale(MapReader& section, double scale, const camera::Intrinsics& camera) {
  const int width = workingSize(camera.width_px, scale);
  const int height = workingSize(camera.height_px, scale);
  if (std::min(width, height) < kMinWorkingSide_px) {
    section.fail("working_scale",
                 formatNumber(scale) + " makes the " + std::to_string(camera.width_px) + " x " +
                     std::to_string(camera.height_px) + " frame " + std::to_string(width) + " x " +
                     std::to_string(height) + " working px; the shorter side must be at least " +
                     std::to_string(kMinWorkingSide_px) + " px");
  }
  if (scale < kUnusualWorkingScale) {
    section.warn("working_scale", "unusual: " + formatNumber(scale) + " makes the frame " +
                                      std::to_string(width) + " x " + std::to_string(height) +
                                      " working px (below " + formatNumber(kUnusualWorkingScale) +
                                      "; vehicles shrink to a few pixels, check the value)");
  }
}

// A model that exists without its checksum file loads unchecked (inference/model_checksum.hpp):
// said once at start-up, as a warning.
void warnUnchecked(const std::string& modelPath, const char* key, AppConfig& config) {
  std::error_code error;
  if (modelPath.empty() || !std::filesystem::is_regular_file(modelPath, error) ||
      std::filesystem::exists(inference::checksumPath(modelPath), error)) {
    return;
  }
  config.warnings.push_back(
      config.sourcePath + ": perception." + key + ": " + modelPath + " has no checksum file " +
      std::filesystem::path(inference::checksumPath(modelPath)).filename().string() +
      ": its integrity is not verified (scripts/model_checksums.sh)");
}

}  // namespace

void readPerception(MapReader section, const std::string& baseDir, AppConfig& config) {
  const perception::PipelineOptions d;  // the modules' defaults
  perception::PipelineOptions& p = config.perception;
  preprocess::PreprocessOptions& pre = p.preprocess;
  detection::DetectionStageOptions& det = p.detection;
  det.detectorModelPath =
      resolvePath(section.text("detector_model", std::string(kDefaultDetectorModel)), baseDir);
  det.cropModelPath = readOptionalPath(section, "crop_model", baseDir, kDefaultCropModel);
  config.asmPath = resolvePath(section.text("asm", std::string(kDefaultAsm)), baseDir);
  warnUnchecked(det.detectorModelPath, "detector_model", config);
  warnUnchecked(det.cropModelPath, "crop_model", config);
  det.engine.backend = section.choice<inference::Backend>(
      "backend", inference::backendFromString, kBackendNames, d.detection.engine.backend);
  // One knob for the detector's threads and the preprocessing row loops.
  det.engine.threads = section.integer("threads", kThreadsRange, d.detection.engine.threads);
  pre.threads = det.engine.threads;
  det.cropEngineThreads =
      section.integer("crop_threads", kThreadsRange, d.detection.cropEngineThreads);
  // Both networks (the crop engine copies the detector's options).
  det.engine.planMemory = section.boolean("plan_memory", d.detection.engine.planMemory);
  pre.undistort = section.boolean("undistort", d.preprocess.undistort);
  pre.whiteBalance = section.boolean("white_balance", d.preprocess.whiteBalance);
  preprocess::WhiteBalanceOptions& wb = pre.whiteBalanceOptions;
  const preprocess::WhiteBalanceOptions& wbDefaults = d.preprocess.whiteBalanceOptions;
  if (section.has("white_balance_regions")) {
    const std::vector<int> regions =
        section.integers("white_balance_regions", kWhiteBalanceGridRange, 2);
    wb.regionRows = regions[0];
    wb.regionCols = regions[1];
  }
  wb.sampleStride_px = section.integer("white_balance_sample_stride_px", kSampleStrideRange_px,
                                       wbDefaults.sampleStride_px);
  wb.whitePointShare =
      section.number("white_balance_white_share", kShareRange, wbDefaults.whitePointShare);
  wb.maxGain = section.number("white_balance_max_gain", kMaxGainRange, wbDefaults.maxGain);
  preprocess::ExposureOptions& exposure = pre.exposure;
  const preprocess::ExposureOptions& exposureDefaults = d.preprocess.exposure;
  exposure.enabled = section.boolean("exposure", exposureDefaults.enabled);
  exposure.darkMeanLuma =
      section.number("exposure_dark_mean", kLumaRange, exposureDefaults.darkMeanLuma);
  exposure.targetMeanLuma =
      section.number("exposure_target_mean", kLumaRange, exposureDefaults.targetMeanLuma);
  if (exposure.targetMeanLuma < exposure.darkMeanLuma) {
    section.fail("exposure_target_mean", "must be >= exposure_dark_mean (" +
                                             formatNumber(exposure.darkMeanLuma) + "), got " +
                                             formatNumber(exposure.targetMeanLuma));
  }
  exposure.maxGain = section.number("exposure_max_gain", kMaxGainRange, exposureDefaults.maxGain);
  exposure.sampleStride_px = section.integer("exposure_sample_stride_px", kSampleStrideRange_px,
                                             exposureDefaults.sampleStride_px);
  pre.workingScale = section.number("working_scale", kWorkingScaleRange, d.preprocess.workingScale);
  checkWorkingScale(section, pre.workingScale, config.camera.intrinsics);
  pre.workingGsd_m = section.number("working_gsd_m", kFixedGsdRange_m, d.preprocess.workingGsd_m);
  pre.minWorkingScale =
      section.number("min_working_scale", kWorkingScaleRange, d.preprocess.minWorkingScale);
  pre.maxWorkingScale =
      section.number("max_working_scale", kWorkingScaleRange, d.preprocess.maxWorkingScale);
  pre.maxWorkingGsd_m =
      section.number("max_working_gsd_m", kFixedGsdRange_m, d.preprocess.maxWorkingGsd_m);
  pre.tileOverlap_px =
      section.integer("tile_overlap_px", kTileOverlapRange_px, d.preprocess.tileOverlap_px);

  detection::DecoderOptions& decoder = det.decoder;
  const detection::DecoderOptions& decoderDefaults = d.detection.decoder;
  decoder.scoreThreshold = static_cast<float>(
      section.number("score_threshold", kProbabilityRange, decoderDefaults.scoreThreshold));
  decoder.topKPerTile = section.integer("top_k_per_tile", kTopKRange, decoderDefaults.topKPerTile);
  decoder.nmsIou = section.number("nms_iou", kShareRange, decoderDefaults.nmsIou);
  decoder.duplicateOverlap =
      section.number("duplicate_overlap", kShareRange, decoderDefaults.duplicateOverlap);
  decoder.cutEdgeMargin_px =
      section.number("cut_edge_margin_px", kCutMarginRange_px, decoderDefaults.cutEdgeMargin_px);
  det.maxCrops = section.integer("max_crops", kMaxCropsRange, d.detection.maxCrops);

  detection::SecondStageOptions& second = det.secondStage;
  const detection::SecondStageOptions& secondDefaults = d.detection.secondStage;
  second.applyFlip = section.boolean("apply_flip", secondDefaults.applyFlip);
  second.applyRefine = section.boolean("apply_refine", secondDefaults.applyRefine);
  second.refineSize = section.boolean("crop_refine_size", secondDefaults.refineSize);
  second.mirrorAverage = section.boolean("crop_mirror_average", secondDefaults.mirrorAverage);
  second.turnAverage = section.boolean("crop_turn_average", secondDefaults.turnAverage);
  second.turnTypeAverage =
      section.boolean("crop_turn_type_average", secondDefaults.turnTypeAverage);
  second.turnTypeWeight = static_cast<float>(
      section.number("crop_turn_type_weight", kProbabilityRange, secondDefaults.turnTypeWeight));
  second.mirrorRefine = section.boolean("crop_mirror_refine", secondDefaults.mirrorRefine);
  second.largeVehicleEnds =
      section.boolean("crop_large_vehicle_ends", secondDefaults.largeVehicleEnds);
  second.minVehicleProbability = static_cast<float>(section.number(
      "crop_min_vehicle_probability", kProbabilityRange, secondDefaults.minVehicleProbability));
  second.frameEdgeKeepBox =
      section.boolean("crop_frame_edge_keep_box", secondDefaults.frameEdgeKeepBox);
  second.frameEdgeMinVehicleProbability = static_cast<float>(
      section.number("crop_frame_edge_min_vehicle_probability", kProbabilityRange,
                     secondDefaults.frameEdgeMinVehicleProbability));
  second.frameEdgeOwnVerifier =
      section.boolean("crop_frame_edge_own_verifier", secondDefaults.frameEdgeOwnVerifier);
  detection::LargeVehicleMergeOptions& merge = det.largeMerge;
  merge.enabled = section.boolean("large_vehicle_merge", d.detection.largeMerge.enabled);
  merge.maxLength_m = section.number("large_vehicle_max_length_m", kLargeVehicleLengthRange_m,
                                     d.detection.largeMerge.maxLength_m);
  det.gsd.fixedGsd_m = section.number("fixed_gsd_m", kFixedGsdRange_m, d.detection.gsd.fixedGsd_m);
  det.gsd.nominalCarLength_m =
      section.number("nominal_car_length_m", kCarLengthRange_m, d.detection.gsd.nominalCarLength_m);
  p.lift.boxHeightShare =
      section.number("lift_height_share", kProbabilityRange, d.lift.boxHeightShare);
  p.footprintType.enabled = section.boolean("footprint_type", d.footprintType.enabled);
  section.warnUnknownKeys();
}

}  // namespace vp::config::detail
