#include "rasterizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "noise.hpp"

namespace vp::sim {

namespace {

struct Projected {
  double x[3];
  double y[3];
  float iz[3];
  int minX, maxX, minY, maxY;
  bool valid;
};

void rasterStrip(const std::vector<RenderTriangle>& triangles,
                 const std::vector<RenderSurface>& surfaces, const std::vector<Projected>& proj,
                 const PinholeView& view, SampleBuffers& out, int rowBegin, int rowEnd) {
  for (std::size_t t = 0; t < proj.size(); ++t) {
    const Projected& q = proj[t];
    if (!q.valid || q.maxY < rowBegin || q.minY >= rowEnd) {
      continue;
    }
    const double area =
        (q.x[1] - q.x[0]) * (q.y[2] - q.y[0]) - (q.x[2] - q.x[0]) * (q.y[1] - q.y[0]);
    if (std::fabs(area) < 1e-10) {
      continue;
    }
    const double inv = 1.0 / area;
    const RenderSurface& surface = surfaces[triangles[t].surface];
    const bool alpha = surface.material == Material::Canopy;
    const int y0 = std::max(q.minY, rowBegin);
    const int y1 = std::min(q.maxY, rowEnd - 1);
    // Edge e opposite vertex e: E_e(P) = (b - a) x (P - a) with a = v[e+1], b = v[e+2].
    double ex[3];
    double ey[3];
    double e0[3];
    for (int e = 0; e < 3; ++e) {
      const int a = (e + 1) % 3;
      const int b = (e + 2) % 3;
      ex[e] = -(q.y[b] - q.y[a]);
      ey[e] = q.x[b] - q.x[a];
      e0[e] = (q.x[b] - q.x[a]) * (-q.y[a]) - (q.y[b] - q.y[a]) * (-q.x[a]);
    }
    for (int y = y0; y <= y1; ++y) {
      double w[3];
      for (int e = 0; e < 3; ++e) {
        w[e] = (e0[e] + ey[e] * y + ex[e] * q.minX) * inv;
      }
      const double dw[3] = {ex[0] * inv, ex[1] * inv, ex[2] * inv};
      std::size_t idx = static_cast<std::size_t>(y) * static_cast<std::size_t>(out.width) +
                        static_cast<std::size_t>(q.minX);
      for (int x = q.minX; x <= q.maxX; ++x, ++idx) {
        if (w[0] >= 0.0 && w[1] >= 0.0 && w[2] >= 0.0) {
          const auto iz = static_cast<float>(w[0] * static_cast<double>(q.iz[0]) +
                                             w[1] * static_cast<double>(q.iz[1]) +
                                             w[2] * static_cast<double>(q.iz[2]));
          if (iz > out.invDepth[idx]) {
            bool keep = true;
            if (alpha) {
              const Eigen::Vector3d p = view.unproject(x, y, 1.0 / static_cast<double>(iz));
              keep = canopyOpaque(surface, p.cast<float>());
            }
            if (keep) {
              out.invDepth[idx] = iz;
              out.triangle[idx] = static_cast<std::int32_t>(t);
            }
          }
        }
        w[0] += dw[0];
        w[1] += dw[1];
        w[2] += dw[2];
      }
    }
  }
}

}  // namespace

bool canopyOpaque(const RenderSurface& surface, const Eigen::Vector3f& p) {
  const float gap = surface.param;
  if (gap > 0.5F) {
    // Bare crown: a tangle of twigs (thin ridges of 3D noise) and a few dense knots.
    const float n = valueNoise3(p.x() * 1.7F, p.y() * 1.7F, p.z() * 1.7F, surface.seed);
    const float m = valueNoise3(p.x() * 4.3F, p.y() * 4.3F, p.z() * 4.3F, surface.seed + 1U);
    const float twig = 1.0F - std::fabs(2.0F * n - 1.0F);
    const float twig2 = 1.0F - std::fabs(2.0F * m - 1.0F);
    return twig > 0.9F + 0.1F * (gap - 0.5F) || twig2 > 0.93F;
  }
  const float n = 0.6F * valueNoise3(p.x() * 2.2F, p.y() * 2.2F, p.z() * 2.2F, surface.seed) +
                  0.4F * valueNoise3(p.x() * 7.0F, p.y() * 7.0F, p.z() * 7.0F, surface.seed + 1U);
  return n > 0.25F + 0.55F * gap;
}

Eigen::Vector3d PinholeView::unproject(double x, double y, double z) const {
  const Eigen::Vector3d c((x - cx) / fx * z, (y - cy) / fy * z, z);
  return centre + worldToCamera.transpose() * c;
}

void SampleBuffers::reset(int w, int h) {
  width = w;
  height = h;
  invDepth.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0.0F);
  triangle.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), -1);
}

void rasterize(const std::vector<RenderTriangle>& triangles,
               const std::vector<RenderSurface>& surfaces, const PinholeView& view,
               SampleBuffers& out, int threads) {
  out.reset(view.width, view.height);
  std::vector<Projected> proj(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    Projected& q = proj[t];
    q.valid = true;
    double minX = 1e18, maxX = -1e18, minY = 1e18, maxY = -1e18;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d c =
          view.worldToCamera *
          (triangles[t].p[static_cast<std::size_t>(k)].cast<double>() - view.centre);
      if (c.z() < 0.3) {
        q.valid = false;
        break;
      }
      q.x[k] = view.fx * c.x() / c.z() + view.cx;
      q.y[k] = view.fy * c.y() / c.z() + view.cy;
      q.iz[k] = static_cast<float>(1.0 / c.z());
      minX = std::min(minX, q.x[k]);
      maxX = std::max(maxX, q.x[k]);
      minY = std::min(minY, q.y[k]);
      maxY = std::max(maxY, q.y[k]);
    }
    if (!q.valid) {
      continue;
    }
    q.minX = std::max(0, static_cast<int>(std::ceil(minX)));
    q.maxX = std::min(view.width - 1, static_cast<int>(std::floor(maxX)));
    q.minY = std::max(0, static_cast<int>(std::ceil(minY)));
    q.maxY = std::min(view.height - 1, static_cast<int>(std::floor(maxY)));
    q.valid = q.minX <= q.maxX && q.minY <= q.maxY;
  }
  threads = std::max(1, threads);
  if (threads == 1) {
    rasterStrip(triangles, surfaces, proj, view, out, 0, view.height);
    return;
  }
  std::vector<std::thread> pool;
  const int rows = (view.height + threads - 1) / threads;
  for (int i = 0; i < threads; ++i) {
    const int r0 = i * rows;
    const int r1 = std::min(view.height, r0 + rows);
    if (r0 < r1) {
      pool.emplace_back([&, r0, r1] { rasterStrip(triangles, surfaces, proj, view, out, r0, r1); });
    }
  }
  for (auto& th : pool) {
    th.join();
  }
}

void ShadowMap::init(const Eigen::Vector3d& sunDirection, const Eigen::Vector3d& boxMin,
                     const Eigen::Vector3d& boxMax, double texel_m, int maxSize) {
  s_ = sunDirection.normalized();
  e1_ = (std::fabs(s_.z()) < 0.99 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX())
            .cross(s_)
            .normalized();
  e2_ = s_.cross(e1_);
  double aMin = 1e18, aMax = -1e18, bMin = 1e18, bMax = -1e18;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c((i & 1) != 0 ? boxMax.x() : boxMin.x(),
                            (i & 2) != 0 ? boxMax.y() : boxMin.y(),
                            (i & 4) != 0 ? boxMax.z() : boxMin.z());
    aMin = std::min(aMin, c.dot(e1_));
    aMax = std::max(aMax, c.dot(e1_));
    bMin = std::min(bMin, c.dot(e2_));
    bMax = std::max(bMax, c.dot(e2_));
  }
  texel_ = std::max(texel_m, std::max(aMax - aMin, bMax - bMin) / maxSize);
  a0_ = aMin - 2 * texel_;
  b0_ = bMin - 2 * texel_;
  width_ = static_cast<int>(std::ceil((aMax - aMin) / texel_)) + 4;
  height_ = static_cast<int>(std::ceil((bMax - bMin) / texel_)) + 4;
  clear();
}

void ShadowMap::clear() {
  top_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_),
              -std::numeric_limits<float>::infinity());
  blocksX_ = (width_ + kBlock - 1) / kBlock;
  blocksY_ = (height_ + kBlock - 1) / kBlock;
  const std::size_t blocks =
      static_cast<std::size_t>(blocksX_) * static_cast<std::size_t>(blocksY_);
  blockTop_.assign(blocks, -std::numeric_limits<float>::infinity());
  blockLow_.assign(blocks, -std::numeric_limits<float>::infinity());
  nearTop_.assign(blocks, -std::numeric_limits<float>::infinity());
  nearLow_.assign(blocks, -std::numeric_limits<float>::infinity());
  dynamicNear_.assign(blocks, 0);
  dirty_.assign(blocks, 0);
  dirtyList_.clear();
}

template <bool kDynamic>
void ShadowMap::draw(const RenderTriangle& triangle, const RenderSurface& surface) {
  double x[3], y[3], d[3];
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d p = triangle.p[static_cast<std::size_t>(k)].cast<double>();
    x[k] = (p.dot(e1_) - a0_) / texel_ - 0.5;
    y[k] = (p.dot(e2_) - b0_) / texel_ - 0.5;
    d[k] = p.dot(s_);
  }
  const double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
  if (std::fabs(area) < 1e-9) {
    return;
  }
  const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({x[0], x[1], x[2]}))));
  const int x1 = std::min(width_ - 1, static_cast<int>(std::floor(std::max({x[0], x[1], x[2]}))));
  const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({y[0], y[1], y[2]}))));
  const int y1 = std::min(height_ - 1, static_cast<int>(std::floor(std::max({y[0], y[1], y[2]}))));
  const bool alpha = surface.material == Material::Canopy;
  for (int py = y0; py <= y1; ++py) {
    for (int px = x0; px <= x1; ++px) {
      const double w0 = ((x[2] - x[1]) * (py - y[1]) - (y[2] - y[1]) * (px - x[1])) / area;
      const double w1 = ((x[0] - x[2]) * (py - y[2]) - (y[0] - y[2]) * (px - x[2])) / area;
      const double w2 = 1.0 - w0 - w1;
      if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) {
        continue;
      }
      const double depth = w0 * d[0] + w1 * d[1] + w2 * d[2];
      float& cell = top_[static_cast<std::size_t>(py) * static_cast<std::size_t>(width_) +
                         static_cast<std::size_t>(px)];
      if (depth <= static_cast<double>(cell)) {
        continue;
      }
      if (alpha) {
        const double a = a0_ + (px + 0.5) * texel_;
        const double b = b0_ + (py + 0.5) * texel_;
        const Eigen::Vector3d p = a * e1_ + b * e2_ + depth * s_;
        if (!canopyOpaque(surface, p.cast<float>())) {
          continue;
        }
      }
      cell = static_cast<float>(depth);
      if (kDynamic) {
        const std::size_t block =
            static_cast<std::size_t>(py / kBlock) * static_cast<std::size_t>(blocksX_) +
            static_cast<std::size_t>(px / kBlock);
        if (dirty_[block] == 0) {
          dirty_[block] = 1;
          dirtyList_.push_back(block);
        }
      }
    }
  }
}

void ShadowMap::add(const RenderTriangle& triangle, const RenderSurface& surface) {
  draw<false>(triangle, surface);
}

void ShadowMap::addDynamic(const RenderTriangle& triangle, const RenderSurface& surface) {
  draw<true>(triangle, surface);
}

void ShadowMap::summarize(std::size_t b) {
  const int bx = static_cast<int>(b % static_cast<std::size_t>(blocksX_));
  const int by = static_cast<int>(b / static_cast<std::size_t>(blocksX_));
  float top = -std::numeric_limits<float>::infinity();
  float low = std::numeric_limits<float>::infinity();
  for (int y = by * kBlock; y < std::min(height_, (by + 1) * kBlock); ++y) {
    for (int x = bx * kBlock; x < std::min(width_, (bx + 1) * kBlock); ++x) {
      const float t = top_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                           static_cast<std::size_t>(x)];
      top = std::max(top, t);
      low = std::min(low, t);
    }
  }
  blockTop_[b] = top;
  blockLow_[b] = low;
}

void ShadowMap::updateNear(int bx, int by) {
  float top = -std::numeric_limits<float>::infinity();
  float low = std::numeric_limits<float>::infinity();
  bool dynamic = false;
  for (int j = std::max(0, by - 1); j <= std::min(blocksY_ - 1, by + 1); ++j) {
    for (int i = std::max(0, bx - 1); i <= std::min(blocksX_ - 1, bx + 1); ++i) {
      const std::size_t b = static_cast<std::size_t>(j) * static_cast<std::size_t>(blocksX_) +
                            static_cast<std::size_t>(i);
      top = std::max(top, blockTop_[b]);
      low = std::min(low, blockLow_[b]);
      dynamic = dynamic || dirty_[b] != 0;
    }
  }
  // Blocks at the border see taps outside the map (lit): never all dark.
  const bool inner =
      bx >= 1 && by >= 1 && (bx + 2) * kBlock <= width_ && (by + 2) * kBlock <= height_;
  const std::size_t b = static_cast<std::size_t>(by) * static_cast<std::size_t>(blocksX_) +
                        static_cast<std::size_t>(bx);
  nearTop_[b] = top;
  nearLow_[b] = inner ? low : -std::numeric_limits<float>::infinity();
  dynamicNear_[b] = dynamic ? 1 : 0;
}

void ShadowMap::finishStatic() {
  for (std::size_t b = 0; b < blockTop_.size(); ++b) {
    summarize(b);
  }
  for (int by = 0; by < blocksY_; ++by) {
    for (int bx = 0; bx < blocksX_; ++bx) {
      updateNear(bx, by);
    }
  }
}

void ShadowMap::restoreFrom(const ShadowMap& base) {
  for (const std::size_t b : dirtyList_) {
    const int bx = static_cast<int>(b % static_cast<std::size_t>(blocksX_));
    const int by = static_cast<int>(b / static_cast<std::size_t>(blocksX_));
    for (int y = by * kBlock; y < std::min(height_, (by + 1) * kBlock); ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_);
      const std::size_t x0 = static_cast<std::size_t>(bx * kBlock);
      const std::size_t x1 = static_cast<std::size_t>(std::min(width_, (bx + 1) * kBlock));
      std::copy(base.top_.begin() + static_cast<std::ptrdiff_t>(row + x0),
                base.top_.begin() + static_cast<std::ptrdiff_t>(row + x1),
                top_.begin() + static_cast<std::ptrdiff_t>(row + x0));
    }
    blockTop_[b] = base.blockTop_[b];
    blockLow_[b] = base.blockLow_[b];
    dirty_[b] = 0;
  }
  for (const std::size_t b : dirtyList_) {
    const int bx = static_cast<int>(b % static_cast<std::size_t>(blocksX_));
    const int by = static_cast<int>(b / static_cast<std::size_t>(blocksX_));
    for (int j = std::max(0, by - 1); j <= std::min(blocksY_ - 1, by + 1); ++j) {
      for (int i = std::max(0, bx - 1); i <= std::min(blocksX_ - 1, bx + 1); ++i) {
        const std::size_t n = static_cast<std::size_t>(j) * static_cast<std::size_t>(blocksX_) +
                              static_cast<std::size_t>(i);
        nearTop_[n] = base.nearTop_[n];
        nearLow_[n] = base.nearLow_[n];
        dynamicNear_[n] = 0;
      }
    }
  }
  dirtyList_.clear();
}

void ShadowMap::finishDynamic() {
  for (const std::size_t b : dirtyList_) {
    summarize(b);
  }
  for (const std::size_t b : dirtyList_) {
    const int bx = static_cast<int>(b % static_cast<std::size_t>(blocksX_));
    const int by = static_cast<int>(b / static_cast<std::size_t>(blocksX_));
    for (int j = std::max(0, by - 1); j <= std::min(blocksY_ - 1, by + 1); ++j) {
      for (int i = std::max(0, bx - 1); i <= std::min(blocksX_ - 1, bx + 1); ++i) {
        updateNear(i, j);
      }
    }
  }
}

std::size_t ShadowMap::blockOf(double fx, double fy) const {
  // Block of the texel nearest to (fx, fy); blocks_ (out of range) when outside the map.
  const double vx = fx + 0.5;
  const double vy = fy + 0.5;
  if (vx < 0.0 || vy < 0.0 || vx >= width_ || vy >= height_) {
    return std::numeric_limits<std::size_t>::max();
  }
  return static_cast<std::size_t>(static_cast<int>(vy) / kBlock) *
             static_cast<std::size_t>(blocksX_) +
         static_cast<std::size_t>(static_cast<int>(vx) / kBlock);
}

bool ShadowMap::boxLit(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  double aMin = 1e18, aMax = -1e18, bMin = 1e18, bMax = -1e18, dMin = 1e18;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c((i & 1) != 0 ? hi.x() : lo.x(), (i & 2) != 0 ? hi.y() : lo.y(),
                            (i & 4) != 0 ? hi.z() : lo.z());
    aMin = std::min(aMin, c.dot(e1_));
    aMax = std::max(aMax, c.dot(e1_));
    bMin = std::min(bMin, c.dot(e2_));
    bMax = std::max(bMax, c.dot(e2_));
    dMin = std::min(dMin, c.dot(s_));
  }
  // Texel range of every tap (radius <= kBlock - 2) around any point of the box.
  const auto texel = [&](double v, double origin) { return (v - origin) / texel_ - 0.5; };
  const int x0 = std::max(0, static_cast<int>(std::floor(texel(aMin, a0_))) - kBlock) / kBlock;
  const int x1 =
      std::min(width_ - 1, static_cast<int>(std::ceil(texel(aMax, a0_))) + kBlock) / kBlock;
  const int y0 = std::max(0, static_cast<int>(std::floor(texel(bMin, b0_))) - kBlock) / kBlock;
  const int y1 =
      std::min(height_ - 1, static_cast<int>(std::ceil(texel(bMax, b0_))) + kBlock) / kBlock;
  const double bias = 0.04 + 1.5 * texel_;
  for (int by = y0; by <= y1; ++by) {
    for (int bx = x0; bx <= x1; ++bx) {
      const float top =
          blockTop_[static_cast<std::size_t>(by) * static_cast<std::size_t>(blocksX_) +
                    static_cast<std::size_t>(bx)];
      if (dMin + bias < static_cast<double>(top)) {
        return false;
      }
    }
  }
  return true;
}

bool ShadowMap::dynamicNear(const Eigen::Vector3f& pf) const {
  if (dirtyList_.empty()) {
    return false;
  }
  const Eigen::Vector3d p = pf.cast<double>();
  const std::size_t b =
      blockOf((p.dot(e1_) - a0_) / texel_ - 0.5, (p.dot(e2_) - b0_) / texel_ - 0.5);
  return b != std::numeric_limits<std::size_t>::max() && dynamicNear_[b] != 0;
}

float ShadowMap::visibility(const Eigen::Vector3f& pf, float radiusTexels) const {
  const Eigen::Vector3d p = pf.cast<double>();
  const double fx = (p.dot(e1_) - a0_) / texel_ - 0.5;
  const double fy = (p.dot(e2_) - b0_) / texel_ - 0.5;
  const double d = p.dot(s_);
  const double bias = 0.04 + 1.5 * texel_;
  // Every tap lies within one block of the centre texel's block (radius <= kBlock - 2): when
  // no caster there is above p, all taps are lit.
  const std::size_t block = blockOf(fx, fy);
  if (block != std::numeric_limits<std::size_t>::max()) {
    if (d + bias >= static_cast<double>(nearTop_[block])) {
      return 1.0F;
    }
    // Likewise in the core of a shadow: every caster nearby is above p.
    if (d + bias < static_cast<double>(nearLow_[block])) {
      return 0.0F;
    }
  }
  constexpr int kTaps = 3;
  int lit = 0;
  for (int j = 0; j < kTaps; ++j) {
    for (int i = 0; i < kTaps; ++i) {
      const double ox = (i + 0.5) / kTaps * 2.0 - 1.0;
      const double oy = (j + 0.5) / kTaps * 2.0 - 1.0;
      // floor(v + 0.5) by truncation: v is positive inside the map (checked below).
      const double vx = fx + ox * static_cast<double>(radiusTexels) + 0.5;
      const double vy = fy + oy * static_cast<double>(radiusTexels) + 0.5;
      const int x = vx < 0.0 ? -1 : static_cast<int>(vx);
      const int y = vy < 0.0 ? -1 : static_cast<int>(vy);
      if (x < 0 || y < 0 || x >= width_ || y >= height_) {
        ++lit;
        continue;
      }
      if (d + bias >=
          static_cast<double>(top_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                                   static_cast<std::size_t>(x)])) {
        ++lit;
      }
    }
  }
  return static_cast<float>(lit) / (kTaps * kTaps);
}

}  // namespace vp::sim
