// The traffic topics (docs/dds.md, "Traffic"): statistics and events written by
// TrafficPublisher and read back over loopback, native and ROS 2, every field compared with the
// hand-filled report; the statistics' transient-local history for a late reader; our
// conversion allocates nothing; Cyclone's allocations per write measured; bad ids refused.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "dds_test_support.hpp"
#include "platform/dds/ros2_publisher.hpp"
#include "platform/dds/traffic_publisher.hpp"

namespace vp::platform::dds {
namespace {

using namespace std::chrono_literals;
using traffic::TrafficEvent;
using traffic::TrafficEventKind;
using traffic::TrafficStatistics;

const std::vector<std::string> kGates{"north-in", "south-out", "east"};
const std::vector<std::string> kZones{"box-1"};
const std::vector<std::string> kLanes{"lane-a", "lane-b"};
const geodesy::LocalFrame kWorld{geodesy::GeodeticPoint{48.1, 11.5, 520.0}};

TrafficFeatureIdViews ids() {
  return TrafficFeatureIdViews{kGates, kZones, kLanes};
}

TrafficStatistics makeStatistics(std::uint64_t period) {
  TrafficStatistics s;
  s.sequence = period;
  s.start_ns = static_cast<std::int64_t>(period) * 60'000'000'000;
  s.end_ns = s.start_ns + 60'000'000'000;
  s.gateCount = 3;
  for (std::uint32_t g = 0; g < 3; ++g) {
    s.gates[g].gateIndex = g;
    for (std::size_t t = 0; t < traffic::kReportTypeCount; ++t) {
      s.gates[g].byDirectionAndType[0][t] = g * 10 + static_cast<std::uint32_t>(t);
      s.gates[g].byDirectionAndType[1][t] = g * 20 + static_cast<std::uint32_t>(t) + 100;
    }
  }
  s.movements[0][2] = 3;
  s.movements[2][1] = static_cast<std::uint32_t>(period + 1);
  s.zoneCount = 1;
  s.zones[0] = {0, 2, 1.25, 4, 1, 3, 6.5, 17.25, 5, 12.5, 40.125};
  s.laneCount = 2;
  s.lanes[0] = {0, 9, 11.5, 13.875, 15.0};
  s.lanes[1] = {1, 1, 2.0, 2.5, 3.0};
  s.wrongWayEvents = 2;
  s.boxJunctionStops = 1;
  return s;
}

TrafficEvent makeEvent(TrafficEventKind kind, std::uint32_t feature) {
  TrafficEvent e;
  e.kind = kind;
  e.time_ns = 123'456'789'000;
  e.trackId = 42;
  e.featureIndex = feature;
  e.toFeatureIndex = kind == TrafficEventKind::TurningMovement ? 1 : 0;
  e.direction = kind == TrafficEventKind::GateCrossing ? 1 : 0;
  e.type = shape::VehicleType::Van;
  e.speed_mps = 7.5;
  e.positionEnu_m = {12.5, -30.25};
  return e;
}

// Every field of a statistics sample (native or ROS: the same member names) against the report.
template <typename Sample>
void expectStatistics(const Sample& got, const TrafficStatistics& want) {
  EXPECT_EQ(got.drone_id, 7U);
  EXPECT_EQ(got.period, want.sequence);
  EXPECT_EQ(got.start_ns, want.start_ns);
  EXPECT_EQ(got.end_ns, want.end_ns);
  ASSERT_EQ(got.gates._length, 3U);
  for (std::size_t g = 0; g < 3; ++g) {
    EXPECT_STREQ(got.gates._buffer[g].gate_id, kGates[g].c_str());
    for (std::size_t t = 0; t < traffic::kReportTypeCount; ++t) {
      EXPECT_EQ(got.gates._buffer[g].forward[t], want.gates[g].byDirectionAndType[0][t]);
      EXPECT_EQ(got.gates._buffer[g].backward[t], want.gates[g].byDirectionAndType[1][t]);
    }
  }
  ASSERT_EQ(got.movements._length, 2U);
  EXPECT_STREQ(got.movements._buffer[0].from_gate_id, "north-in");
  EXPECT_STREQ(got.movements._buffer[0].to_gate_id, "east");
  EXPECT_EQ(got.movements._buffer[0].count, 3U);
  EXPECT_STREQ(got.movements._buffer[1].from_gate_id, "east");
  EXPECT_STREQ(got.movements._buffer[1].to_gate_id, "south-out");
  EXPECT_EQ(got.movements._buffer[1].count, want.movements[2][1]);
  ASSERT_EQ(got.zones._length, 1U);
  const auto& zone = got.zones._buffer[0];
  EXPECT_STREQ(zone.zone_id, "box-1");
  EXPECT_EQ(zone.vehicles_now, 2U);
  EXPECT_EQ(zone.mean_vehicles, 1.25);
  EXPECT_EQ(zone.max_vehicles, 4U);
  EXPECT_EQ(zone.queue_now_vehicles, 1U);
  EXPECT_EQ(zone.max_queue_vehicles, 3U);
  EXPECT_EQ(zone.queue_now_m, 6.5);
  EXPECT_EQ(zone.max_queue_m, 17.25);
  EXPECT_EQ(zone.dwell_count, 5U);
  EXPECT_EQ(zone.mean_dwell_s, 12.5);
  EXPECT_EQ(zone.max_dwell_s, 40.125);
  ASSERT_EQ(got.lanes._length, 2U);
  EXPECT_STREQ(got.lanes._buffer[1].lane_id, "lane-b");
  EXPECT_EQ(got.lanes._buffer[0].vehicles, 9U);
  EXPECT_EQ(got.lanes._buffer[0].mean_speed_mps, 11.5);
  EXPECT_EQ(got.lanes._buffer[0].p85_speed_mps, 13.875);
  EXPECT_EQ(got.lanes._buffer[0].max_speed_mps, 15.0);
  EXPECT_EQ(got.wrong_way_events, 2U);
  EXPECT_EQ(got.box_junction_stops, 1U);
}

// Takes up to `count` samples of type T (copied: strings are inline, sequences copied out).
template <typename T, typename OnSample>
int takeAll(dds_entity_t reader, int count, std::chrono::milliseconds timeout, OnSample&& on) {
  int taken = 0;
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (taken < count && std::chrono::steady_clock::now() < end) {
    void* samples[16] = {nullptr};
    dds_sample_info_t infos[16];
    const dds_return_t n = dds_take(reader, samples, infos, 16, 16);
    for (int k = 0; k < n; ++k) {
      if (infos[k].valid_data) {
        on(*static_cast<const T*>(samples[k]));
        ++taken;
      }
    }
    if (n > 0) {
      dds_return_loan(reader, samples, n);
    } else {
      std::this_thread::sleep_for(5ms);
    }
  }
  return taken;
}

class TrafficPublisherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    test::useLoopbackDds();
    config_ = test::uniqueDdsConfig();
    config_.droneId = 7;
    config_.ros2.topicNamespace = config_.partition;  // ROS topics have no partition
    ASSERT_TRUE(participant_.open(config_).ok());
  }
  void openReaders() {
    ASSERT_TRUE(statsTopic_
                    .open(participant_, vp_msg_TrafficStatistics_desc,
                          trafficStatisticsTopicName(config_), config_.trafficStatistics)
                    .ok());
    ASSERT_TRUE(
        statsReader_.open(participant_, statsTopic_, config_.trafficStatistics, config_.partition)
            .ok());
    ASSERT_TRUE(eventsTopic_
                    .open(participant_, vp_msg_TrafficEvent_desc, trafficEventsTopicName(config_),
                          config_.trafficEvents)
                    .ok());
    ASSERT_TRUE(
        eventsReader_.open(participant_, eventsTopic_, config_.trafficEvents, config_.partition)
            .ok());
    ASSERT_TRUE(rosStatsTopic_
                    .open(participant_, vp_msgs_msg_dds__TrafficStatistics__desc,
                          ros2TopicName(config_.ros2, "traffic_statistics"),
                          config_.trafficStatistics)
                    .ok());
    ASSERT_TRUE(
        rosStatsReader_.open(participant_, rosStatsTopic_, config_.trafficStatistics, "").ok());
    ASSERT_TRUE(rosEventsTopic_
                    .open(participant_, vp_msgs_msg_dds__TrafficEvent__desc,
                          ros2TopicName(config_.ros2, "traffic_events"), config_.trafficEvents)
                    .ok());
    ASSERT_TRUE(
        rosEventsReader_.open(participant_, rosEventsTopic_, config_.trafficEvents, "").ok());
  }

  config::DdsConfig config_;
  Participant participant_;
  TrafficPublisher publisher_;
  Topic statsTopic_, eventsTopic_, rosStatsTopic_, rosEventsTopic_;
  Reader statsReader_, eventsReader_, rosStatsReader_, rosEventsReader_;
};

TEST_F(TrafficPublisherTest, StatisticsAndEventsArriveWithEveryField) {
  std::string why;
  ASSERT_TRUE(publisher_.open(participant_, config_, ids(), kWorld, &why).ok()) << why;
  openReaders();
  for (const dds_entity_t writer :
       {publisher_.statisticsWriter(), publisher_.eventsWriter(), publisher_.rosStatisticsWriter(),
        publisher_.rosEventsWriter()}) {
    ASSERT_TRUE(test::waitForMatch(writer, 1, 5000ms));
  }
  const TrafficStatistics statistics = makeStatistics(3);
  const std::int64_t stamp_ns = 1'700'000'000'500'000'000;
  ASSERT_TRUE(publisher_.writeStatistics(statistics, stamp_ns).ok());
  const std::vector<TrafficEvent> events{makeEvent(TrafficEventKind::GateCrossing, 2),
                                         makeEvent(TrafficEventKind::WrongWay, 1),
                                         makeEvent(TrafficEventKind::BoxJunctionStop, 0),
                                         makeEvent(TrafficEventKind::TurningMovement, 0)};
  for (const TrafficEvent& e : events) {
    ASSERT_TRUE(publisher_.writeEvent(e, stamp_ns).ok());
  }

  EXPECT_EQ(takeAll<vp_msg_TrafficStatistics>(
                statsReader_.get(), 1, 5000ms,
                [&](const vp_msg_TrafficStatistics& got) { expectStatistics(got, statistics); }),
            1);
  EXPECT_EQ(takeAll<vp_msgs_msg_dds__TrafficStatistics_>(
                rosStatsReader_.get(), 1, 5000ms,
                [&](const vp_msgs_msg_dds__TrafficStatistics_& got) {
                  expectStatistics(got, statistics);
                  EXPECT_EQ(got.header.stamp.sec, 1'700'000'000);
                  EXPECT_EQ(got.header.stamp.nanosec, 500'000'000U);
                  EXPECT_STREQ(got.header.frame_id, "map");
                }),
            1);

  const geodesy::GeodeticPoint where = kWorld.toGeodetic(Eigen::Vector3d(12.5, -30.25, 0.0));
  const std::vector<std::pair<const char*, const char*>> names{
      {"east", ""}, {"lane-b", ""}, {"box-1", ""}, {"north-in", "south-out"}};
  std::size_t k = 0;
  EXPECT_EQ(takeAll<vp_msg_TrafficEvent>(
                eventsReader_.get(), 4, 5000ms,
                [&](const vp_msg_TrafficEvent& got) {
                  ASSERT_LT(k, events.size());
                  const TrafficEvent& want = events[k];
                  EXPECT_EQ(got.drone_id, 7U);
                  EXPECT_EQ(got.time_ns, want.time_ns);
                  EXPECT_EQ(static_cast<int>(got.kind), static_cast<int>(want.kind));
                  EXPECT_EQ(got.track_id, 42U);
                  EXPECT_STREQ(got.feature_id, names[k].first);
                  EXPECT_STREQ(got.to_feature_id, names[k].second);
                  EXPECT_EQ(got.direction, want.direction);
                  EXPECT_EQ(got.type, vp_msg_TYPE_VAN);
                  EXPECT_EQ(got.speed_mps, 7.5F);
                  EXPECT_EQ(got.enu_m[0], 12.5);
                  EXPECT_EQ(got.enu_m[1], -30.25);
                  EXPECT_EQ(got.position.latitude_deg, where.latitude_deg);
                  EXPECT_EQ(got.position.longitude_deg, where.longitude_deg);
                  ++k;
                }),
            4);
  k = 0;
  EXPECT_EQ(takeAll<vp_msgs_msg_dds__TrafficEvent_>(
                rosEventsReader_.get(), 4, 5000ms,
                [&](const vp_msgs_msg_dds__TrafficEvent_& got) {
                  ASSERT_LT(k, events.size());
                  const TrafficEvent& want = events[k];
                  EXPECT_EQ(got.header.stamp.sec, 1'700'000'000);
                  EXPECT_EQ(got.drone_id, 7U);
                  EXPECT_EQ(got.time_ns, want.time_ns);
                  EXPECT_EQ(got.kind, static_cast<std::uint8_t>(want.kind));
                  EXPECT_EQ(got.track_id, 42U);
                  EXPECT_STREQ(got.feature_id, names[k].first);
                  EXPECT_STREQ(got.to_feature_id, names[k].second);
                  EXPECT_EQ(got.direction, want.direction);
                  EXPECT_EQ(got.type, vp_msgs_msg_dds__VehicleState_Constants_TYPE_VAN);
                  EXPECT_EQ(got.speed_mps, 7.5F);
                  EXPECT_EQ(got.east_m, 12.5);
                  EXPECT_EQ(got.north_m, -30.25);
                  EXPECT_EQ(got.position.latitude_deg, where.latitude_deg);
                  EXPECT_EQ(got.position.longitude_deg, where.longitude_deg);
                  ++k;
                }),
            4);
}

TEST_F(TrafficPublisherTest, ALateReaderGetsTheLastFourPeriods) {
  std::string why;
  ASSERT_TRUE(publisher_.open(participant_, config_, ids(), kWorld, &why).ok()) << why;
  for (std::uint64_t period = 0; period < 6; ++period) {
    ASSERT_TRUE(publisher_.writeStatistics(makeStatistics(period), 1'000 + period).ok());
  }
  openReaders();
  std::vector<std::uint64_t> periods;
  takeAll<vp_msg_TrafficStatistics>(
      statsReader_.get(), 4, 5000ms,
      [&](const vp_msg_TrafficStatistics& got) { periods.push_back(got.period); });
  EXPECT_EQ(periods, (std::vector<std::uint64_t>{2, 3, 4, 5}));
}

TEST_F(TrafficPublisherTest, RefusesUnknownFeaturesAndLongIds) {
  std::string why;
  const std::vector<std::string> longGate{std::string(65, 'g')};
  TrafficPublisher tooLong;
  EXPECT_FALSE(
      tooLong.open(participant_, config_, TrafficFeatureIdViews{longGate, {}, {}}, kWorld, &why)
          .ok());
  EXPECT_NE(why.find("gate id 'ggg"), std::string::npos) << why;
  EXPECT_NE(why.find("longer than 64 bytes"), std::string::npos) << why;

  ASSERT_TRUE(publisher_.open(participant_, config_, ids(), kWorld, &why).ok()) << why;
  EXPECT_EQ(publisher_.writeEvent(makeEvent(TrafficEventKind::WrongWay, 2), 1).rc,
            DDS_RETCODE_BAD_PARAMETER);  // two lanes
  TrafficStatistics s = makeStatistics(0);
  s.zoneCount = 2;  // one zone
  EXPECT_EQ(publisher_.writeStatistics(s, 1).rc, DDS_RETCODE_BAD_PARAMETER);
  TrafficPublisher closed;
  EXPECT_FALSE(closed.writeStatistics(makeStatistics(0), 1).ok());
}

// Our part of a write (conversion into the preallocated samples), in a process with no DDS
// entity at the time, so that no Cyclone thread allocates meanwhile.
TEST(TrafficConversion, OurWritePathDoesNotAllocate) {
  TrafficSampleIds sampleIds;
  std::string why;
  ASSERT_TRUE(makeSampleIds(ids(), &sampleIds, &why)) << why;
  auto native = std::make_unique<NativeStatisticsStorage>();
  auto ros = std::make_unique<RosStatisticsStorage>();
  vp_msg_TrafficStatistics statistics{};
  vp_msgs_msg_dds__TrafficStatistics_ rosStatistics{};
  vp_msg_TrafficEvent event{};
  vp_msgs_msg_dds__TrafficEvent_ rosEvent{};
  const TrafficStatistics report = makeStatistics(1);
  const TrafficEvent crossing = makeEvent(TrafficEventKind::TurningMovement, 2);
  test::AllocationCounter counter;
  bool ok = true;
  for (int i = 0; i < 100; ++i) {
    ok = toSample(report, sampleIds, 7, *native, statistics) && ok;
    ok = toRosSample(report, sampleIds, 7, 5, *ros, rosStatistics) && ok;
    const geodesy::GeodeticPoint where =
        kWorld.toGeodetic(Eigen::Vector3d(crossing.positionEnu_m.x(), 0.0, 0.0));
    ok = toSample(crossing, sampleIds, 7, where, event) && ok;
    ok = toRosSample(crossing, sampleIds, 7, 5, where, rosEvent) && ok;
  }
  counter.stop();
  EXPECT_TRUE(ok);
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(statistics.movements._length, 2U);
  EXPECT_STREQ(rosEvent.to_feature_id, "south-out");
}

// The whole write path including Cyclone's, with a matched reader in this process: reported
// (Cyclone allocates per sample, as for the vehicle states; docs/dds.md).
TEST_F(TrafficPublisherTest, AllocationsPerWriteMeasured) {
  std::string why;
  ASSERT_TRUE(publisher_.open(participant_, config_, ids(), kWorld, &why).ok()) << why;
  openReaders();
  ASSERT_TRUE(test::waitForMatch(publisher_.eventsWriter(), 1, 5000ms));
  ASSERT_TRUE(test::waitForMatch(publisher_.rosEventsWriter(), 1, 5000ms));
  const TrafficEvent event = makeEvent(TrafficEventKind::GateCrossing, 0);
  const TrafficStatistics statistics = makeStatistics(0);
  ASSERT_TRUE(publisher_.writeEvent(event, 1).ok());  // warm-up
  ASSERT_TRUE(publisher_.writeStatistics(statistics, 1).ok());
  constexpr int kWrites = 100;
  test::AllocationCounter counter;
  for (int i = 0; i < kWrites; ++i) {
    publisher_.writeEvent(event, 2 + i);
  }
  counter.stop();
  const double perEvent = static_cast<double>(counter.count()) / kWrites;
  test::AllocationCounter statisticsCounter;
  for (int i = 0; i < 10; ++i) {
    publisher_.writeStatistics(statistics, 2 + i);
  }
  statisticsCounter.stop();
  const double perPeriod = static_cast<double>(statisticsCounter.count()) / 10.0;
  std::printf(
      "allocations per traffic write (native + ROS 2, whole path incl. Cyclone, in-process "
      "reader): event %.2f, statistics %.2f\n",
      perEvent, perPeriod);
  RecordProperty("allocations_per_traffic_event", std::to_string(perEvent));
  RecordProperty("allocations_per_traffic_statistics", std::to_string(perPeriod));
  EXPECT_GT(takeAll<vp_msg_TrafficEvent>(eventsReader_.get(), kWrites + 1, 5000ms,
                                         [](const vp_msg_TrafficEvent&) {}),
            0);
}

}  // namespace
}  // namespace vp::platform::dds
