#include "evaluation/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vp::evaluation {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double medianInPlace(std::vector<double>& values) {
  if (values.empty()) {
    return kNan;
  }
  const std::size_t n = values.size();
  const std::size_t mid = n / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  const double upper = values[mid];
  if (n % 2 == 1) {
    return upper;
  }
  const double lower =
      *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

}  // namespace

double median(std::span<const double> values) {
  std::vector<double> copy(values.begin(), values.end());
  return medianInPlace(copy);
}

RobustSummary robustSummary(std::span<const double> errors) {
  RobustSummary out;
  out.count = static_cast<int>(errors.size());
  if (errors.empty()) {
    out.median = kNan;
    out.mad = kNan;
    return out;
  }
  std::vector<double> absolute(errors.size());
  std::transform(errors.begin(), errors.end(), absolute.begin(),
                 [](double e) { return std::abs(e); });
  std::vector<double> work = absolute;
  out.median = medianInPlace(work);
  for (std::size_t i = 0; i < absolute.size(); ++i) {
    work[i] = std::abs(absolute[i] - out.median);
  }
  out.mad = kMadToSigma * medianInPlace(work);
  return out;
}

double rootMeanSquare(std::span<const double> values) {
  if (values.empty()) {
    return kNan;
  }
  double sum = 0.0;
  for (const double v : values) {
    sum += v * v;
  }
  return std::sqrt(sum / static_cast<double>(values.size()));
}

std::vector<double> cumulativeShare(std::span<const double> values,
                                    std::span<const double> thresholds) {
  std::vector<double> out(thresholds.size(), kNan);
  if (values.empty()) {
    return out;
  }
  std::vector<double> sorted(values.begin(), values.end());
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    const auto below = std::upper_bound(sorted.begin(), sorted.end(), thresholds[i]);
    out[i] = static_cast<double>(below - sorted.begin()) / static_cast<double>(sorted.size());
  }
  return out;
}

double shareAbove(std::span<const double> values, double threshold) {
  if (values.empty()) {
    return kNan;
  }
  const auto above =
      std::count_if(values.begin(), values.end(), [threshold](double v) { return v > threshold; });
  return static_cast<double>(above) / static_cast<double>(values.size());
}

}  // namespace vp::evaluation
