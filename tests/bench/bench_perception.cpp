// vp_bench_perception: per-stage latency of the image side of the pipeline on one 2592 x 2048
// frame (the camera of seed 000): undistortion, white balance, area resize, detector network,
// decoding + NMS, second-stage crops - with 1 and 2 threads (crop network: 1, and 2 to show
// why 1 is the default).
//
// Models: models/detector/{detector,crop}_int8.onnx of the source tree (XnnpackInt8). The
// frame is a synthetic grey scene with car-sized rectangles; the decoder threshold is 0 and
// the second stage is capped at 30 crops, so every frame carries 30 vehicles' worth of crops
// whatever the (interim, untrained) detector outputs. Each iteration is one whole frame
// (Preprocessor::process + DetectionStage::run); the counters are the stages' own timings
// (ms per frame, steady clock inside the stages).
//
// Run (medians over repetitions):
//   vp_bench_perception --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <array>
#include <string>

#include <opencv2/imgproc.hpp>

#include "bench_camera.hpp"
#include "detection/detection_stage.hpp"
#include "preprocess/preprocessor.hpp"
#include "synthetic_frame.hpp"

namespace {

using vp::detection::Detection;
using vp::detection::DetectionStage;
using vp::detection::DetectionStageOptions;
using vp::detection::DetectionStatus;

using vp::bench::kFrameHeight_px;
using vp::bench::kFrameWidth_px;
constexpr int kCropsPerFrame = 30;  // a busy intersection

using vp::bench::benchCamera;

cv::Mat benchFrame() {
  return vp::test::syntheticCarFrame(kFrameWidth_px, kFrameHeight_px, 2024, 60);
}

void frameStages(benchmark::State& state, int threads, int cropThreads) {
  const std::string root = VP_SOURCE_DIR;
  vp::preprocess::PreprocessOptions preOptions;
  preOptions.undistort = true;
  preOptions.whiteBalance = true;
  preOptions.threads = threads;
  vp::preprocess::Preprocessor pre;
  std::string why;
  if (!pre.init(preOptions, benchCamera(), {kFrameWidth_px, kFrameHeight_px}, &why)) {
    state.SkipWithError(why.c_str());
    return;
  }
  DetectionStageOptions options;
  options.detectorModelPath = root + "/models/detector/detector_int8.onnx";
  options.cropModelPath = root + "/models/detector/crop_int8.onnx";
  options.engine.threads = threads;
  options.cropEngineThreads = cropThreads;
  options.decoder.scoreThreshold = 0.0F;
  options.maxCrops = kCropsPerFrame;
  DetectionStage stage;
  if (!stage.init(options, static_cast<int>(pre.tileCount()), &why)) {
    state.SkipWithError(why.c_str());
    return;
  }
  const cv::Mat frame = benchFrame();
  std::array<Detection, vp::detection::kMaxDetectionsPerFrame> out{};
  std::size_t count = 0;
  double undistort = 0.0;
  double whiteBalance = 0.0;
  double resize = 0.0;
  double detector = 0.0;
  double decode = 0.0;
  double crops = 0.0;
  double cropCount = 0.0;
  // Warm-up frame (first touch of every buffer).
  pre.process(frame);
  stage.run(pre.output(), out, &count);
  for (auto _ : state) {
    if (pre.process(frame) != vp::preprocess::PreprocessStatus::Ok ||
        stage.run(pre.output(), out, &count) != DetectionStatus::Ok) {
      state.SkipWithError("frame failed");
      break;
    }
    const vp::preprocess::PreprocessTimings& t = pre.output().timings;
    const vp::detection::DetectionStats& s = stage.stats();
    undistort += t.undistort_ms;
    whiteBalance += t.whiteBalance_ms;
    resize += t.resize_ms;
    detector += s.detector_ms;
    decode += s.decode_ms;
    crops += s.crops_ms;
    cropCount += s.crops;
  }
  const auto average = benchmark::Counter::kAvgIterations;
  state.counters["undistort_ms"] = benchmark::Counter(undistort, average);
  state.counters["awb_ms"] = benchmark::Counter(whiteBalance, average);
  state.counters["resize_ms"] = benchmark::Counter(resize, average);
  state.counters["detector_ms"] = benchmark::Counter(detector, average);
  state.counters["decode_ms"] = benchmark::Counter(decode, average);
  state.counters["crops_ms"] = benchmark::Counter(crops, average);
  state.counters["crops"] = benchmark::Counter(cropCount, average);
  state.counters["threads"] = benchmark::Counter(threads);
  state.counters["crop_threads"] = benchmark::Counter(cropThreads);
}

}  // namespace

int main(int argc, char** argv) {
  // Row loops and the detector on `threads`; the crop network on 1 thread (the default) and,
  // to show why that is the default, on 2.
  const int variants[][2] = {{1, 1}, {2, 1}, {2, 2}};
  for (const auto& variant : variants) {
    const int threads = variant[0];
    const int cropThreads = variant[1];
    const std::string name = "perception/frame_2592x2048/threads:" + std::to_string(threads) +
                             "/crop_threads:" + std::to_string(cropThreads);
    benchmark::RegisterBenchmark(name.c_str(),
                                 [threads, cropThreads](benchmark::State& state) {
                                   frameStages(state, threads, cropThreads);
                                 })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MinTime(2.0);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
