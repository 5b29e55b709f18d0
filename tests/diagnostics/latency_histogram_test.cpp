#include "diagnostics/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "alloc_counter.hpp"

namespace {

using vp::diagnostics::LatencyHistogram;

TEST(LatencyHistogram, QuantilesWithinOneBinOfTheExactOnes) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> latency(std::log(20e6), 0.6);  // ~20 ms median
  LatencyHistogram h;
  std::vector<std::int64_t> values;
  for (int i = 0; i < 20000; ++i) {
    const auto ns = static_cast<std::int64_t>(latency(rng));
    values.push_back(ns);
    h.record(ns);
  }
  std::sort(values.begin(), values.end());
  for (const double q : {0.5, 0.9, 0.99}) {
    const double exact =
        static_cast<double>(values[static_cast<std::size_t>(q * values.size()) - 1]);
    const double estimate = static_cast<double>(h.quantile_ns(q));
    // upper bin edge: never below the exact value by more than rounding, at most 1/8 octave above
    EXPECT_GE(estimate, exact * 0.999) << q;
    EXPECT_LE(estimate, exact * 1.0906) << q;
  }
  EXPECT_EQ(h.count(), 20000U);
  EXPECT_EQ(h.max_ns(), values.back());
  EXPECT_EQ(h.min_ns(), values.front());
}

TEST(LatencyHistogram, OutOfSpanValuesAreCountedAndClamped) {
  LatencyHistogram h;
  h.record(-5);
  h.record(10);
  h.record(100'000'000'000);  // 100 s
  EXPECT_EQ(h.count(), 3U);
  EXPECT_EQ(h.max_ns(), 100'000'000'000);
  EXPECT_EQ(h.quantile_ns(1.0), 100'000'000'000);
  EXPECT_EQ(h.quantile_ns(0.0), 0);
  h.reset();
  EXPECT_EQ(h.count(), 0U);
  EXPECT_EQ(h.median_ns(), 0);
}

TEST(LatencyHistogram, RecordingAllocatesNothing) {
  LatencyHistogram h;
  vp::test::AllocationCounter allocations;
  for (int i = 0; i < 1000; ++i)
    h.record(i * 12345);
  EXPECT_GT(h.p99_ns(), 0);
  EXPECT_EQ(allocations.count(), 0U);
}

}  // namespace
