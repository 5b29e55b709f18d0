// Twin car draws for the tests of the simulator's per-car options (two-tone roofs, city cars,
// pickups): two factories, one without the option and one with it, fed the same seed. The
// options draw from each car's own shape, so both factories must draw the same types and looks
// from the sequence stream (checked here); each test checks what its option changes.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "vehicles.hpp"

namespace vp::sim::test {

// Draws `count` cars from each factory and calls check(type, plain car, car with the option).
template <typename Check>
void forEachTwinCar(const VehicleFactory& plain, const VehicleFactory& withOption,
                    std::uint64_t seed, int count, Check&& check) {
  Rng rngPlain(seed);
  Rng rngOption(seed);
  for (int i = 0; i < count; ++i) {
    const shape::VehicleType type = plain.drawCarType(rngPlain);
    ASSERT_EQ(withOption.drawCarType(rngOption), type) << "car " << i;
    const auto a = plain.makeCar(rngPlain, type);
    const auto b = withOption.makeCar(rngOption, type);
    EXPECT_TRUE(a->look.paint.isApprox(b->look.paint)) << "car " << i << ": the stream moved";
    check(type, *a, *b);
  }
}

}  // namespace vp::sim::test
