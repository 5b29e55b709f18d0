// vp_test_ros_telemetry_writer: stands in for a flight stack's ROS 2 bridge in the loopback
// tests. Publishes the known attitudes of telemetry_cases.hpp with the ROS 2 type and topic
// names (ArduPilot geopose, or PX4 attitude + global position), then one broken sample.
//
//   vp_test_ros_telemetry_writer ardupilot|px4 DOMAIN_ID [PERIOD_MS]
//
// Waits (up to 15 s) until a reader matches each writer, lets discovery settle, writes every
// case once PERIOD_MS apart, then a sample with an all-zero quaternion (PX4 attitude / ArduPilot
// geopose), and exits. Exit status 0, 2 on a usage error, 1 on a DDS error.
#include <dds/dds.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "config/dds_config.hpp"
#include "dds_test_support.hpp"
#include "platform/dds/dds_handles.hpp"
#include "telemetry_cases.hpp"

namespace {

namespace dds = vp::platform::dds;
using namespace std::chrono_literals;

int fail(const dds::DdsResult& result) {
  std::fprintf(stderr, "vp_test_ros_telemetry_writer: %s\n", dds::describe(result).c_str());
  return 1;
}

bool waitForReader(dds_entity_t writer) {
  for (int i = 0; i < 1500; ++i) {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(writer, &status) >= 0 && status.current_count > 0) {
      return true;
    }
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

int write(dds_entity_t writer, const void* sample) {
  if (const dds_return_t rc = dds_write(writer, sample); rc < 0) {
    std::fprintf(stderr, "vp_test_ros_telemetry_writer: dds_write: %s\n", dds_strretcode(rc));
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || (std::string(argv[1]) != "ardupilot" && std::string(argv[1]) != "px4")) {
    std::fprintf(stderr, "usage: %s ardupilot|px4 DOMAIN_ID [PERIOD_MS]\n", argv[0]);
    return 2;
  }
  const bool px4 = std::string(argv[1]) == "px4";
  const auto domainId = static_cast<std::uint32_t>(std::strtoul(argv[2], nullptr, 10));
  const int period_ms = argc > 3 ? std::atoi(argv[3]) : 20;
  vp::test::useLoopbackDds();

  const vp::config::TelemetryConfig names;  // the default ROS 2 topic names
  // A reliable writer, as ROS 2 nodes default to; the subscriber's best-effort reader matches.
  vp::config::QosProfile qos;
  qos.historyDepth = 16;
  dds::Participant participant;
  if (auto r = participant.open(domainId); !r.ok()) {
    return fail(r);
  }
  dds::Topic first;
  dds::Topic second;
  dds::Writer firstWriter;
  dds::Writer secondWriter;
  if (auto r = first.open(participant,
                          px4 ? px4_msgs_msg_dds__VehicleAttitude__desc
                              : geographic_msgs_msg_dds__GeoPoseStamped__desc,
                          px4 ? names.px4AttitudeTopic : names.ardupilotGeoPoseTopic, qos);
      !r.ok()) {
    return fail(r);
  }
  if (auto r = firstWriter.open(participant, first, qos, ""); !r.ok()) {
    return fail(r);
  }
  if (px4) {
    if (auto r = second.open(participant, px4_msgs_msg_dds__VehicleGlobalPosition__desc,
                             names.px4GlobalPositionTopic, qos);
        !r.ok()) {
      return fail(r);
    }
    if (auto r = secondWriter.open(participant, second, qos, ""); !r.ok()) {
      return fail(r);
    }
  }
  if (!waitForReader(firstWriter.get()) || (px4 && !waitForReader(secondWriter.get()))) {
    std::fprintf(stderr, "vp_test_ros_telemetry_writer: no reader matched\n");
    return 1;
  }
  // The reader may match the writer a little after the writer matched the reader.
  std::this_thread::sleep_for(500ms);

  char frameId[] = "base_link";
  int status = 0;
  for (std::size_t i = 0; i < vp::test::kAttitudeCases.size() && status == 0; ++i) {
    if (px4) {
      const auto attitude = vp::test::makePx4Attitude(i);
      const auto position = vp::test::makePx4GlobalPosition(i);
      status = write(firstWriter.get(), &attitude) + write(secondWriter.get(), &position);
    } else {
      const auto geoPose = vp::test::makeGeoPose(i, frameId);
      status = write(firstWriter.get(), &geoPose);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(period_ms));
  }
  if (px4) {
    auto broken = vp::test::makePx4Attitude(0);
    broken.q[0] = broken.q[1] = broken.q[2] = broken.q[3] = 0.0F;
    status += write(firstWriter.get(), &broken);
  } else {
    auto broken = vp::test::makeGeoPose(0, frameId);
    broken.pose.orientation = {0.0, 0.0, 0.0, 0.0};
    status += write(firstWriter.get(), &broken);
  }
  // Reliable writers: give the samples time to be acknowledged before leaving.
  (void)dds_wait_for_acks(firstWriter.get(), DDS_SECS(2));
  std::this_thread::sleep_for(200ms);
  return status == 0 ? 0 : 1;
}
