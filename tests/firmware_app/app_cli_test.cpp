// The vp_firmware_app executable: --help, usage and configuration errors (exit 2, the message
// names the option or key), a start-up failure (exit 1), the shipped default configuration on
// the fixture sequence, and a clean stop on SIGTERM (exit 0, every frame back in the pool).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app_test_support.hpp"
#include "output_files/trajectory_file.hpp"
#include "time_scale.hpp"

extern char** environ;

namespace vp::app {
namespace {

namespace fs = std::filesystem;

struct Result {
  int exitCode = -1;
  std::string output;  // stdout and stderr together
};

// Runs the app with the arguments through the shell, capturing both outputs.
Result runApp(const std::string& arguments) {
  const std::string command = std::string(VP_FIRMWARE_APP) + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  Result result;
  if (pipe == nullptr) {
    return result;
  }
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
    result.output += buffer;
  }
  const int status = pclose(pipe);
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

const std::string kDefaultConfig = std::string(VP_SOURCE_DIR) + "/config/default.yaml";
const std::string kSequence = std::string(VP_FIXTURE_DIR) + "/sequence_min";

TEST(AppCli, HelpListsEveryOptionAndExitsZero) {
  const Result help = runApp("--help");
  EXPECT_EQ(help.exitCode, 0);
  for (const char* option :
       {"--config",         "--sequence",       "--camera",      "--camera-bus",
        "--fast",           "--every-frame",    "--loop",        "--max-frames",
        "--trajectory-csv", "--detections-csv", "--traffic-dir", "--annotated-video",
        "--record",         "--no-dds",         "--threads",     "--backend",
        "--pipeline",       "--quiet",          "--help",        "Exit status"}) {
    EXPECT_NE(help.output.find(option), std::string::npos) << option;
  }
}

TEST(AppCli, UsageErrorsExitTwoNamingTheOption) {
  Result r = runApp("");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("--config FILE is required"), std::string::npos) << r.output;
  r = runApp("--config " + kDefaultConfig + " --frobnicate");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("unknown option '--frobnicate'"), std::string::npos) << r.output;
  r = runApp("--config " + kDefaultConfig + " --threads 99");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("--threads: expected an integer in [1, 16], got '99'"), std::string::npos)
      << r.output;
  r = runApp("--config " + kDefaultConfig + " --backend int4");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("--backend: expected int8, fp32, opencv, int8-dnnl or auto, got 'int4'"),
            std::string::npos)
      << r.output;
  r = runApp("--config " + kDefaultConfig + " --pipeline both");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("--pipeline: expected off or on, got 'both'"), std::string::npos)
      << r.output;
  r = runApp("--config " + kDefaultConfig + " --sequence a --camera /dev/video0");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("exclude each other"), std::string::npos) << r.output;
  r = runApp("--config " + kDefaultConfig);  // replay, but of what?
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find("source.sequence_dir: no recorded sequence"), std::string::npos)
      << r.output;
}

TEST(AppCli, ConfigurationErrorsExitTwoNamingTheKey) {
  const std::string dir = test::scratchDir("cli_config");
  std::string text = test::readText(kDefaultConfig);
  text.replace(text.find("queue_depth: 1"), 14, "queue_depth: 9");
  // Beside config/ so that the relative paths still resolve.
  const std::string path =
      std::string(VP_SOURCE_DIR) + "/config/.cli_test_" + std::to_string(getpid()) + ".yaml";
  std::ofstream(path) << text;
  const Result r = runApp("--config " + path + " --sequence " + kSequence + " --no-dds");
  fs::remove(path);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.output.find(path + ": app.queue_depth: must be in [1, 8], got 9"), std::string::npos)
      << r.output;
  const Result missing = runApp("--config " + dir + "/absent.yaml --sequence " + kSequence);
  EXPECT_EQ(missing.exitCode, 2);
  EXPECT_NE(missing.output.find("absent.yaml: cannot open configuration file"), std::string::npos)
      << missing.output;
}

TEST(AppCli, StartUpFailureExitsOneNamingWhatFailed) {
  const Result r = runApp("--config " + kDefaultConfig + " --sequence /nonexistent/seq --no-dds");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.output.find("start-up failed: sequence /nonexistent/seq"), std::string::npos)
      << r.output;
}

TEST(AppCli, DefaultConfigurationRunsTheFixtureSequence) {
  const std::string dir = test::scratchDir("cli_run");
  const Result r = runApp("--config " + kDefaultConfig + " --sequence " + kSequence +
                          " --no-dds --fast --every-frame --trajectory-csv " + dir +
                          "/tracks.csv --detections-csv " + dir + "/detections.csv");
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("summary: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames_in=2 processed=2 dropped=0 bad=0"), std::string::npos)
      << r.output;
  output_files::TrajectoryFile tracks;
  std::string why;
  EXPECT_TRUE(output_files::readTrajectoryFile(dir + "/tracks.csv", &tracks, &why)) << why;
  EXPECT_TRUE(fs::exists(dir + "/detections.csv"));
}

TEST(AppCli, SigtermStopsCleanly) {
  // A paced, looping replay never ends by itself; SIGTERM must stop it with exit 0 and every
  // frame back in the pool (the app checks and exits 1 otherwise).
  const std::string log = test::scratchDir("cli_sigterm") + "/log.txt";
  std::vector<std::string> args = {VP_FIRMWARE_APP, "--config", kDefaultConfig, "--sequence",
                                   kSequence,       "--loop",   "--no-dds"};
  const pid_t pid = test::spawnApp(args, log);
  ASSERT_GT(pid, 0);
  // Signal once the loop runs (start-up can take seconds on a loaded machine), then let it
  // take a few frames.
  test::waitUntilRunning(log, std::chrono::seconds(120));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  const std::string output = test::readText(log);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  EXPECT_NE(output.find("summary: "), std::string::npos) << output;
  EXPECT_EQ(output.find("not returned to the pool"), std::string::npos) << output;
}

// A private copy of the fixture sequence (and the DTM its rig.yaml points at, ../dtm).
std::string fixtureCopy(const std::string& name) {
  const fs::path root = test::scratchDir(name);
  fs::remove_all(root / "sequence_min");
  fs::remove_all(root / "dtm");
  fs::copy(kSequence, root / "sequence_min", fs::copy_options::recursive);
  fs::copy(fs::path(VP_FIXTURE_DIR) / "dtm", root / "dtm", fs::copy_options::recursive);
  return (root / "sequence_min").string();
}

void setFrameTimes(const std::string& sequence, const std::string& t0, const std::string& t1) {
  std::ofstream(sequence + "/frames.csv", std::ios::trunc)
      << "frame_id,timestamp_ns,file\n0," << t0 << ",frames/000000.png\n1," << t1
      << ",frames/000001.png\n";
}

// Every line of a CSV output has the header's field count and the file ends with a line break.
void expectWholeRows(const std::string& path) {
  const std::string text = test::readText(path);
  ASSERT_FALSE(text.empty()) << path;
  EXPECT_EQ(text.back(), '\n') << path;
  std::istringstream lines(text);
  std::string line;
  long fields = -1;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    const long count = std::count(line.begin(), line.end(), ',') + 1;
    if (fields < 0) {
      fields = count;
    }
    EXPECT_EQ(count, fields) << path << ": " << line;
  }
}

TEST(AppCli, SigtermDuringALongPacedWaitExitsPromptlyAndCleanly) {
  // The second frame is recorded 50 s after the first: the paced replay waits for it. SIGTERM
  // during that wait must end the app within seconds, exit 0, with both CSV files whole.
  const std::string sequence = fixtureCopy("cli_long_wait");
  setFrameTimes(sequence, "1700000000000000000", "1700000050000000000");
  const std::string dir = fs::path(sequence).parent_path().string();
  const std::string log = dir + "/log.txt";
  std::vector<std::string> args = {VP_FIRMWARE_APP,    "--config",
                                   kDefaultConfig,     "--sequence",
                                   sequence,           "--no-dds",
                                   "--trajectory-csv", dir + "/tracks.csv",
                                   "--detections-csv", dir + "/detections.csv"};
  const pid_t pid = test::spawnApp(args, log);
  ASSERT_GT(pid, 0);
  test::waitUntilRunning(log, std::chrono::seconds(120));
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // frame 0 done, frame 1 waits
  ASSERT_EQ(kill(pid, SIGTERM), 0);
  const auto signalled = std::chrono::steady_clock::now();
  int status = 0;
  pid_t done = 0;
  while ((done = waitpid(pid, &status, WNOHANG)) == 0 &&
         std::chrono::steady_clock::now() - signalled < std::chrono::seconds(10)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const double exit_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  if (done == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    FAIL() << "still running 10 s after SIGTERM:\n" << test::readText(log);
  }
  const std::string output = test::readText(log);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  EXPECT_LT(exit_s, 3.0) << output;
  EXPECT_NE(output.find("summary: "), std::string::npos) << output;
  std::printf("exit %.3f s after SIGTERM during a 50 s paced wait\n", exit_s);
  expectWholeRows(dir + "/tracks.csv");
  expectWholeRows(dir + "/detections.csv");
  std::string why;
  output_files::TrajectoryFile tracks;
  EXPECT_TRUE(output_files::readTrajectoryFile(dir + "/tracks.csv", &tracks, &why)) << why;
}

// Under systemd's watchdog (WATCHDOG_USEC), a source that gives no frame for longer than the
// watchdog period - a silent camera, a reopen backing off, here a recording's 4 s pause - must not
// get the service killed: while the capture thread is alive the loop keeps sending WATCHDOG=1 at
// half the period. A fake service manager (a datagram socket at NOTIFY_SOCKET) records them.
TEST(AppCli, TheWatchdogIsFedWhileTheSourceIsSilent) {
  const std::string sequence = fixtureCopy("cli_watchdog");
  setFrameTimes(sequence, "1700000000000000000", "1700000004000000000");
  const std::string dir = fs::path(sequence).parent_path().string();
  const std::string socketPath = dir + "/notify.sock";
  fs::remove(socketPath);
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(socketPath.size(), sizeof(address.sun_path));
  std::copy(socketPath.begin(), socketPath.end(), address.sun_path);
  ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);

  std::vector<std::string> args = {VP_FIRMWARE_APP, "--config", kDefaultConfig,
                                   "--sequence",    sequence,   "--no-dds"};
  std::vector<char*> argv;
  for (std::string& arg : args) {
    argv.push_back(arg.data());
  }
  argv.push_back(nullptr);
  std::vector<std::string> env = {"NOTIFY_SOCKET=" + socketPath, "WATCHDOG_USEC=1000000"};
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    if (entry.rfind("NOTIFY_SOCKET=", 0) != 0 && entry.rfind("WATCHDOG_", 0) != 0) {
      env.push_back(entry);
    }
  }
  std::vector<char*> envp;
  for (std::string& entry : env) {
    envp.push_back(entry.data());
  }
  envp.push_back(nullptr);
  const std::string log = dir + "/log.txt";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, VP_FIRMWARE_APP, &actions, nullptr, argv.data(), envp.data()), 0);
  posix_spawn_file_actions_destroy(&actions);

  using Clock = std::chrono::steady_clock;
  std::vector<Clock::time_point> kicks;
  bool ready = false;
  bool stopping = false;
  int status = 0;
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) > 0) {
      char message[512];
      const ssize_t n = ::recv(fd, message, sizeof(message) - 1, 0);
      if (n > 0) {
        const std::string text(message, static_cast<std::size_t>(n));
        ready = ready || text.find("READY=1") != std::string::npos;
        stopping = stopping || text.find("STOPPING=1") != std::string::npos;
        if (ready && !stopping && text.find("WATCHDOG=1") != std::string::npos) {
          kicks.push_back(Clock::now());
        }
      }
      continue;
    }
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      pid = 0;
      break;
    }
  }
  if (pid != 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  ::close(fd);
  const std::string output = test::readText(log);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  ASSERT_TRUE(ready) << output;
  ASSERT_GE(kicks.size(), 2U) << output;
  double longest_s = 0.0;
  for (std::size_t i = 1; i < kicks.size(); ++i) {
    longest_s = std::max(longest_s, std::chrono::duration<double>(kicks[i] - kicks[i - 1]).count());
  }
  // Due every 0.5 s; systemd would kill after 1 s without one. The pause alone is 4 s. (Under
  // an emulator the loop's own steps stretch the gaps: the bound is scaled, time_scale.hpp.)
  EXPECT_LT(longest_s, 1.0 * test::timeScale()) << kicks.size() << " WATCHDOG=1\n" << output;
  EXPECT_GE(kicks.size(), 6U) << output;
  std::printf("%zu WATCHDOG=1 over a 4 s pause of the source, longest gap %.3f s\n", kicks.size(),
              longest_s);
}

TEST(AppCli, AnAbsurdTimestampGapIsAStartUpErrorNamingFileAndLine) {
  // The first frame at -0.1 s, the next at 1.7e18 ns (what made a paced replay sleep for
  // decades): refused at start-up.
  const std::string sequence = fixtureCopy("cli_gap");
  setFrameTimes(sequence, "-100000000", "1700000000000000000");
  const Result r = runApp("--config " + kDefaultConfig + " --sequence " + sequence + " --no-dds");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("frames.csv:3: timestamp_ns: jumps 1700000000.100 s after the "
                          "previous frame"),
            std::string::npos)
      << r.output;
}

TEST(AppCli, AllFramesBadExitsOneSayingNoFrameWasProcessed) {
  const std::string sequence = fixtureCopy("cli_all_bad");
  for (const char* frame : {"/frames/000000.png", "/frames/000001.png"}) {
    std::ofstream(sequence + frame, std::ios::binary | std::ios::trunc) << "not a PNG";
  }
  const Result r = runApp("--config " + kDefaultConfig + " --sequence " + sequence +
                          " --no-dds --fast --every-frame");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("no frame was processed (2 frames in: 2 bad, 0 refused, 0 dropped)"),
            std::string::npos)
      << r.output;
}

TEST(AppCli, AnOutputOnAFullDiskFailsNamingTheFile) {
  // /dev/full refuses every write: the header write at start-up already fails.
  const Result r = runApp("--config " + kDefaultConfig + " --sequence " + kSequence +
                          " --no-dds --fast --every-frame --detections-csv /dev/full");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("/dev/full: write failed: No space left on device"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace vp::app
