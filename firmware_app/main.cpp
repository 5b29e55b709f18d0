// vp_firmware_app: the product's executable. Parses the command line, loads the configuration,
// wires the loop (firmware_app/app.hpp) and runs it until the source ends or a stop signal.
#include <cstdio>
#include <exception>
#include <string>

#include "app.hpp"
#include "app_options.hpp"
#include "config/config.hpp"
#include "platform/system/stop_signals.hpp"

int main(int argc, char** argv) {
  using namespace vp::app;
  CommandLine line;
  std::string why;
  switch (parseCommandLine(argc, argv, &line, &why)) {
    case ParseOutcome::Help:
      std::fputs(helpText(), stdout);
      return kExitOk;
    case ParseOutcome::UsageError:
      std::fprintf(stderr, "vp_firmware_app: %s\n", why.c_str());
      return kExitUsageError;
    case ParseOutcome::Run:
      break;
  }
  vp::config::AppConfig config;
  try {
    config = vp::config::loadConfig(line.configPath);
  } catch (const vp::config::ConfigError& error) {
    std::fprintf(stderr, "vp_firmware_app: %s\n", error.what());
    return kExitUsageError;
  }
  for (const std::string& warning : config.warnings) {
    std::fprintf(stderr, "vp_firmware_app: warning: %s\n", warning.c_str());
  }
  applyCommandLine(line, config);
  if (const std::string problem = checkConsistency(config); !problem.empty()) {
    std::fprintf(stderr, "vp_firmware_app: %s: %s\n", line.configPath.c_str(), problem.c_str());
    return kExitUsageError;
  }

  vp::platform::StopSignals signals;
  if (!signals.install(&why)) {
    std::fprintf(stderr, "vp_firmware_app: %s\n", why.c_str());
    return kExitRuntimeError;
  }
  App app;
  try {
    if (!app.init(config, runSettings(line), AppSeams{}, &why)) {
      std::fprintf(stderr, "vp_firmware_app: start-up failed: %s\n", why.c_str());
      return kExitRuntimeError;
    }
    if (!app.run(&why)) {
      std::fprintf(stderr, "vp_firmware_app: %s\n", why.c_str());
      return kExitRuntimeError;
    }
  } catch (const std::exception& error) {  // start-up only: the loop itself does not throw
    std::fprintf(stderr, "vp_firmware_app: %s\n", error.what());
    return kExitRuntimeError;
  }
  std::fprintf(stderr, "vp_firmware_app: %s\n", app.summaryLine().c_str());
  // Not 0 when frames leaked, an output write failed, or the source ended before any frame
  // was processed (one line each).
  std::string problems;
  const int status =
      runExitStatus(app.counters(), app.stopRequested(), app.poolCapacity() - app.framesInPool(),
                    app.poolCapacity(), &problems);
  std::size_t begin = 0;
  for (std::size_t end = problems.find('\n'); end != std::string::npos;
       begin = end + 1, end = problems.find('\n', begin)) {
    std::fprintf(stderr, "vp_firmware_app: %s\n", problems.substr(begin, end - begin).c_str());
  }
  return status;
}
