// vp_bench_dds: the drone's vehicle-state load on DDS, written as the app writes it: every
// frame, one VehicleState per vehicle (VehicleStatePublisher::publish), then endFrame(), with
// the frame time as DDS source timestamp. Run by scripts/bench_dds.sh, which starts the
// roadside-unit subscribers (vp_rsu_subscriber: received samples and latency from the source
// timestamp) and ddsperf for comparison.
//
//   vp_bench_dds --domain D --partition P [--vehicles 200] [--rate-hz 10] [--duration-s 20]
//                [--readers 4]
//
// Waits (up to 30 s) for --readers matched readers, publishes for --duration-s, then prints
// one line per figure: samples written, write time per frame (median, p99, max), and heap
// allocations per written sample (process-wide, as tests/platform/dds measures them).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "config/dds_config.hpp"
#include "platform/dds/perception_publisher.hpp"

namespace {

namespace dds = vp::platform::dds;
using Clock = std::chrono::steady_clock;

struct Options {
  std::uint32_t domainId = 0;
  std::string partition = "vp_bench";
  std::uint32_t vehicles = 200;
  double rate_hz = 10.0;
  double duration_s = 20.0;
  std::uint32_t readers = 4;
};

[[noreturn]] void usage(const std::string& problem) {
  std::fprintf(stderr,
               "vp_bench_dds: %s\nusage: vp_bench_dds --domain D --partition P [--vehicles N] "
               "[--rate-hz R] [--duration-s S] [--readers N]\n",
               problem.c_str());
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    const char* value = argv[i + 1];
    if (key == "--domain") {
      o.domainId = static_cast<std::uint32_t>(std::strtoul(value, nullptr, 10));
    } else if (key == "--partition") {
      o.partition = value;
    } else if (key == "--vehicles") {
      o.vehicles = static_cast<std::uint32_t>(std::strtoul(value, nullptr, 10));
    } else if (key == "--rate-hz") {
      o.rate_hz = std::strtod(value, nullptr);
    } else if (key == "--duration-s") {
      o.duration_s = std::strtod(value, nullptr);
    } else if (key == "--readers") {
      o.readers = static_cast<std::uint32_t>(std::strtoul(value, nullptr, 10));
    } else {
      usage("unknown option '" + key + "'");
    }
  }
  if (o.vehicles == 0 || o.vehicles > dds::VehicleStatePublisher::kMaxTracks || o.rate_hz <= 0 ||
      o.duration_s <= 0) {
    usage("--vehicles must be in [1, 1024], --rate-hz and --duration-s > 0");
  }
  return o;
}

// A plausible moving vehicle: every field set, positions spread over the scene.
vp::messages::VehicleState vehicle(std::uint32_t id, std::int64_t time_ns, double t_s) {
  vp::messages::VehicleState s;
  s.droneId = 1;
  s.trackId = id;
  s.measurementTime_ns = time_ns;
  s.trackAge_s = static_cast<float>(t_s);
  const double east = -50.0 + 0.5 * (id % 200) + 10.0 * t_s;
  const double north = -50.0 + 0.5 * (id / 2);
  s.position = {43.0731 + north * 9e-6, -89.4012 + east * 1.2e-5, 260.0};
  s.enu_m = {east, north, 0.0};
  s.headingEnu_rad = 0.0;
  s.headingTrueNorth_deg = 90.0;
  s.speed_mps = 10.0F;
  s.velocityEnu_mps = {10.0F, 0.0F};
  s.length_m = 4.6F;
  s.width_m = 1.8F;
  s.height_m = 1.5F;
  s.typeProbability = {0.1F, 0.1F, 0.1F, 0.4F, 0.1F, 0.1F, 0.1F};
  s.shape.count = 3;
  s.poseCovariance = {0.04F, 0.0F, 0.0F, 0.04F, 0.0F, 0.002F};
  s.detectionConfidence = 0.9F;
  s.status = vp::messages::TrackStatus::Confirmed;
  return s;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) {
    return 0.0;
  }
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5);
  return values[index];
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse(argc, argv);
  vp::config::DdsConfig config;
  config.domainId = options.domainId;
  config.partition = options.partition;
  dds::Participant participant;
  dds::VehicleStatePublisher publisher;
  if (auto r = participant.open(config); !r.ok()) {
    std::fprintf(stderr, "vp_bench_dds: %s\n", dds::describe(r).c_str());
    return 1;
  }
  if (auto r = publisher.open(participant, config); !r.ok()) {
    std::fprintf(stderr, "vp_bench_dds: %s\n", dds::describe(r).c_str());
    return 1;
  }
  const Clock::time_point waitEnd = Clock::now() + std::chrono::seconds(30);
  dds_publication_matched_status_t matched{};
  while (Clock::now() < waitEnd) {
    if (dds_get_publication_matched_status(publisher.writer(), &matched) >= 0 &&
        matched.current_count >= options.readers) {
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (matched.current_count < options.readers) {
    std::fprintf(stderr, "vp_bench_dds: only %u of %u readers matched\n", matched.current_count,
                 options.readers);
    return 1;
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));  // readers match the writer too

  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / options.rate_hz));
  const auto frames = static_cast<int>(options.duration_s * options.rate_hz);
  const int warmup = std::max(1, frames / 20);
  std::vector<vp::messages::VehicleState> states(options.vehicles);
  std::vector<double> frameWrite_ms;
  frameWrite_ms.reserve(static_cast<std::size_t>(frames));
  std::uint64_t written = 0;
  std::uint64_t errors = 0;
  std::size_t allocations = 0;
  std::uint64_t countedSamples = 0;
  const Clock::time_point start = Clock::now();
  for (int frame = 0; frame < frames; ++frame) {
    std::this_thread::sleep_until(start + frame * period);
    const std::int64_t now = dds_time();
    const double t_s = frame / options.rate_hz;
    for (std::uint32_t id = 0; id < options.vehicles; ++id) {
      states[id] = vehicle(id + 1, now, t_s);
    }
    vp::test::AllocationCounter counter;
    if (frame < warmup) {
      counter.stop();
    }
    const Clock::time_point t0 = Clock::now();
    for (const auto& s : states) {
      if (publisher.publish(s).ok()) {
        ++written;
      } else {
        ++errors;
      }
    }
    errors += publisher.endFrame(now).errors;
    const Clock::time_point t1 = Clock::now();
    counter.stop();
    if (frame >= warmup) {
      allocations += counter.count();
      countedSamples += options.vehicles;
    }
    frameWrite_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "vp_bench_dds: %u vehicles x %d frames at %.1f Hz in %.1f s: %llu samples written, "
      "%llu errors, %u readers\n",
      options.vehicles, frames, options.rate_hz, elapsed_s,
      static_cast<unsigned long long>(written), static_cast<unsigned long long>(errors),
      matched.current_count);
  std::printf(
      "vp_bench_dds: write time per frame (%u samples): median %.3f ms, p99 %.3f ms, max "
      "%.3f ms\n",
      options.vehicles, percentile(frameWrite_ms, 0.5), percentile(frameWrite_ms, 0.99),
      percentile(frameWrite_ms, 1.0));
  std::printf(
      "vp_bench_dds: heap allocations per written sample (steady state, process-wide): "
      "%.3f\n",
      countedSamples ? static_cast<double>(allocations) / countedSamples : 0.0);
  // Leave time for the readers' last acknowledgements before the writer disappears.
  (void)dds_wait_for_acks(publisher.writer(), DDS_SECS(5));
  return errors == 0 ? 0 : 1;
}
