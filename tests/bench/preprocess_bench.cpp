// vp_bench_preprocess: Preprocessor::process on one 2592 x 2048 camera frame, per configuration
// and thread count, with the sub-steps' own timings as counters (undistort_ms, awb_ms,
// resize_ms, and convert_ms for the camera's YUV layouts).
//
// Cases (the shipped configuration first):
//   bgr/default        BGR frame, working scale 0.25 (4 x 4 area mean), no undistortion, no AWB
//   bgr/rung           BGR frame, the ladder's next rung above 0.25 (a non-integer area resize)
//   bgr/awb            the default with white balance on
//   bgr/undistort_awb  undistortion + white balance + 0.25
//   yuyv/default, nv12/default: the camera's layouts into the default configuration, the way the
//                      app is fed: the capture side's full-frame YUV -> BGR conversion
//                      (platform/v4l2, timed as convert_ms) then process().
//   yuyv/direct, nv12/direct: the same buffers through the direct camera path
//                      (process(YuvFrame): rows converted inside the resize sweep, no
//                      full-size BGR frame).
// The frame is a synthetic grey scene with car-sized rectangles (tests/support).
//
// Run (medians over repetitions):
//   vp_bench_preprocess --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "bench_camera.hpp"
#include "platform/v4l2/yuv_to_bgr.hpp"
#include "preprocess/preprocessor.hpp"
#include "synthetic_frame.hpp"

namespace {

using vp::preprocess::PreprocessOptions;
using vp::preprocess::Preprocessor;
using vp::preprocess::PreprocessStatus;

using vp::bench::kFrameHeight_px;
using vp::bench::kFrameWidth_px;

enum class Input { Bgr, Yuyv, Nv12, YuyvDirect, Nv12Direct };

using vp::bench::benchCamera;

// The camera's buffers for the synthetic frame: luma from the BGR frame's green channel, chroma
// a slow ramp (both layouts carry the same picture).
struct YuvBuffers {
  std::vector<std::uint8_t> yuyv;  // 2 bytes per pixel
  std::vector<std::uint8_t> nv12;  // Y plane then interleaved UV at half resolution
};

YuvBuffers yuvFrom(const cv::Mat& bgr) {
  YuvBuffers out;
  const auto w = static_cast<std::size_t>(bgr.cols);
  const auto h = static_cast<std::size_t>(bgr.rows);
  out.yuyv.resize(w * h * 2);
  out.nv12.resize(w * h * 3 / 2);
  for (std::size_t y = 0; y < h; ++y) {
    const std::uint8_t* row = bgr.ptr<std::uint8_t>(static_cast<int>(y));
    for (std::size_t x = 0; x < w; x += 2) {
      const auto u = static_cast<std::uint8_t>(96 + (x * 64) / w);
      const auto v = static_cast<std::uint8_t>(160 - (y * 64) / h);
      std::uint8_t* p = &out.yuyv[(y * w + x) * 2];
      p[0] = row[x * 3 + 1];
      p[1] = u;
      p[2] = row[(x + 1) * 3 + 1];
      p[3] = v;
      out.nv12[y * w + x] = p[0];
      out.nv12[y * w + x + 1] = p[2];
      if (y % 2 == 0) {
        std::uint8_t* uv = &out.nv12[w * h + (y / 2) * w + x];
        uv[0] = u;
        uv[1] = v;
      }
    }
  }
  return out;
}

void preprocessFrame(benchmark::State& state, Input input, PreprocessOptions options) {
  Preprocessor pre;
  std::string why;
  if (!pre.init(options, benchCamera(), {kFrameWidth_px, kFrameHeight_px}, &why)) {
    state.SkipWithError(why.c_str());
    return;
  }
  const cv::Mat source = vp::test::syntheticCarFrame(kFrameWidth_px, kFrameHeight_px, 2024, 60);
  const YuvBuffers yuv = yuvFrom(source);
  cv::Mat converted(kFrameHeight_px, kFrameWidth_px, CV_8UC3);
  const auto w = static_cast<std::size_t>(kFrameWidth_px);
  const auto h = static_cast<std::size_t>(kFrameHeight_px);
  vp::preprocess::YuvFrame direct;
  direct.width_px = kFrameWidth_px;
  direct.height_px = kFrameHeight_px;
  if (input == Input::YuyvDirect) {
    direct.data = yuv.yuyv.data();
    direct.strideBytes = w * 2;
  } else if (input == Input::Nv12Direct) {
    direct.layout = vp::preprocess::YuvFrame::Layout::Nv12;
    direct.data = yuv.nv12.data();
    direct.strideBytes = w;
    direct.uv = yuv.nv12.data() + w * h;
    direct.uvStrideBytes = w;
  }
  const bool isDirect = input == Input::YuyvDirect || input == Input::Nv12Direct;
  auto convert = [&]() {
    switch (input) {
      case Input::Bgr:
      case Input::YuyvDirect:
      case Input::Nv12Direct:
        return true;
      case Input::Yuyv:
        return vp::platform::v4l2::yuyvToBgr(yuv.yuyv.data(), w * 2, kFrameWidth_px,
                                             kFrameHeight_px, converted);
      case Input::Nv12:
        return vp::platform::v4l2::nv12ToBgr(yuv.nv12.data(), w, yuv.nv12.data() + w * h, w,
                                             kFrameWidth_px, kFrameHeight_px, converted);
    }
    return false;
  };
  const cv::Mat& frame = input == Input::Bgr ? source : converted;
  auto run = [&]() { return isDirect ? pre.process(direct) : pre.process(frame); };
  // Warm-up frame (first touch of every buffer).
  if (!convert() || run() != PreprocessStatus::Ok) {
    state.SkipWithError("warm-up frame failed");
    return;
  }
  double convertSum = 0.0;
  double undistort = 0.0;
  double whiteBalance = 0.0;
  double resize = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const bool ok = convert();
    convertSum +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!ok || run() != PreprocessStatus::Ok) {
      state.SkipWithError("frame failed");
      break;
    }
    const vp::preprocess::PreprocessTimings& t = pre.output().timings;
    undistort += t.undistort_ms;
    whiteBalance += t.whiteBalance_ms;
    resize += t.resize_ms;
    benchmark::DoNotOptimize(pre.output().tiles.data());
  }
  const auto average = benchmark::Counter::kAvgIterations;
  state.counters["convert_ms"] = benchmark::Counter(convertSum, average);
  state.counters["undistort_ms"] = benchmark::Counter(undistort, average);
  state.counters["awb_ms"] = benchmark::Counter(whiteBalance, average);
  state.counters["resize_ms"] = benchmark::Counter(resize, average);
  state.counters["threads"] = benchmark::Counter(options.threads);
}

struct Case {
  const char* name;
  Input input;
  bool undistort;
  bool whiteBalance;
  double scale;
};

}  // namespace

int main(int argc, char** argv) {
  const double rung = vp::preprocess::kDefaultWorkingScale * vp::preprocess::kScaleStep;
  const Case cases[] = {
      {"bgr/default", Input::Bgr, false, false, vp::preprocess::kDefaultWorkingScale},
      {"bgr/rung", Input::Bgr, false, false, rung},
      {"bgr/awb", Input::Bgr, false, true, vp::preprocess::kDefaultWorkingScale},
      {"bgr/undistort_awb", Input::Bgr, true, true, vp::preprocess::kDefaultWorkingScale},
      {"yuyv/default", Input::Yuyv, false, false, vp::preprocess::kDefaultWorkingScale},
      {"nv12/default", Input::Nv12, false, false, vp::preprocess::kDefaultWorkingScale},
      {"yuyv/direct", Input::YuyvDirect, false, false, vp::preprocess::kDefaultWorkingScale},
      {"nv12/direct", Input::Nv12Direct, false, false, vp::preprocess::kDefaultWorkingScale},
  };
  for (const Case& c : cases) {
    for (const int threads : {1, 2}) {
      PreprocessOptions options;
      options.undistort = c.undistort;
      options.whiteBalance = c.whiteBalance;
      options.workingScale = c.scale;
      options.threads = threads;
      const std::string name =
          std::string("preprocess/") + c.name + "/threads:" + std::to_string(threads);
      const Input input = c.input;
      benchmark::RegisterBenchmark(
          name.c_str(),
          [input, options](benchmark::State& state) { preprocessFrame(state, input, options); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinTime(0.5);
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
