// Test helper: small simulated sequences rendered into a scratch folder, for the tests that
// compare what the simulator writes with and without an option.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "simulator.hpp"

namespace vp::sim::testing {

// An empty scratch folder named after the test process and `name`.
inline std::filesystem::path freshDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("vp_sim_test_" + std::to_string(::getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  return dir;
}

// Two PNG frames of `scene` from `seed` into `out`, at a small size with the camera's field of
// view (fx scales with the width: the same view as 2592 x 2048), the source tree's ASM.
inline SimOptions smallOptions(SceneKind scene, std::uint64_t seed,
                               const std::filesystem::path& out, int width = 240,
                               int height = 190) {
  SimOptions o;
  o.scene = scene;
  o.seed = seed;
  o.frames = 2;
  o.outDir = out.string();
  o.width = width;
  o.height = height;
  o.png = true;
  o.asmPath = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";
  return o;
}

inline std::string readAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string bytes(static_cast<std::size_t>(std::filesystem::file_size(p)), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return bytes;
}

// Every file under `dir`: path relative to it -> bytes.
inline std::map<std::string, std::string> dirContents(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) {
      files[std::filesystem::relative(e.path(), dir).string()] = readAll(e.path());
    }
  }
  return files;
}

// Renders the options' sequence and returns its files (dirContents), removing the folder.
inline std::map<std::string, std::string> renderedFiles(const SimOptions& o) {
  Simulator sim;
  std::string why;
  EXPECT_TRUE(sim.init(o, &why)) << why;
  EXPECT_TRUE(sim.write(&why)) << why;
  auto files = dirContents(o.outDir);
  std::filesystem::remove_all(o.outDir);
  return files;
}

}  // namespace vp::sim::testing
