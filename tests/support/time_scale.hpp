// tests/support/time_scale: how much slower than real hardware the tests run, for the few tests
// that bound a wall time (a recovery, a watchdog's period).
//
// Contract: timeScale() is VP_TEST_TIME_SCALE from the environment (a number >= 1), else 1.
// tests/CMakeLists.txt sets it for every test when the tree is cross-built and its tests run
// under an emulator (CMAKE_CROSSCOMPILING_EMULATOR: qemu-user runs aarch64 code several times
// slower than the host), so a bound that holds on the device is not failed by the emulation.
// Natively it is 1 and every bound is the device's.
#pragma once

#include <cstdlib>

namespace vp::test {

inline double timeScale() {
  const char* text = std::getenv("VP_TEST_TIME_SCALE");
  if (text == nullptr)
    return 1.0;
  char* end = nullptr;
  const double scale = std::strtod(text, &end);
  return end != text && scale >= 1.0 ? scale : 1.0;
}

}  // namespace vp::test
