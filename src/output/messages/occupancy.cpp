// messages/occupancy: grid rasterisation by cell-centre tests.
#include "messages/occupancy.hpp"

#include <algorithm>
#include <cmath>

namespace vp::messages {
namespace {

// Even-odd rule; points exactly on an edge may fall either way, which is fine at cell scale.
bool insidePolygon(std::span<const Eigen::Vector2d> polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

}  // namespace

void rasterizeOccupancy(std::span<const Eigen::Vector2d> observedPolygon,
                        std::span<const VehicleState> vehicles, OccupancyGrid& grid) {
  const double res = static_cast<double>(grid.resolution_m);
  const auto centre = [&](std::uint32_t row, std::uint32_t col) {
    return Eigen::Vector2d(grid.originEast_m + (col + 0.5) * res,
                           grid.originNorth_m + (row + 0.5) * res);
  };
  for (std::uint32_t row = 0; row < grid.rows; ++row) {
    for (std::uint32_t col = 0; col < grid.cols; ++col) {
      const bool seen =
          observedPolygon.size() >= 3 && insidePolygon(observedPolygon, centre(row, col));
      grid.cells[static_cast<std::size_t>(row) * grid.cols + col] =
          static_cast<std::uint8_t>(seen ? Occupancy::Free : Occupancy::Unobserved);
    }
  }
  for (const VehicleState& v : vehicles) {
    if (v.status == TrackStatus::Tentative) {
      continue;
    }
    const double c = std::cos(v.headingEnu_rad);
    const double s = std::sin(v.headingEnu_rad);
    const double halfL = 0.5 * static_cast<double>(v.length_m);
    const double halfW = 0.5 * static_cast<double>(v.width_m);
    // Only the cells under the footprint's bounding box are tested.
    const double extentE = std::abs(c) * halfL + std::abs(s) * halfW;
    const double extentN = std::abs(s) * halfL + std::abs(c) * halfW;
    const auto clampIndex = [](double value, std::uint32_t count) {
      return static_cast<std::int64_t>(
          std::clamp(value, 0.0, static_cast<double>(count)));  // [0, count]
    };
    const std::int64_t col0 =
        clampIndex(std::floor((v.enu_m[0] - extentE - grid.originEast_m) / res), grid.cols);
    const std::int64_t col1 =
        clampIndex(std::ceil((v.enu_m[0] + extentE - grid.originEast_m) / res), grid.cols);
    const std::int64_t row0 =
        clampIndex(std::floor((v.enu_m[1] - extentN - grid.originNorth_m) / res), grid.rows);
    const std::int64_t row1 =
        clampIndex(std::ceil((v.enu_m[1] + extentN - grid.originNorth_m) / res), grid.rows);
    for (std::int64_t row = row0; row < row1; ++row) {
      for (std::int64_t col = col0; col < col1; ++col) {
        const Eigen::Vector2d d =
            centre(static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(col)) -
            Eigen::Vector2d(v.enu_m[0], v.enu_m[1]);
        const double along = c * d.x() + s * d.y();
        const double across = -s * d.x() + c * d.y();
        if (std::abs(along) <= halfL && std::abs(across) <= halfW) {
          grid.cells[static_cast<std::size_t>(row) * grid.cols + static_cast<std::size_t>(col)] =
              static_cast<std::uint8_t>(Occupancy::Occupied);
        }
      }
    }
  }
}

}  // namespace vp::messages
