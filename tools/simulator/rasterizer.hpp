// simulator/rasterizer: a software triangle rasterizer with a z-buffer and a triangle-index
// (hence object-id) buffer, in an ideal pinhole camera, plus an orthographic shadow map
// along the sun direction.
//
// Contract: triangles are in the world ENU frame (float, metres) and reference a surface
// (material, albedo, object id). rasterize() fills per-sample inverse depth (1 / z_camera)
// and triangle index (-1: nothing) on a sample grid; a sample is covered when its centre
// lies inside the triangle (edge functions, shared edges covered by both sides, the z-test
// decides); the nearest surface wins, ties go to the earlier triangle. Triangles with a
// vertex closer than 0.3 m to the camera plane are culled (the camera is far above the
// scene). Canopy surfaces are alpha-tested by canopyOpaque() (leaf gaps), in the camera and
// in the shadow map alike. Work is split into horizontal strips over `threads` threads;
// each sample is written by one strip only, so the result does not depend on the threads.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vehicles.hpp"

namespace vp::sim {

struct RenderSurface {
  Material material = Material::Ground;
  Eigen::Vector3f albedo{0.5F, 0.5F, 0.5F};
  float specular = 0.0F;
  float shininess = 20.0F;
  int objectId = 0;  // 0: ground; > 0: vehicle track id; < 0: buildings and trees
  std::uint32_t seed = 0;
  float param = 0.0F;                      // canopy: gap fraction; wall: base height (z)
  Eigen::Vector3f axis{1.0F, 0.0F, 0.0F};  // wall: horizontal direction along the wall
};

struct RenderTriangle {
  std::array<Eigen::Vector3f, 3> p{};  // world ENU
  std::array<Eigen::Vector3f, 3> n{};  // corner normals (unit)
  std::uint32_t surface = 0;
};

// True where a canopy is opaque (leaves or branches) at world point p.
bool canopyOpaque(const RenderSurface& surface, const Eigen::Vector3f& p);

// Ideal pinhole camera on a sample grid (pixel centres at integers).
struct PinholeView {
  Eigen::Matrix3d worldToCamera = Eigen::Matrix3d::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double fx = 1.0;
  double fy = 1.0;
  double cx = 0.0;
  double cy = 0.0;
  int width = 0;
  int height = 0;

  // World point on the viewing ray of sample (x, y) at camera depth z.
  Eigen::Vector3d unproject(double x, double y, double z) const;
};

struct SampleBuffers {
  int width = 0;
  int height = 0;
  std::vector<float> invDepth;         // 1 / z_camera, 0 where empty
  std::vector<std::int32_t> triangle;  // index into the triangle list, -1 where empty
  void reset(int w, int h);
};

void rasterize(const std::vector<RenderTriangle>& triangles,
               const std::vector<RenderSurface>& surfaces, const PinholeView& view,
               SampleBuffers& out, int threads);

// Rasterizes the silhouette of a subset of triangles (no depth test) on the sample grid,
// unclipped by the grid: calls visit(x, y) for every covered sample centre (each once).
template <typename Visit>
void rasterizeSilhouette(const std::vector<RenderTriangle>& triangles, std::size_t first,
                         std::size_t count, const PinholeView& view,
                         std::vector<std::uint8_t>& scratch, Visit&& visit);

// The static casters (buildings, trees) are added once per sequence and finished; each frame
// then goes back to them (restoreFrom: only the blocks vehicles touched) and adds the
// vehicles as dynamic casters. Per block of kBlock x kBlock texels the map keeps the highest
// and lowest texel of the block and its 8 neighbours, so points above every caster nearby
// (most of the ground) or below all of them (the core of a shadow) need no filtering.
class ShadowMap {
 public:
  // Covers the receivers' bounding box (world) as seen along sunDirection (unit, towards the
  // sun) with square texels of about texel_m (enlarged to keep within maxSize per side).
  void init(const Eigen::Vector3d& sunDirection, const Eigen::Vector3d& boxMin,
            const Eigen::Vector3d& boxMax, double texel_m, int maxSize);
  void clear();
  // A static caster; finishStatic() after the last one.
  void add(const RenderTriangle& triangle, const RenderSurface& surface);
  void finishStatic();
  // Back to the static casters of `base` (a finished copy of this map's static state).
  void restoreFrom(const ShadowMap& base);
  // A caster of this frame (vehicle); finishDynamic() after the last one.
  void addDynamic(const RenderTriangle& triangle, const RenderSurface& surface);
  void finishDynamic();
  // Share of the sun visible from p (percentage-closer filtering over radius texels,
  // radius <= kBlock - 2).
  float visibility(const Eigen::Vector3f& p, float radiusTexels) const;
  // True when every point of the world box [lo, hi] is certainly in full sun.
  bool boxLit(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  // True where a dynamic caster may shadow p (its filter footprint meets a touched block).
  bool dynamicNear(const Eigen::Vector3f& p) const;
  double texel_m() const { return texel_; }

 private:
  static constexpr int kBlock = 8;
  template <bool kDynamic>
  void draw(const RenderTriangle& triangle, const RenderSurface& surface);
  void summarize(std::size_t block);
  void updateNear(int bx, int by);
  std::size_t blockOf(double fx, double fy) const;

  Eigen::Vector3d e1_ = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2_ = Eigen::Vector3d::UnitY();
  Eigen::Vector3d s_ = Eigen::Vector3d::UnitZ();
  double a0_ = 0.0;
  double b0_ = 0.0;
  double texel_ = 0.05;
  int width_ = 0;
  int height_ = 0;
  std::vector<float> top_;  // highest caster along the sun direction (p . s), -inf if none
  int blocksX_ = 0;
  int blocksY_ = 0;
  std::vector<float> blockTop_;            // highest caster in the block
  std::vector<float> blockLow_;            // lowest texel (-inf: no caster) in the block
  std::vector<float> nearTop_;             // highest caster in the block and its neighbours
  std::vector<float> nearLow_;             // lowest texel there (-inf at the map's border)
  std::vector<std::uint8_t> dynamicNear_;  // a dynamic caster in the block or a neighbour
  std::vector<std::uint8_t> dirty_;        // block touched by a dynamic caster
  std::vector<std::size_t> dirtyList_;
};

// --- implementation of the template ---------------------------------------------------------

template <typename Visit>
void rasterizeSilhouette(const std::vector<RenderTriangle>& triangles, std::size_t first,
                         std::size_t count, const PinholeView& view,
                         std::vector<std::uint8_t>& scratch, Visit&& visit) {
  struct P2 {
    double x, y;
  };
  std::vector<std::array<P2, 3>> projected;
  projected.reserve(count);
  double minX = 1e18, minY = 1e18, maxX = -1e18, maxY = -1e18;
  for (std::size_t t = first; t < first + count; ++t) {
    std::array<P2, 3> q{};
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d c =
          view.worldToCamera *
          (triangles[t].p[static_cast<std::size_t>(k)].cast<double>() - view.centre);
      if (c.z() < 0.3) {
        ok = false;
        break;
      }
      q[static_cast<std::size_t>(k)] = {view.fx * c.x() / c.z() + view.cx,
                                        view.fy * c.y() / c.z() + view.cy};
      minX = std::min(minX, q[static_cast<std::size_t>(k)].x);
      maxX = std::max(maxX, q[static_cast<std::size_t>(k)].x);
      minY = std::min(minY, q[static_cast<std::size_t>(k)].y);
      maxY = std::max(maxY, q[static_cast<std::size_t>(k)].y);
    }
    if (ok) {
      projected.push_back(q);
    }
  }
  if (projected.empty()) {
    return;
  }
  const int x0 = static_cast<int>(std::ceil(minX));
  const int y0 = static_cast<int>(std::ceil(minY));
  const int x1 = static_cast<int>(std::floor(maxX));
  const int y1 = static_cast<int>(std::floor(maxY));
  if (x1 < x0 || y1 < y0 || static_cast<long>(x1 - x0 + 1) * (y1 - y0 + 1) > 40'000'000L) {
    return;
  }
  const int w = x1 - x0 + 1;
  scratch.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(y1 - y0 + 1), 0);
  for (const auto& q : projected) {
    const double area =
        (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
    if (std::fabs(area) < 1e-12) {
      continue;
    }
    const double sign = area > 0 ? 1.0 : -1.0;
    const int tx0 = std::max(x0, static_cast<int>(std::ceil(std::min({q[0].x, q[1].x, q[2].x}))));
    const int tx1 = std::min(x1, static_cast<int>(std::floor(std::max({q[0].x, q[1].x, q[2].x}))));
    const int ty0 = std::max(y0, static_cast<int>(std::ceil(std::min({q[0].y, q[1].y, q[2].y}))));
    const int ty1 = std::min(y1, static_cast<int>(std::floor(std::max({q[0].y, q[1].y, q[2].y}))));
    for (int y = ty0; y <= ty1; ++y) {
      for (int x = tx0; x <= tx1; ++x) {
        bool inside = true;
        for (int e = 0; e < 3 && inside; ++e) {
          const P2& a = q[static_cast<std::size_t>(e)];
          const P2& b = q[static_cast<std::size_t>((e + 1) % 3)];
          inside = sign * ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) >= 0.0;
        }
        if (inside) {
          scratch[static_cast<std::size_t>(y - y0) * static_cast<std::size_t>(w) +
                  static_cast<std::size_t>(x - x0)] = 1;
        }
      }
    }
  }
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (scratch[static_cast<std::size_t>(y - y0) * static_cast<std::size_t>(w) +
                  static_cast<std::size_t>(x - x0)] != 0) {
        visit(x, y);
      }
    }
  }
}

}  // namespace vp::sim
