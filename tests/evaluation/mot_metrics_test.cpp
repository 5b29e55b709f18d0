// Tests for evaluation/mot_metrics on hand-made sequences with known answers.
#include "evaluation/mot_metrics.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace vp::evaluation {
namespace {

MotObject obj(int id, double x, double y = 0.0) {
  MotObject o;
  o.id = id;
  o.position = {x, y};
  return o;
}

TEST(MotMetrics, PerfectTracking) {
  MotAccumulator acc;
  for (int k = 0; k < 5; ++k) {
    const std::vector<MotObject> truth = {obj(1, k), obj(2, k, 10.0)};
    const std::vector<MotObject> hyp = {obj(7, k + 0.1), obj(8, k, 10.2)};
    acc.addFrame(truth, hyp);
  }
  const MotSummary s = acc.summary();
  EXPECT_DOUBLE_EQ(s.mota, 1.0);
  EXPECT_NEAR(s.motp_m, 0.15, 1e-9);
  EXPECT_DOUBLE_EQ(s.idf1, 1.0);
  EXPECT_EQ(s.idSwitches, 0);
  EXPECT_EQ(s.mostlyTracked, 2);
  EXPECT_EQ(s.mostlyLost, 0);
}

TEST(MotMetrics, IdSwitchMissAndFragmentation) {
  // Truth 1 over 4 frames: hyp A on frames 0-1, nothing on 2, hyp B on 3.
  MotAccumulator acc;
  acc.addFrame(std::vector{obj(1, 0.0)}, std::vector{obj(100, 0.0)});
  acc.addFrame(std::vector{obj(1, 1.0)}, std::vector{obj(100, 1.0)});
  acc.addFrame(std::vector{obj(1, 2.0)}, std::vector<MotObject>{});
  acc.addFrame(std::vector{obj(1, 3.0)}, std::vector{obj(200, 3.0)});
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.matches, 3);
  EXPECT_EQ(s.misses, 1);
  EXPECT_EQ(s.idSwitches, 1);
  EXPECT_EQ(s.fragmentations, 1);
  EXPECT_EQ(s.falsePositives, 0);
  EXPECT_DOUBLE_EQ(s.mota, 1.0 - 2.0 / 4.0);
  // IDTP = 2 (truth 1 <-> hyp 100), truth objects 4, hypotheses 3: IDF1 = 4 / 7.
  EXPECT_NEAR(s.idf1, 4.0 / 7.0, 1e-12);
  EXPECT_EQ(s.mostlyTracked, 0);  // 3 of 4 = 75 %: partially tracked
  EXPECT_EQ(s.partiallyTracked, 1);
}

TEST(MotMetrics, FalsePositivesFarMatchesAndStickyCorrespondence) {
  MotAccumulator acc(MotParams{1.0, 0.8, 0.2});
  // Frame 0: truth 1 matched to hyp 5; hyp 6 far away is a false positive.
  acc.addFrame(std::vector{obj(1, 0.0)}, std::vector{obj(5, 0.5), obj(6, 30.0)});
  // Frame 1: hyp 7 is nearer, but hyp 5 is still within 1 m: the match is kept (no switch).
  acc.addFrame(std::vector{obj(1, 0.0)}, std::vector{obj(5, 0.9), obj(7, 0.1)});
  // Frame 2: hyp 5 beyond 1 m: miss by distance, hyp 5 is a false positive.
  acc.addFrame(std::vector{obj(1, 0.0)}, std::vector{obj(5, 1.5)});
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.matches, 2);
  EXPECT_EQ(s.idSwitches, 0);
  EXPECT_EQ(s.falsePositives, 3);
  EXPECT_EQ(s.misses, 1);
  EXPECT_DOUBLE_EQ(s.mota, 1.0 - 4.0 / 3.0);
  EXPECT_NEAR(s.motp_m, 0.7, 1e-12);
}

TEST(MotMetrics, MostlyLostSpeedHeadingAndType) {
  MotAccumulator acc;
  for (int k = 0; k < 10; ++k) {
    MotObject t = obj(1, k);
    t.speed_mps = 10.0;
    t.heading_rad = 0.0;
    t.type = 3;
    std::vector<MotObject> hyp;
    if (k < 2) {
      MotObject h = obj(9, k);
      h.speed_mps = k == 0 ? 12.0 : 10.0;
      h.heading_rad = k == 0 ? 3.0 : 0.1;
      h.type = k == 0 ? 3 : 2;
      hyp.push_back(h);
    }
    acc.addFrame(std::vector{t, obj(2, k, 50.0)}, hyp);
  }
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.mostlyLost, 2);  // 2 of 10 = 20 % and 0 %
  EXPECT_EQ(s.speedSamples, 2);
  EXPECT_NEAR(s.speedRmse_mps, std::sqrt(2.0), 1e-12);
  EXPECT_EQ(s.headingOver90, 1);
  EXPECT_EQ(s.typeCorrect, 1);
  EXPECT_EQ(s.typeSamples, 2);
}

}  // namespace
}  // namespace vp::evaluation
