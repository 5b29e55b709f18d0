// tests/firmware_app/app_traffic_test: the traffic analysis in the loop. The simulated
// intersection (its site.geojson has gates, lanes and zones) replayed with the truth vehicles:
// the periods' statistics and the events arrive over DDS (native topics, read in this process)
// and are written to the traffic files, and the two agree row for row; the gate counts agree
// with the gate_crossing events; the counters of the summary line say the same. Without a site
// (or with traffic.enabled false) nothing of it runs.
#include <dds/dds.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "app.hpp"
#include "app_test_support.hpp"
#include "dds_test_support.hpp"
#include "output_files/traffic_files.hpp"
#include "platform/dds/dds_handles.hpp"
#include "platform/dds/traffic_publisher.hpp"

namespace vp::app {
namespace {

using namespace std::chrono_literals;
using output_files::TrafficFile;

// Every valid sample of a reader, copied out with `copy`.
template <typename T, typename Copy>
void takeAll(dds_entity_t reader, Copy&& copy) {
  for (;;) {
    void* samples[16] = {nullptr};
    dds_sample_info_t infos[16];
    const dds_return_t n = dds_take(reader, samples, infos, 16, 16);
    if (n <= 0) {
      return;
    }
    for (int k = 0; k < n; ++k) {
      if (infos[k].valid_data) {
        copy(*static_cast<const T*>(samples[k]));
      }
    }
    dds_return_loan(reader, samples, n);
  }
}

std::vector<std::vector<std::string>> readRows(const std::string& dir, TrafficFile file) {
  output_files::TrafficFileRows rows;
  std::string why;
  EXPECT_TRUE(
      output_files::readTrafficFile(dir + "/" + output_files::fileName(file), file, &rows, &why))
      << why;
  return rows.rows;
}

// 8 s of the simulated intersection (small frames: the truth is what counts here) in which at
// least three vehicles cross the gates. Seed 7 has them on x86-64; the simulator draws other
// scenes from a seed on CPUs whose math rounds differently (docs/simulator.md "Determinism":
// aarch64), so the next seeds are taken, each probed by a quick run without DDS, until one does.
std::string trafficSequence() {
  for (const int seed : {7, 8, 9, 10, 11, 12}) {
    const std::string dir =
        test::simulatedSequence("traffic_" + std::to_string(seed), 80, test::kLoopWidth_px,
                                test::kLoopHeight_px, static_cast<std::uint64_t>(seed));
    if (dir.empty())
      return dir;
    config::AppConfig config = test::defaultConfigFor(dir);
    config.dds.enabled = false;
    config.source.paced = false;
    config.app.statsPeriod_s = 3600.0;
    config.app.trafficDir = test::scratchDir("traffic_probe_" + std::to_string(seed));
    App app;
    AppSeams seams;
    auto truth = std::make_unique<test::TruthPerception>();
    std::string why;
    if (!truth->init(dir, &why))
      return {};
    seams.perception = std::move(truth);
    if (!app.init(config, test::everyFrame(), std::move(seams), &why) || !app.run(&why))
      return {};
    if (app.counters().gateCrossings >= 3U)
      return dir;
  }
  return {};
}

TEST(AppTraffic, StatisticsAndEventsOverDdsAgreeWithTheTrafficFiles) {
  test::useLoopbackDds();
  const std::string dir = trafficSequence();
  ASSERT_FALSE(dir.empty());
  const std::string out = test::scratchDir("traffic");
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds = test::uniqueDdsConfig();
  config.dds.droneId = 5;
  config.dds.ros2.enabled = false;
  config.app.statsPeriod_s = 3600.0;
  config.app.trafficDir = out;
  config.source.paced = false;
  config.traffic.period_s = 2.0;  // 80 frames at 10 Hz: three periods in the run, one at its end

  platform::dds::Participant participant;
  ASSERT_TRUE(participant.open(config.dds).ok());
  platform::dds::Topic statisticsTopic;
  platform::dds::Topic eventsTopic;
  platform::dds::Reader statisticsReader;
  platform::dds::Reader eventsReader;
  ASSERT_TRUE(statisticsTopic
                  .open(participant, vp_msg_TrafficStatistics_desc,
                        platform::dds::trafficStatisticsTopicName(config.dds),
                        config.dds.trafficStatistics)
                  .ok());
  ASSERT_TRUE(eventsTopic
                  .open(participant, vp_msg_TrafficEvent_desc,
                        platform::dds::trafficEventsTopicName(config.dds), config.dds.trafficEvents)
                  .ok());
  // Deep enough for every period and event of the run.
  config::QosProfile statisticsQos = config.dds.trafficStatistics;
  statisticsQos.historyDepth = 100;
  config::QosProfile eventsQos = config.dds.trafficEvents;
  eventsQos.historyDepth = 1000;
  ASSERT_TRUE(
      statisticsReader.open(participant, statisticsTopic, statisticsQos, config.dds.partition)
          .ok());
  ASSERT_TRUE(eventsReader.open(participant, eventsTopic, eventsQos, config.dds.partition).ok());

  LoopCounters counters;
  std::string summary;
  {
    App app;
    AppSeams seams;
    auto truth = std::make_unique<test::TruthPerception>();
    std::string why;
    ASSERT_TRUE(truth->init(dir, &why)) << why;
    seams.perception = std::move(truth);
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_NE(app.trafficEventsWriter(), 0);
    ASSERT_TRUE(test::waitForMatch(app.trafficEventsWriter(), 1, 10000ms));
    ASSERT_TRUE(test::waitForMatch(app.trafficStatisticsWriter(), 1, 10000ms));
    ASSERT_TRUE(app.run(&why)) << why;
    EXPECT_EQ(dds_wait_for_acks(app.trafficEventsWriter(), DDS_SECS(5)), DDS_RETCODE_OK);
    EXPECT_EQ(dds_wait_for_acks(app.trafficStatisticsWriter(), DDS_SECS(5)), DDS_RETCODE_OK);
    counters = app.counters();
    summary = app.summaryLine();
  }
  std::printf(
      "traffic on the simulated intersection: %llu periods, %llu events, %llu gate crossings\n",
      static_cast<unsigned long long>(counters.trafficPeriods),
      static_cast<unsigned long long>(counters.trafficEvents),
      static_cast<unsigned long long>(counters.gateCrossings));
  EXPECT_TRUE(counters.traffic);
  EXPECT_EQ(counters.trafficErrors, 0U);
  EXPECT_EQ(counters.outputErrors, 0U);
  EXPECT_GE(counters.trafficPeriods, 4U);
  EXPECT_GE(counters.gateCrossings, 3U) << "vehicles cross the intersection's gates";
  EXPECT_NE(summary.find(" gate_crossings=" + std::to_string(counters.gateCrossings) + " "),
            std::string::npos)
      << summary;

  // Statistics: per (period, gate, direction, type) from DDS and from traffic_counts.csv.
  using CountKey = std::tuple<std::uint64_t, std::string, std::string, std::string>;
  static const char* const kTypes[] = {"estate", "compact", "sports", "sedan",
                                       "suv",    "van",     "large"};
  std::map<CountKey, std::uint64_t> ddsCounts;
  std::map<std::tuple<std::uint64_t, std::string, std::string>, std::uint64_t> ddsMovements;
  std::vector<std::uint64_t> periods;
  std::uint64_t countedCrossings = 0;
  takeAll<vp_msg_TrafficStatistics>(statisticsReader.get(), [&](const vp_msg_TrafficStatistics& s) {
    EXPECT_EQ(s.drone_id, 5U);
    EXPECT_LT(s.start_ns, s.end_ns);
    periods.push_back(s.period);
    for (std::uint32_t g = 0; g < s.gates._length; ++g) {
      const vp_msg_TrafficGateCount& gate = s.gates._buffer[g];
      for (std::size_t t = 0; t < 7; ++t) {
        if (gate.forward[t] > 0) {
          ddsCounts[{s.period, gate.gate_id, "forward", kTypes[t]}] = gate.forward[t];
        }
        if (gate.backward[t] > 0) {
          ddsCounts[{s.period, gate.gate_id, "backward", kTypes[t]}] = gate.backward[t];
        }
        countedCrossings += gate.forward[t] + gate.backward[t];
      }
    }
    for (std::uint32_t m = 0; m < s.movements._length; ++m) {
      ddsMovements[{s.period, s.movements._buffer[m].from_gate_id,
                    s.movements._buffer[m].to_gate_id}] = s.movements._buffer[m].count;
    }
  });
  ASSERT_EQ(periods.size(), counters.trafficPeriods);
  for (std::size_t p = 0; p < periods.size(); ++p) {
    EXPECT_EQ(periods[p], p) << "periods in order, none missing";
  }
  std::map<CountKey, std::uint64_t> fileCounts;
  for (const std::vector<std::string>& row : readRows(out, TrafficFile::Counts)) {
    fileCounts[{std::stoull(row[0]), row[3], row[4], row[5]}] = std::stoull(row[6]);
  }
  EXPECT_EQ(fileCounts, ddsCounts);
  EXPECT_FALSE(fileCounts.empty());
  std::map<std::tuple<std::uint64_t, std::string, std::string>, std::uint64_t> fileMovements;
  for (const std::vector<std::string>& row : readRows(out, TrafficFile::Movements)) {
    fileMovements[{std::stoull(row[0]), row[3], row[4]}] = std::stoull(row[5]);
  }
  EXPECT_EQ(fileMovements, ddsMovements);
  // One zone row and one lane row per zone / lane per period.
  const std::vector<std::vector<std::string>> zones = readRows(out, TrafficFile::Zones);
  const std::vector<std::vector<std::string>> lanes = readRows(out, TrafficFile::Lanes);
  EXPECT_EQ(zones.size() % periods.size(), 0U);
  EXPECT_EQ(lanes.size() % periods.size(), 0U);
  EXPECT_GT(lanes.size(), 0U) << "the simulated intersection has lanes";

  // Events: the same rows over DDS and in traffic_events.csv, in order.
  std::vector<std::vector<std::string>> ddsEvents;
  std::uint64_t crossingEvents = 0;
  takeAll<vp_msg_TrafficEvent>(eventsReader.get(), [&](const vp_msg_TrafficEvent& e) {
    static const char* const kKinds[] = {"gate_crossing", "wrong_way", "box_junction_stop",
                                         "turning_movement"};
    ddsEvents.push_back({std::to_string(e.time_ns), kKinds[e.kind], std::to_string(e.track_id),
                         e.feature_id, e.to_feature_id});
    crossingEvents += e.kind == vp_msg_EVENT_GATE_CROSSING ? 1 : 0;
  });
  std::vector<std::vector<std::string>> fileEvents;
  for (const std::vector<std::string>& row : readRows(out, TrafficFile::Events)) {
    fileEvents.push_back({row[0], row[1], row[2], row[3], row[4]});
  }
  EXPECT_EQ(fileEvents, ddsEvents);
  EXPECT_EQ(ddsEvents.size(), counters.trafficEvents);
  // Every crossing is an event and is counted in its period's statistics.
  EXPECT_EQ(crossingEvents, counters.gateCrossings);
  EXPECT_EQ(countedCrossings, crossingEvents);
}

// The roadside unit: vp_rsu_subscriber with the sequence's site prints each period's gate
// counts and the totals, which add up to the app's crossings, and draws its bird's-eye view.
TEST(AppTraffic, TheSubscriberPrintsEachPeriodsCountsAndDrawsTheSite) {
  test::useLoopbackDds();
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  const std::string out = test::scratchDir("traffic_rsu");
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds = test::uniqueDdsConfig();
  config.dds.droneId = 9;
  config.dds.ros2.enabled = false;
  config.app.statsPeriod_s = 3600.0;
  config.source.paced = false;
  config.traffic.period_s = 1.0;
  const std::string log = out + "/subscriber.log";
  const std::string command =
      std::string(VP_RSU_SUBSCRIBER) + " --domain " + std::to_string(config.dds.domainId) +
      " --partition " + config.dds.partition + " --site " + dir + "/site.geojson" + " --bev-png " +
      out + "/bev.png --until-writers-gone" + " --duration-s 60 >/dev/null 2>" + log;
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  LoopCounters counters;
  bool matched = false;
  {
    App app;
    AppSeams seams;
    auto truth = std::make_unique<test::TruthPerception>();
    std::string why;
    ASSERT_TRUE(truth->init(dir, &why)) << why;
    seams.perception = std::move(truth);
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    matched = test::waitForMatch(app.trafficEventsWriter(), 1, 15000ms) &&
              test::waitForMatch(app.vehicleStateWriter(), 1, 15000ms);
    std::this_thread::sleep_for(500ms);  // the subscriber's side of discovery
    ASSERT_TRUE(app.run(&why)) << why;
    EXPECT_EQ(dds_wait_for_acks(app.trafficEventsWriter(), DDS_SECS(5)), DDS_RETCODE_OK);
    EXPECT_EQ(dds_wait_for_acks(app.trafficStatisticsWriter(), DDS_SECS(5)), DDS_RETCODE_OK);
    counters = app.counters();
  }  // the writers leave: the subscriber stops
  EXPECT_EQ(pclose(pipe), 0);
  ASSERT_TRUE(matched) << "the subscriber process was not discovered";
  const std::string text = test::readText(log);
  EXPECT_NE(text.find("site " + dir + "/site.geojson (26 features)"), std::string::npos) << text;
  std::size_t periodLines = 0;
  for (std::size_t at = text.find("traffic: drone 9 period "); at != std::string::npos;
       at = text.find("traffic: drone 9 period ", at + 1)) {
    ++periodLines;
  }
  EXPECT_EQ(periodLines, counters.trafficPeriods) << text;
  // The totals line: forward + backward of every gate = the app's crossings.
  const std::size_t totals = text.find("traffic totals: ");
  ASSERT_NE(totals, std::string::npos) << text;
  const std::string line = text.substr(totals, text.find('\n', totals) - totals);
  std::uint64_t sum = 0;
  for (const char* word : {" forward ", " backward "}) {
    for (std::size_t at = line.find(word); at != std::string::npos; at = line.find(word, at + 1)) {
      sum += std::stoull(line.substr(at + std::string(word).size()));
    }
  }
  EXPECT_EQ(sum, counters.gateCrossings) << line;
  EXPECT_GT(sum, 0U);
  EXPECT_TRUE(std::filesystem::exists(out + "/bev.png"));
}

TEST(AppTraffic, OffWithoutTheOptionAndWithoutASite) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  for (const bool withSite : {true, false}) {
    config::AppConfig config = test::defaultConfigFor(dir);
    config.dds.enabled = false;
    config.source.paced = false;
    config.app.statsPeriod_s = 3600.0;
    const std::string out = test::scratchDir(withSite ? "traffic_off" : "traffic_nosite");
    config.app.trafficDir = out;
    if (withSite) {
      config.traffic.enabled = false;
    } else {
      // A sequence copy whose rig.yaml names no site.
      const std::string copy = test::copySequence(dir, "no_site");
      std::string rig = test::readText(copy + "/rig.yaml");
      const std::size_t at = rig.find("site:");
      ASSERT_NE(at, std::string::npos);
      rig = rig.substr(0, at);
      std::ofstream(copy + "/rig.yaml", std::ios::trunc) << rig;
      config = test::defaultConfigFor(copy);
      config.dds.enabled = false;
      config.source.paced = false;
      config.app.trafficDir = out;
    }
    App app;
    std::string why;
    auto truth = std::make_unique<test::TruthPerception>();
    ASSERT_TRUE(truth->init(dir, &why)) << why;
    AppSeams seams;
    seams.perception = std::move(truth);
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    EXPECT_FALSE(app.counters().traffic);
    EXPECT_EQ(app.summaryLine().find("gate_crossings="), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(out + "/traffic_counts.csv"));
  }
}

}  // namespace
}  // namespace vp::app
