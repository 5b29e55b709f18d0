// The DnnlInt8 backend (inference/dnnl_int8.hpp) against XnnpackInt8 on the shipped models,
// the load-time choice of Backend::Auto, and that run() allocates nothing.
//
// Tolerance: both backends compute every convolution from the same int8 inputs, weights and
// int32 biases; only the requantization rounding differs, so a convolution output may be one
// quantization step apart, and over the detector's ~50 layers such flips add up (as they do
// between XNNPACK and the generator's fake-quant reference: up to 5 steps, engine_test.cpp).
// An output is accepted when max |a - b| <= 8 steps of its int8 quantization and the mean
// |a - b| <= 0.5 step over outputs of 16 values or more (measured on the detector: max 7,
// mean <= 0.31; crop model: max 1, on a one-value logit).
// The detections decoded from both are compared in tests/detection/detection_stage_test.cpp.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "core/transient_arena.hpp"
#include "inference/dnnl_int8.hpp"
#include "inference/engine.hpp"
#include "synthetic_frame.hpp"

namespace vp::inference {
namespace {

const std::string kDetectorModel =
    std::string(VP_SOURCE_DIR) + "/models/detector/detector_int8.onnx";
const std::string kCropModel = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";

constexpr int kMaxStepDifference = 8;
constexpr double kMaxMeanStepDifference = 0.5;

// Why the oneDNN comparison cannot run here, or empty when it can.
std::string dnnlSkipReason() {
  if (!dnnlInt8Available())
    return "this build has no oneDNN (libdnnl-dev absent at configure time): int8-dnnl disabled";
  if (!cpuHasVnni())
    return "this CPU has no AVX512-VNNI / AVX-VNNI: DnnlInt8 is not the backend it would use";
  return {};
}

Engine loadEngine(const std::string& path, Backend backend, int threads) {
  EngineOptions options;
  options.backend = backend;
  options.threads = threads;
  Engine engine;
  std::string why;
  EXPECT_TRUE(engine.load(path, options, &why)) << why;
  return engine;
}

// The simulator-like road frame with cars, scaled to the model's input.
cv::Mat frameFor(const Engine& engine, std::uint64_t seed) {
  const TensorShape s = engine.inputShape();
  const cv::Mat big = test::syntheticCarFrame(4 * s.w, 4 * s.h, seed, 12);
  cv::Mat small;
  cv::resize(big, small, cv::Size(s.w, s.h), 0, 0, cv::INTER_AREA);
  return small;
}

ImageView viewOf(const cv::Mat& image) {
  return ImageView{image.data, image.cols, image.rows, image.step[0]};
}

TEST(DnnlInt8, AutoPicksDnnlExactlyWhenBuiltAndVnni) {
  const Backend expected =
      dnnlInt8Available() && cpuHasVnni() ? Backend::DnnlInt8 : Backend::XnnpackInt8;
  EXPECT_EQ(resolveAutoBackend(), expected);
  Engine engine = loadEngine(kCropModel, Backend::Auto, 1);
  ASSERT_TRUE(engine.loaded());
  EXPECT_EQ(engine.backend(), expected) << "auto resolved to " << toString(engine.backend());
  EXPECT_EQ(backendFromString("auto"), Backend::Auto);
  EXPECT_EQ(backendFromString("int8-dnnl"), Backend::DnnlInt8);
  EXPECT_STREQ(toString(Backend::DnnlInt8), "int8-dnnl");
}

TEST(DnnlInt8, ForcedWithoutOneDnnIsALoadErrorNamingTheFile) {
  if (dnnlInt8Available())
    GTEST_SKIP() << "this build has oneDNN: the refusal only exists in builds without it";
  EngineOptions options;
  options.backend = Backend::DnnlInt8;
  Engine engine;
  std::string why;
  EXPECT_FALSE(engine.load(kCropModel, options, &why));
  EXPECT_NE(why.find("crop_int8.onnx"), std::string::npos) << why;
  EXPECT_NE(why.find("no oneDNN"), std::string::npos) << why;
}

TEST(DnnlInt8, ConvolutionsRunOnOneDnnTheRestOnXnnpack) {
  if (const auto reason = dnnlSkipReason(); !reason.empty())
    GTEST_SKIP() << reason;
  Engine engine = loadEngine(kDetectorModel, Backend::DnnlInt8, 1);
  ASSERT_TRUE(engine.loaded());
  std::size_t convs = 0;
  for (const auto& layer : engine.layers()) {
    const bool isConv = layer.opType.rfind("Conv", 0) == 0 && layer.opType.rfind("ConvT", 0) != 0;
    if (isConv) {
      ++convs;
      EXPECT_EQ(layer.backendKernel.rfind("dnnl ", 0), 0U) << layer.nodeName;
      // A reference (scalar) implementation would mean no VNNI kernel was found.
      EXPECT_EQ(layer.backendKernel.find("ref"), std::string::npos)
          << layer.nodeName << ": " << layer.backendKernel;
    } else {
      EXPECT_EQ(layer.backendKernel.rfind("dnnl ", 0), std::string::npos) << layer.nodeName;
    }
  }
  EXPECT_GT(convs, 0U);
}

void expectMatchesXnnpack(const std::string& path, int threads) {
  Engine dnnl = loadEngine(path, Backend::DnnlInt8, threads);
  Engine xnn = loadEngine(path, Backend::XnnpackInt8, threads);
  ASSERT_TRUE(dnnl.loaded() && xnn.loaded());
  ASSERT_EQ(dnnl.outputCount(), xnn.outputCount());
  for (const std::uint64_t seed : {3U, 29U}) {
    const cv::Mat frame = frameFor(xnn, seed);
    ASSERT_EQ(dnnl.run(viewOf(frame)), RunStatus::Ok);
    ASSERT_EQ(xnn.run(viewOf(frame)), RunStatus::Ok);
    for (std::size_t o = 0; o < xnn.outputCount(); ++o) {
      const OutputTensor& a = dnnl.output(o);
      const OutputTensor& b = xnn.output(o);
      ASSERT_NE(a.quantized, nullptr);
      ASSERT_EQ(a.shape.elements(), b.shape.elements());
      ASSERT_EQ(a.scale, b.scale);
      ASSERT_EQ(a.zeroPoint, b.zeroPoint);
      int maxSteps = 0;
      double sumSteps = 0.0;
      const std::size_t n = a.shape.elements();
      for (std::size_t i = 0; i < n; ++i) {
        const int d = std::abs(static_cast<int>(a.quantized[i]) - static_cast<int>(b.quantized[i]));
        maxSteps = std::max(maxSteps, d);
        sumSteps += d;
      }
      const double mean = sumSteps / static_cast<double>(n);
      std::printf("  %s output '%s' seed %u threads %d: max %d steps, mean %.3f steps\n",
                  path.substr(path.find_last_of('/') + 1).c_str(), a.name.c_str(),
                  static_cast<unsigned>(seed), threads, maxSteps, mean);
      EXPECT_LE(maxSteps, kMaxStepDifference) << path << " output " << a.name;
      // A mean over a handful of values (the crop model's one-value logits) says nothing.
      if (n >= 16) {
        EXPECT_LE(mean, kMaxMeanStepDifference) << path << " output " << a.name;
      }
    }
  }
}

TEST(DnnlInt8, DetectorMatchesXnnpackInt8WithinRounding) {
  if (const auto reason = dnnlSkipReason(); !reason.empty())
    GTEST_SKIP() << reason;
  expectMatchesXnnpack(kDetectorModel, 1);
  expectMatchesXnnpack(kDetectorModel, 2);
}

TEST(DnnlInt8, CropModelMatchesXnnpackInt8WithinRounding) {
  if (const auto reason = dnnlSkipReason(); !reason.empty())
    GTEST_SKIP() << reason;
  expectMatchesXnnpack(kCropModel, 1);
  expectMatchesXnnpack(kCropModel, 2);
}

// oneDNN 2.6's dnnl_primitive_execute() builds its argument map and execution context on the
// heap on every call (inside libdnnl, not avoidable through its API); the backend serves those
// blocks from an arena reserved at load (core/transient_arena.hpp), so run() allocates nothing,
// on any thread (the OpenMP team's included), run after run, like XnnpackInt8. Under
// AddressSanitizer the arena does not redirect operator new: there the count is only held to
// being the same on every run (nothing grows or leaks).
TEST(DnnlInt8, RunAllocatesNothingItsOneDnnBlocksComeFromTheArena) {
  if (const auto reason = dnnlSkipReason(); !reason.empty())
    GTEST_SKIP() << reason;
  for (const std::string& path : {kDetectorModel, kCropModel}) {
    for (const int threads : {1, 2}) {
      Engine engine = loadEngine(path, Backend::DnnlInt8, threads);
      Engine xnn = loadEngine(path, Backend::XnnpackInt8, threads);
      ASSERT_TRUE(engine.loaded() && xnn.loaded());
      const cv::Mat frame = frameFor(engine, 5);
      for (int i = 0; i < 2; ++i) {  // warm-up (OpenMP team, caches)
        ASSERT_EQ(engine.run(viewOf(frame)), RunStatus::Ok);
        ASSERT_EQ(xnn.run(viewOf(frame)), RunStatus::Ok);
      }
      std::size_t convs = 0;
      for (const auto& layer : engine.layers())
        convs += layer.backendKernel.rfind("dnnl ", 0) == 0 ? 1U : 0U;
      ASSERT_GT(convs, 0U);
      std::vector<std::size_t> perRun;
      for (int i = 0; i < 5; ++i) {
        test::AllocationCounter counter;
        ASSERT_EQ(engine.run(viewOf(frame)), RunStatus::Ok);
        counter.stop();
        perRun.push_back(counter.count());
      }
      test::AllocationCounter xnnCounter;
      xnn.run(viewOf(frame));
      xnnCounter.stop();
      std::printf("  %s threads %d: %zu allocations per run over %zu oneDNN convolutions\n",
                  path.substr(path.find_last_of('/') + 1).c_str(), threads, perRun[0], convs);
      for (const std::size_t count : perRun) {
        if (core::TransientArena::redirects())
          EXPECT_EQ(count, 0U) << path << " threads " << threads;
        else
          EXPECT_EQ(count, perRun[0]) << path << " threads " << threads;
      }
      EXPECT_EQ(xnnCounter.count(), 0U) << path << " threads " << threads;
    }
  }
}

}  // namespace
}  // namespace vp::inference
