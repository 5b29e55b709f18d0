#include "preprocess/working_scale.hpp"

#include <algorithm>
#include <cmath>

namespace vp::preprocess {

std::size_t buildScaleLadder(double anchor, double minScale, double maxScale,
                             std::span<double> out) {
  const double top = std::min(maxScale, 1.0);
  if (!(anchor > 0.0) || !(minScale > 0.0) || anchor < minScale || anchor > top) {
    return 0;
  }
  // Rungs below and above the anchor, counted in whole steps; a tiny tolerance keeps a bound
  // that is itself a rung (e.g. 0.125 = 0.25 / 2) inside.
  const double logStep = std::log(kScaleStep);
  const int below = static_cast<int>(std::floor(std::log(anchor / minScale) / logStep + 1e-9));
  const int above = static_cast<int>(std::floor(std::log(top / anchor) / logStep + 1e-9));
  const std::size_t count = static_cast<std::size_t>(below + above + 1);
  if (count > out.size()) {
    return 0;
  }
  for (int k = -below; k <= above; ++k) {
    out[static_cast<std::size_t>(k + below)] = k == 0 ? anchor : anchor * std::pow(kScaleStep, k);
  }
  return count;
}

std::size_t chooseRung(std::span<const double> ladder, std::size_t current, double idealScale,
                       double hysteresis_rungs) {
  if (ladder.empty() || current >= ladder.size() || !(idealScale > 0.0) ||
      !std::isfinite(idealScale)) {
    return current;
  }
  const double logStep = std::log(kScaleStep);
  const double offset = std::log(idealScale / ladder[current]) / logStep;  // in rungs
  if (std::abs(offset) <= hysteresis_rungs) {
    return current;
  }
  const double target = static_cast<double>(current) + std::round(offset);
  return static_cast<std::size_t>(std::clamp(target, 0.0, static_cast<double>(ladder.size() - 1)));
}

std::size_t fewerTilesRung(std::span<const double> ladder, std::span<const std::size_t> tileCounts,
                           std::size_t ideal, double maxGsdRatio) {
  if (ideal >= ladder.size() || ladder.size() != tileCounts.size() || !(maxGsdRatio > 1.0)) {
    return ideal;
  }
  std::size_t best = ideal;
  for (std::size_t k = ideal; k-- > 0;) {
    if (ladder[ideal] / ladder[k] > maxGsdRatio * (1.0 + 1e-9)) {
      break;  // ascending ladder: every rung further down is coarser still
    }
    if (tileCounts[k] < tileCounts[best]) {
      best = k;
    }
  }
  return best;
}

}  // namespace vp::preprocess
