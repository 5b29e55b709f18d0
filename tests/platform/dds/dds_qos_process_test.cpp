// The vehicle-state QoS (docs/dds.md, "QoS defaults and why") proved across processes on
// loopback: the roadside unit is the real vp_rsu_subscriber in another process, and where the
// drone must die (SIGKILL) it is vp_test_drone_writer, a third process. Each test uses its own
// domain and partition, so the tests may run in parallel.
//   - late joiner: a subscriber started after the drone wrote gets exactly the newest state of
//     each live vehicle (transient-local, KEEP_LAST 1); the lifespan bounds that history; with
//     volatile it gets nothing of the past;
//   - deadline and liveliness: when the drone stops writing the subscriber reports one
//     deadline_missed per track ~0.3 s after its newest state; when the drone process leaves or
//     is killed it reports writer_lost (at once, or when the 2 s lease expires);
//   - restart: a subscriber killed and restarted while the drone deletes tracks never shows a
//     deleted track alive.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "platform/dds/perception_publisher.hpp"
#include "state_format.hpp"

extern char** environ;

namespace vp::platform::dds {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A child process with stdout and stderr in files (a full pipe would stall it).
struct Child {
  pid_t pid = -1;
  fs::path out;
  fs::path err;
};

Child spawn(const std::vector<std::string>& args, const fs::path& out, const fs::path& err) {
  Child child{-1, out, err};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  for (const std::string& a : args) {
    argv.push_back(const_cast<char*>(a.c_str()));
  }
  argv.push_back(nullptr);
  const int rc = posix_spawn(&child.pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  EXPECT_EQ(rc, 0) << "posix_spawn " << args[0];
  if (rc != 0) {
    child.pid = -1;
  }
  return child;
}

// Exit status, or -1 if it did not end within `timeout` (then it is killed).
int waitExit(Child& child, std::chrono::milliseconds timeout) {
  if (child.pid <= 0) {
    return -1;
  }
  const auto end = Clock::now() + timeout;
  int status = 0;
  while (Clock::now() < end) {
    if (waitpid(child.pid, &status, WNOHANG) == child.pid) {
      child.pid = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    std::this_thread::sleep_for(20ms);
  }
  kill(child.pid, SIGKILL);
  waitpid(child.pid, &status, 0);
  child.pid = -1;
  return -1;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// One CSV row of vp_rsu_subscriber: the first five columns parsed, all kept as text.
struct Row {
  std::string event;
  std::string droneId;
  std::uint32_t trackId = 0;
  std::int64_t time_ns = 0;  // measurement time (of the state, or the newest one before an event)
  double latency_ms = 0.0;
  std::vector<std::string> columns;
  // For QoS events: when the subscriber got the event (newest state's time + time since it).
  std::int64_t eventTime_ns() const {
    return time_ns + static_cast<std::int64_t>(latency_ms * 1e6);
  }
};

std::vector<Row> readRows(const fs::path& csv) {
  std::vector<Row> rows;
  std::istringstream lines(readFile(csv));
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line.rfind("event,", 0) == 0) {
      continue;  // header
    }
    Row row;
    std::stringstream split(line);
    for (std::string column; std::getline(split, column, ',');) {
      row.columns.push_back(column);
    }
    if (row.columns.size() < 5) {
      continue;  // a row being written
    }
    row.event = row.columns[0];
    row.droneId = row.columns[1];
    row.trackId =
        row.columns[2].empty() ? 0 : static_cast<std::uint32_t>(std::stoul(row.columns[2]));
    row.time_ns = row.columns[3].empty() ? 0 : std::stoll(row.columns[3]);
    row.latency_ms = row.columns[4].empty() ? 0.0 : std::stod(row.columns[4]);
    rows.push_back(row);
  }
  return rows;
}

// Polls the subscriber's output until `done` holds for its rows or the timeout passes.
bool waitForRows(const fs::path& csv, const std::function<bool(const std::vector<Row>&)>& done,
                 std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    if (done(readRows(csv))) {
      return true;
    }
    std::this_thread::sleep_for(50ms);
  }
  return false;
}

std::set<std::uint32_t> tracksWith(const std::vector<Row>& rows, const std::string& event) {
  std::set<std::uint32_t> ids;
  for (const Row& r : rows) {
    if (r.event == event) {
      ids.insert(r.trackId);
    }
  }
  return ids;
}

// The drone in this process: deleting it (reset) deletes the writer, which readers see leave.
struct LocalDrone {
  Participant participant;
  VehicleStatePublisher publisher;  // destroyed first
  explicit LocalDrone(const config::DdsConfig& config) {
    EXPECT_TRUE(participant.open(config).ok());
    EXPECT_TRUE(publisher.open(participant, config).ok());
  }
};

class QosProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    test::useLoopbackDds();  // inherited by the child processes
    config_ = test::uniqueDdsConfig();
    dir_ = fs::temp_directory_path() /
           ("vp_dds_qos_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) {
      fs::remove_all(dir_);
    }
  }

  // vp_rsu_subscriber on this test's domain and partition, CSV into dir_/NAME.csv.
  Child subscriber(const std::string& name, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {
        VP_RSU_SUBSCRIBER, "--domain", std::to_string(config_.domainId), "--partition",
        config_.partition, "--out",    (dir_ / (name + ".csv")).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return spawn(args, dir_ / (name + ".stdout"), dir_ / (name + ".err"));
  }
  fs::path csv(const std::string& name) const { return dir_ / (name + ".csv"); }
  std::string errors(const std::string& name) const { return readFile(dir_ / (name + ".err")); }

  // Subscriber A killed with `signal`, B restarted while the drone deletes tracks (below).
  void restart(int signal);

  config::DdsConfig config_;
  fs::path dir_;
};

// ---------------------------------------------------------------------------------------------
// 1. Late joiner across processes.

constexpr std::uint32_t kDroneId = 7;  // test::makeState's drone

// Writes `statesPerVehicle` states of each of `vehicles` vehicles (each state different), then
// deletes vehicle `removed`. Returns the newest state of each live vehicle.
std::map<std::uint32_t, messages::VehicleState> writeHistory(VehicleStatePublisher& publisher,
                                                             std::uint32_t vehicles,
                                                             int statesPerVehicle,
                                                             std::uint32_t removed) {
  std::map<std::uint32_t, messages::VehicleState> last;
  const std::int64_t start = dds_time();
  for (int k = 0; k < statesPerVehicle; ++k) {
    const std::int64_t t = start + k * 100'000'000LL;
    for (std::uint32_t id = 1; id <= vehicles; ++id) {
      messages::VehicleState s = test::makeState(id, t);
      s.speed_mps += static_cast<float>(k);
      EXPECT_TRUE(publisher.publish(s).ok());
      last[id] = s;
    }
    EXPECT_EQ(publisher.endFrame(t).disposed, 0U);
  }
  EXPECT_TRUE(publisher.remove(kDroneId, removed, dds_time()).ok());
  last.erase(removed);
  return last;
}

// Every column but latency_ms equals what was sent.
void expectSameFields(const Row& row, const messages::VehicleState& sent) {
  std::vector<std::string> expected;
  std::stringstream split(rsu::formatCsv(rsu::EventKind::State, sent, 0.0));
  for (std::string column; std::getline(split, column, ',');) {
    expected.push_back(column);
  }
  std::vector<std::string> got = row.columns;
  ASSERT_EQ(got.size(), expected.size());
  got[4] = expected[4];
  EXPECT_EQ(got, expected) << "track " << row.trackId << ": not the newest state";
}

TEST_F(QosProcessTest, LateJoinerGetsTheNewestStateOfEachLiveVehicle) {
  ASSERT_EQ(config_.vehicleState.durability, config::Durability::TransientLocal);
  ASSERT_EQ(config_.vehicleState.historyDepth, 1);
  // The subscriber process starts in ~0.1-1 s on a loaded machine: the lifespan (0.5 s, its
  // effect is the next test) is switched off here so that the start-up time does not matter.
  config_.vehicleState.lifespan_s = 0.0;
  constexpr std::uint32_t kVehicles = 5;
  std::optional<LocalDrone> drone(config_);
  VehicleStatePublisher& publisher = drone->publisher;
  ASSERT_TRUE(publisher.writer() > 0);
  const auto last = writeHistory(publisher, kVehicles, 4, 3);

  Child rsu = subscriber("late", {"--until-writers-gone", "--duration-s", "30"});
  const auto started = Clock::now();
  ASSERT_TRUE(test::waitForMatch(publisher.writer(), 1, 15000ms)) << errors("late");
  // The late reader acknowledges the history it was handed.
  EXPECT_EQ(dds_wait_for_acks(publisher.writer(), DDS_SECS(10)), DDS_RETCODE_OK);
  ASSERT_TRUE(waitForRows(
      csv("late"),
      [](const std::vector<Row>& rows) { return tracksWith(rows, "state").size() >= 4; }, 10000ms));
  const double joined_s = std::chrono::duration<double>(Clock::now() - started).count();
  std::this_thread::sleep_for(300ms);  // anything more would show up too
  drone.reset();                       // the drone leaves: the subscriber stops
  ASSERT_EQ(waitExit(rsu, 20000ms), 0) << errors("late");

  std::map<std::uint32_t, int> states;
  for (const Row& row : readRows(csv("late"))) {
    if (row.event != "state") {
      continue;  // the disposals at the end (the writer left) or of the deleted vehicle
    }
    ++states[row.trackId];
    ASSERT_EQ(last.count(row.trackId), 1U) << "state of the deleted vehicle " << row.trackId;
    expectSameFields(row, last.at(row.trackId));
  }
  EXPECT_EQ(states.size(), last.size());
  for (const auto& [id, count] : states) {
    EXPECT_EQ(count, 1) << "vehicle " << id << ": only the newest state is kept";
  }
  std::printf(
      "late joiner process: %zu live vehicles, each its newest state once; start to "
      "all states %.2f s\n",
      states.size(), joined_s);
}

// With the default lifespan (0.5 s) the writer drops a state from its history 0.5 s after
// writing it: a subscriber that starts after the drone fell silent for longer gets no stale
// state (while the drone runs at 10 Hz the history is never older than 0.1 s).
TEST_F(QosProcessTest, LateJoinerGetsNoStateOlderThanTheLifespan) {
  ASSERT_DOUBLE_EQ(config_.vehicleState.lifespan_s, 0.5);
  std::optional<LocalDrone> drone(config_);
  VehicleStatePublisher& publisher = drone->publisher;
  ASSERT_TRUE(publisher.writer() > 0);
  writeHistory(publisher, 5, 4, 3);
  std::this_thread::sleep_for(700ms);
  Child rsu = subscriber("stale", {"--until-writers-gone", "--duration-s", "30"});
  ASSERT_TRUE(test::waitForMatch(publisher.writer(), 1, 15000ms)) << errors("stale");
  EXPECT_EQ(dds_wait_for_acks(publisher.writer(), DDS_SECS(10)), DDS_RETCODE_OK);
  std::this_thread::sleep_for(500ms);
  drone.reset();
  ASSERT_EQ(waitExit(rsu, 20000ms), 0) << errors("stale");
  EXPECT_TRUE(tracksWith(readRows(csv("stale")), "state").empty());
}

// A volatile writer (and reader) hands a late subscriber nothing of the past: it gets only
// what is written after it matched.
TEST_F(QosProcessTest, VolatileLateJoinerGetsNothingOfThePast) {
  config_.vehicleState.durability = config::Durability::Volatile;
  const fs::path yaml = dir_ / "volatile.yaml";
  std::ofstream(yaml) << "dds:\n  qos:\n    vehicle_state:\n      durability: volatile\n";
  std::optional<LocalDrone> drone(config_);
  VehicleStatePublisher& publisher = drone->publisher;
  ASSERT_TRUE(publisher.writer() > 0);
  writeHistory(publisher, 5, 4, 3);
  Child rsu = subscriber("volatile",
                         {"--config", yaml.string(), "--until-writers-gone", "--duration-s", "30"});
  ASSERT_TRUE(test::waitForMatch(publisher.writer(), 1, 15000ms)) << errors("volatile");
  // The writer may match before the reader knows the writer (then the reader drops the data):
  // write the new frame until it is acknowledged.
  const std::int64_t now = dds_time() + 1'000'000'000LL;  // later than every old state
  for (int attempt = 0; attempt < 50; ++attempt) {
    for (std::uint32_t id : {1U, 2U, 4U, 5U}) {
      ASSERT_TRUE(publisher.publish(test::makeState(id, now)).ok());
    }
    publisher.endFrame(now);
    if (dds_wait_for_acks(publisher.writer(), DDS_MSECS(200)) == DDS_RETCODE_OK &&
        tracksWith(readRows(csv("volatile")), "state").size() == 4) {
      break;
    }
  }
  drone.reset();
  ASSERT_EQ(waitExit(rsu, 20000ms), 0) << errors("volatile");
  const std::vector<Row> rows = readRows(csv("volatile"));
  EXPECT_EQ(tracksWith(rows, "state"), (std::set<std::uint32_t>{1, 2, 4, 5}));
  for (const Row& row : rows) {
    if (row.event == "state") {
      EXPECT_EQ(row.time_ns, now) << "track " << row.trackId << ": a state of the past";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 2. Deadline and liveliness when the drone stops.

constexpr std::uint32_t kTracks = 5;

// The deadline counts from the reception of an instance's newest state: the event comes at
// least 0.3 s after its measurement (= write) time; the upper bound allows for the subscriber's
// scheduling on a loaded machine (Cyclone's event thread, the 2 shared cores).
constexpr double kDeadlineMin_ms = 295.0;
constexpr double kDeadlineMax_ms = 800.0;

Child droneProcess(const config::DdsConfig& config, const fs::path& dir, int frames,
                   double idle_s) {
  return spawn({VP_DRONE_WRITER, std::to_string(config.domainId), config.partition,
                std::to_string(kTracks), std::to_string(frames), std::to_string(idle_s)},
               dir / "drone.out", dir / "drone.err");
}

std::int64_t droneValue(const fs::path& out, const std::string& key) {
  std::istringstream lines(readFile(out));
  std::string word;
  long long value = 0;
  while (lines >> word) {
    if (word == key && (lines >> value)) {
      return value;
    }
  }
  return 0;
}

// One deadline_missed per track, within the bounds of its newest state. Returns the worst.
double expectDeadlineEvents(const std::vector<Row>& rows, std::int64_t lastWrite_ns) {
  std::map<std::uint32_t, int> count;
  double worst = 0.0;
  for (const Row& r : rows) {
    if (r.event != "deadline_missed") {
      continue;
    }
    ++count[r.trackId];
    EXPECT_EQ(r.droneId, std::to_string(kDroneId));
    if (lastWrite_ns != 0) {
      EXPECT_EQ(r.time_ns, lastWrite_ns) << "track " << r.trackId << ": not its newest state";
    }
    EXPECT_GE(r.latency_ms, kDeadlineMin_ms) << "track " << r.trackId;
    EXPECT_LE(r.latency_ms, kDeadlineMax_ms) << "track " << r.trackId;
    worst = std::max(worst, r.latency_ms);
  }
  EXPECT_EQ(count.size(), kTracks);
  for (const auto& [id, n] : count) {
    EXPECT_EQ(n, 1) << "track " << id << ": once per silence";
  }
  return worst;
}

const Row* findEvent(const std::vector<Row>& rows, const std::string& event) {
  for (const Row& r : rows) {
    if (r.event == event) {
      return &r;
    }
  }
  return nullptr;
}

// The drone stops writing and stays alive 3 s, then leaves cleanly: a deadline miss per track
// ~0.3 s after its newest state, no liveliness change while the process lives (automatic
// liveliness is asserted by the participant, not by writes), writer_lost when it leaves.
TEST_F(QosProcessTest, DeadlinePerTrackWhenTheDroneStopsAndWriterLostWhenItLeaves) {
  ASSERT_DOUBLE_EQ(config_.vehicleState.deadline_s, 0.3);
  ASSERT_DOUBLE_EQ(config_.vehicleState.livelinessLease_s, 2.0);
  Child rsu = subscriber("rsu");
  Child json = subscriber("json", {"--format", "json"});
  Child writer = droneProcess(config_, dir_, 20, 3.0);
  ASSERT_EQ(waitExit(writer, 30000ms), 0) << readFile(dir_ / "drone.err") << errors("rsu");
  const std::int64_t lastWrite_ns = droneValue(dir_ / "drone.out", "last_write_ns");
  const std::int64_t exit_ns = droneValue(dir_ / "drone.out", "exit_ns");
  ASSERT_NE(lastWrite_ns, 0);
  ASSERT_NE(exit_ns, 0);
  const bool lost = waitForRows(
      csv("rsu"),
      [](const std::vector<Row>& rows) { return findEvent(rows, "writer_lost") != nullptr; },
      5000ms);
  kill(rsu.pid, SIGTERM);
  kill(json.pid, SIGTERM);
  ASSERT_EQ(waitExit(rsu, 10000ms), 0) << errors("rsu");
  ASSERT_EQ(waitExit(json, 10000ms), 0) << errors("json");
  ASSERT_TRUE(lost) << errors("rsu");

  const std::vector<Row> rows = readRows(csv("rsu"));
  ASSERT_NE(findEvent(rows, "writer_alive"), nullptr);
  // The same events as JSON lines, and as status lines on stderr.
  const std::string jsonText = readFile(csv("json"));
  const std::string stderrText = errors("rsu");
  for (std::uint32_t id = 1; id <= kTracks; ++id) {
    EXPECT_NE(jsonText.find("{\"event\":\"deadline_missed\",\"drone_id\":7,\"track_id\":" +
                            std::to_string(id) + ","),
              std::string::npos)
        << jsonText;
    EXPECT_NE(stderrText.find("deadline missed: drone 7 track " + std::to_string(id) + ","),
              std::string::npos)
        << stderrText;
  }
  EXPECT_NE(jsonText.find("{\"event\":\"writer_lost\",\"drone_id\":7,"), std::string::npos);
  EXPECT_NE(stderrText.find("writer lost: drone 7,"), std::string::npos) << stderrText;
  const double worstDeadline_ms = expectDeadlineEvents(rows, lastWrite_ns);
  const Row& writerLost = *findEvent(rows, "writer_lost");
  EXPECT_EQ(writerLost.droneId, std::to_string(kDroneId));
  const double afterExit_ms = static_cast<double>(writerLost.eventTime_ns() - exit_ns) * 1e-6;
  // Not before the process left (3 s of silence did not end the liveliness), and at once then.
  EXPECT_GE(afterExit_ms, -5.0);
  EXPECT_LE(afterExit_ms, 1000.0);
  std::printf(
      "drone stopped: deadline_missed per track after its newest state <= %.1f ms "
      "(deadline 300 ms); writer_lost %.1f ms after the drone left (silent 3 s before)\n",
      worstDeadline_ms, afterExit_ms);
  RecordProperty("deadline_missed_worst_ms", std::to_string(worstDeadline_ms));
  RecordProperty("writer_lost_after_exit_ms", std::to_string(afterExit_ms));
}

// The drone process is killed while writing: deadline misses as above, and writer_lost when
// the liveliness lease (2 s, automatic) runs out, counted from the last message received,
// which is at most one frame (0.1 s) before the kill.
constexpr double kLeaseMin_ms = 1800.0;
constexpr double kLeaseMax_ms = 3000.0;

TEST_F(QosProcessTest, WriterLostWithinTheLeaseWhenTheDroneIsKilled) {
  ASSERT_DOUBLE_EQ(config_.vehicleState.livelinessLease_s, 2.0);
  Child rsu = subscriber("rsu");
  Child writer = droneProcess(config_, dir_, 100000, 0.0);
  // A second of states, then SIGKILL.
  ASSERT_TRUE(waitForRows(
      csv("rsu"),
      [](const std::vector<Row>& rows) {
        return std::count_if(rows.begin(), rows.end(),
                             [](const Row& r) { return r.event == "state"; }) >= 10 * kTracks;
      },
      20000ms))
      << readFile(dir_ / "drone.err") << errors("rsu");
  const std::int64_t kill_ns = dds_time();
  ASSERT_EQ(kill(writer.pid, SIGKILL), 0);
  EXPECT_EQ(waitExit(writer, 5000ms), 128 + SIGKILL);
  const bool lost = waitForRows(
      csv("rsu"),
      [](const std::vector<Row>& rows) { return findEvent(rows, "writer_lost") != nullptr; },
      8000ms);
  kill(rsu.pid, SIGTERM);
  ASSERT_EQ(waitExit(rsu, 10000ms), 0) << errors("rsu");
  ASSERT_TRUE(lost) << errors("rsu");

  const std::vector<Row> rows = readRows(csv("rsu"));
  const double worstDeadline_ms = expectDeadlineEvents(rows, 0);
  const Row& writerLost = *findEvent(rows, "writer_lost");
  const double afterKill_ms = static_cast<double>(writerLost.eventTime_ns() - kill_ns) * 1e-6;
  EXPECT_GE(afterKill_ms, kLeaseMin_ms);
  EXPECT_LE(afterKill_ms, kLeaseMax_ms);
  EXPECT_GE(writerLost.latency_ms, 2000.0 - 5.0);  // since the writer's newest state
  std::printf(
      "drone killed: deadline_missed per track after its newest state <= %.1f ms; "
      "writer_lost %.1f ms after SIGKILL (%.1f ms after its newest state; lease 2 s)\n",
      worstDeadline_ms, afterKill_ms, writerLost.latency_ms);
  RecordProperty("writer_lost_after_kill_ms", std::to_string(afterKill_ms));
}

// ---------------------------------------------------------------------------------------------
// 3. Disposals and a subscriber that restarts.

// Subscriber A runs and is killed; while it is down the drone deletes tracks 1-3 (its frames
// no longer carry them: endFrame disposes and unregisters them); B starts 0.5 s later, while
// the drone goes on at 10 Hz with tracks 4-10. B must never show a deleted track as alive: it
// gets no state of 1-3, and every live track's state.
TEST_F(QosProcessTest, RestartedSubscriberNeverShowsDeletedTracksAlive) {
  restart(SIGKILL);
}

// The same with A stopped cleanly (SIGTERM): its reader leaves at once, nothing holds the
// deletion unacknowledged, and B never hears of the deleted tracks.
TEST_F(QosProcessTest, RestartedSubscriberAfterACleanStopNeverHearsOfDeletedTracks) {
  restart(SIGTERM);
}

void QosProcessTest::restart(int signal) {
  constexpr std::uint32_t kAll = 10;
  constexpr std::uint32_t kDeleted = 3;  // tracks 1..3
  std::optional<LocalDrone> drone(config_);
  VehicleStatePublisher& publisher = drone->publisher;
  ASSERT_TRUE(publisher.writer() > 0);
  auto next = Clock::now();
  std::uint32_t firstLive = 1;
  int errorsWritten = 0;
  const auto frame = [&] {
    const std::int64_t t = dds_time();
    for (std::uint32_t id = firstLive; id <= kAll; ++id) {
      errorsWritten += publisher.publish(test::makeState(id, t)).ok() ? 0 : 1;
    }
    errorsWritten += static_cast<int>(publisher.endFrame(t).errors);
    next += 100ms;
    std::this_thread::sleep_until(next);
  };
  const auto runUntil = [&](const fs::path& file, const std::set<std::uint32_t>& ids,
                            std::chrono::milliseconds timeout) {
    const auto end = Clock::now() + timeout;
    while (Clock::now() < end) {
      frame();
      const std::set<std::uint32_t> got = tracksWith(readRows(file), "state");
      if (std::includes(got.begin(), got.end(), ids.begin(), ids.end())) {
        return true;
      }
    }
    return false;
  };
  std::set<std::uint32_t> all;
  std::set<std::uint32_t> live;
  for (std::uint32_t id = 1; id <= kAll; ++id) {
    all.insert(id);
    if (id > kDeleted) {
      live.insert(id);
    }
  }

  Child a = subscriber("a");
  ASSERT_TRUE(runUntil(csv("a"), all, 20000ms)) << errors("a");
  ASSERT_EQ(kill(a.pid, signal), 0);
  EXPECT_EQ(waitExit(a, 5000ms), signal == SIGKILL ? 128 + SIGKILL : 0) << errors("a");
  firstLive = kDeleted + 1;  // the tracker deleted 1..3: the next endFrame disposes them
  const std::int64_t deleted_ns = dds_time();
  for (int k = 0; k < 5; ++k) {
    frame();
  }
  dds_publication_matched_status_t matched{};
  ASSERT_GE(dds_get_publication_matched_status(publisher.writer(), &matched), 0);
  const std::uint32_t zombies = matched.current_count;  // A until its participant lease ends
  Child b = subscriber("b", {"--until-writers-gone", "--duration-s", "30"});
  ASSERT_TRUE(runUntil(csv("b"), live, 20000ms)) << errors("b");
  for (int k = 0; k < 10; ++k) {
    frame();  // one more second of the live stream
  }
  drone.reset();
  ASSERT_EQ(waitExit(b, 20000ms), 0) << errors("b");
  EXPECT_EQ(errorsWritten, 0);

  const std::vector<Row> rows = readRows(csv("b"));
  std::set<std::uint32_t> deletedSeen;
  for (const Row& row : rows) {
    if (row.trackId >= 1 && row.trackId <= kDeleted) {
      EXPECT_NE(row.event, "state") << "B got a state of deleted track " << row.trackId;
      if (row.event == "disposed") {
        deletedSeen.insert(row.trackId);
      }
    }
    if (row.event == "state") {
      EXPECT_GT(row.time_ns, deleted_ns) << "B got a state from before the deletion";
    }
  }
  EXPECT_EQ(tracksWith(rows, "state"), live);
  // Either B never hears of 1..3 (the deletion was acknowledged by every matched reader, so
  // the writer dropped them) or, while the killed A still counts as matched (its participant
  // lease, 10 s by default, has not run out), it gets their dispose + unregister from the
  // writer's history and reports them disposed.
  if (zombies > 0) {
    EXPECT_EQ(deletedSeen.size(), kDeleted);
  } else {
    EXPECT_TRUE(deletedSeen.empty());
  }
  EXPECT_EQ(zombies, signal == SIGKILL ? 1U : 0U);
  std::printf(
      "restart after %s: readers still matched when B started: %u; B reported %zu of %u deleted "
      "tracks disposed, no state of them; %zu live tracks\n",
      signal == SIGKILL ? "SIGKILL" : "SIGTERM", zombies, deletedSeen.size(), kDeleted,
      tracksWith(rows, "state").size());
}

}  // namespace
}  // namespace vp::platform::dds
