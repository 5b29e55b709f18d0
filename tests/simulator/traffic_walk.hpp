// Test helper: drives a scene's traffic and shows every vehicle's footprint at every step, for
// the tests that check that no vehicle, parked or moving, overlaps a static object.
#pragma once

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scene.hpp"
#include "shape/vehicle_model.hpp"
#include "traffic.hpp"
#include "vehicles.hpp"

namespace vp::sim::testing {

// The default ASM's vehicle factory (loaded once; a failed load fails the calling test).
inline const VehicleFactory& defaultFactory() {
  static const shape::ActiveShapeModel asmModel = [] {
    shape::ActiveShapeModel m;
    std::string why;
    EXPECT_TRUE(m.load(std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml", &why)) << why;
    return m;
  }();
  static const VehicleFactory factory(asmModel);
  return factory;
}

// 30 s of traffic (300 steps of 0.1 s) after a 30 s warm-up, drawn from rng; visit(vehicle,
// footprint, step) for each vehicle at each step.
template <typename Visit>
void walkTraffic(const SceneSpec& scene, Rng& rng, Visit&& visit) {
  Traffic traffic;
  traffic.init(scene, defaultFactory(), 120.0, 30.0, 0.1, rng);
  for (int step = 0; step < 300; ++step) {
    for (const auto& v : traffic.vehicles()) {
      const Eigen::Vector2d f(std::cos(v.rear.psi), std::sin(v.rear.psi));
      const Footprint footprint{v.centre() + 0.5 * (v.model->frontXM + v.model->rearXM) * f, f,
                                0.5 * (v.model->frontXM - v.model->rearXM), v.model->halfWidth_m};
      visit(v, footprint, step);
    }
    traffic.step(rng);
  }
}

}  // namespace vp::sim::testing
