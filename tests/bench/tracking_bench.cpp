// Tracker step with 200 vehicles (20 lanes x 10 cars at 10 m/s, one detection each, 10 Hz).
// Run: build-tracking/tests/bench/vp_bench_tracking [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "tracking/track_manager.hpp"

namespace {

using vp::tracking::WorldDetection;

std::vector<WorldDetection> convoy(int count, int frame) {
  std::vector<WorldDetection> out(static_cast<std::size_t>(count));
  const double t = frame / 10.0;
  for (int i = 0; i < count; ++i) {
    WorldDetection& d = out[static_cast<std::size_t>(i)];
    d.timestamp_ns = static_cast<std::int64_t>(std::llround(t * 1e9));
    d.centreEnu = Eigen::Vector2d(-100.0 + 12.0 * (i / 20) + 10.0 * t, -50.0 + 5.0 * (i % 20));
    d.length_m = 4.5;
    d.width_m = 1.8;
    d.score = 0.9f;
    d.typeProbabilities.fill(0.05f);
    d.typeProbabilities[3] = 0.7f;
  }
  return out;
}

void trackerStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  constexpr int kFrames = 64;
  std::vector<std::vector<WorldDetection>> frames;
  for (int k = 0; k < kFrames; ++k) {
    frames.push_back(convoy(n, k));
  }
  vp::tracking::TrackManager tracker;
  vp::tracking::TrackerConfig config;
  config.maxTracks = 256;
  config.maxDetections = 256;
  if (!tracker.init(config)) {
    state.SkipWithError("init failed");
    return;
  }
  int k = 0;
  std::int64_t offset = 0;
  for (auto _ : state) {
    if (k == kFrames) {  // replay the convoy: reset to a fresh tracker state time-wise
      k = 0;
      offset += static_cast<std::int64_t>(kFrames + 100) * 100'000'000;
    }
    auto& f = frames[static_cast<std::size_t>(k)];
    for (auto& d : f) {
      d.timestamp_ns = offset + k * 100'000'000LL;
    }
    auto r = tracker.step(offset + k * 100'000'000LL, f);
    benchmark::DoNotOptimize(r);
    ++k;
  }
  state.counters["tracks"] = static_cast<double>(tracker.tracks().size());
}
BENCHMARK(trackerStep)->Arg(200)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
