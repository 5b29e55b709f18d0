// Acceptance: the app replaying a simulated sequence publishes its tracks over DDS
// and the roadside-unit subscriber in ANOTHER process (vp_rsu_subscriber, CSV output) receives
// every confirmed track with equal fields, and sees every track disposed. Vehicles are injected
// from the sequence's ground truth (TruthPerception), so the test does not depend on the
// detector's accuracy; what the app says it published is recorded by a LoopObserver.
#include <dds/dds.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app.hpp"
#include "app_test_support.hpp"
#include "dds_test_support.hpp"
#include "loop_log.hpp"
#include "state_format.hpp"
#include "time_scale.hpp"

namespace vp::app {
namespace {

using namespace std::chrono_literals;

class PublishedLog final : public LoopObserver {
 public:
  // Reserved up front: the observer runs on the processing thread.
  PublishedLog() { states.reserve(20000); }
  void onPublished(const messages::VehicleState& state) override { states.push_back(state); }
  std::vector<messages::VehicleState> states;
};

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> columns;
  std::stringstream split(line);
  for (std::string column; std::getline(split, column, ',');) {
    columns.push_back(column);
  }
  return columns;
}

TEST(AppDds, SubscriberProcessReceivesEveryPublishedStateAndTheDisposals) {
  test::useLoopbackDds();
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.domainId = static_cast<std::uint32_t>(1 + (getpid() * 7 + 3) % 200);
  config.dds.partition = "app_test_" + std::to_string(getpid());
  config.dds.droneId = 42;
  config.app.statsPeriod_s = 3600.0;
  config.source.paced = true;  // 10 Hz, as live

  const std::string command =
      std::string(VP_RSU_SUBSCRIBER) + " --domain " + std::to_string(config.dds.domainId) +
      " --partition " + config.dds.partition + " --until-writers-gone --duration-s 60 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);

  PublishedLog log;
  LoopCounters counters;
  bool matched = false;
  {
    App app;
    AppSeams seams;
    auto truth = std::make_unique<test::TruthPerception>();
    std::string why;
    ASSERT_TRUE(truth->init(dir, &why)) << why;
    seams.perception = std::move(truth);
    seams.observer = &log;
    RunSettings run;
    run.quiet = true;
    ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
    matched = test::waitForMatch(app.vehicleStateWriter(), 1, 15000ms);
    // The writer may see the reader before the reader has seen the writer; the first
    // confirmed tracks come 0.3 s after the start anyway, this leaves discovery some more.
    std::this_thread::sleep_for(500ms);
    ASSERT_TRUE(app.run(&why)) << why;
    EXPECT_EQ(dds_wait_for_acks(app.vehicleStateWriter(), DDS_SECS(5)), DDS_RETCODE_OK);
    counters = app.counters();
  }  // the writers leave: the subscriber stops
  std::string output;
  char buffer[8192];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
    output += buffer;
  }
  const int status = pclose(pipe);
  ASSERT_TRUE(matched) << "the subscriber process was not discovered";
  EXPECT_EQ(status, 0);
  ASSERT_FALSE(log.states.empty()) << "no confirmed track was published";
  EXPECT_EQ(counters.statesPublished, log.states.size());
  EXPECT_EQ(counters.publishErrors, 0U);

  // What the app published, keyed by (track, measurement time), as the subscriber formats it.
  std::map<std::pair<std::uint32_t, std::string>, std::vector<std::string>> sent;
  std::set<std::uint32_t> sentTracks;
  for (const messages::VehicleState& state : log.states) {
    std::vector<std::string> columns = splitCsv(rsu::formatCsv(rsu::EventKind::State, state, 0.0));
    sent[{state.trackId, columns[3]}] = columns;
    sentTracks.insert(state.trackId);
    EXPECT_EQ(state.droneId, 42U);
    EXPECT_NE(state.status, messages::TrackStatus::Tentative);
  }

  std::istringstream lines(output);
  std::string line;
  ASSERT_TRUE(std::getline(lines, line));
  EXPECT_EQ(line, rsu::csvHeader());
  std::set<std::uint32_t> receivedTracks;
  std::set<std::uint32_t> disposedTracks;
  std::size_t received = 0;
  while (std::getline(lines, line)) {
    std::vector<std::string> columns = splitCsv(line);
    if (!columns.empty() && columns[0] != "state" && columns[0] != "disposed") {
      continue;  // the reader's QoS events (writer_alive, writer_lost, deadline_missed)
    }
    ASSERT_GT(columns.size(), 5U) << line;
    const auto trackId = static_cast<std::uint32_t>(std::stoul(columns[2]));
    if (columns[0] == "disposed") {
      disposedTracks.insert(trackId);
      continue;
    }
    ++received;
    receivedTracks.insert(trackId);
    const auto found = sent.find({trackId, columns[3]});
    ASSERT_NE(found, sent.end()) << "received a state the app did not publish: " << line;
    columns[4] = found->second[4];  // latency: the receiver's own measure
    EXPECT_EQ(columns, found->second) << line;
  }
  // Every confirmed track arrives and every track is disposed by the end (deleted by the
  // tracker, or at shutdown). Not every sample: the QoS keeps the latest state per track
  // (KEEP_LAST 1, docs/dds.md), so a reader that takes later sees only the newest one.
  EXPECT_EQ(receivedTracks, sentTracks);
  EXPECT_EQ(disposedTracks, sentTracks);
  EXPECT_GT(received, sentTracks.size());
  std::printf(
      "app -> vp_rsu_subscriber: %zu states of %zu tracks published, %zu received "
      "(fields equal), %zu tracks disposed (%llu disposed while running)\n",
      log.states.size(), sentTracks.size(), received, disposedTracks.size(),
      static_cast<unsigned long long>(counters.tracksDisposed));
}

// Replay: a state's measurement time is its frame's capture time on the UTC clock, so the
// latency a receiver computes (reception - measurement time) is positive and close to the
// app's own capture -> publish figure. The replay here runs faster than the recording (not
// paced, frames dropped while the loop works): with the UTC offset taken once at the first
// frame, measurement times ran ahead of the wall clock and latencies went below zero.
class PublishTimes final : public LoopObserver {
 public:
  PublishTimes() { latency_ns.reserve(20000); }
  void onPublished(const messages::VehicleState& state) override {
    latency_ns.push_back(realtimeNow_ns() - state.measurementTime_ns);
  }
  std::vector<std::int64_t> latency_ns;
};

TEST(AppDds, ReplayLatencyAtTheReceiverIsPositiveAndMatchesTheAppsEndToEnd) {
  test::useLoopbackDds();
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.domainId = static_cast<std::uint32_t>(1 + (getpid() * 11 + 5) % 200);
  config.dds.partition = "latency_test_" + std::to_string(getpid());
  config.app.statsPeriod_s = 3600.0;
  config.source.paced = false;  // faster than the recording's 10 Hz

  PublishTimes times;
  App app;
  AppSeams seams;
  auto truth = std::make_unique<test::TruthPerception>();
  std::string why;
  ASSERT_TRUE(truth->init(dir, &why)) << why;
  seams.perception = std::move(truth);
  seams.observer = &times;
  RunSettings run;
  run.quiet = true;
  run.maxFrames = 300;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  ASSERT_GT(times.latency_ns.size(), 20U) << "too few states published";

  std::vector<std::int64_t> sorted = times.latency_ns;
  std::sort(sorted.begin(), sorted.end());
  const double median_ms = static_cast<double>(sorted[sorted.size() / 2]) / 1e6;
  const double e2eMedian_ms =
      static_cast<double>(app.stats().total(Stage::EndToEnd).median_ns()) / 1e6;
  std::printf(
      "latency at publish: min %.2f ms, median %.2f ms; app e2e median %.2f ms (%zu states)\n",
      static_cast<double>(sorted.front()) / 1e6, median_ms, e2eMedian_ms, sorted.size());
  EXPECT_GE(sorted.front(), 0) << "a state was published before its frame was captured";
  // The two clocks stop a few steps apart (the publish, then the end of the loop's frame): 5 ms
  // on the device; under an emulator those steps stretch, so the bound is scaled (time_scale.hpp).
  EXPECT_NEAR(median_ms, e2eMedian_ms, 5.0 * test::timeScale());
}

}  // namespace
}  // namespace vp::app
