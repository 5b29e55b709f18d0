// simulator/ground_cache: the static ground of a sequence (procedural albedo and the sun's
// visibility past buildings and trees) sampled once into world-aligned texel tiles, so that a
// frame only interpolates them instead of evaluating the texture and filtering the static
// shadow map per sample.
//
// Contract: texels lie on square grids in the ENU plane, texel size texel_m * 2^level (levels
// chosen per sample from its ground footprint, so distant ground is not over-sampled); a
// texel holds the albedo (GroundTexture::fillTile) and the filtered visibility of the sun in
// the static shadow map at the ground mesh under it. Tiles of kTile x kTile texels are filled
// on first use, from any thread; a tile's content is a pure function of (level, tile), so
// results do not depend on the thread count or on the order of use. sample() takes the
// nearest texel.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ground_texture.hpp"
#include "rasterizer.hpp"

namespace vp::sim {

namespace detail {

// Texel (i, j) of a tile in Z order (bits of i and j interleaved): samples walk the ground
// in any direction (the view's azimuth is arbitrary), and rows of a row-major tile made
// nearly every lookup a cache miss; in Z order neighbours in both directions share lines.
struct ZOrder {
  std::array<std::uint32_t, 128> spread{};
  constexpr ZOrder() {
    for (std::uint32_t v = 0; v < 128; ++v) {
      std::uint32_t s = 0;
      for (std::uint32_t b = 0; b < 7; ++b) {
        s |= ((v >> b) & 1U) << (2 * b);
      }
      spread[v] = s;
    }
  }
};
inline constexpr ZOrder kZOrder;

inline std::size_t zIndex(unsigned i, unsigned j) {
  return kZOrder.spread[i] | (kZOrder.spread[j] << 1U);
}

}  // namespace detail

// Heights of the renderer's ground mesh: a regular grid, each cell split along its
// (i, j)-(i + 1, j + 1) diagonal, so z() is exactly the rasterized surface.
struct HeightGrid {
  Eigen::Vector2d origin{0, 0};
  double cell_m = 1.0;
  int nx = 0;
  int ny = 0;
  std::vector<double> z;
  double at(double x, double y) const;
  // Lowest and highest z over the rectangle [x0, x1] x [y0, y1].
  std::pair<double, double> range(double x0, double y0, double x1, double y1) const;
};

struct GroundSample {
  Eigen::Vector3f albedo{0, 0, 0};
  float sunVisibility = 1.0F;  // static casters only
};

class GroundCache {
 public:
  GroundCache() = default;
  GroundCache(const GroundCache&) = delete;
  GroundCache& operator=(const GroundCache&) = delete;

  // Covers [lo, hi]; texel_m: the finest texel (about the finest sample footprint). The
  // referenced objects must outlive the cache.
  void init(const GroundTexture& texture, const ShadowMap& staticShadow, float softnessTexels,
            const HeightGrid& heights, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
            double texel_m);
  // Level whose texels are no larger than a sample covering footprintM2 of ground.
  int level(double footprintM2) const;
  GroundSample sample(double x, double y, int level) const {
    // Nearest texel: texels are no larger than a sample, and the samples of a pixel are
    // averaged, so interpolating would only blur (and cost four times the reads).
    const Level& l = levels_[static_cast<std::size_t>(level)];
    const double u = std::clamp((x - lo_.x()) * l.invTexel_m + 0.5, 0.0, l.texelsX - 1.0);
    const double v = std::clamp((y - lo_.y()) * l.invTexel_m + 0.5, 0.0, l.texelsY - 1.0);
    const auto i = static_cast<unsigned>(u);
    const auto j = static_cast<unsigned>(v);
    const std::uint16_t* t = tile(level, static_cast<int>(i / kTile), static_cast<int>(j / kTile));
    const std::uint16_t* a = t + 4 * detail::zIndex(i % kTile, j % kTile);
    constexpr float kInvScale = 1.0F / 32768.0F;
    GroundSample s;
    s.albedo = Eigen::Vector3f(a[0], a[1], a[2]) * kInvScale;
    s.sunVisibility = static_cast<float>(a[3]) * kInvScale;
    return s;
  }
  // Starts loading the texel of (x, y) into the cache, if its tile exists (a hint only).
  void prefetch(double x, double y, int level) const {
    const Level& l = levels_[static_cast<std::size_t>(level)];
    const double u = (x - lo_.x()) * l.invTexel_m + 0.5;
    const double v = (y - lo_.y()) * l.invTexel_m + 0.5;
    if (!(u >= 0.0 && v >= 0.0 && u < l.texelsX && v < l.texelsY)) {
      return;
    }
    const auto i = static_cast<unsigned>(u);
    const auto j = static_cast<unsigned>(v);
    const std::uint16_t* t =
        l.tiles[static_cast<std::size_t>(j / kTile) * static_cast<std::size_t>(l.tilesX) +
                static_cast<std::size_t>(i / kTile)]
            .load(std::memory_order_relaxed);
    if (t != nullptr) {
      __builtin_prefetch(t + 4 * detail::zIndex(i % kTile, j % kTile));
    }
  }
  // Texels filled so far (memory use).
  std::size_t texels() const;

 private:
  static constexpr int kTile = 64;
  static constexpr int kLevels = 10;
  static constexpr int kLocks = 64;

  struct Level {
    double texel_m = 0.0;
    double invTexel_m = 0.0;
    int texelsX = 0;  // valid texel indices 0 .. texelsX - 1
    int texelsY = 0;
    int tilesX = 0;
    int tilesY = 0;
    std::unique_ptr<std::atomic<const std::uint16_t*>[]> tiles;
  };

  const std::uint16_t* tile(int level, int tx, int ty) const {
    const Level& l = levels_[static_cast<std::size_t>(level)];
    const std::uint16_t* data =
        l.tiles[static_cast<std::size_t>(ty) * static_cast<std::size_t>(l.tilesX) +
                static_cast<std::size_t>(tx)]
            .load(std::memory_order_acquire);
    return data != nullptr ? data : fillSlot(level, tx, ty);
  }
  const std::uint16_t* fillSlot(int level, int tx, int ty) const;
  void fill(int level, int tx, int ty, std::uint16_t* out) const;

  const GroundTexture* texture_ = nullptr;
  const ShadowMap* shadow_ = nullptr;
  const HeightGrid* heights_ = nullptr;
  float softness_ = 1.0F;
  Eigen::Vector2d lo_{0, 0};
  double invTexel0Sq_ = 1.0;
  std::vector<Level> levels_;
  mutable std::vector<std::unique_ptr<std::uint16_t[]>> storage_;
  mutable std::mutex storageMutex_;
  mutable std::array<std::mutex, kLocks> locks_;
};

}  // namespace vp::sim
