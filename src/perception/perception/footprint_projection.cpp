#include "perception/footprint_projection.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace vp::perception {

Expected<geometry::RotatedBox, lifting::LiftError> footprintToImageBox(
    const lifting::Lifter& lifter, const lifting::CameraPoseWorld& cameraPose,
    const terrain::TerrainModel& terrain, const shape::GroundFootprint& footprint) {
  const Eigen::Vector2d f(std::cos(footprint.headingEnu_rad), std::sin(footprint.headingEnu_rad));
  const Eigen::Vector2d n(-f.y(), f.x());  // left of the driving direction
  const Eigen::Vector2d c = footprint.centreEnu.head<2>();
  const double halfL = 0.5 * footprint.length_m;
  const double halfW = 0.5 * footprint.width_m;
  // Front two first (left, right), then rear right, rear left, as geometry::corners().
  const std::array<Eigen::Vector2d, 4> cornersXy = {
      c + halfL * f + halfW * n, c + halfL * f - halfW * n, c - halfL * f - halfW * n,
      c - halfL * f + halfW * n};
  std::array<Eigen::Vector2d, 4> pixels;
  for (std::size_t i = 0; i < cornersXy.size(); ++i) {
    const auto ground = terrain.groundPointEnu(cornersXy[i].x(), cornersXy[i].y());
    if (!ground) {
      return unexpected(ground.error() == terrain::TerrainError::NoData
                            ? lifting::LiftError::NoData
                            : lifting::LiftError::OutsideDtm);
    }
    const auto pixel = lifter.worldToPixel(cameraPose, *ground);
    if (!pixel) {
      return unexpected(pixel.error());
    }
    pixels[i] = *pixel;
  }
  const auto centre = lifter.worldToPixel(cameraPose, footprint.centreEnu);
  if (!centre) {
    return unexpected(centre.error());
  }
  // The rectangle through the projected edge midpoints: its axis is the projected driving
  // direction, its length the distance between the projected front and rear midpoints, its
  // width the spread of the projected side midpoints across that axis. (The rectangle
  // enclosing the projected corners would be longer and wider wherever perspective skews the
  // footprint, and lifting it would overstate the size.)
  const Eigen::Vector2d forward = 0.5 * (pixels[0] + pixels[1]) - 0.5 * (pixels[2] + pixels[3]);
  const Eigen::Vector2d across = 0.5 * (pixels[0] + pixels[3]) - 0.5 * (pixels[1] + pixels[2]);
  const double angle = geometry::wrapTwoPi(std::atan2(forward.y(), forward.x()));
  const Eigen::Vector2d normal(-std::sin(angle), std::cos(angle));
  geometry::RotatedBox box;
  box.cx = centre->x();
  box.cy = centre->y();
  box.length = forward.norm();
  box.width = std::abs(across.dot(normal));
  box.angle = angle;
  return box;
}

}  // namespace vp::perception
