// evaluation/statistics: the summary statistics of seed 000, section 5.1, over per-vehicle
// errors: the median of the absolute errors (Eq. 7), the median absolute deviation scaled to a
// normal sigma (Eq. 8, Hampel et al. 2005), root mean squares (Eq. 9, 10) and the cumulative
// histogram of absolute errors (the seed's Figure 2).
//
// Contract: pure functions over caller-given values, offline (they copy and sort, so they
// allocate: never call them in the real-time loop). An empty input gives NaN (count 0), never
// an invented 0. Medians of an even count are the mean of the two middle values (numpy's
// definition, so tools/detector/evaluate.py gives the same numbers).
#pragma once

#include <span>
#include <vector>

namespace vp::evaluation {

constexpr double kMadToSigma = 1.4826;  // Eq. 8: MAD of a normal distribution -> its sigma

// Eq. 7 and 8 over errors d_i: median = median(|d_i|), mad = 1.4826 median(| |d_i| - median |).
// The seed writes d_i - median; we take |d_i| throughout (position errors are distances, and
// the orientation errors are reported as absolute values), as evaluate.py does.
struct RobustSummary {
  int count = 0;
  double median = 0.0;  // NaN when count is 0
  double mad = 0.0;     // NaN when count is 0
};

double median(std::span<const double> values);  // NaN when empty
RobustSummary robustSummary(std::span<const double> errors);
// sqrt(mean(values^2)); NaN when empty.
double rootMeanSquare(std::span<const double> values);
// Share of values <= each threshold (the cumulative histogram); NaN entries when empty.
std::vector<double> cumulativeShare(std::span<const double> values,
                                    std::span<const double> thresholds);
// Share of values > threshold; NaN when empty.
double shareAbove(std::span<const double> values, double threshold);

}  // namespace vp::evaluation
