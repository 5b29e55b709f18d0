// firmware_app/app_options: the command line of vp_firmware_app and how it overrides the
// configuration file.
//
// Contract: parseCommandLine() reads argv into a CommandLine without touching the file system;
// a usage error (unknown option, missing or malformed value, conflicting options) returns
// UsageError with a message naming the option. applyCommandLine() then overrides the loaded
// configuration: a command-line value always wins over the file's; relative paths given on
// the command line are relative to the working directory (those in the file stay relative to
// the file). helpText() is the complete --help (every option, the exit codes, the files).
// Start-up only (allocates, may throw nothing).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "app.hpp"
#include "config/config.hpp"

namespace vp::app {

// Exit codes of vp_firmware_app.
constexpr int kExitOk = 0;
// Start-up (models, DTM, device, DDS) or loop failure: the source ended before any frame was
// processed, an output write failed, frames were not returned to the pool.
constexpr int kExitRuntimeError = 1;
constexpr int kExitUsageError = 2;  // command line or configuration error

struct CommandLine {
  std::string configPath;
  std::optional<std::string> sequenceDir;
  std::optional<std::string> cameraDevice;
  std::optional<std::string> cameraBus;
  bool fast = false;
  bool loop = false;
  bool everyFrame = false;
  bool noDds = false;
  bool quiet = false;
  std::int64_t maxFrames = 0;
  std::optional<std::string> trajectoryCsv;
  std::optional<std::string> detectionsCsv;
  std::optional<std::string> trafficDir;
  std::optional<std::string> annotatedVideo;
  std::optional<std::string> recordDir;
  std::optional<int> threads;
  std::optional<inference::Backend> backend;
  std::optional<config::PipelineMode> pipeline;
};

enum class ParseOutcome { Run, Help, UsageError };

ParseOutcome parseCommandLine(int argc, const char* const* argv, CommandLine* out,
                              std::string* why);
const char* helpText();

// Overrides config with the command line's values (see the contract).
void applyCommandLine(const CommandLine& line, config::AppConfig& config);
RunSettings runSettings(const CommandLine& line);
// The exit status of a run that started (kExitOk or kExitRuntimeError) and, for each reason it
// is not 0, one line in *why: frames not returned to the pool, a failed output or recording write,
// or a source that ended before any frame was processed (a stop requested before the first frame is
// not a failure).
int runExitStatus(const LoopCounters& counters, bool stopRequested, std::size_t framesNotReturned,
                  std::size_t poolCapacity, std::string* why);

// The configuration after the overrides, checked as a whole: "key: problem" for the first
// inconsistency (no sequence to replay, recorded telemetry without a recording), else "".
std::string checkConsistency(const config::AppConfig& config);

}  // namespace vp::app
