// simulator/mesh_build: small helpers that build flat-shaded static geometry (triangles,
// quads, boxes) for the renderer's buildings, roof fixtures and street furniture.
//
// Contract: every triangle gets its face normal at all three corners (flat shading) and the
// given surface index; boxes are closed except for their bottom.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rasterizer.hpp"

namespace vp::sim {

inline RenderTriangle flatTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c, std::uint32_t surface) {
  RenderTriangle t;
  t.p = {a.cast<float>(), b.cast<float>(), c.cast<float>()};
  Eigen::Vector3f n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
  n = n.norm() > 0 ? n.normalized() : Eigen::Vector3f::UnitZ();
  t.n = {n, n, n};
  t.surface = surface;
  return t;
}

inline void addQuad(std::vector<RenderTriangle>& out, const Eigen::Vector3d& a,
                    const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d,
                    std::uint32_t surface) {
  out.push_back(flatTriangle(a, b, c, surface));
  out.push_back(flatTriangle(a, c, d, surface));
}

// Closed box without its bottom, on (x, y) centre with half sizes, from z0 to z1.
inline void addBox(std::vector<RenderTriangle>& out, const Eigen::Vector2d& c,
                   const Eigen::Vector2d& f, double halfL, double halfW, double z0, double z1,
                   std::uint32_t wall, std::uint32_t top) {
  const Eigen::Vector2d n(-f.y(), f.x());
  std::array<Eigen::Vector2d, 4> k = {c + halfL * f + halfW * n, c - halfL * f + halfW * n,
                                      c - halfL * f - halfW * n, c + halfL * f - halfW * n};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d& a = k[static_cast<std::size_t>(i)];
    const Eigen::Vector2d& b = k[static_cast<std::size_t>((i + 1) % 4)];
    addQuad(out, {a.x(), a.y(), z0}, {b.x(), b.y(), z0}, {b.x(), b.y(), z1}, {a.x(), a.y(), z1},
            wall);
  }
  addQuad(out, {k[0].x(), k[0].y(), z1}, {k[1].x(), k[1].y(), z1}, {k[2].x(), k[2].y(), z1},
          {k[3].x(), k[3].y(), z1}, top);
}

}  // namespace vp::sim
