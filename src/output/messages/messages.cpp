// messages/messages: names and validation of the published states.
#include "messages/messages.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vp::messages {
namespace {

bool finite(double value) {
  return std::isfinite(value);
}

template <class Array>
bool allFinite(const Array& values) {
  return std::all_of(values.begin(), values.end(), [](auto v) { return std::isfinite(v); });
}

constexpr std::uint8_t kMaxUtmZone = 60;

}  // namespace

const char* toString(ValidationError error) {
  switch (error) {
    case ValidationError::None:
      return "ok";
    case ValidationError::NotFinite:
      return "a value is NaN or infinite";
    case ValidationError::InvalidPosition:
      return "WGS84 position out of range";
    case ValidationError::HeadingOutOfRange:
      return "heading out of [0, 2pi) / [0, 360)";
    case ValidationError::NegativeDimension:
      return "negative length, width or height";
    case ValidationError::ProbabilityOutOfRange:
      return "probability or confidence outside [0, 1]";
    case ValidationError::ShapeCountOutOfRange:
      return "ASM component count outside [0, kMaxShapeComponents]";
    case ValidationError::GridSizeMismatch:
      return "occupancy grid cells do not match rows * cols";
    case ValidationError::UtmZoneOutOfRange:
      return "UTM zone outside 0 (not computed) .. 60";
    case ValidationError::KeypointCountOutOfRange:
      return "keypoint count neither 0 nor kKeypointCount";
    case ValidationError::NegativeVariance:
      return "negative length or width variance";
  }
  return "unknown";
}

void DroneStatus::setModelId(std::string_view id) {
  const std::size_t n = std::min(id.size(), kModelIdCapacity);
  std::copy_n(id.data(), n, modelId.data());
  modelId[n] = '\0';
}

void OccupancyGrid::resize(std::uint32_t rowCount, std::uint32_t colCount) {
  rows = rowCount;
  cols = colCount;
  cells.assign(static_cast<std::size_t>(rows) * cols,
               static_cast<std::uint8_t>(Occupancy::Unobserved));
}

ValidationError validate(const VehicleState& s) {
  const bool scalarsFinite = finite(s.headingEnu_rad) && finite(s.headingTrueNorth_deg) &&
                             finite(s.speed_mps) && finite(s.yawRate_radps) &&
                             finite(s.acceleration_mps2) && finite(s.length_m) &&
                             finite(s.width_m) && finite(s.height_m) && finite(s.trackAge_s) &&
                             finite(s.heightVariance_m2) && finite(s.speedVariance_m2ps2) &&
                             finite(s.yawRateVariance_rad2ps2) && finite(s.detectionConfidence) &&
                             finite(s.utmEasting_m) && finite(s.utmNorthing_m) &&
                             finite(s.lengthVariance_m2) && finite(s.widthVariance_m2);
  const bool keypointsFinite =
      std::all_of(s.keypointsEnu_m.begin(), s.keypointsEnu_m.end(),
                  [](const std::array<float, 3>& p) { return allFinite(p); });
  if (!scalarsFinite || !allFinite(s.enu_m) || !allFinite(s.velocityEnu_mps) ||
      !allFinite(s.typeProbability) || !allFinite(s.shape.gamma) || !allFinite(s.poseCovariance) ||
      !allFinite(s.rearAxleEnu_m) || !keypointsFinite) {
    return ValidationError::NotFinite;
  }
  if (!geodesy::isValid(s.position) || !geodesy::isValid(s.rearAxlePosition)) {
    return ValidationError::InvalidPosition;
  }
  if (s.headingEnu_rad < 0.0 || s.headingEnu_rad >= 2.0 * std::numbers::pi ||
      s.headingTrueNorth_deg < 0.0 || s.headingTrueNorth_deg >= 360.0) {
    return ValidationError::HeadingOutOfRange;
  }
  if (s.length_m < 0.0F || s.width_m < 0.0F || s.height_m < 0.0F) {
    return ValidationError::NegativeDimension;
  }
  const auto outside01 = [](float p) { return p < 0.0F || p > 1.0F; };
  if (outside01(s.detectionConfidence) ||
      std::any_of(s.typeProbability.begin(), s.typeProbability.end(), outside01)) {
    return ValidationError::ProbabilityOutOfRange;
  }
  if (s.shape.count < 0 || s.shape.count > shape::kMaxShapeComponents) {
    return ValidationError::ShapeCountOutOfRange;
  }
  if (s.utmZone > kMaxUtmZone) {
    return ValidationError::UtmZoneOutOfRange;
  }
  if (s.keypointCount != 0 && s.keypointCount != shape::kKeypointCount) {
    return ValidationError::KeypointCountOutOfRange;
  }
  if (s.lengthVariance_m2 < 0.0F || s.widthVariance_m2 < 0.0F) {
    return ValidationError::NegativeVariance;
  }
  return ValidationError::None;
}

ValidationError validate(const OccupancyGrid& grid) {
  if (!finite(grid.originEast_m) || !finite(grid.originNorth_m) ||
      !std::isfinite(grid.resolution_m) || grid.resolution_m <= 0.0F) {
    return ValidationError::NotFinite;
  }
  if (grid.cells.size() != static_cast<std::size_t>(grid.rows) * grid.cols) {
    return ValidationError::GridSizeMismatch;
  }
  return ValidationError::None;
}

}  // namespace vp::messages
