// TelemetrySubscriber on real Cyclone DDS over loopback: a writer process publishes ROS 2-typed
// ArduPilot / PX4 telemetry (vp_test_ros_telemetry_writer); our subscriber receives every
// sample, converts it to the known attitude and position, rejects the broken one, and its
// poll() allocates nothing in our code.
#include <gtest/gtest.h>
#include <pthread.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "alloc_counter.hpp"
#include "dds_test_support.hpp"
#include "platform/dds/telemetry_subscriber.hpp"
#include "telemetry_cases.hpp"

namespace vp::platform::dds {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kCases = test::kAttitudeCases.size();

// Runs the writer process and polls until `expected` samples (or 20 s); returns the ring.
struct Received {
  PoseRing<64> ring;
  TelemetryCounters counters;
  int writerStatus = -1;
};

void receive(const char* source, config::TelemetryConfig config, std::size_t expected,
             Received& out) {
  test::useLoopbackDds();
  const std::uint32_t domain = test::uniqueDdsConfig().domainId;
  Participant participant;
  ASSERT_TRUE(participant.open(domain).ok());
  TelemetrySubscriber subscriber;
  const DdsResult opened = subscriber.open(participant, config);
  ASSERT_TRUE(opened.ok()) << describe(opened);
  const std::string command =
      std::string(VP_ROS_TELEMETRY_WRITER) + " " + source + " " + std::to_string(domain) + " 20";
  FILE* writer = popen(command.c_str(), "r");
  ASSERT_NE(writer, nullptr);
  const Clock::time_point end = Clock::now() + std::chrono::seconds(20);
  std::size_t got = 0;
  while (got < expected && Clock::now() < end) {
    ASSERT_TRUE(subscriber.wait(DDS_MSECS(100)).ok());
    std::size_t delivered = 0;
    const DdsResult polled = subscriber.poll(out.ring, &delivered);
    ASSERT_TRUE(polled.ok()) << describe(polled);
    got += delivered;
  }
  out.writerStatus = pclose(writer);
  // The broken sample comes last: poll once more after the writer has left.
  std::size_t delivered = 0;
  ASSERT_TRUE(subscriber.poll(out.ring, &delivered).ok());
  out.counters = subscriber.counters();
}

// Case index of a sample from its time stamp.
std::size_t caseOf(const PoseSample& pose) {
  if (pose.source == PoseSource::ArduPilotGeoPose) {
    return static_cast<std::size_t>(pose.time_ns / 1'000'000'000 - test::kStampBase_s);
  }
  return static_cast<std::size_t>(pose.time_ns / 1000 / test::kPx4SampleBase_us - 1);
}

TEST(TelemetrySubscriber, ArduPilotGeoPoseOverLoopback) {
  config::TelemetryConfig config;
  config.source = config::TelemetrySource::ArduPilot;
  config.ardupilotAltitudeOffset_m = -33.5;
  Received received;
  receive("ardupilot", config, kCases, received);
  EXPECT_EQ(received.writerStatus, 0);
  ASSERT_EQ(received.ring.size(), kCases);
  bool seen[kCases] = {};
  PoseSample pose;
  while (received.ring.pop(&pose)) {
    const std::size_t i = caseOf(pose);
    ASSERT_LT(i, kCases);
    seen[i] = true;
    const test::AttitudeCase& c = test::kAttitudeCases[i];
    EXPECT_TRUE(pose.hasAttitude && pose.hasPosition);
    EXPECT_LT(test::angleBetween(pose.bodyToNed, test::expectedBodyToNed(c)), 1e-9) << i;
    EXPECT_EQ(pose.position.latitude_deg, c.latitude_deg);
    EXPECT_EQ(pose.position.longitude_deg, c.longitude_deg);
    EXPECT_EQ(pose.position.height_m, c.height_m - 33.5);
    EXPECT_EQ(pose.timeBase, TelemetryTimeBase::Utc);
    EXPECT_GT(pose.sourceTimestamp_ns, 0);  // the writer's DDS source timestamp
  }
  for (std::size_t i = 0; i < kCases; ++i) {
    EXPECT_TRUE(seen[i]) << "case " << i << " not received";
  }
  EXPECT_EQ(received.counters.delivered, kCases);
  EXPECT_EQ(received.counters.notUnitQuaternion, 1U);  // the broken sample
}

TEST(TelemetrySubscriber, Px4AttitudeAndGlobalPositionOverLoopback) {
  config::TelemetryConfig config;
  config.source = config::TelemetrySource::Px4;
  Received received;
  receive("px4", config, 2 * kCases, received);
  EXPECT_EQ(received.writerStatus, 0);
  ASSERT_EQ(received.ring.size(), 2 * kCases);
  int attitudes = 0;
  int positions = 0;
  PoseSample pose;
  while (received.ring.pop(&pose)) {
    const std::size_t i = caseOf(pose);
    ASSERT_LT(i, kCases);
    const test::AttitudeCase& c = test::kAttitudeCases[i];
    EXPECT_EQ(pose.timeBase, TelemetryTimeBase::AutopilotBoot);
    if (pose.source == PoseSource::Px4Attitude) {
      ++attitudes;
      EXPECT_LT(test::angleBetween(pose.bodyToNed, test::expectedBodyToNed(c)), 1e-6) << i;
    } else {
      ++positions;
      ASSERT_EQ(pose.source, PoseSource::Px4GlobalPosition);
      EXPECT_EQ(pose.position.latitude_deg, c.latitude_deg);
      EXPECT_EQ(pose.position.height_m, static_cast<double>(static_cast<float>(c.height_m)));
      EXPECT_EQ(pose.horizontalStd_m, 0.8F);
    }
  }
  EXPECT_EQ(attitudes, static_cast<int>(kCases));
  EXPECT_EQ(positions, static_cast<int>(kCases));
  EXPECT_EQ(received.counters.notUnitQuaternion, 1U);
}

TEST(TelemetrySubscriber, OpenWithoutASourceIsAnError) {
  test::useLoopbackDds();
  Participant participant;
  ASSERT_TRUE(participant.open(test::uniqueDdsConfig().domainId).ok());
  TelemetrySubscriber subscriber;
  const DdsResult result = subscriber.open(participant, config::TelemetryConfig{});
  EXPECT_FALSE(result.ok());
  EXPECT_EQ(describe(result),
            std::string("TelemetrySubscriber::open (telemetry source is none): ") +
                dds_strretcode(DDS_RETCODE_BAD_PARAMETER));
  PoseRing<4> ring;
  EXPECT_FALSE(subscriber.poll(ring).ok());
}

TEST(TelemetrySubscriber, PoseRingKeepsTheNewestSamples) {
  PoseRing<3> ring;
  for (int k = 0; k < 5; ++k) {
    PoseSample pose;
    pose.time_ns = k;
    ring.onPose(pose);
  }
  EXPECT_EQ(ring.size(), 3U);
  EXPECT_EQ(ring.overwritten(), 2U);
  PoseSample pose;
  for (int k = 2; k < 5; ++k) {
    ASSERT_TRUE(ring.pop(&pose));
    EXPECT_EQ(pose.time_ns, k);
  }
  EXPECT_FALSE(ring.pop(&pose));
}

// Steady state: a local writer keeps publishing PX4 attitude; poll() on the other side takes
// and converts with Cyclone's loans. Counted process-wide, so Cyclone's threads (receive,
// deserialise) are included: the figure is printed, and our own part is asserted zero in
// telemetry_conversion_test (ConvertingAllocatesNothing).
TEST(TelemetrySubscriber, PollAllocationsInSteadyState) {
  test::useLoopbackDds();
  const std::uint32_t domain = test::uniqueDdsConfig().domainId;
  Participant participant;
  ASSERT_TRUE(participant.open(domain).ok());
  config::TelemetryConfig config;
  config.source = config::TelemetrySource::Px4;
  TelemetrySubscriber subscriber;
  ASSERT_TRUE(subscriber.open(participant, config).ok());
  // The writer in its own participant (the topic's QoS is per participant).
  Participant writerParticipant;
  ASSERT_TRUE(writerParticipant.open(domain).ok());
  config::QosProfile qos;
  Topic topic;
  Writer writer;
  ASSERT_TRUE(topic
                  .open(writerParticipant, px4_msgs_msg_dds__VehicleAttitude__desc,
                        config.px4AttitudeTopic, qos)
                  .ok());
  ASSERT_TRUE(writer.open(writerParticipant, topic, qos, "").ok());
  PoseRing<64> ring;
  const auto sample = test::makePx4Attitude(3);
  for (int k = 0; k < 200; ++k) {  // warm-up: loans and caches are created
    ASSERT_GE(dds_write(writer.get(), &sample), 0);
    ASSERT_TRUE(subscriber.poll(ring).ok());
  }
  constexpr int kSamples = 2000;
  std::size_t pollAllocations = 0;
  std::size_t total = 0;
  for (int k = 0; k < kSamples; ++k) {
    ASSERT_GE(dds_write(writer.get(), &sample), 0);
    std::size_t delivered = 0;
    test::AllocationCounter counter;
    // Only this thread: Cyclone's receive and GC threads allocate on their own schedule.
    counter.startOnThread(static_cast<unsigned long>(pthread_self()));
    ASSERT_TRUE(subscriber.poll(ring, &delivered).ok());
    counter.stop();
    pollAllocations += counter.count();
    total += delivered;
  }
  EXPECT_GT(total, static_cast<std::size_t>(kSamples / 2));
  std::printf("allocations per poll() (take + convert + return loan, calling thread): %.3f\n",
              static_cast<double>(pollAllocations) / kSamples);
  RecordProperty("allocations_per_poll", std::to_string(pollAllocations));
  EXPECT_EQ(pollAllocations, 0U);
}

}  // namespace
}  // namespace vp::platform::dds
