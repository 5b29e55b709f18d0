// DetectionStage on the shipped models (models/detector/; the tests check interfaces and
// consistency, not accuracy): a 2592 x 2048 frame runs end to end,
// performs zero heap allocations per frame after the first, and bad input gives statuses.
#include "detection/detection_stage.hpp"
#include "synthetic_frame.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "inference/dnnl_int8.hpp"
#include "preprocess/preprocessor.hpp"
#include "preprocess/white_balance.hpp"

namespace vp::detection {
namespace {

const std::string kDetectorModel =
    std::string(VP_SOURCE_DIR) + "/models/detector/detector_int8.onnx";
const std::string kCropModel = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";

camera::CameraModel camera2592() {
  camera::Intrinsics k;
  k.width_px = 2592;
  k.height_px = 2048;
  k.fx_px = 3000.0;  // ~3 cm/px at 90 m
  k.fy_px = 3000.0;
  k.cx_px = 1295.5;
  k.cy_px = 1023.5;
  camera::Distortion d;
  d.model = camera::LensModel::BrownConrady;
  d.k1 = -0.1;
  d.k2 = 0.03;
  camera::CameraModel camera;
  EXPECT_TRUE(camera.init(k, d));
  return camera;
}

// A grey road texture with car-sized bright and dark rotated rectangles (not realistic; the
// interim models only have to see some structure).
cv::Mat sceneFrame() {
  return test::syntheticCarFrame(2592, 2048, 17, 40);
}

DetectionStageOptions stageOptions(int threads) {
  DetectionStageOptions options;
  options.detectorModelPath = kDetectorModel;
  options.cropModelPath = kCropModel;
  options.engine.threads = threads;
  // XnnpackInt8, the reference the tolerances of these tests were measured with (the engine's
  // default, auto, would take int8-dnnl on a VNNI CPU; that backend is held to this one by
  // OneDnnBackendDecodesTheSameDetectionsAsXnnpack below).
  options.engine.backend = inference::Backend::XnnpackInt8;
  // The interim heatmap is weak: a low threshold makes sure the decoder, the NMS and the
  // second stage all have work to do.
  options.decoder.scoreThreshold = 0.0F;
  options.decoder.topKPerTile = 64;
  options.maxCrops = 32;
  // One crop per vehicle and no verifier, as these tests were written for.
  options.secondStage.mirrorAverage = false;
  options.secondStage.mirrorRefine = false;
  options.secondStage.largeVehicleEnds = false;
  options.secondStage.minVehicleProbability = 0.0F;
  return options;
}

// Undistorted frames, as these tests were written for (the shipped default keeps them raw).
preprocess::PreprocessOptions undistorting() {
  preprocess::PreprocessOptions options;
  options.undistort = true;
  return options;
}

TEST(DetectionStage, RunsTheShippedModelsOnAFullFrame) {
  preprocess::Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(undistorting(), camera2592(), {2592, 2048}, &why)) << why;
  DetectionStage stage;
  ASSERT_TRUE(stage.init(stageOptions(1), static_cast<int>(pre.tileCount()), &why)) << why;
  EXPECT_EQ(stage.detectorInputWidth(), 672);
  EXPECT_EQ(stage.detectorInputHeight(), 512);
  EXPECT_EQ(stage.stride_px(), 4);
  const cv::Mat frame = sceneFrame();
  ASSERT_EQ(pre.process(frame), preprocess::PreprocessStatus::Ok);
  std::array<Detection, kMaxDetectionsPerFrame> out{};
  std::size_t count = 0;
  ASSERT_EQ(stage.run(pre.output(), out, &count), DetectionStatus::Ok);
  const DetectionStats& stats = stage.stats();
  EXPECT_EQ(stats.tiles, 1);
  EXPECT_GT(count, 0U);
  EXPECT_LE(count, static_cast<std::size_t>(stats.candidates));
  EXPECT_EQ(stats.crops, std::min<int>(static_cast<int>(count), 32));
  EXPECT_GT(stats.frameGsd_m, 0.0);
  int classified = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const Detection& d = out[i];
    EXPECT_TRUE(std::isfinite(d.box.cx) && std::isfinite(d.box.cy));
    EXPECT_GE(d.box.cx, -0.5);
    EXPECT_LT(d.box.cx, 2591.5);
    EXPECT_GT(d.box.length, 0.0);
    EXPECT_GE(d.box.angle, 0.0);
    EXPECT_LT(d.box.angle, 2.0 * geometry::kPi);
    if (i > 0) {
      EXPECT_GE(out[i - 1].score, d.score);  // best first
    }
    double sum = 0.0;
    for (const float p : d.typeProbabilities) {
      sum += static_cast<double>(p);
    }
    EXPECT_NEAR(sum, 1.0, 1e-5);
    classified += (d.gamma.count == 3 || topTwoTypes(d).first == shape::VehicleType::Large);
  }
  // Every detection the second stage classified is in the output, unless the suppression of
  // refined duplicates dropped it (then a later, unclassified one moves up: no index rule).
  EXPECT_GE(classified, stats.crops - stats.refinedDuplicates);
  // Deterministic: the same frame gives the same detections.
  std::array<Detection, kMaxDetectionsPerFrame> again{};
  std::size_t countAgain = 0;
  ASSERT_EQ(pre.process(frame), preprocess::PreprocessStatus::Ok);
  ASSERT_EQ(stage.run(pre.output(), again, &countAgain), DetectionStatus::Ok);
  ASSERT_EQ(countAgain, count);
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(again[i].box.cx, out[i].box.cx);
    EXPECT_EQ(again[i].box.angle, out[i].box.angle);
    EXPECT_EQ(again[i].typeProbabilities, out[i].typeProbabilities);
  }
}

// cropBackend changes the second stage's engine only: with the second stage's boxes not
// applied, the first stage's boxes are those of the all-int8 run, the types are not.
// The verifier drops what it doubts and nothing else; a crop network without it keeps all.
TEST(DetectionStage, VerifierDropsOnlyDetectionsBelowTheMinimumVehicleProbability) {
  preprocess::Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(undistorting(), camera2592(), {2592, 2048}, &why)) << why;
  ASSERT_EQ(pre.process(sceneFrame()), preprocess::PreprocessStatus::Ok);
  DetectionStageOptions options = stageOptions(1);
  options.maxCrops = kMaxDetectionsPerFrame;  // every detection gets its crop run
  DetectionStage all;
  ASSERT_TRUE(all.init(options, static_cast<int>(pre.tileCount()), &why)) << why;
  constexpr float kMin = 0.5F;
  options.secondStage.minVehicleProbability = kMin;
  DetectionStage verified;
  ASSERT_TRUE(verified.init(options, static_cast<int>(pre.tileCount()), &why)) << why;
  std::array<Detection, kMaxDetectionsPerFrame> outAll{};
  std::array<Detection, kMaxDetectionsPerFrame> outVerified{};
  std::size_t countAll = 0;
  std::size_t countVerified = 0;
  ASSERT_EQ(all.run(pre.output(), outAll, &countAll), DetectionStatus::Ok);
  ASSERT_EQ(verified.run(pre.output(), outVerified, &countVerified), DetectionStatus::Ok);
  ASSERT_GT(countAll, 0U);
  EXPECT_EQ(all.stats().rejectedByVerifier, 0);
  if (!verified.hasVerifier()) {
    EXPECT_EQ(countVerified, countAll);
    EXPECT_EQ(verified.stats().rejectedByVerifier, 0);
    for (std::size_t i = 0; i < countAll; ++i) {
      EXPECT_TRUE(std::isnan(outAll[i].vehicleProbability));
    }
    return;
  }
  // The synthetic rectangles at score threshold 0 are mostly no vehicles: some go. Each one
  // the unfiltered run kept below the minimum is among them (the refined-duplicate suppression
  // comes after the verifier, so a box it removed there may be rejected too, or may survive
  // when the box it duplicated was rejected).
  int below = 0;
  for (std::size_t i = 0; i < countAll; ++i) {
    ASSERT_FALSE(std::isnan(outAll[i].vehicleProbability)) << "detection " << i;
    below += outAll[i].vehicleProbability < kMin ? 1 : 0;
  }
  EXPECT_GT(below, 0);
  EXPECT_GE(verified.stats().rejectedByVerifier, below);
  EXPECT_LT(countVerified, countAll);
  for (std::size_t i = 0; i < countVerified; ++i) {
    EXPECT_GE(outVerified[i].vehicleProbability, kMin) << "detection " << i;
  }
}

TEST(DetectionStage, CropBackendSwitchesOnlyTheSecondStage) {
  preprocess::Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(undistorting(), camera2592(), {2592, 2048}, &why)) << why;
  const cv::Mat frame = sceneFrame();
  auto runWith = [&](std::optional<inference::Backend> cropBackend,
                     std::array<Detection, kMaxDetectionsPerFrame>& out) {
    DetectionStageOptions options = stageOptions(1);
    options.secondStage.applyRefine = false;
    options.secondStage.applyFlip = false;
    options.cropBackend = cropBackend;
    DetectionStage stage;
    std::string error;
    EXPECT_TRUE(stage.init(options, static_cast<int>(pre.tileCount()), &error)) << error;
    EXPECT_EQ(pre.process(frame), preprocess::PreprocessStatus::Ok);
    std::size_t count = 0;
    EXPECT_EQ(stage.run(pre.output(), out, &count), DetectionStatus::Ok);
    return count;
  };
  std::array<Detection, kMaxDetectionsPerFrame> int8{}, fp32Crops{};
  const std::size_t count = runWith(std::nullopt, int8);
  ASSERT_GT(count, 0U);
  ASSERT_EQ(runWith(inference::Backend::XnnpackFp32, fp32Crops), count);
  int typesDiffer = 0;
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(fp32Crops[i].box.cx, int8[i].box.cx);
    EXPECT_EQ(fp32Crops[i].box.angle, int8[i].box.angle);
    typesDiffer += fp32Crops[i].typeProbabilities != int8[i].typeProbabilities;
  }
  EXPECT_GT(typesDiffer, 0);
}

// A vehicle cut by the frame's border keeps the first stage's box (the crop network learnt whole
// vehicles: its refinement would stretch the box past the border); the others are refined as
// before; the verifier's threshold at the border is its own.
TEST(DetectionStage, AVehicleCutByTheFrameBorderKeepsTheDetectorsBox) {
  preprocess::Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(undistorting(), camera2592(), {2592, 2048}, &why)) << why;
  cv::Mat frame = sceneFrame();
  // Two bright cars cut by the left and the bottom border.
  cv::rectangle(frame, cv::Rect(0, 900, 90, 70), cv::Scalar(230, 230, 235), cv::FILLED);
  cv::rectangle(frame, cv::Rect(1500, 1990, 70, 58), cv::Scalar(30, 30, 200), cv::FILLED);
  ASSERT_EQ(pre.process(frame), preprocess::PreprocessStatus::Ok);
  using Out = std::array<Detection, kMaxDetectionsPerFrame>;
  auto runWith = [&](const SecondStageOptions& second, Out& out) {
    DetectionStageOptions options = stageOptions(1);
    options.maxCrops = kMaxDetectionsPerFrame;  // every detection gets its crop run
    options.secondStage = second;
    DetectionStage stage;
    std::string error;
    EXPECT_TRUE(stage.init(options, static_cast<int>(pre.tileCount()), &error)) << error;
    std::size_t count = 0;
    EXPECT_EQ(stage.run(pre.output(), out, &count), DetectionStatus::Ok);
    return count;
  };
  const SecondStageOptions base = stageOptions(1).secondStage;
  SecondStageOptions keep = base;
  keep.frameEdgeKeepBox = true;
  SecondStageOptions refineAll = base;
  refineAll.frameEdgeKeepBox = false;
  SecondStageOptions firstStageBoxes = base;
  firstStageBoxes.applyRefine = false;
  Out kept{}, refined{}, unrefined{};
  const std::size_t keptCount = runWith(keep, kept);
  const std::size_t refinedCount = runWith(refineAll, refined);
  const std::size_t unrefinedCount = runWith(firstStageBoxes, unrefined);
  const auto find = [](const Out& out, std::size_t count, const Detection& d) -> const Detection* {
    for (std::size_t i = 0; i < count; ++i) {
      if (out[i].box.cx == d.box.cx && out[i].box.cy == d.box.cy &&
          out[i].box.length == d.box.length && out[i].box.width == d.box.width) {
        return &out[i];
      }
    }
    return nullptr;
  };
  // Each box is either the first stage's, kept because it reaches the border, or refined as
  // without the switch (a refined box may end at the border too).
  int edge = 0;
  int inner = 0;
  int innerRefinedAlike = 0;
  for (std::size_t i = 0; i < keptCount; ++i) {
    const Detection& d = kept[i];
    const Detection* first = find(unrefined, unrefinedCount, d);
    if (first != nullptr) {
      ++edge;
      EXPECT_TRUE(d.atFrameEdge) << "detection " << i << " kept its first-stage box inside "
                                 << d.box.cx << " " << d.box.cy << " " << d.box.length << " "
                                 << d.box.width << " " << d.box.angle << " first "
                                 << first->box.length << " " << first->box.angle << " "
                                 << first->atFrameEdge;
      EXPECT_EQ(first->typeProbabilities, d.typeProbabilities);  // the crops still ran
    } else {
      ++inner;
      const Detection* other = find(refined, refinedCount, d);
      innerRefinedAlike += other != nullptr ? 1 : 0;
    }
  }
  // Without the switch, some edge box is refined (moved or resized).
  int refinedEdge = 0;
  for (std::size_t i = 0; i < refinedCount; ++i) {
    refinedEdge += find(unrefined, unrefinedCount, refined[i]) == nullptr ? 1 : 0;
  }
  EXPECT_GT(refinedEdge, 0);

  // The verifier's two thresholds: everything at the border stays, the rest needs 0.99.
  SecondStageOptions verified = keep;
  verified.minVehicleProbability = 0.99F;
  verified.frameEdgeMinVehicleProbability = 0.0F;
  Out out{};
  const std::size_t count = runWith(verified, out);
  int edgeVerified = 0;
  int edgeBelowStrict = 0;  // of those at the border, below the stricter threshold further down
  for (std::size_t i = 0; i < count; ++i) {
    if (find(unrefined, unrefinedCount, out[i]) != nullptr) {
      ++edgeVerified;
      edgeBelowStrict += out[i].vehicleProbability < 0.99F ? 1 : 0;
    } else {
      EXPECT_GE(out[i].vehicleProbability, 0.99F) << "detection " << i;
    }
  }
  EXPECT_EQ(edgeVerified, edge);

  // The border's threshold is its own when it is the stricter one too: inside nearly all stay,
  // of the vehicles cut by the border (those keeping the first stage's box; a refined box that
  // ends at the border was verified as inside) only those of 0.99 or more.
  verified.minVehicleProbability = 0.01F;
  verified.frameEdgeMinVehicleProbability = 0.99F;
  Out strict{};
  const std::size_t strictCount = runWith(verified, strict);
  int edgeStrict = 0;
  for (std::size_t i = 0; i < strictCount; ++i) {
    if (find(unrefined, unrefinedCount, strict[i]) != nullptr) {
      ++edgeStrict;
      EXPECT_GE(strict[i].vehicleProbability, 0.99F) << "detection " << i;
    }
  }
  EXPECT_GT(edgeBelowStrict, 0);
  EXPECT_EQ(edgeStrict, edgeVerified - edgeBelowStrict);
}

class FixedGsd : public GsdProvider {
 public:
  double groundSampleDistance_m(const Detection& detection) const override {
    ++calls;
    return detection.box.cx < 1296.0 ? 0.03 : -1.0;  // unknown on the right half
  }
  mutable int calls = 0;
};

TEST(DetectionStage, GsdProviderIsAskedPerDetection) {
  preprocess::Preprocessor pre;
  ASSERT_TRUE(pre.init(undistorting(), camera2592(), {2592, 2048}));
  DetectionStage stage;
  DetectionStageOptions options = stageOptions(1);
  options.maxCrops = 8;
  ASSERT_TRUE(stage.init(options, 1));
  ASSERT_EQ(pre.process(sceneFrame()), preprocess::PreprocessStatus::Ok);
  std::array<Detection, kMaxDetectionsPerFrame> out{};
  std::size_t count = 0;
  const FixedGsd provider;
  ASSERT_EQ(stage.run(pre.output(), out, &count, &provider), DetectionStatus::Ok);
  EXPECT_EQ(provider.calls, std::min<int>(static_cast<int>(count), 8));
  EXPECT_EQ(stage.stats().crops, provider.calls);  // unknown ones fall back to the frame GSD
}

TEST(DetectionStage, NoHeapAllocationPerFrame) {
  const cv::Mat frame = sceneFrame();
  for (const int threads : {1, 2}) {
    preprocess::PreprocessOptions preOptions = undistorting();
    preOptions.threads = threads;
    preOptions.whiteBalance = true;
    preprocess::Preprocessor pre;
    ASSERT_TRUE(pre.init(preOptions, camera2592(), {2592, 2048}));
    DetectionStage stage;
    std::string why;
    ASSERT_TRUE(stage.init(stageOptions(threads), 1, &why)) << why;
    std::array<Detection, kMaxDetectionsPerFrame> out{};
    std::size_t count = 0;
    ASSERT_EQ(pre.process(frame), preprocess::PreprocessStatus::Ok);  // first frame: warm-up
    ASSERT_EQ(stage.run(pre.output(), out, &count), DetectionStatus::Ok);
    test::AllocationCounter counter;
    ASSERT_EQ(pre.process(frame), preprocess::PreprocessStatus::Ok);
    ASSERT_EQ(stage.run(pre.output(), out, &count), DetectionStatus::Ok);
    counter.stop();
    const DetectionStats& stats = stage.stats();
    EXPECT_GT(stats.crops, 0);
    EXPECT_EQ(counter.count(), 0U) << "threads " << threads;
    std::printf(
        "  threads %d: preprocess %.1f ms, detector %.1f ms, decode %.2f ms, %d crops %.1f ms\n",
        threads, pre.output().timings.total_ms, stats.detector_ms, stats.decode_ms, stats.crops,
        stats.crops_ms);
  }
}

TEST(DetectionStage, BadInputGivesStatuses) {
  DetectionStage stage;
  std::array<Detection, 16> out{};
  std::size_t count = 7;
  preprocess::PreprocessedFrame frame;
  EXPECT_EQ(stage.run(frame, out, &count), DetectionStatus::NotInitialised);
  EXPECT_EQ(count, 0U);
  std::string why;
  ASSERT_TRUE(stage.init(stageOptions(1), 1, &why)) << why;
  EXPECT_EQ(stage.run(frame, out, &count), DetectionStatus::NoTiles);

  // A frame preprocessed for another network size: wrong tiles.
  preprocess::PreprocessOptions small = undistorting();
  small.networkWidth_px = 320;
  small.networkHeight_px = 256;
  small.tileOverlap_px = 64;
  preprocess::Preprocessor pre;
  ASSERT_TRUE(pre.init(small, camera2592(), {2592, 2048}, &why)) << why;
  ASSERT_EQ(pre.process(sceneFrame()), preprocess::PreprocessStatus::Ok);
  EXPECT_EQ(stage.run(pre.output(), out, &count), DetectionStatus::TooManyTiles);
  DetectionStage wide;
  ASSERT_TRUE(wide.init(stageOptions(1), 64, &why)) << why;
  EXPECT_EQ(wide.run(pre.output(), out, &count), DetectionStatus::WrongTileSize);

  // Tiles but no frame to crop from.
  preprocess::Preprocessor good;
  ASSERT_TRUE(good.init(undistorting(), camera2592(), {2592, 2048}));
  ASSERT_EQ(good.process(sceneFrame()), preprocess::PreprocessStatus::Ok);
  preprocess::PreprocessedFrame noFrame = good.output();
  noFrame.frame = cv::Mat();
  EXPECT_EQ(stage.run(noFrame, out, &count), DetectionStatus::EmptyFrame);
  // A bad frame never reaches the stage: the preprocessor refuses it first.
  EXPECT_EQ(good.process(cv::Mat(100, 100, CV_8UC3)), preprocess::PreprocessStatus::WrongFrameSize);
}

TEST(DetectionStage, InitNamesModelProblems) {
  DetectionStage stage;
  std::string why;
  DetectionStageOptions options = stageOptions(1);
  options.detectorModelPath = kCropModel;  // the wrong network
  EXPECT_FALSE(stage.init(options, 1, &why));
  EXPECT_NE(why.find("no output named 'heatmap'"), std::string::npos) << why;
  EXPECT_NE(why.find("crop_int8.onnx"), std::string::npos) << why;
  options = stageOptions(1);
  options.cropModelPath = kDetectorModel;
  EXPECT_FALSE(stage.init(options, 1, &why));
  EXPECT_NE(why.find("crop network needs 3x48x96"), std::string::npos) << why;
  options = stageOptions(1);
  options.detectorModelPath = "/nonexistent/detector.onnx";
  EXPECT_FALSE(stage.init(options, 1, &why));
  EXPECT_NE(why.find("detector.onnx"), std::string::npos) << why;
  options = stageOptions(1);
  options.maxCrops = -1;
  EXPECT_FALSE(stage.init(options, 1, &why));
  EXPECT_NE(why.find("max_crops"), std::string::npos) << why;
  EXPECT_FALSE(stage.initialised());
}

// The oneDNN int8 backend (int8-dnnl, what `auto` picks on VNNI CPUs) decodes the same
// vehicles as XNNPACK's on a simulated frame. The network outputs differ only by
// requantization rounding (tests/inference/dnnl_int8_test.cpp: a few steps at most), but the
// stage has discontinuities that such a step can cross: the weakest heatmap maxima (the test's
// threshold is 0) appear in one run and not the other; the crop classifier's argmax flips
// where two types are nearly tied; two refined boxes of one long vehicle with equal scores
// are ordered by a tie, and the duplicate suppression keeps the other one. So the test holds
// the two runs to this: every confident detection (score >= kSolidScore) has its twin in the
// other run - within kTwinDistance_px (3 % of a ~165 px car) and a score within 0.02 - and
// most of them (kAgreeingShare) agree in full: centre within 2.5 px, length within 5.5 px
// (four of the crop network's 1.35 px length steps on this frame), the same type. Measured
// with detector v8: 76 confident detections over both runs, every one with a twin within
// 3.5 px, 87 % in full agreement (the rest: three type flips, two lengths 5 and 8 steps
// apart, one suppression tie); with v10: 78, every twin within 4.8 px, 97 % in full agreement.
// Every detection gets its crop: with a crop budget, which detections are refined would depend on
// their score rank as well.
TEST(DetectionStage, OneDnnBackendDecodesTheSameDetectionsAsXnnpack) {
  if (!inference::dnnlInt8Available())
    GTEST_SKIP() << "this build has no oneDNN (libdnnl-dev absent at configure time)";
  if (!inference::cpuHasVnni())
    GTEST_SKIP() << "this CPU has no AVX512-VNNI / AVX-VNNI: int8-dnnl is not what it would use";
  preprocess::Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(undistorting(), camera2592(), {2592, 2048}, &why)) << why;
  ASSERT_EQ(pre.process(sceneFrame()), preprocess::PreprocessStatus::Ok);
  std::array<std::array<Detection, kMaxDetectionsPerFrame>, 2> out{};
  std::array<std::size_t, 2> count{};
  const std::array<inference::Backend, 2> backends{inference::Backend::XnnpackInt8,
                                                   inference::Backend::DnnlInt8};
  for (std::size_t b = 0; b < 2; ++b) {
    DetectionStageOptions options = stageOptions(1);
    options.maxCrops = kMaxDetectionsPerFrame;
    options.engine.backend = backends[b];
    DetectionStage stage;
    ASSERT_TRUE(stage.init(options, static_cast<int>(pre.tileCount()), &why)) << why;
    ASSERT_EQ(stage.run(pre.output(), out[b], &count[b]), DetectionStatus::Ok);
  }
  constexpr float kSolidScore = 0.2F;
  constexpr double kTwinDistance_px = 5.0;
  constexpr double kAgreeingShare = 0.8;
  std::size_t solid = 0;
  std::size_t agreeing = 0;
  double maxShift = 0.0;
  double maxScore = 0.0;
  for (std::size_t from = 0; from < 2; ++from) {
    const std::size_t to = 1 - from;
    for (std::size_t i = 0; i < count[from]; ++i) {
      const Detection& d = out[from][i];
      if (d.score < kSolidScore)
        continue;
      ++solid;
      const Detection* twin = nullptr;
      double best = 1e9;
      for (std::size_t j = 0; j < count[to]; ++j) {
        const Detection& e = out[to][j];
        const double dist = std::hypot(e.box.cx - d.box.cx, e.box.cy - d.box.cy);
        if (dist < best) {
          best = dist;
          twin = &e;
        }
      }
      ASSERT_NE(twin, nullptr) << "no detections from " << inference::toString(backends[to]);
      EXPECT_LE(best, kTwinDistance_px)
          << inference::toString(backends[from]) << " detection " << i << " has no twin";
      const double scoreDifference = std::abs(twin->score - d.score);
      EXPECT_LE(scoreDifference, 0.02) << inference::toString(backends[from]) << " detection " << i;
      maxShift = std::max(maxShift, best);
      maxScore = std::max(maxScore, scoreDifference);
      agreeing += best <= 2.5 && std::abs(twin->box.length - d.box.length) <= 5.5 &&
                  topTwoTypes(*twin).first == topTwoTypes(d).first;
    }
  }
  const double agreeingShare =
      solid == 0 ? 0.0 : static_cast<double>(agreeing) / static_cast<double>(solid);
  std::printf(
      "  int8 %zu / int8-dnnl %zu detections, %zu above %.2f (both runs); twins: max centre "
      "distance %.3f px, score difference %.4f; in full agreement %zu (%.1f %%)\n",
      count[0], count[1], solid, static_cast<double>(kSolidScore), maxShift, maxScore, agreeing,
      100.0 * agreeingShare);
  EXPECT_GE(solid, 20U) << "the frame gives too few confident detections for the comparison";
  EXPECT_GE(agreeingShare, kAgreeingShare);
}

// An under-exposed frame (the scene at a fifth of its brightness) is detected as the same
// frame exposed right: the preprocessor gains the working image, the crops get the gain
// through FirstStageOutput::frameGain (no full-size copy). The reference is the dark frame
// gained beforehand through the same tables with the exposure off: the tiles are identical
// (tests/preprocess/exposure_test.cpp), the crops differ only by where the rounding falls (gain
// before or after the bilinear sampling), so every detection must have its twin: centre within
// 1.5 px, the same type but for near ties, score within 0.02. Without the crops' gain the types
// and boxes change.
TEST(DetectionStage, ADarkFrameIsDetectedAsTheSameFrameExposedRight) {
  cv::Mat dark;
  sceneFrame().convertTo(dark, CV_8UC3, 0.2);
  std::string why;
  preprocess::Preprocessor exposed;
  ASSERT_TRUE(exposed.init(preprocess::PreprocessOptions{}, camera2592(), dark.size(), &why))
      << why;
  ASSERT_EQ(exposed.process(dark), preprocess::PreprocessStatus::Ok);
  const float gain = exposed.output().frameGain;
  ASSERT_TRUE(exposed.output().exposure.applied);
  ASSERT_GT(gain, 2.0F);
  preprocess::WhiteBalancer tables;
  preprocess::WhiteBalanceGains gains;
  gains.gain = {gain, gain, gain};
  tables.setGains(gains);
  cv::Mat bright(dark.size(), CV_8UC3);
  tables.applyRows(dark, bright, 0, dark.rows);
  preprocess::PreprocessOptions off;
  off.exposure.enabled = false;
  preprocess::Preprocessor reference;
  ASSERT_TRUE(reference.init(off, camera2592(), bright.size(), &why)) << why;
  ASSERT_EQ(reference.process(bright), preprocess::PreprocessStatus::Ok);
  ASSERT_FLOAT_EQ(reference.output().frameGain, 1.0F);

  DetectionStageOptions options = stageOptions(1);
  options.maxCrops = kMaxDetectionsPerFrame;
  options.decoder.scoreThreshold = 0.2F;  // confident detections: no weak maxima at the edge
  DetectionStage stage;
  ASSERT_TRUE(stage.init(options, static_cast<int>(exposed.tileCount()), &why)) << why;
  std::array<std::array<Detection, kMaxDetectionsPerFrame>, 2> out{};
  std::array<std::size_t, 2> count{};
  ASSERT_EQ(stage.run(exposed.output(), out[0], &count[0]), DetectionStatus::Ok);
  ASSERT_EQ(stage.run(reference.output(), out[1], &count[1]), DetectionStatus::Ok);
  ASSERT_GE(count[1], 10U);
  EXPECT_EQ(count[0], count[1]);
  // Centres within 1.5 px (1 % of a ~165 px car; v10's largest shift 1.32 px, from the crop
  // network's refinement of a crop that differs by rounding).
  constexpr double kTwinDistance_px = 1.5;
  // The type may flip only where the reference's top two are a near tie (measured: v9 two flips
  // at 0.018 and 0.038 apart, v10 one at 0.019, with the type averaged over four looks; v12 none
  // on x86-64 and three on aarch64 under QEMU, at 0.016, 0.049 and 0.079, where the top type had
  // 0.41-0.53: the scene's synthetic cars are ties for the crop network, and v12's type leans 0.8
  // on the second look, cut where the refinement, itself moved by the rounding, puts it).
  constexpr float kTypeTie = 0.1F;
  constexpr std::size_t kMaxTypeFlips = 3;
  std::size_t typeFlips = 0;
  for (std::size_t i = 0; i < count[1]; ++i) {
    const Detection& r = out[1][i];
    const Detection* twin = nullptr;
    double best = 1e9;
    for (std::size_t j = 0; j < count[0]; ++j) {
      const double d = std::hypot(out[0][j].box.cx - r.box.cx, out[0][j].box.cy - r.box.cy);
      if (d < best) {
        best = d;
        twin = &out[0][j];
      }
    }
    ASSERT_NE(twin, nullptr);
    EXPECT_LE(best, kTwinDistance_px) << "detection " << i;
    const TopTwoTypes types = topTwoTypes(r);
    if (topTwoTypes(*twin).first != types.first) {
      ++typeFlips;
      std::printf("  detection %zu: type %d -> %d, reference top two %.3f / %.3f\n", i,
                  static_cast<int>(types.first), static_cast<int>(topTwoTypes(*twin).first),
                  static_cast<double>(types.firstProbability),
                  static_cast<double>(types.secondProbability));
      EXPECT_LE(types.firstProbability - types.secondProbability, kTypeTie)
          << "detection " << i << ": a type flip that is no near tie";
    }
    EXPECT_LE(std::abs(twin->score - r.score), 0.02F) << "detection " << i;
  }
  EXPECT_LE(typeFlips, kMaxTypeFlips);
}

}  // namespace
}  // namespace vp::detection
