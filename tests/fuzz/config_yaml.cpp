// fuzz/config_yaml: the application's configuration loader (src/config) on arbitrary YAML.
// Contract checked: parseConfig(), parseRigConfig() and parseDdsSection() either return or
// throw config::ConfigError whose message names the file; no other exception, no crash.
#include <cstddef>
#include <cstdint>
#include <string>

#include "config/config.hpp"
#include "fuzz_support.hpp"
#include "rig_config/rig_config.hpp"

namespace {

constexpr const char* kTarget = "config_yaml";
constexpr const char* kSource = "fuzz_config.yaml";

template <typename Parse>
void parseChecked(const char* what, Parse&& parse) {
  try {
    parse();
    vp::fuzz::note(kTarget, std::string(what) + ": accepted");
  } catch (const vp::config::ConfigError& error) {
    vp::fuzz::note(kTarget, std::string(what) + ": " + error.what());
    vp::fuzz::expect(std::string(error.what()).find(kSource) != std::string::npos, kTarget,
                     std::string(what) + ": message does not name the file: " + error.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(vp::fuzz::asText(data, size));
  // Relative paths resolve against the scratch directory (existence checks see real files).
  const std::string baseDir = vp::fuzz::scratchDirectory().string();
  parseChecked("parseConfig", [&] {
    const vp::config::AppConfig config = vp::config::parseConfig(text, kSource, baseDir);
    vp::fuzz::expect(config.sourcePath == kSource, kTarget, "sourcePath not the file's name");
  });
  parseChecked("parseRigConfig", [&] { vp::config::parseRigConfig(text, kSource, baseDir); });
  parseChecked("parseDdsSection", [&] { vp::config::parseDdsSection(text, kSource, baseDir); });
  return 0;
}
