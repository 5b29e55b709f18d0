#include "noise.hpp"

#include <cmath>

#include "sim_random.hpp"

namespace vp::sim {

namespace {

inline float fade(float t) {
  return t * t * t * (t * (t * 6.0F - 15.0F) + 10.0F);
}

inline float lerp(float a, float b, float t) {
  return a + (b - a) * t;
}

inline std::uint32_t latticeHash(int x, int y, std::uint32_t seed) {
  return hashCombine(hashCombine(seed, static_cast<std::uint32_t>(x)),
                     static_cast<std::uint32_t>(y));
}

}  // namespace

float latticeValue(int x, int y, std::uint32_t seed) {
  return hashToUnit(latticeHash(x, y, seed));
}

float valueNoise(float x, float y, std::uint32_t seed) {
  const float fx = std::floor(x);
  const float fy = std::floor(y);
  const int ix = static_cast<int>(fx);
  const int iy = static_cast<int>(fy);
  const float tx = fade(x - fx);
  const float ty = fade(y - fy);
  const float a = latticeValue(ix, iy, seed);
  const float b = latticeValue(ix + 1, iy, seed);
  const float c = latticeValue(ix, iy + 1, seed);
  const float d = latticeValue(ix + 1, iy + 1, seed);
  return lerp(lerp(a, b, tx), lerp(c, d, tx), ty);
}

float fbm(float x, float y, int octaves, std::uint32_t seed) {
  float sum = 0.0F;
  float amplitude = 0.5F;
  float norm = 0.0F;
  for (int i = 0; i < octaves; ++i) {
    // Rotate each octave a little so lattice axes do not line up into visible streaks.
    const float rx = 0.8F * x - 0.6F * y;
    const float ry = 0.6F * x + 0.8F * y;
    sum += amplitude * valueNoise(rx, ry, seed + static_cast<std::uint32_t>(i) * 1013U);
    norm += amplitude;
    amplitude *= 0.5F;
    x = rx * 2.03F + 17.1F;
    y = ry * 2.03F - 9.7F;
  }
  return sum / norm;
}

float ridge(float x, float y, std::uint32_t seed) {
  const float n =
      0.65F * valueNoise(x, y, seed) + 0.35F * valueNoise(2.1F * x, 2.1F * y, seed + 7U);
  return 1.0F - std::fabs(2.0F * n - 1.0F);
}

float cellular(float x, float y, std::uint32_t seed, std::uint32_t* cellHash) {
  const int ix = static_cast<int>(std::floor(x));
  const int iy = static_cast<int>(std::floor(y));
  float best = 1e9F;
  std::uint32_t bestHash = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const std::uint32_t h = latticeHash(ix + dx, iy + dy, seed);
      const float px = static_cast<float>(ix + dx) + hashToUnit(h);
      const float py = static_cast<float>(iy + dy) + hashToUnit(hashU32(h));
      const float d2 = (px - x) * (px - x) + (py - y) * (py - y);
      if (d2 < best) {
        best = d2;
        bestHash = h;
      }
    }
  }
  if (cellHash != nullptr) {
    *cellHash = bestHash;
  }
  return std::sqrt(best);
}

float valueNoise3(float x, float y, float z, std::uint32_t seed) {
  const float fz = std::floor(z);
  const auto iz = static_cast<std::uint32_t>(static_cast<int>(fz));
  const float tz = fade(z - fz);
  const float a = valueNoise(x, y, hashCombine(seed, iz));
  const float b = valueNoise(x, y, hashCombine(seed, iz + 1U));
  return lerp(a, b, tz);
}

}  // namespace vp::sim
