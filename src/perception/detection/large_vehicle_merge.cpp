#include "detection/large_vehicle_merge.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotated_box.hpp"

namespace vp::detection {
namespace {

bool mostLikelyLarge(const Detection& d) {
  return topTwoTypes(d).first == shape::VehicleType::Large;
}

// Tries to stretch `into` over `part` (contract); true when it did.
bool tryMerge(Detection& into, const Detection& part, double gsd_m,
              const LargeVehicleMergeOptions& options) {
  const geometry::RotatedBox& a = into.box;
  const geometry::RotatedBox& b = part.box;
  if (geometry::axisAngleDifference(a.angle, b.angle) >
      options.maxAxisAngle_deg * geometry::kPi / 180.0) {
    return false;
  }
  const double c = std::cos(a.angle);
  const double s = std::sin(a.angle);
  const double du = b.cx - a.cx;
  const double dv = b.cy - a.cy;
  const double along = c * du + s * dv;
  const double across = -s * du + c * dv;
  if (std::abs(across) > options.maxLateralShare * std::min(a.width, b.width)) {
    return false;
  }
  const double lowA = -0.5 * a.length;
  const double highA = 0.5 * a.length;
  const double lowB = along - 0.5 * b.length;
  const double highB = along + 0.5 * b.length;
  if (lowB > highA || lowA > highB) {
    return false;  // a gap between them: two vehicles
  }
  const double low = std::min(lowA, lowB);
  const double high = std::max(highA, highB);
  const double length = high - low;
  if (gsd_m > 0.0 && length * gsd_m > options.maxLength_m) {
    return false;
  }
  const double middle = 0.5 * (low + high);
  into.box.cx += c * middle;
  into.box.cy += s * middle;
  into.box.length = length;
  into.box.width = std::max(a.width, b.width);
  into.score = std::max(into.score, part.score);
  return true;
}

}  // namespace

bool absorbLongerDuplicate(Detection& kept, const Detection& duplicate, double gsd_m,
                           const LargeVehicleMergeOptions& options) {
  return options.enabled && mostLikelyLarge(kept) && duplicate.box.length > kept.box.length &&
         tryMerge(kept, duplicate, gsd_m, options);
}

std::size_t mergeLargeVehicleParts(std::span<Detection> detections, double gsd_m,
                                   const LargeVehicleMergeOptions& options) {
  if (!options.enabled) {
    return detections.size();
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    bool absorbed = false;
    if (mostLikelyLarge(detections[i])) {
      for (std::size_t k = 0; k < kept && !absorbed; ++k) {
        absorbed = mostLikelyLarge(detections[k]) &&
                   tryMerge(detections[k], detections[i], gsd_m, options);
      }
    }
    if (!absorbed) {
      detections[kept++] = detections[i];
    }
  }
  return kept;
}

}  // namespace vp::detection
