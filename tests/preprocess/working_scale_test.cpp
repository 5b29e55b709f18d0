// Working-scale ladder: the rungs the preprocessor prepares and the hysteresis of the choice.
#include "preprocess/working_scale.hpp"

#include <array>
#include <cmath>

#include <gtest/gtest.h>

namespace vp::preprocess {
namespace {

TEST(WorkingScaleLadder, HoldsTheAnchorExactlyAndStepsBetweenTheBounds) {
  std::array<double, kMaxScaleRungs> ladder{};
  const std::size_t n = buildScaleLadder(0.25, 0.125, 1.0, ladder);
  ASSERT_EQ(n, 25U);  // 8 rungs down to 0.125, 16 up to 1.0
  EXPECT_EQ(ladder[8], 0.25);
  EXPECT_NEAR(ladder[0], 0.125, 1e-12);
  EXPECT_NEAR(ladder[24], 1.0, 1e-12);
  for (std::size_t i = 1; i < n; ++i) {
    EXPECT_NEAR(ladder[i] / ladder[i - 1], kScaleStep, 1e-12) << i;
  }
  // Bounds that are not rungs: only the rungs inside them, never above 1.
  const std::size_t m = buildScaleLadder(0.4, 0.3, 2.0, ladder);
  ASSERT_GT(m, 0U);
  EXPECT_GE(ladder[0], 0.3);
  EXPECT_LE(ladder[m - 1], 1.0);
  EXPECT_GT(ladder[m - 1] * kScaleStep, 1.0);
}

TEST(WorkingScaleLadder, RefusesAnAnchorOutsideTheBoundsOrTooManyRungs) {
  std::array<double, kMaxScaleRungs> ladder{};
  EXPECT_EQ(buildScaleLadder(0.1, 0.125, 1.0, ladder), 0U);
  EXPECT_EQ(buildScaleLadder(0.0, 0.0, 1.0, ladder), 0U);
  std::array<double, 4> small{};
  EXPECT_EQ(buildScaleLadder(0.25, 0.125, 1.0, small), 0U);
  EXPECT_EQ(buildScaleLadder(0.25, 0.25, 0.25, small), 1U);
}

TEST(WorkingScaleLadder, MovesOnlyBeyondTheHysteresisToTheNearestRung) {
  std::array<double, kMaxScaleRungs> ladder{};
  const std::size_t n = buildScaleLadder(0.25, 0.125, 1.0, ladder);
  const std::span<const double> rungs(ladder.data(), n);
  // Half a rung up or down: stays.
  EXPECT_EQ(chooseRung(rungs, 8, 0.25 * std::pow(kScaleStep, 0.5)), 8U);
  EXPECT_EQ(chooseRung(rungs, 8, 0.25 * std::pow(kScaleStep, -0.7)), 8U);
  // Twice the GSD (a drone twice as high): eight rungs up, exactly 0.5.
  EXPECT_EQ(chooseRung(rungs, 8, 0.5), 16U);
  EXPECT_EQ(chooseRung(rungs, 8, 0.25 * std::pow(kScaleStep, 1.2)), 9U);
  // Clamped to the ladder; unusable ideals keep the rung.
  EXPECT_EQ(chooseRung(rungs, 8, 5.0), n - 1);
  EXPECT_EQ(chooseRung(rungs, 8, 0.01), 0U);
  EXPECT_EQ(chooseRung(rungs, 8, 0.0), 8U);
  EXPECT_EQ(chooseRung(rungs, 8, std::nan("")), 8U);
}

TEST(WorkingScaleLadder, FewerTilesRungStepsDownOnlyWithinTheGsdRatio) {
  const std::array<double, 5> ladder{0.2, 0.22, 0.24, 0.26, 0.28};
  const std::array<std::size_t, 5> tiles{1, 1, 2, 4, 4};
  // From 0.28 (4 tiles): 0.24 (2 tiles) is 1.167x coarser, 0.22 (1 tile) 1.27x.
  EXPECT_EQ(fewerTilesRung(ladder, tiles, 4, 1.2), 2U);
  EXPECT_EQ(fewerTilesRung(ladder, tiles, 4, 1.3), 1U);   // the finest of the 1-tile rungs
  EXPECT_EQ(fewerTilesRung(ladder, tiles, 4, 1.05), 4U);  // 0.26 has as many tiles: stay
  EXPECT_EQ(fewerTilesRung(ladder, tiles, 1, 2.0), 1U);   // nothing fewer than 1 tile
  EXPECT_EQ(fewerTilesRung(ladder, tiles, 4, 1.0), 4U);   // off
  EXPECT_EQ(fewerTilesRung(ladder, std::span<const std::size_t>(tiles.data(), 4), 4, 2.0), 4U);
}

}  // namespace
}  // namespace vp::preprocess
