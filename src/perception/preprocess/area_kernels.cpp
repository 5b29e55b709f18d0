#include "preprocess/area_kernels.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#define VP_AREA_SSE2 1
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define VP_AREA_AVX2 1
#define VP_TARGET_AVX2 __attribute__((target("avx2")))
#endif

// This file is compiled with -ffp-contract=off (CMakeLists.txt): a fused multiply-add would
// round differently from the separate multiply and add that OpenCV's float path does.

namespace vp::preprocess::kernels {

namespace {

Isa bestIsa() {
#if defined(VP_AREA_AVX2)
  if (__builtin_cpu_supports("avx2") != 0) {
    return Isa::Avx2;
  }
#endif
#if defined(VP_AREA_SSE2)
  return Isa::Sse2;
#else
  return Isa::Scalar;
#endif
}

std::atomic<int>& isaLimit() {
  static std::atomic<int> limit{static_cast<int>(bestIsa())};
  return limit;
}

[[maybe_unused]] bool useSse2() {
  return isaLimit().load(std::memory_order_relaxed) >= static_cast<int>(Isa::Sse2);
}
[[maybe_unused]] bool useAvx2() {
  return isaLimit().load(std::memory_order_relaxed) >= static_cast<int>(Isa::Avx2);
}

// Gains are clamped here before rounding: any larger product saturates to 255 anyway, and the
// vector conversion to int32 must not overflow.
constexpr float kProductLimit = 1024.0F;

inline std::uint8_t saturateRound(float value) {
  const long rounded = std::lrint(value);  // half to even, as cvRound
  return static_cast<std::uint8_t>(std::clamp(rounded, 0L, 255L));
}

inline std::uint8_t roundBlock(std::uint32_t sum, const BlockRounding& rounding) {
  switch (rounding.kind) {
    case BlockRounding::Kind::HalfUpShift:
      return static_cast<std::uint8_t>((sum + (1U << (rounding.shift - 1))) >> rounding.shift);
    case BlockRounding::Kind::HalfEvenShift: {
      if (rounding.shift == 0) {
        return static_cast<std::uint8_t>(sum);
      }
      const std::uint32_t q = sum >> rounding.shift;
      const std::uint32_t r = sum & ((1U << rounding.shift) - 1U);
      const std::uint32_t half = 1U << (rounding.shift - 1);
      return static_cast<std::uint8_t>(q + ((r > half || (r == half && (q & 1U) != 0U)) ? 1U : 0U));
    }
    case BlockRounding::Kind::Float:
      break;
  }
  return saturateRound(static_cast<float>(sum) * rounding.inverseArea);
}

#if defined(VP_AREA_AVX2)
// AVX2 variants of the hottest loops (16 values per instruction), chosen at run time; each
// does per element exactly what its SSE2 / scalar counterpart does.

VP_TARGET_AVX2 std::size_t applyGainsAvx2(const std::uint8_t* in, std::uint8_t* out, std::size_t n,
                                          const float* pattern) {
  const __m256 limit = _mm256_set1_ps(kProductLimit);
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    const float* p = pattern + (i % 48);
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
    const __m256 f0 = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(v));
    const __m256 f1 = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_srli_si128(v, 8)));
    const __m256i r0 =
        _mm256_cvtps_epi32(_mm256_min_ps(_mm256_mul_ps(f0, _mm256_loadu_ps(p)), limit));
    const __m256i r1 =
        _mm256_cvtps_epi32(_mm256_min_ps(_mm256_mul_ps(f1, _mm256_loadu_ps(p + 8)), limit));
    // packs/packus work per 128-bit lane: values 0-3, 8-11 | 4-7, 12-15 -> fix the order.
    const __m256i words = _mm256_permute4x64_epi64(_mm256_packs_epi32(r0, r1), 0xD8);
    const __m128i bytes =
        _mm_packus_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), bytes);
  }
  return i;
}

VP_TARGET_AVX2 std::size_t accumulateColumns16Avx2(const std::uint8_t* const* rows, int count,
                                                   std::uint16_t* sum, std::size_t n, bool first) {
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    auto* s = reinterpret_cast<__m256i*>(sum + i);
    __m256i acc = first ? _mm256_setzero_si256() : _mm256_loadu_si256(s);
    for (int r = 0; r < count; ++r) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rows[r] + i));
      acc = _mm256_add_epi16(acc, _mm256_cvtepu8_epi16(v));
    }
    _mm256_storeu_si256(s, acc);
  }
  return i;
}

VP_TARGET_AVX2 std::size_t pairSums16Avx2(std::uint16_t* sum, std::size_t n, std::size_t d) {
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    auto* s = reinterpret_cast<__m256i*>(sum + i);
    const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(sum + i + d));
    _mm256_storeu_si256(s, _mm256_add_epi16(_mm256_loadu_si256(s), b));
  }
  return i;
}

VP_TARGET_AVX2 std::size_t roundShift16Avx2(const std::uint16_t* sum, std::size_t n,
                                            std::uint8_t* rounded, int shift, std::uint32_t bias,
                                            bool halfEven) {
  const __m256i one = _mm256_set1_epi16(1);
  const __m256i biasV = _mm256_set1_epi16(static_cast<short>(bias));
  const __m128i count = _mm_cvtsi32_si128(shift);
  std::size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    __m256i r[2];
    for (int h = 0; h < 2; ++h) {
      const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(sum + i + 16 * h));
      __m256i t = _mm256_add_epi16(v, biasV);
      if (halfEven) {
        t = _mm256_add_epi16(t, _mm256_and_si256(_mm256_srl_epi16(v, count), one));
      }
      r[h] = _mm256_srl_epi16(t, count);
    }
    // packus works per 128-bit lane: restore the order afterwards.
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi16(r[0], r[1]), 0xD8);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(rounded + i), packed);
  }
  return i;
}

VP_TARGET_AVX2 std::size_t toFloatAvx2(const std::uint8_t* in, float* out, std::size_t n) {
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    const __m128i v = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(in + i));
    _mm256_storeu_ps(out + i, _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(v)));
  }
  return i;
}

VP_TARGET_AVX2 void horizontalTapsAvx2(const float* row, float* out, int width, const int* first,
                                       const float* weights, const float* pairWeights, int taps) {
  // Two output pixels per vector (4 lanes each: B, G, R and a lane overwritten later); their
  // weights come broadcast, eight floats per tap.
  int d = 0;
  for (; d + 2 <= width; d += 2) {
    const float* p0 = row + static_cast<std::ptrdiff_t>(first[d]) * 3;
    const float* p1 = row + static_cast<std::ptrdiff_t>(first[d + 1]) * 3;
    const float* pw = pairWeights + static_cast<std::ptrdiff_t>(d / 2) * taps * 8;
    __m256 acc = _mm256_setzero_ps();
    for (int t = 0; t < taps; ++t) {
      const __m256 v = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p0 + 3 * t)),
                                            _mm_loadu_ps(p1 + 3 * t), 1);
      const __m256 w = _mm256_loadu_ps(pw + 8 * t);
      acc = _mm256_add_ps(acc, _mm256_mul_ps(v, w));
    }
    float* o = out + static_cast<std::ptrdiff_t>(d) * 3;
    _mm_storeu_ps(o, _mm256_castps256_ps128(acc));
    _mm_storeu_ps(o + 3, _mm256_extractf128_ps(acc, 1));
  }
  for (; d < width; ++d) {
    const float* p = row + static_cast<std::ptrdiff_t>(first[d]) * 3;
    const float* w = weights + static_cast<std::ptrdiff_t>(d) * taps;
    __m128 acc = _mm_setzero_ps();
    for (int t = 0; t < taps; ++t) {
      acc = _mm_add_ps(acc, _mm_mul_ps(_mm_loadu_ps(p + 3 * t), _mm_set1_ps(w[t])));
    }
    _mm_storeu_ps(out + static_cast<std::ptrdiff_t>(d) * 3, acc);
  }
}

VP_TARGET_AVX2 std::size_t accumulateWeightedAvx2(const float* values, float* sum, std::size_t n,
                                                  float weight, bool first) {
  const __m256 w = _mm256_set1_ps(weight);
  std::size_t i = 0;
  if (first) {
    for (; i + 8 <= n; i += 8) {
      _mm256_storeu_ps(sum + i, _mm256_mul_ps(_mm256_loadu_ps(values + i), w));
    }
  } else {
    for (; i + 8 <= n; i += 8) {
      _mm256_storeu_ps(sum + i, _mm256_add_ps(_mm256_loadu_ps(sum + i),
                                              _mm256_mul_ps(_mm256_loadu_ps(values + i), w)));
    }
  }
  return i;
}
#endif
}  // namespace

void applyGains(const std::uint8_t* in, std::uint8_t* out, std::size_t n,
                const std::array<float, 3>& gains) {
  std::size_t i = 0;
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    // The channel of value i is i % 3; 16-value blocks start at phases 0, 16, 32 of a 48 cycle.
    alignas(16) float pattern[48];
    for (int e = 0; e < 48; ++e) {
      pattern[e] = gains[static_cast<std::size_t>(e % 3)];
    }
#if defined(VP_AREA_AVX2)
    if (useAvx2()) {
      i = applyGainsAvx2(in, out, n, pattern);
    }
#endif
    const __m128i zero = _mm_setzero_si128();
    const __m128 limit = _mm_set1_ps(kProductLimit);
    for (; i + 16 <= n; i += 16) {
      const float* p = pattern + (i % 48);
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
      const __m128i lo = _mm_unpacklo_epi8(v, zero);
      const __m128i hi = _mm_unpackhi_epi8(v, zero);
      const __m128 f0 = _mm_cvtepi32_ps(_mm_unpacklo_epi16(lo, zero));
      const __m128 f1 = _mm_cvtepi32_ps(_mm_unpackhi_epi16(lo, zero));
      const __m128 f2 = _mm_cvtepi32_ps(_mm_unpacklo_epi16(hi, zero));
      const __m128 f3 = _mm_cvtepi32_ps(_mm_unpackhi_epi16(hi, zero));
      const __m128i r0 = _mm_cvtps_epi32(_mm_min_ps(_mm_mul_ps(f0, _mm_load_ps(p)), limit));
      const __m128i r1 = _mm_cvtps_epi32(_mm_min_ps(_mm_mul_ps(f1, _mm_load_ps(p + 4)), limit));
      const __m128i r2 = _mm_cvtps_epi32(_mm_min_ps(_mm_mul_ps(f2, _mm_load_ps(p + 8)), limit));
      const __m128i r3 = _mm_cvtps_epi32(_mm_min_ps(_mm_mul_ps(f3, _mm_load_ps(p + 12)), limit));
      const __m128i packed = _mm_packus_epi16(_mm_packs_epi32(r0, r1), _mm_packs_epi32(r2, r3));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), packed);
    }
  }
#endif
  for (; i < n; ++i) {
    out[i] = saturateRound(std::min(static_cast<float>(in[i]) * gains[i % 3], kProductLimit));
  }
}

void accumulateColumns16(const std::uint8_t* const* rows, int count, std::uint16_t* sum,
                         std::size_t n, bool first) {
  std::size_t i = 0;
#if defined(VP_AREA_AVX2)
  if (useAvx2()) {
    i = accumulateColumns16Avx2(rows, count, sum, n, first);
  }
#endif
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    const __m128i zero = _mm_setzero_si128();
    for (; i + 16 <= n; i += 16) {
      auto* s = reinterpret_cast<__m128i*>(sum + i);
      __m128i lo = first ? zero : _mm_loadu_si128(s);
      __m128i hi = first ? zero : _mm_loadu_si128(s + 1);
      for (int r = 0; r < count; ++r) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rows[r] + i));
        lo = _mm_add_epi16(lo, _mm_unpacklo_epi8(v, zero));
        hi = _mm_add_epi16(hi, _mm_unpackhi_epi8(v, zero));
      }
      _mm_storeu_si128(s, lo);
      _mm_storeu_si128(s + 1, hi);
    }
  }
#endif
  for (; i < n; ++i) {
    std::uint32_t v = first ? 0U : sum[i];
    for (int r = 0; r < count; ++r) {
      v += rows[r][i];
    }
    sum[i] = static_cast<std::uint16_t>(v);
  }
}

void blockSums16(std::uint16_t* sum, std::size_t n, int fx, int log2fx) {
  if (log2fx >= 0) {
    // Pairwise doubling: after step k, sum[i] holds 2^(k+1) pixels' column sums from i on.
    // Ascending i reads only values not yet overwritten (the distance is >= 3).
    for (int k = 0; k < log2fx; ++k) {
      const std::size_t d = static_cast<std::size_t>(3) << k;
      std::size_t i = 0;
#if defined(VP_AREA_AVX2)
      if (useAvx2()) {
        i = pairSums16Avx2(sum, n, d);
      }
#endif
#if defined(VP_AREA_SSE2)
      if (useSse2()) {
        for (; i + 8 <= n; i += 8) {
          auto* s = reinterpret_cast<__m128i*>(sum + i);
          const __m128i a = _mm_loadu_si128(s);
          const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sum + i + d));
          _mm_storeu_si128(s, _mm_add_epi16(a, b));
        }
      }
#endif
      for (; i < n; ++i) {
        sum[i] = static_cast<std::uint16_t>(sum[i] + sum[i + d]);
      }
    }
    return;
  }
  const std::size_t block = static_cast<std::size_t>(3) * static_cast<std::size_t>(fx);
  for (std::size_t b = 0; b + block <= n; b += block) {
    for (std::size_t c = 0; c < 3; ++c) {
      std::uint32_t s = 0;
      for (std::size_t k = 0; k < block; k += 3) {
        s += sum[b + k + c];
      }
      sum[b + c] = static_cast<std::uint16_t>(s);
    }
  }
}

BlockRounding blockRounding(int fx, int fy) {
  BlockRounding rounding;
  const int area = fx * fy;
  if (fx == 2 && fy == 2) {
    rounding.kind = BlockRounding::Kind::HalfUpShift;
    rounding.shift = 2;
    return rounding;
  }
  for (int k = 0; k < 31; ++k) {
    if ((1 << k) == area) {
      // sum / 2^k is exact in float, so this equals the float path, half to even.
      rounding.kind = BlockRounding::Kind::HalfEvenShift;
      rounding.shift = k;
      return rounding;
    }
  }
  rounding.kind = BlockRounding::Kind::Float;
  rounding.inverseArea = 1.0F / static_cast<float>(area);
  return rounding;
}

void roundBlocks16(const std::uint16_t* sum, std::size_t n, std::uint8_t* rounded,
                   std::uint8_t* out, std::size_t outValues, int fx,
                   const BlockRounding& rounding) {
  const std::size_t block = static_cast<std::size_t>(3) * static_cast<std::size_t>(fx);
  const std::size_t width = outValues / 3;
  if (rounding.kind == BlockRounding::Kind::Float || (rounding.shift == 0)) {
    for (std::size_t d = 0; d < width; ++d) {
      for (std::size_t c = 0; c < 3; ++c) {
        out[d * 3 + c] = roundBlock(sum[d * block + c], rounding);
      }
    }
    return;
  }
  // Shifts: every position is rounded (vectors), then the block starts are picked out.
  const auto shift = static_cast<std::uint32_t>(rounding.shift);
  const bool halfEven = rounding.kind == BlockRounding::Kind::HalfEvenShift;
  const std::uint32_t bias = halfEven ? (1U << (shift - 1)) - 1U : 1U << (shift - 1);
  std::size_t i = 0;
#if defined(VP_AREA_AVX2)
  if (useAvx2()) {
    i = roundShift16Avx2(sum, n, rounded, static_cast<int>(shift), bias, halfEven);
  }
#endif
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    const __m128i one = _mm_set1_epi16(1);
    const __m128i biasV = _mm_set1_epi16(static_cast<short>(bias));
    const __m128i count = _mm_cvtsi32_si128(static_cast<int>(shift));
    auto roundEight = [&](const std::uint16_t* p) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
      __m128i t = _mm_add_epi16(v, biasV);  // sums fit 16 bits with room for the bias
      if (halfEven) {
        t = _mm_add_epi16(t, _mm_and_si128(_mm_srl_epi16(v, count), one));
      }
      return _mm_srl_epi16(t, count);
    };
    for (; i + 16 <= n; i += 16) {
      const __m128i packed = _mm_packus_epi16(roundEight(sum + i), roundEight(sum + i + 8));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(rounded + i), packed);
    }
  }
#endif
  for (; i < n; ++i) {
    const std::uint32_t v = sum[i];
    const std::uint32_t odd = halfEven ? (v >> shift) & 1U : 0U;
    rounded[i] = static_cast<std::uint8_t>((v + bias + odd) >> shift);
  }
  // Four-byte copies, each overwriting the previous one's spare byte; the last pixel exact.
  std::size_t d = 0;
  for (; d + 1 < width; ++d) {
    std::memcpy(out + d * 3, rounded + d * block, 4);
  }
  std::memcpy(out + d * 3, rounded + d * block, 3);
}

void roundBlocks32(const std::uint32_t* columnSums, std::uint8_t* out, std::size_t outValues,
                   int fx, const BlockRounding& rounding) {
  const std::size_t block = static_cast<std::size_t>(3) * static_cast<std::size_t>(fx);
  const std::size_t width = outValues / 3;
  for (std::size_t d = 0; d < width; ++d) {
    for (std::size_t c = 0; c < 3; ++c) {
      std::uint32_t s = 0;
      for (std::size_t k = 0; k < block; k += 3) {
        s += columnSums[d * block + k + c];
      }
      out[d * 3 + c] = roundBlock(s, rounding);
    }
  }
}

void toFloat(const std::uint8_t* in, float* out, std::size_t n) {
  std::size_t i = 0;
#if defined(VP_AREA_AVX2)
  if (useAvx2()) {
    i = toFloatAvx2(in, out, n);
  }
#endif
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    const __m128i zero = _mm_setzero_si128();
    for (; i + 16 <= n; i += 16) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
      const __m128i lo = _mm_unpacklo_epi8(v, zero);
      const __m128i hi = _mm_unpackhi_epi8(v, zero);
      _mm_storeu_ps(out + i, _mm_cvtepi32_ps(_mm_unpacklo_epi16(lo, zero)));
      _mm_storeu_ps(out + i + 4, _mm_cvtepi32_ps(_mm_unpackhi_epi16(lo, zero)));
      _mm_storeu_ps(out + i + 8, _mm_cvtepi32_ps(_mm_unpacklo_epi16(hi, zero)));
      _mm_storeu_ps(out + i + 12, _mm_cvtepi32_ps(_mm_unpackhi_epi16(hi, zero)));
    }
  }
#endif
  for (; i < n; ++i) {
    out[i] = static_cast<float>(in[i]);
  }
}

void horizontalTaps(const float* row, float* out, int width, const int* first, const float* weights,
                    const float* pairWeights, int taps) {
#if defined(VP_AREA_AVX2)
  if (useAvx2()) {
    horizontalTapsAvx2(row, out, width, first, weights, pairWeights, taps);
    return;
  }
#endif
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    // One output pixel per vector: lanes B, G, R and the next pixel's B (overwritten by the next
    // store; out has one value of slack).
    for (int d = 0; d < width; ++d) {
      const float* p = row + static_cast<std::ptrdiff_t>(first[d]) * 3;
      const float* w = weights + static_cast<std::ptrdiff_t>(d) * taps;
      __m128 acc = _mm_setzero_ps();
      for (int t = 0; t < taps; ++t) {
        acc = _mm_add_ps(acc, _mm_mul_ps(_mm_loadu_ps(p + 3 * t), _mm_set1_ps(w[t])));
      }
      _mm_storeu_ps(out + static_cast<std::ptrdiff_t>(d) * 3, acc);
    }
    return;
  }
#endif
  for (int d = 0; d < width; ++d) {
    const float* p = row + static_cast<std::ptrdiff_t>(first[d]) * 3;
    const float* w = weights + static_cast<std::ptrdiff_t>(d) * taps;
    float b = 0.0F;
    float g = 0.0F;
    float r = 0.0F;
    for (int t = 0; t < taps; ++t) {
      b = b + p[3 * t] * w[t];
      g = g + p[3 * t + 1] * w[t];
      r = r + p[3 * t + 2] * w[t];
    }
    float* o = out + static_cast<std::ptrdiff_t>(d) * 3;
    o[0] = b;
    o[1] = g;
    o[2] = r;
  }
}

void accumulateWeighted(const float* values, float* sum, std::size_t n, float weight, bool first) {
  std::size_t i = 0;
#if defined(VP_AREA_AVX2)
  if (useAvx2()) {
    i = accumulateWeightedAvx2(values, sum, n, weight, first);
  }
#endif
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    const __m128 w = _mm_set1_ps(weight);
    if (first) {
      for (; i + 4 <= n; i += 4) {
        _mm_storeu_ps(sum + i, _mm_mul_ps(_mm_loadu_ps(values + i), w));
      }
    } else {
      for (; i + 4 <= n; i += 4) {
        _mm_storeu_ps(sum + i,
                      _mm_add_ps(_mm_loadu_ps(sum + i), _mm_mul_ps(_mm_loadu_ps(values + i), w)));
      }
    }
  }
#endif
  if (first) {
    for (; i < n; ++i) {
      sum[i] = values[i] * weight;
    }
  } else {
    for (; i < n; ++i) {
      sum[i] = sum[i] + values[i] * weight;
    }
  }
}

void roundToBytes(const float* sum, std::uint8_t* out, std::size_t n) {
  std::size_t i = 0;
#if defined(VP_AREA_SSE2)
  if (useSse2()) {
    for (; i + 16 <= n; i += 16) {
      const __m128i r0 = _mm_cvtps_epi32(_mm_loadu_ps(sum + i));
      const __m128i r1 = _mm_cvtps_epi32(_mm_loadu_ps(sum + i + 4));
      const __m128i r2 = _mm_cvtps_epi32(_mm_loadu_ps(sum + i + 8));
      const __m128i r3 = _mm_cvtps_epi32(_mm_loadu_ps(sum + i + 12));
      const __m128i packed = _mm_packus_epi16(_mm_packs_epi32(r0, r1), _mm_packs_epi32(r2, r3));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), packed);
    }
  }
#endif
  for (; i < n; ++i) {
    out[i] = saturateRound(sum[i]);
  }
}

Isa activeIsa() {
  return static_cast<Isa>(isaLimit().load(std::memory_order_relaxed));
}

Isa limitIsa(Isa limit) {
  const int best = static_cast<int>(bestIsa());
  const int chosen = std::min(best, static_cast<int>(limit));
  isaLimit().store(chosen, std::memory_order_relaxed);
  return static_cast<Isa>(chosen);
}

}  // namespace vp::preprocess::kernels
