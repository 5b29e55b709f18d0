#include "ground_cache.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace vp::sim {

namespace {

// Albedo and visibility are stored as 16-bit fixed point in [0, 2).
constexpr float kScale = 32768.0F;

std::uint16_t encode(float v) {
  return static_cast<std::uint16_t>(std::clamp(v, 0.0F, 65535.0F / kScale) * kScale + 0.5F);
}

}  // namespace

double HeightGrid::at(double x, double y) const {
  const double u = std::clamp((x - origin.x()) / cell_m, 0.0, nx - 1.0);
  const double v = std::clamp((y - origin.y()) / cell_m, 0.0, ny - 1.0);
  const int i = std::min(static_cast<int>(u), nx - 2);
  const int j = std::min(static_cast<int>(v), ny - 2);
  const double fx = u - i;
  const double fy = v - j;
  const auto idx = [&](int a, int b) {
    return static_cast<std::size_t>(b) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(a);
  };
  const double z00 = z[idx(i, j)];
  const double z10 = z[idx(i + 1, j)];
  const double z01 = z[idx(i, j + 1)];
  const double z11 = z[idx(i + 1, j + 1)];
  if (fy <= fx) {
    return z00 + fx * (z10 - z00) + fy * (z11 - z10);
  }
  return z00 + fy * (z01 - z00) + fx * (z11 - z01);
}

std::pair<double, double> HeightGrid::range(double x0, double y0, double x1, double y1) const {
  // Heights are linear within cells: the extremes are at the nodes of the covering cells.
  const auto clampI = [](double v, int n) { return std::clamp(static_cast<int>(v), 0, n - 1); };
  const int i0 = clampI(std::floor((x0 - origin.x()) / cell_m), nx);
  const int i1 = clampI(std::ceil((x1 - origin.x()) / cell_m), nx);
  const int j0 = clampI(std::floor((y0 - origin.y()) / cell_m), ny);
  const int j1 = clampI(std::ceil((y1 - origin.y()) / cell_m), ny);
  double lo = 1e18;
  double hi = -1e18;
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const double v = z[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                         static_cast<std::size_t>(i)];
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  return {lo, hi};
}

void GroundCache::init(const GroundTexture& texture, const ShadowMap& staticShadow,
                       float softnessTexels, const HeightGrid& heights, const Eigen::Vector2d& lo,
                       const Eigen::Vector2d& hi, double texel_m) {
  texture_ = &texture;
  shadow_ = &staticShadow;
  heights_ = &heights;
  softness_ = softnessTexels;
  lo_ = lo;
  invTexel0Sq_ = 1.0 / (texel_m * texel_m);
  storage_.clear();
  levels_.clear();
  levels_.resize(kLevels);
  for (int l = 0; l < kLevels; ++l) {
    Level& level = levels_[static_cast<std::size_t>(l)];
    level.texel_m = texel_m * std::ldexp(1.0, l);
    level.invTexel_m = 1.0 / level.texel_m;
    const double tile_m = level.texel_m * kTile;
    level.tilesX = static_cast<int>(std::ceil((hi.x() - lo.x()) / tile_m)) + 1;
    level.tilesY = static_cast<int>(std::ceil((hi.y() - lo.y()) / tile_m)) + 1;
    level.texelsX = level.tilesX * kTile;
    level.texelsY = level.tilesY * kTile;
    const std::size_t n =
        static_cast<std::size_t>(level.tilesX) * static_cast<std::size_t>(level.tilesY);
    level.tiles = std::make_unique<std::atomic<const std::uint16_t*>[]>(n);
    for (std::size_t i = 0; i < n; ++i) {
      level.tiles[i].store(nullptr, std::memory_order_relaxed);
    }
  }
}

int GroundCache::level(double footprintM2) const {
  // floor(log2(sqrt(footprint) / texel0)), by the exponent of footprint / texel0^2.
  const int e = std::ilogb(footprintM2 * invTexel0Sq_);
  if (e <= 0) {
    return 0;
  }
  return std::min(kLevels - 1, e / 2);
}

void GroundCache::fill(int level, int tx, int ty, std::uint16_t* out) const {
  const Level& l = levels_[static_cast<std::size_t>(level)];
  const double x0 = lo_.x() + static_cast<double>(tx) * kTile * l.texel_m;
  const double y0 = lo_.y() + static_cast<double>(ty) * kTile * l.texel_m;
  std::vector<Eigen::Vector3f> albedo(static_cast<std::size_t>(kTile) * kTile);
  texture_->fillTile(x0, y0, l.texel_m, kTile, albedo.data());
  // Most tiles lie in open sun: one test of the tile's box spares the per-texel filtering.
  const double x1 = x0 + (kTile - 1) * l.texel_m;
  const double y1 = y0 + (kTile - 1) * l.texel_m;
  const auto [zLo, zHi] = heights_->range(x0, y0, x1, y1);
  const bool lit = shadow_->boxLit({x0, y0, zLo + 0.03}, {x1, y1, zHi + 0.03});
  for (int j = 0; j < kTile; ++j) {
    for (int i = 0; i < kTile; ++i) {
      const double x = x0 + i * l.texel_m;
      const double y = y0 + j * l.texel_m;
      float visibility = 1.0F;
      if (!lit) {
        // Lifted off the surface like a shaded sample (normal offset; the ground is flat).
        const Eigen::Vector3f p(static_cast<float>(x), static_cast<float>(y),
                                static_cast<float>(heights_->at(x, y) + 0.03));
        visibility = shadow_->visibility(p, softness_);
      }
      const Eigen::Vector3f& a =
          albedo[static_cast<std::size_t>(j) * kTile + static_cast<std::size_t>(i)];
      std::uint16_t* texel =
          out + 4 * detail::zIndex(static_cast<unsigned>(i), static_cast<unsigned>(j));
      texel[0] = encode(a.x());
      texel[1] = encode(a.y());
      texel[2] = encode(a.z());
      texel[3] = encode(visibility);
    }
  }
}

const std::uint16_t* GroundCache::fillSlot(int level, int tx, int ty) const {
  const Level& l = levels_[static_cast<std::size_t>(level)];
  const std::size_t index = static_cast<std::size_t>(ty) * static_cast<std::size_t>(l.tilesX) +
                            static_cast<std::size_t>(tx);
  std::atomic<const std::uint16_t*>& slot = l.tiles[index];
  const std::uint16_t* data = nullptr;
  std::lock_guard<std::mutex> lock(
      locks_[(index * 7U + static_cast<std::size_t>(level)) % static_cast<std::size_t>(kLocks)]);
  data = slot.load(std::memory_order_acquire);
  if (data != nullptr) {
    return data;
  }
  auto buffer = std::make_unique<std::uint16_t[]>(static_cast<std::size_t>(kTile) * kTile * 4);
  fill(level, tx, ty, buffer.get());
  data = buffer.get();
  {
    std::lock_guard<std::mutex> storageLock(storageMutex_);
    storage_.push_back(std::move(buffer));
  }
  slot.store(data, std::memory_order_release);
  return data;
}

std::size_t GroundCache::texels() const {
  std::lock_guard<std::mutex> lock(storageMutex_);
  return storage_.size() * static_cast<std::size_t>(kTile) * kTile;
}

}  // namespace vp::sim
