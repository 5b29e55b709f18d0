// The shipped Active Shape Model (models/asm/default_asm.yaml) for the simulator's vehicle tests;
// a load failure is reported as a test failure with the loader's message.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "shape/vehicle_model.hpp"

namespace vp::sim::test {

inline vp::shape::ActiveShapeModel loadDefaultAsm() {
  vp::shape::ActiveShapeModel asmModel;
  std::string why;
  EXPECT_TRUE(asmModel.load(std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml", &why))
      << why;
  return asmModel;
}

}  // namespace vp::sim::test
