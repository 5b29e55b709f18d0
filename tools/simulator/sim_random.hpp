// simulator/sim_random: the simulator's single source of randomness.
//
// Contract: every random decision of a simulated sequence comes from one Rng, a
// std::mt19937_64 seeded by --seed, drawn in a fixed program order. The distributions are
// implemented here (not std::uniform_real_distribution / std::normal_distribution, whose
// algorithms differ between standard libraries) so a seed gives the same scene everywhere.
// Per-pixel noise that must not depend on evaluation order (threads) uses counter-based
// hashing (hashU32) keyed by a value drawn from the Rng.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace vp::sim {

// SplitMix-style 32-bit finaliser: a deterministic hash of (key, counters).
inline std::uint32_t hashU32(std::uint32_t x) {
  x ^= x >> 16U;
  x *= 0x7feb352dU;
  x ^= x >> 15U;
  x *= 0x846ca68bU;
  x ^= x >> 16U;
  return x;
}

inline std::uint32_t hashCombine(std::uint32_t seed, std::uint32_t value) {
  return hashU32(seed ^ (value + 0x9e3779b9U + (seed << 6U) + (seed >> 2U)));
}

// Uniform in [0, 1) from a hash value.
inline float hashToUnit(std::uint32_t h) {
  return static_cast<float>(h >> 8U) * (1.0F / 16777216.0F);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  std::uint64_t next() { return engine_(); }
  // The engine itself, for library code that draws from a std::mt19937_64 (car generator).
  std::mt19937_64& engine() { return engine_; }
  std::uint32_t nextU32() { return static_cast<std::uint32_t>(engine_() >> 32U); }

  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11U) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [lo, hi] (inclusive); tiny modulo bias is irrelevant here.
  int uniformInt(int lo, int hi) {
    const auto span = static_cast<std::uint64_t>(hi - lo + 1);
    return lo + static_cast<int>(engine_() % span);
  }
  bool chance(double p) { return uniform() < p; }

  // Standard normal by Box-Muller (one value per call, no cached state to keep it simple).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
  double normal(double mean, double sigma) { return mean + sigma * normal(); }

  // Index drawn with the given (non-negative, not all zero) weights.
  template <typename Container>
  int weighted(const Container& weights) {
    double total = 0.0;
    for (const double w : weights) {
      total += w;
    }
    double x = uniform() * total;
    int index = 0;
    for (const double w : weights) {
      if (x < w) {
        return index;
      }
      x -= w;
      ++index;
    }
    return index - 1;
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace vp::sim
