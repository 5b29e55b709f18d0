#include "preprocess/yuv_rows.hpp"

#include <algorithm>

#include "preprocess/area_kernels.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define VP_YUV_AVX2 1
#endif

namespace vp::preprocess {

namespace {

// The coefficients scaled by 2^20 and rounded.
constexpr int kShift = 20;
constexpr int kRound = 1 << (kShift - 1);
constexpr int kCy = 1220542;   // 1.164
constexpr int kCvr = 1673527;  // 1.596
constexpr int kCvg = -852492;  // -0.813
constexpr int kCug = -409993;  // -0.391
constexpr int kCub = 2116026;  // 2.018

struct Chroma {
  int r, g, b;
};

inline Chroma chroma(int u, int v) {
  const int uu = u - 128;
  const int vv = v - 128;
  return {kRound + kCvr * vv, kRound + kCvg * vv + kCug * uu, kRound + kCub * uu};
}

inline std::uint8_t clampToByte(int value) {
  return static_cast<std::uint8_t>(std::clamp(value, 0, 255));
}

inline void writePixel(int luma, const Chroma& c, std::uint8_t* bgr) {
  const int y = std::max(0, luma - 16) * kCy;
  bgr[0] = clampToByte((y + c.b) >> kShift);
  bgr[1] = clampToByte((y + c.g) >> kShift);
  bgr[2] = clampToByte((y + c.r) >> kShift);
}

#if defined(VP_YUV_AVX2)
// int32 x 8 -> int16 x 8, saturating (packs works per 128-bit lane: gather the halves first).
__attribute__((target("avx2"))) inline __m128i toWords(__m256i v) {
  return _mm_packs_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
}

// Eight pixels: Y, U, V (one byte per pixel, chroma already repeated for each pixel of a pair)
// in the low 8 bytes of y8, u8, v8 -> 24 bytes of BGR. The same integer arithmetic as
// writePixel, eight lanes at a time; packs / packus saturate as clampToByte does (the 20-bit
// results lie well within int16).
__attribute__((target("avx2"))) inline void eightPixels(__m128i y8, __m128i u8, __m128i v8,
                                                        std::uint8_t* bgr) {
  const __m256i y = _mm256_mullo_epi32(
      _mm256_max_epi32(_mm256_sub_epi32(_mm256_cvtepu8_epi32(y8), _mm256_set1_epi32(16)),
                       _mm256_setzero_si256()),
      _mm256_set1_epi32(kCy));
  const __m256i uu = _mm256_sub_epi32(_mm256_cvtepu8_epi32(u8), _mm256_set1_epi32(128));
  const __m256i vv = _mm256_sub_epi32(_mm256_cvtepu8_epi32(v8), _mm256_set1_epi32(128));
  const __m256i base = _mm256_add_epi32(y, _mm256_set1_epi32(kRound));
  const __m256i b = _mm256_srai_epi32(
      _mm256_add_epi32(base, _mm256_mullo_epi32(uu, _mm256_set1_epi32(kCub))), kShift);
  const __m256i g = _mm256_srai_epi32(
      _mm256_add_epi32(base, _mm256_add_epi32(_mm256_mullo_epi32(vv, _mm256_set1_epi32(kCvg)),
                                              _mm256_mullo_epi32(uu, _mm256_set1_epi32(kCug)))),
      kShift);
  const __m256i r = _mm256_srai_epi32(
      _mm256_add_epi32(base, _mm256_mullo_epi32(vv, _mm256_set1_epi32(kCvr))), kShift);
  const __m128i bg = _mm_packus_epi16(toWords(b), toWords(g));  // B0..B7 G0..G7
  const __m128i rr = _mm_packus_epi16(toWords(r), toWords(r));  // R0..R7 R0..R7
  // Interleave: byte k of the output is pixel k / 3, channel k % 3 (-1: zero).
  const __m128i fromBg0 = _mm_setr_epi8(0, 8, -1, 1, 9, -1, 2, 10, -1, 3, 11, -1, 4, 12, -1, 5);
  const __m128i fromR0 = _mm_setr_epi8(-1, -1, 0, -1, -1, 1, -1, -1, 2, -1, -1, 3, -1, -1, 4, -1);
  const __m128i fromBg1 =
      _mm_setr_epi8(13, -1, 6, 14, -1, 7, 15, -1, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m128i fromR1 = _mm_setr_epi8(-1, 5, -1, -1, 6, -1, -1, 7, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m128i out0 = _mm_or_si128(_mm_shuffle_epi8(bg, fromBg0), _mm_shuffle_epi8(rr, fromR0));
  const __m128i out1 = _mm_or_si128(_mm_shuffle_epi8(bg, fromBg1), _mm_shuffle_epi8(rr, fromR1));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(bgr), out0);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(bgr + 16), out1);
}

__attribute__((target("avx2"))) int yuyvRowAvx2(const std::uint8_t* yuyv, int width_px,
                                                std::uint8_t* bgr) {
  // 16 bytes = 8 pixels: Y at even bytes, U at 1, 5, 9, 13 and V at 3, 7, 11, 15.
  const __m128i ySel = _mm_setr_epi8(0, 2, 4, 6, 8, 10, 12, 14, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m128i uSel = _mm_setr_epi8(1, 1, 5, 5, 9, 9, 13, 13, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m128i vSel = _mm_setr_epi8(3, 3, 7, 7, 11, 11, 15, 15, -1, -1, -1, -1, -1, -1, -1, -1);
  int col = 0;
  for (; col + 8 <= width_px; col += 8) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(yuyv + 2 * col));
    eightPixels(_mm_shuffle_epi8(v, ySel), _mm_shuffle_epi8(v, uSel), _mm_shuffle_epi8(v, vSel),
                bgr + 3 * col);
  }
  return col;
}

__attribute__((target("avx2"))) int nv12RowAvx2(const std::uint8_t* y, const std::uint8_t* uv,
                                                int width_px, std::uint8_t* bgr) {
  const __m128i uSel = _mm_setr_epi8(0, 0, 2, 2, 4, 4, 6, 6, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m128i vSel = _mm_setr_epi8(1, 1, 3, 3, 5, 5, 7, 7, -1, -1, -1, -1, -1, -1, -1, -1);
  int col = 0;
  for (; col + 8 <= width_px; col += 8) {
    const __m128i luma = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(y + col));
    const __m128i chroma = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(uv + col));
    eightPixels(luma, _mm_shuffle_epi8(chroma, uSel), _mm_shuffle_epi8(chroma, vSel),
                bgr + 3 * col);
  }
  return col;
}
#endif

}  // namespace

void yuyvRowToBgr(const std::uint8_t* yuyv, int width_px, std::uint8_t* bgr) {
  int col = 0;
#if defined(VP_YUV_AVX2)
  if (kernels::activeIsa() == kernels::Isa::Avx2) {
    col = yuyvRowAvx2(yuyv, width_px, bgr);
    yuyv += 2 * col;
    bgr += 3 * col;
  }
#endif
  for (; col < width_px; col += 2, yuyv += 4, bgr += 6) {
    const Chroma c = chroma(yuyv[1], yuyv[3]);
    writePixel(yuyv[0], c, bgr);
    writePixel(yuyv[2], c, bgr + 3);
  }
}

void nv12RowToBgr(const std::uint8_t* y, const std::uint8_t* uv, int width_px, std::uint8_t* bgr) {
  int col = 0;
#if defined(VP_YUV_AVX2)
  if (kernels::activeIsa() == kernels::Isa::Avx2) {
    col = nv12RowAvx2(y, uv, width_px, bgr);
    bgr += 3 * col;
  }
#endif
  for (; col < width_px; col += 2, bgr += 6) {
    const Chroma c = chroma(uv[col], uv[col + 1]);
    writePixel(y[col], c, bgr);
    writePixel(y[col + 1], c, bgr + 3);
  }
}

}  // namespace vp::preprocess
