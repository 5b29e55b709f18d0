// The app's ROS 2 / Autoware outputs end to end: the app replays a simulated sequence (vehicles
// injected from the ground truth by TruthPerception, so the test does not depend on the
// detector) with dds.ros2 and dds.autoware on, and vp_test_ros2_reader (tests/platform/dds/
// ros2_reader: a separate process built only from the C types generated from interfaces/ and
// ddsc, reading as a ROS 2 node on rmw_cyclonedds does: rt/ topics, default partition, plain CDR)
// prints every field it receives. Every VehicleStateArray and TrackedObjects it receives is
// compared field by field with what the app published (recorded by a LoopObserver, converted
// with the documented mapping of docs/dds.md by tests/platform/dds/ros2_fields), including UTM,
// rear axle, keypoints and variances; every track appears in removed_track_ids once it is gone
// (deleted by the tracker, or at shutdown); the drone status and the occupancy grid arrive with
// the app's identity, frame and grid geometry.
#include <dds/dds.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "app.hpp"
#include "app_test_support.hpp"
#include "dds_test_support.hpp"
#include "ros2_fields.hpp"

namespace vp::app {
namespace {

using namespace std::chrono_literals;
using test::ros2::Fields;

// What the app published, frame by frame (a frame ends at onFrameDone).
class PublishedFrames final : public LoopObserver {
 public:
  // Reserved up front: the observer runs on the processing thread.
  PublishedFrames() {
    states.reserve(20000);
    frameEnds.reserve(2000);
  }
  void onPublished(const messages::VehicleState& state) override { states.push_back(state); }
  void onFrameDone(std::uint64_t /*framesProcessed*/) override {
    frameEnds.push_back(states.size());
  }
  std::vector<messages::VehicleState> states;
  std::vector<std::size_t> frameEnds;
};

// One VehicleStateArray / TrackedObjects the app wrote: its states, the tracks it lists as
// removed (published in the previous frame, missing now) and its stamp (the states'
// measurement time; unknown for a frame without states).
struct ExpectedFrame {
  std::span<const messages::VehicleState> states;
  std::vector<std::uint32_t> removed;
  std::optional<std::int64_t> time_ns;
};

std::vector<ExpectedFrame> expectedFrames(const PublishedFrames& log) {
  std::vector<ExpectedFrame> frames;
  std::size_t begin = 0;
  std::span<const messages::VehicleState> previous;
  const auto add = [&](std::span<const messages::VehicleState> states) {
    ExpectedFrame frame;
    frame.states = states;
    for (const messages::VehicleState& before : previous) {
      bool kept = false;
      for (const messages::VehicleState& now : states) {
        kept = kept || now.trackId == before.trackId;
      }
      if (!kept) {
        frame.removed.push_back(before.trackId);
      }
    }
    if (!states.empty()) {
      frame.time_ns = states.front().measurementTime_ns;
      for (const messages::VehicleState& s : states) {
        EXPECT_EQ(s.measurementTime_ns, *frame.time_ns) << "track " << s.trackId;
      }
    }
    frames.push_back(std::move(frame));
    previous = states;
  };
  for (const std::size_t end : log.frameEnds) {
    add(std::span<const messages::VehicleState>(log.states).subspan(begin, end - begin));
    begin = end;
  }
  // At shutdown the app ends one more frame without states: every remaining track is removed.
  add({});
  return frames;
}

std::int64_t stampOf(const Fields& f, const std::string& topic) {
  return std::stoll(f.at(topic + ".header.stamp.sec")) * 1'000'000'000 +
         std::stoll(f.at(topic + ".header.stamp.nanosec"));
}

std::vector<std::uint32_t> removedOf(const Fields& f) {
  std::vector<std::uint32_t> ids;
  const int count = std::stoi(f.at("vehicle_states.removed_track_ids.length"));
  for (int k = 0; k < count; ++k) {
    ids.push_back(static_cast<std::uint32_t>(
        std::stoul(f.at("vehicle_states.removed_track_ids." + std::to_string(k)))));
  }
  return ids;
}

// The first expected frame at or after `from` that a received message of this stamp can be:
// a frame with states has the same stamp; one without has none, lies between the stamps of its
// neighbours with states, and (VehicleStateArray) lists the same removed tracks.
std::optional<std::size_t> matchFrame(const std::vector<ExpectedFrame>& frames, std::size_t from,
                                      std::int64_t stamp, bool hasStates,
                                      const std::vector<std::uint32_t>* removed) {
  std::int64_t before = 0;
  for (std::size_t k = 0; k < from; ++k) {
    before = frames[k].time_ns.value_or(before);
  }
  for (std::size_t k = from; k < frames.size(); ++k) {
    const ExpectedFrame& frame = frames[k];
    if (hasStates) {
      if (frame.time_ns == stamp) {
        return k;
      }
      continue;
    }
    if (frame.time_ns) {
      before = *frame.time_ns;
      continue;
    }
    std::optional<std::int64_t> after;
    for (std::size_t n = k + 1; n < frames.size() && !after; ++n) {
      after = frames[n].time_ns;
    }
    if (stamp > before && (!after || stamp < *after) &&
        (removed == nullptr || *removed == frame.removed)) {
      return k;
    }
  }
  return std::nullopt;
}

// The app's ROS 2 writers (DDS topic names starting with "rt/"), found through its participant
// (the publishers' children that have a publication-matched status).
std::vector<dds_entity_t> rosWriters(std::uint32_t domainId) {
  std::vector<dds_entity_t> writers;
  dds_entity_t participants[8];
  const dds_return_t count = dds_lookup_participant(domainId, participants, 8);
  for (dds_return_t p = 0; p < std::min<dds_return_t>(count, 8); ++p) {
    dds_entity_t children[64];
    const dds_return_t n = dds_get_children(participants[p], children, 64);
    for (dds_return_t c = 0; c < std::min<dds_return_t>(n, 64); ++c) {
      dds_entity_t entities[64];
      const dds_return_t m = dds_get_children(children[c], entities, 64);
      for (dds_return_t w = 0; w < std::min<dds_return_t>(m, 64); ++w) {
        char name[256] = {};
        dds_publication_matched_status_t status{};  // only a writer has one
        if (dds_get_publication_matched_status(entities[w], &status) == DDS_RETCODE_OK &&
            dds_get_name(dds_get_topic(entities[w]), name, sizeof name) >= 0 &&
            std::string(name).rfind("rt/", 0) == 0) {
          writers.push_back(entities[w]);
        }
      }
    }
  }
  return writers;
}

bool waitForReaders(const std::vector<dds_entity_t>& writers, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (const dds_entity_t writer : writers) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (!test::waitForMatch(writer, 1, std::max(left, std::chrono::milliseconds(0)))) {
      return false;
    }
  }
  return true;
}

TEST(AppRos2, ReaderProcessReceivesEveryArrayAndObjectListFieldByFieldAndEveryRemoval) {
  test::useLoopbackDds();
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.domainId = static_cast<std::uint32_t>(1 + (getpid() * 13 + 7) % 200);
  config.dds.partition = "ros2_app_test_" + std::to_string(getpid());
  config.dds.droneId = 42;
  config.dds.ros2.enabled = true;
  config.dds.ros2.topicNamespace = "vp_app_" + std::to_string(getpid());
  config.dds.ros2.frameId = "site_enu";
  config.dds.autoware.enabled = true;
  config.dds.autoware.topic = "/perception/app_test_" + std::to_string(getpid()) + "/objects";
  config.app.statsPeriod_s = 3600.0;
  config.source.paced = true;  // 10 Hz, as live
  // The vehicle-state family only: the traffic topics (the sequence's site has gates) are read
  // back in tests/platform/dds/traffic_publisher_test.cpp and AppTraffic.*.
  config.traffic.enabled = false;

  const std::string command =
      std::string(VP_ROS2_READER) + " --domain " + std::to_string(config.dds.domainId) +
      " --namespace " + config.dds.ros2.topicNamespace + " --autoware-topic " +
      config.dds.autoware.topic +
      " --states 1 --objects 1 --status 1 --occupancy 1 --until-writers-gone --timeout-s 90";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  // Read while the app runs: a reader blocked on a full pipe would stop taking samples.
  std::map<std::string, std::vector<Fields>> received;
  std::thread reading([&] { received = test::ros2::parseReader(pipe); });
  struct Join {
    std::thread& thread;
    ~Join() {
      if (thread.joinable()) {
        thread.join();
      }
    }
  } join{reading};

  PublishedFrames log;
  LoopCounters counters;
  bool matched = false;
  std::size_t writerCount = 0;
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
    const std::vector<dds_entity_t> writers = rosWriters(config.dds.domainId);
    writerCount = writers.size();
    matched = waitForReaders(writers, 15000ms);
    // The writer may see the reader before the reader has seen the writer.
    std::this_thread::sleep_for(500ms);
    ASSERT_TRUE(app.run(&why)) << why;
    counters = app.counters();
  }  // the writers leave (after their acknowledgements): the reader stops
  reading.join();
  EXPECT_EQ(pclose(pipe), 0) << "the reader timed out or failed";
  EXPECT_EQ(writerCount, 4U) << "vehicle_states, tracked_objects, drone_status, occupancy";
  ASSERT_TRUE(matched) << "the reader process was not discovered";
  ASSERT_FALSE(log.states.empty()) << "no confirmed track was published";
  EXPECT_EQ(counters.statesPublished, log.states.size());
  EXPECT_EQ(counters.publishErrors, 0U);

  const std::vector<ExpectedFrame> frames = expectedFrames(log);
  std::set<std::uint32_t> sentTracks;
  for (const messages::VehicleState& s : log.states) {
    sentTracks.insert(s.trackId);
    EXPECT_EQ(s.droneId, 42U);
  }

  // VehicleStateArray: every one received is one the app wrote, in order, field by field.
  ASSERT_EQ(received.count("vehicle_states"), 1U);
  const std::vector<Fields>& arrays = received.at("vehicle_states");
  std::set<std::uint32_t> receivedTracks;
  std::multiset<std::uint32_t> removedTracks;
  std::size_t next = 0;
  std::size_t withUtm = 0;
  std::size_t withKeypoints = 0;
  std::size_t occupiedChecked = 0;
  for (const Fields& array : arrays) {
    const std::int64_t stamp = stampOf(array, "vehicle_states");
    const bool hasStates = array.at("vehicle_states.vehicles.length") != "0";
    const std::vector<std::uint32_t> removed = removedOf(array);
    const std::optional<std::size_t> k = matchFrame(frames, next, stamp, hasStates, &removed);
    ASSERT_TRUE(k) << "received an array the app did not write (or out of order), stamp " << stamp;
    const ExpectedFrame& frame = frames[*k];
    test::ros2::expectSame(
        array, test::ros2::vehicleStateArray(stamp, "site_enu", 42, frame.states, frame.removed));
    for (const messages::VehicleState& s : frame.states) {
      receivedTracks.insert(s.trackId);
      withUtm += s.utmZone != 0 ? 1 : 0;
      withKeypoints += s.keypointCount > 0 ? 1 : 0;
    }
    removedTracks.insert(removed.begin(), removed.end());
    next = *k + 1;
  }
  // Reliable on loopback with a reader that keeps up: every frame's array arrives, the last
  // one (written at shutdown) listing every track still published then.
  EXPECT_EQ(arrays.size(), frames.size()) << "arrays written: one per processed frame + shutdown";
  EXPECT_EQ(receivedTracks, sentTracks);
  EXPECT_EQ(removedTracks, std::multiset<std::uint32_t>(sentTracks.begin(), sentTracks.end()))
      << "every track is listed in removed_track_ids exactly once";
  EXPECT_GT(withUtm, 0U) << "the UTM fields are filled";
  EXPECT_GT(withKeypoints, 0U) << "keypoints are filled";

  // TrackedObjects: the same frames in Autoware's terms.
  ASSERT_EQ(received.count("tracked_objects"), 1U);
  const std::vector<Fields>& objects = received.at("tracked_objects");
  next = 0;
  for (const Fields& list : objects) {
    const std::int64_t stamp = stampOf(list, "tracked_objects");
    const bool hasStates = list.at("tracked_objects.objects.length") != "0";
    const std::optional<std::size_t> k = matchFrame(frames, next, stamp, hasStates, nullptr);
    ASSERT_TRUE(k) << "received objects the app did not write (or out of order), stamp " << stamp;
    test::ros2::expectSame(list, test::ros2::trackedObjects(stamp, "map", frames[*k].states));
    next = *k + 1;
  }
  EXPECT_EQ(objects.size(), frames.size());

  // Drone status: the app's identity and counts no larger than the run's totals.
  ASSERT_EQ(received.count("drone_status"), 1U);
  for (const Fields& status : received.at("drone_status")) {
    EXPECT_EQ(status.at("drone_status.header.frame_id"), "site_enu");
    EXPECT_EQ(status.at("drone_status.drone_id"), "42");
    EXPECT_LE(std::stoull(status.at("drone_status.frames_processed")), counters.framesProcessed);
    EXPECT_EQ(status.at("drone_status.publish_errors"), "0");
    EXPECT_LE(std::stoul(status.at("drone_status.active_tracks")), sentTracks.size());
  }

  // Occupancy grid (the default 200 x 200 cells of 0.5 m): the configured geometry, cells in
  // {-1, 0, 100}, and, when stamped with a frame that had states, the cell under each of its
  // vehicles occupied.
  ASSERT_EQ(received.count("occupancy"), 1U);
  const config::OccupancyGridSpec& spec = config.dds.grid;
  for (const Fields& grid : received.at("occupancy")) {
    EXPECT_EQ(grid.at("occupancy.header.frame_id"), "site_enu");
    EXPECT_EQ(grid.at("occupancy.info.width"), std::to_string(spec.cols));
    EXPECT_EQ(grid.at("occupancy.info.height"), std::to_string(spec.rows));
    EXPECT_EQ(grid.at("occupancy.info.resolution"),
              test::ros2::textF(static_cast<float>(spec.resolution_m)));
    EXPECT_EQ(grid.at("occupancy.info.origin.position.x"), test::ros2::text(spec.originEast_m));
    EXPECT_EQ(grid.at("occupancy.info.origin.position.y"), test::ros2::text(spec.originNorth_m));
    ASSERT_EQ(grid.at("occupancy.data.length"), std::to_string(spec.rows * spec.cols));
    for (std::uint32_t k = 0; k < spec.rows * spec.cols; ++k) {
      const std::string& value = grid.at("occupancy.data." + std::to_string(k));
      ASSERT_TRUE(value == "-1" || value == "0" || value == "100") << k << ": " << value;
    }
    const std::int64_t stamp = stampOf(grid, "occupancy");
    const ExpectedFrame* frame = nullptr;
    for (const ExpectedFrame& f : frames) {
      frame = f.time_ns == stamp ? &f : frame;
    }
    if (frame == nullptr) {
      continue;  // a frame without states: its stamp is not known here
    }
    for (const messages::VehicleState& s : frame->states) {
      const auto col =
          static_cast<long>(std::floor((s.enu_m[0] - spec.originEast_m) / spec.resolution_m));
      const auto row =
          static_cast<long>(std::floor((s.enu_m[1] - spec.originNorth_m) / spec.resolution_m));
      if (col >= 0 && row >= 0 && col < static_cast<long>(spec.cols) &&
          row < static_cast<long>(spec.rows)) {
        EXPECT_EQ(grid.at("occupancy.data." + std::to_string(row * spec.cols + col)), "100")
            << "the cell under track " << s.trackId;
        ++occupiedChecked;
      }
    }
  }
  EXPECT_GT(occupiedChecked, 0U) << "no grid was stamped with a frame that had vehicles in it";
  std::printf(
      "app -> vp_test_ros2_reader: %zu frames written, %zu arrays and %zu object lists received "
      "(fields equal), %zu states of %zu tracks, %zu removals, %zu statuses, %zu grids\n",
      frames.size(), arrays.size(), objects.size(), log.states.size(), sentTracks.size(),
      removedTracks.size(), received.at("drone_status").size(), received.at("occupancy").size());
}

}  // namespace
}  // namespace vp::app
