// vp_bench_engine: Engine::run latency of the backends on one QDQ model, side by side.
//
// Model: --model=PATH (consumed before Google Benchmark sees the arguments), else the
// environment variable VP_BENCH_MODEL, else /tmp/vp_bench_models/mobilenetv2_512.onnx
// (written by tools/engine/make_test_models.py --bench). One benchmark per backend
// {XnnpackInt8, DnnlInt8 (builds with oneDNN), XnnpackFp32, OpenCvFp32} x threads {1, 2}, each
// timing Engine::run on a fixed random image (wall-clock time), with the counters MAC (=
// Engine::totalMacs() / time, per second; 30.5G/s means 30.5 GMAC/s) and GMAC (per run).
//
// Run (medians over repetitions):
//   vp_bench_engine --model=m.onnx --benchmark_repetitions=10
//   --benchmark_report_aggregates_only=true
// scripts/bench_engine.sh runs it together with the PyTorch baselines and prints one table.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "inference/dnnl_int8.hpp"
#include "inference/engine.hpp"

namespace {

using vp::inference::Backend;
using vp::inference::Engine;
using vp::inference::EngineOptions;
using vp::inference::ImageView;
using vp::inference::RunStatus;

void runEngine(benchmark::State& state, const std::string& modelPath, Backend backend,
               int threads) {
  EngineOptions options;
  options.backend = backend;
  options.threads = threads;
  options.imageOrder = vp::inference::ChannelOrder::Bgr;
  Engine engine;
  std::string why;
  if (!engine.load(modelPath, options, &why)) {
    state.SkipWithError(("load failed: " + why).c_str());
    return;
  }
  const vp::inference::TensorShape shape = engine.inputShape();
  cv::Mat image(shape.h, shape.w, CV_8UC3);
  cv::RNG rng(20240229);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  const ImageView view{image.data, image.cols, image.rows, image.step[0]};
  if (engine.run(view) != RunStatus::Ok) {  // warm-up (first-touch, caches)
    state.SkipWithError("Engine::run failed");
    return;
  }
  for (auto _ : state) {
    const RunStatus status = engine.run(view);
    benchmark::DoNotOptimize(status);
    if (status != RunStatus::Ok) {
      state.SkipWithError(vp::inference::toString(status));
      break;
    }
  }
  const double macs = static_cast<double>(engine.totalMacs());
  // "MAC": multiply-accumulates per second (printed with an SI prefix, e.g. 30.5G/s = GMAC/s).
  state.counters["MAC"] = benchmark::Counter(macs, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["GMAC"] = benchmark::Counter(macs * 1e-9);
  state.counters["threads"] = benchmark::Counter(threads);
  state.SetLabel(modelPath.substr(modelPath.find_last_of('/') + 1));
}

// Removes --model=PATH from argv (Google Benchmark rejects unknown flags) and returns it.
std::string takeModelFlag(int* argc, char** argv) {
  std::string model;
  int out = 1;
  for (int i = 1; i < *argc; ++i) {
    constexpr const char* kFlag = "--model=";
    if (std::strncmp(argv[i], kFlag, std::strlen(kFlag)) == 0) {
      model = argv[i] + std::strlen(kFlag);
    } else {
      argv[out++] = argv[i];
    }
  }
  *argc = out;
  return model;
}

}  // namespace

int main(int argc, char** argv) {
  std::string model = takeModelFlag(&argc, argv);
  if (model.empty()) {
    const char* env = std::getenv("VP_BENCH_MODEL");
    model = env != nullptr && *env != '\0' ? env : "/tmp/vp_bench_models/mobilenetv2_512.onnx";
  }
  struct Variant {
    Backend backend;
    const char* name;
  };
  // The oneDNN int8 backend only where it is built (x86 with libdnnl-dev).
  const bool dnnl = vp::inference::dnnlInt8Available();
  const Variant all[] = {{Backend::XnnpackInt8, "XnnpackInt8"},
                         {Backend::DnnlInt8, "DnnlInt8"},
                         {Backend::XnnpackFp32, "XnnpackFp32"},
                         {Backend::OpenCvFp32, "OpenCvFp32"}};
  std::vector<Variant> variants;
  for (const Variant& variant : all) {
    if (variant.backend != Backend::DnnlInt8 || dnnl)
      variants.push_back(variant);
  }
  for (const Variant& variant : variants) {
    const Backend backend = variant.backend;
    for (const int threads : {1, 2}) {
      const std::string name =
          std::string("engine/") + variant.name + "/threads:" + std::to_string(threads);
      benchmark::RegisterBenchmark(name.c_str(),
                                   [model, backend, threads](benchmark::State& state) {
                                     runEngine(state, model, backend, threads);
                                   })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  }
  std::cerr << "vp_bench_engine: model " << model << '\n';
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
