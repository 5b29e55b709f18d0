// vp_test_drone_writer: stands in for the drone in the cross-process QoS tests: a
// VehicleStatePublisher with the default vehicle-state QoS writing TRACKS tracks at 10 Hz,
// as the loop does (publish() per track, then endFrame()), with the write time as measurement
// time and DDS source timestamp.
//
//   vp_test_drone_writer DOMAIN_ID PARTITION TRACKS FRAMES IDLE_S
//
// Waits (up to 15 s) until a reader matches, writes FRAMES frames 100 ms apart and prints
// `last_write_ns <UTC ns>` (the measurement time of the last frame); then stays alive without
// writing for IDLE_S seconds, prints `exit_ns <UTC ns>` and leaves (its writer is deleted:
// readers see it go). Killing it while it writes is what the tests do to a drone that
// crashes. Exit status 0, 2 on a usage error, 1 on a DDS error.
#include <dds/dds.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "dds_test_support.hpp"
#include "platform/dds/perception_publisher.hpp"

namespace {

namespace dds = vp::platform::dds;
using namespace std::chrono_literals;

int fail(const dds::DdsResult& result) {
  std::fprintf(stderr, "vp_test_drone_writer: %s\n", dds::describe(result).c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: vp_test_drone_writer DOMAIN_ID PARTITION TRACKS FRAMES IDLE_S\n");
    return 2;
  }
  vp::config::DdsConfig config;
  config.domainId = static_cast<std::uint32_t>(std::atoi(argv[1]));
  config.partition = argv[2];
  const auto tracks = static_cast<std::uint32_t>(std::atoi(argv[3]));
  const int frames = std::atoi(argv[4]);
  const double idle_s = std::atof(argv[5]);

  dds::Participant participant;
  if (const dds::DdsResult r = participant.open(config); !r.ok()) {
    return fail(r);
  }
  dds::VehicleStatePublisher publisher;
  if (const dds::DdsResult r = publisher.open(participant, config); !r.ok()) {
    return fail(r);
  }
  bool matched = false;
  for (int i = 0; i < 1500 && !matched; ++i) {
    dds_publication_matched_status_t status{};
    const dds_return_t rc = dds_get_publication_matched_status(publisher.writer(), &status);
    if (rc < 0) {
      return fail(dds::DdsResult::failure("dds_get_publication_matched_status", rc));
    }
    matched = status.current_count > 0;
    std::this_thread::sleep_for(10ms);
  }
  if (!matched) {
    std::fprintf(stderr, "vp_test_drone_writer: no reader matched within 15 s\n");
    return 1;
  }
  std::this_thread::sleep_for(300ms);  // the reader discovers the writer too
  auto next = std::chrono::steady_clock::now();
  std::int64_t last = 0;
  for (int frame = 0; frame < frames; ++frame) {
    last = dds_time();
    for (std::uint32_t id = 1; id <= tracks; ++id) {
      const dds::PublishResult r = publisher.publish(vp::test::makeState(id, last));
      if (!r.ok()) {
        std::fprintf(stderr, "vp_test_drone_writer: track %u: %s (%s)\n", id,
                     dds::toString(r.outcome), dds::describe(r.dds).c_str());
        return 1;
      }
    }
    publisher.endFrame(last);
    next += 100ms;
    std::this_thread::sleep_until(next);
  }
  std::printf("last_write_ns %lld\n", static_cast<long long>(last));
  std::fflush(stdout);
  std::this_thread::sleep_for(std::chrono::duration<double>(idle_s));
  std::printf("exit_ns %lld\n", static_cast<long long>(dds_time()));
  std::fflush(stdout);
  return 0;
}
