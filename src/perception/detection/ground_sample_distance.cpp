#include "detection/ground_sample_distance.hpp"

#include <algorithm>
#include <cmath>

namespace vp::detection {

bool validate(const GsdOptions& options, std::string* why) {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) {
      *why = "gsd." + message;
    }
    return false;
  };
  if (!(options.fixedGsd_m >= 0.0) || !std::isfinite(options.fixedGsd_m)) {
    return fail("fixed_gsd_m: must be finite and >= 0 (0 = estimate per frame)");
  }
  if (!(options.nominalCarLength_m > 0.0) || !std::isfinite(options.nominalCarLength_m)) {
    return fail("nominal_car_length_m: must be finite and > 0");
  }
  if (!(options.minGsd_m > 0.0) || !(options.maxGsd_m >= options.minGsd_m) ||
      !std::isfinite(options.maxGsd_m)) {
    return fail("min_gsd_m / max_gsd_m: need 0 < min <= max, got " +
                std::to_string(options.minGsd_m) + " / " + std::to_string(options.maxGsd_m));
  }
  return true;
}

double workingScaleForGsd(double gsd_m) {
  if (!(gsd_m > 0.0) || !std::isfinite(gsd_m)) {
    return 0.0;
  }
  return std::min(1.0, gsd_m / kDetectorWorkingGsd_m);
}

double nadirGsd(double heightAboveGround_m, double focalLength_px) {
  if (!(heightAboveGround_m > 0.0) || !(focalLength_px > 0.0)) {
    return 0.0;
  }
  return heightAboveGround_m / focalLength_px;
}

double medianLengthGsd(std::span<const Detection> detections, const GsdOptions& options,
                       std::span<double> scratch) {
  std::size_t n = 0;
  for (const Detection& d : detections) {
    if (n < scratch.size() && d.box.length > 0.0 && std::isfinite(d.box.length)) {
      scratch[n++] = d.box.length;
    }
  }
  if (n == 0) {
    return 0.0;
  }
  const auto middle = scratch.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(scratch.begin(), middle, scratch.begin() + static_cast<std::ptrdiff_t>(n));
  double median = *middle;
  if (n % 2 == 0) {  // numpy's median: mean of the two middle values
    median = 0.5 * (median + *std::max_element(scratch.begin(), middle));
  }
  return std::clamp(options.nominalCarLength_m / median, options.minGsd_m, options.maxGsd_m);
}

}  // namespace vp::detection
