// depthwise_vnni_probe: two AVX-512 VNNI kernels for the depthwise 3 x 3 int8 convolution (pad 1,
// stride 1 or 2, NHWC, s8 activations with zero points, per-channel scales, a fused Relu), each
// checked bit for bit against a scalar reference and timed beside oneDNN's convolution with the
// same semantics, on the depthwise layers of the bench model or of the detector. It answers one
// question for docs/performance.md ("Where the oneDNN backend's time goes"): can a kernel of
// our own beat oneDNN 2.6 on these layers? (Measured: no.) Not part of the product.
//
// Both kernels copy each input row once into a padded u8 row (sign bit flipped, the input's zero
// point at both ends, channels padded to 64) and feed `vpdpbusd` "quads": the three horizontal
// taps of a channel in one 32-bit lane, made by byte and word unpacks, so an output takes one
// `vpdpbusd` per kernel row and 16 channels; the 128 x sum(w) and the input zero point are folded
// into the bias, and the pack chain of the requantization restores the channel order the
// unpacks permuted.
//   quads    the quads of every row built once into a ring of three rows (each serves the three
//            output rows that read it)
//   direct   the quads made in registers for every output from the three padded rows
//   multiply the quad rows built once and then reused for every row (wrong results, printed as
//            such): what the multiplies and the requantization cost alone
//
// Build: g++ -O2 -std=c++17 -mavx512f -mavx512bw -mavx512vnni -mavx512vl -fopenmp
//            tools/engine/depthwise_vnni_probe.cpp -o depthwise_vnni_probe -ldnnl
// Run:   depthwise_vnni_probe quads|direct|multiply [bench|detector] [threads] [repetitions]
// Output: one line per layer (both times, GMAC/s, ratio, bit-exact or not, oneDNN's largest
// difference from the reference), then the totals. Exit status 1 when a kernel that should be
// exact is not.
#include <immintrin.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include <oneapi/dnnl/dnnl.hpp>

struct Layer {
  int H, W, C, stride;
  int Ho, Wo;
  int zpIn, zpOut, outMin, outMax;
  std::vector<std::int8_t> w;      // [C][9]
  std::vector<std::int32_t> bias;  // accumulator units (input zp not folded)
  std::vector<float> scale;        // acc -> output units
};

static void reference(const Layer& L, const std::int8_t* in, std::int8_t* out) {
  for (int y = 0; y < L.Ho; ++y)
    for (int x = 0; x < L.Wo; ++x)
      for (int c = 0; c < L.C; ++c) {
        std::int32_t acc = L.bias[c];
        for (int ky = 0; ky < 3; ++ky)
          for (int kx = 0; kx < 3; ++kx) {
            const int iy = y * L.stride + ky - 1, ix = x * L.stride + kx - 1;
            const int a = (iy < 0 || iy >= L.H || ix < 0 || ix >= L.W)
                              ? L.zpIn
                              : in[(static_cast<long>(iy) * L.W + ix) * L.C + c];
            acc += (a - L.zpIn) * L.w[c * 9 + ky * 3 + kx];
          }
        const float f = std::nearbyint(static_cast<float>(acc) * L.scale[c]);
        int r = static_cast<int>(f) + L.zpOut;
        r = std::clamp(r, L.outMin, L.outMax);
        out[(static_cast<long>(y) * L.Wo + x) * L.C + c] = static_cast<std::int8_t>(r);
      }
}

// Vectors kept in std::vector (a struct, so the element type carries its alignment).
struct alignas(64) Zi {
  __m512i v;
};
struct alignas(64) Zf {
  __m512 v;
};

// The prepared layer: weights as quads in the order the unpacks produce, folded bias.
struct Prepared {
  const Layer* L;
  int groups;             // ceil(C / 64)
  int cpad;               // groups * 64
  int tail;               // channels of the last group, 1..64
  __mmask64 tailMask;     // their bytes
  Zi zpOut, lo, hi;       // output zero point (16-bit lanes), the fused Relu's bounds (bytes)
  std::vector<Zi> wq;     // [g][ky][i]
  std::vector<Zi> bias;   // [g][i]
  std::vector<Zf> scale;  // [g][i]
  // Per thread: a padded u8 row and a ring of three quad rows.
  struct Scratch {
    std::vector<std::uint8_t> row;  // (W + 2) * cpad
    std::vector<Zi> quads;          // 3 * Wo * groups * 4
    int rowOf[3];
  };
  std::vector<Scratch> scratch;
};

static Prepared prepare(const Layer& L, int threads) {
  Prepared p;
  p.L = &L;
  p.groups = (L.C + 63) / 64;
  p.cpad = p.groups * 64;
  p.tail = L.C - 64 * (p.groups - 1);
  p.tailMask = p.tail == 64 ? ~0ULL : ((1ULL << p.tail) - 1);
  p.zpOut.v = _mm512_set1_epi16(static_cast<short>(L.zpOut));
  p.lo.v = _mm512_set1_epi8(static_cast<char>(L.outMin));
  p.hi.v = _mm512_set1_epi8(static_cast<char>(L.outMax));
  p.wq.resize(static_cast<std::size_t>(p.groups) * 12);
  p.bias.resize(static_cast<std::size_t>(p.groups) * 4);
  p.scale.resize(static_cast<std::size_t>(p.groups) * 4);
  for (int g = 0; g < p.groups; ++g)
    for (int i = 0; i < 4; ++i) {
      alignas(64) std::int8_t wb[3][64] = {};
      alignas(64) std::int32_t bb[16] = {};
      alignas(64) float sb[16] = {};
      for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j) {
          const int c = 64 * g + 16 * k + 4 * i + j;
          const int lane = 4 * k + j;
          if (c >= L.C)
            continue;
          int sum = 0;
          for (int t = 0; t < 9; ++t)
            sum += L.w[c * 9 + t];
          for (int ky = 0; ky < 3; ++ky)
            for (int kx = 0; kx < 3; ++kx)
              wb[ky][4 * lane + kx] = L.w[c * 9 + ky * 3 + kx];
          bb[lane] = L.bias[c] - (L.zpIn + 128) * sum;
          sb[lane] = L.scale[c];
        }
      for (int ky = 0; ky < 3; ++ky)
        p.wq[(static_cast<std::size_t>(g) * 3 + ky) * 4 + i].v = _mm512_load_si512(wb[ky]);
      p.bias[static_cast<std::size_t>(g) * 4 + i].v = _mm512_load_si512(bb);
      p.scale[static_cast<std::size_t>(g) * 4 + i].v = _mm512_load_ps(sb);
    }
  p.scratch.resize(threads);
  for (auto& s : p.scratch) {
    s.row.assign(static_cast<std::size_t>(L.W + 2) * p.cpad, 0);
    s.quads.resize(static_cast<std::size_t>(3) * L.Wo * p.groups * 4);
  }
  return p;
}

// The padded u8 copy of input row r (0 = the top padding, H + 1 = the bottom one): sign bit
// flipped, the input's zero point in the padding pixels, channels padded to 64.
static void buildRow(const Prepared& p, std::uint8_t* row, const std::int8_t* in, int r) {
  const Layer& L = *p.L;
  const int cpad = p.cpad;
  const __m512i padValue = _mm512_set1_epi8(static_cast<char>(L.zpIn ^ 0x80));
  const __m512i flip = _mm512_set1_epi8(static_cast<char>(0x80));
  if (r == 0 || r == L.H + 1) {
    for (int x = 0; x < L.W + 2; ++x)
      for (int g = 0; g < p.groups; ++g)
        _mm512_storeu_si512(row + static_cast<std::size_t>(x) * cpad + 64 * g, padValue);
    return;
  }
  const std::int8_t* src = in + static_cast<std::size_t>(r - 1) * L.W * L.C;
  for (int g = 0; g < p.groups; ++g) {
    _mm512_storeu_si512(row + 64 * g, padValue);
    _mm512_storeu_si512(row + static_cast<std::size_t>(L.W + 1) * cpad + 64 * g, padValue);
  }
  const __mmask64 tailMask = p.tailMask;
  for (int x = 0; x < L.W; ++x) {
    const std::int8_t* px = src + static_cast<std::size_t>(x) * L.C;
    std::uint8_t* d = row + static_cast<std::size_t>(x + 1) * cpad;
    for (int g = 0; g + 1 < p.groups; ++g)
      _mm512_storeu_si512(d + 64 * g, _mm512_xor_si512(_mm512_loadu_si512(px + 64 * g), flip));
    const int g = p.groups - 1;
    _mm512_storeu_si512(d + 64 * g,
                        _mm512_xor_si512(_mm512_maskz_loadu_epi8(tailMask, px + 64 * g), flip));
  }
}

// Quad row of padded input row r (0 = the top padding, H + 1 = the bottom one) into dst.
static void buildQuads(const Prepared& p, Prepared::Scratch& s, const std::int8_t* in, int r,
                       __m512i* dst) {
  const Layer& L = *p.L;
  const int cpad = p.cpad;
  std::uint8_t* row = s.row.data();
  buildRow(p, row, in, r);
  const __m512i zero = _mm512_setzero_si512();
  const int step = L.stride * cpad;
  for (int x = 0; x < L.Wo; ++x) {
    const std::uint8_t* a0 = row + static_cast<std::size_t>(x) * step;
    for (int g = 0; g < p.groups; ++g) {
      const __m512i a = _mm512_loadu_si512(a0 + 64 * g);
      const __m512i b = _mm512_loadu_si512(a0 + cpad + 64 * g);
      const __m512i c = _mm512_loadu_si512(a0 + 2 * cpad + 64 * g);
      const __m512i t0 = _mm512_unpacklo_epi8(a, b);
      const __m512i t1 = _mm512_unpackhi_epi8(a, b);
      const __m512i t2 = _mm512_unpacklo_epi8(c, zero);
      const __m512i t3 = _mm512_unpackhi_epi8(c, zero);
      __m512i* q = dst + (static_cast<std::size_t>(x) * p.groups + g) * 4;
      q[0] = _mm512_unpacklo_epi16(t0, t2);
      q[1] = _mm512_unpackhi_epi16(t0, t2);
      q[2] = _mm512_unpacklo_epi16(t1, t3);
      q[3] = _mm512_unpackhi_epi16(t1, t3);
    }
  }
}

// Requantizes the four accumulators of 64 channels (unpack order), saturates, clamps to the fused
// Relu's bounds and stores them in channel order (the pack chain undoes the unpacks' order).
static inline void requantizeStore(__m512i a0, __m512i a1, __m512i a2, __m512i a3,
                                   const __m512* scale, __m512i zpOut, __m512i lo, __m512i hi,
                                   std::int8_t* d, bool full, __mmask64 tailMask) {
  const __m512i i0 = _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_cvtepi32_ps(a0), scale[0]));
  const __m512i i1 = _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_cvtepi32_ps(a1), scale[1]));
  const __m512i i2 = _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_cvtepi32_ps(a2), scale[2]));
  const __m512i i3 = _mm512_cvtps_epi32(_mm512_mul_ps(_mm512_cvtepi32_ps(a3), scale[3]));
  const __m512i p01 = _mm512_adds_epi16(_mm512_packs_epi32(i0, i1), zpOut);
  const __m512i p23 = _mm512_adds_epi16(_mm512_packs_epi32(i2, i3), zpOut);
  const __m512i v = _mm512_min_epi8(_mm512_max_epi8(_mm512_packs_epi16(p01, p23), lo), hi);
  if (full)
    _mm512_storeu_si512(d, v);
  else
    _mm512_mask_storeu_epi8(d, tailMask, v);
}

static bool gSkipBuild = false;  // "multiply": the quad rows are built once
static void runRows(const Prepared& p, Prepared::Scratch& s, const std::int8_t* in,
                    std::int8_t* out, int y0, int y1) {
  const Layer& L = *p.L;
  const std::size_t quadRow = static_cast<std::size_t>(L.Wo) * p.groups * 4;
  s.rowOf[0] = s.rowOf[1] = s.rowOf[2] = -1;
  const __m512i zpOut = p.zpOut.v, lo = p.lo.v, hi = p.hi.v;
  const int tail = p.tail;
  const __mmask64 tailMask = p.tailMask;
  for (int y = y0; y < y1; ++y) {
    const __m512i* q[3];
    for (int ky = 0; ky < 3; ++ky) {
      const int r = y * L.stride + ky;  // padded input row
      const int slot = r % 3;
      __m512i* dst = &s.quads[slot * quadRow].v;
      if (s.rowOf[slot] != r && !(gSkipBuild && s.rowOf[slot] >= 0)) {
        buildQuads(p, s, in, r, dst);
        s.rowOf[slot] = r;
      }
      q[ky] = dst;
    }
    std::int8_t* o = out + static_cast<std::size_t>(y) * L.Wo * L.C;
    for (int g = 0; g < p.groups; ++g) {
      const __m512i* wq = &p.wq[static_cast<std::size_t>(g) * 12].v;
      const __m512i w00 = wq[0], w01 = wq[1], w02 = wq[2], w03 = wq[3];
      const __m512i w10 = wq[4], w11 = wq[5], w12 = wq[6], w13 = wq[7];
      const __m512i w20 = wq[8], w21 = wq[9], w22 = wq[10], w23 = wq[11];
      const __m512i b0 = p.bias[g * 4 + 0].v, b1 = p.bias[g * 4 + 1].v, b2 = p.bias[g * 4 + 2].v,
                    b3 = p.bias[g * 4 + 3].v;
      const __m512* scale = &p.scale[g * 4].v;
      const bool full = g + 1 < p.groups || tail == 64;
      for (int x = 0; x < L.Wo; ++x) {
        const std::size_t off = (static_cast<std::size_t>(x) * p.groups + g) * 4;
        const __m512i* r0 = q[0] + off;
        const __m512i* r1 = q[1] + off;
        const __m512i* r2 = q[2] + off;
        __m512i a0 = _mm512_dpbusd_epi32(b0, r0[0], w00);
        __m512i a1 = _mm512_dpbusd_epi32(b1, r0[1], w01);
        __m512i a2 = _mm512_dpbusd_epi32(b2, r0[2], w02);
        __m512i a3 = _mm512_dpbusd_epi32(b3, r0[3], w03);
        a0 = _mm512_dpbusd_epi32(a0, r1[0], w10);
        a1 = _mm512_dpbusd_epi32(a1, r1[1], w11);
        a2 = _mm512_dpbusd_epi32(a2, r1[2], w12);
        a3 = _mm512_dpbusd_epi32(a3, r1[3], w13);
        a0 = _mm512_dpbusd_epi32(a0, r2[0], w20);
        a1 = _mm512_dpbusd_epi32(a1, r2[1], w21);
        a2 = _mm512_dpbusd_epi32(a2, r2[2], w22);
        a3 = _mm512_dpbusd_epi32(a3, r2[3], w23);
        requantizeStore(a0, a1, a2, a3, scale, zpOut, lo, hi,
                        o + static_cast<std::size_t>(x) * L.C + 64 * g, full, tailMask);
      }
    }
  }
}

// Direct variant: the quads are made in registers for every output (no quad rows in memory);
// per thread a ring of three padded u8 rows; x outer, channel groups inner (L1-friendly).
static inline void tapRow(const std::uint8_t* a0, int cpad, const __m512i* w, __m512i& a0c,
                          __m512i& a1c, __m512i& a2c, __m512i& a3c) {
  const __m512i zero = _mm512_setzero_si512();
  const __m512i a = _mm512_loadu_si512(a0);
  const __m512i b = _mm512_loadu_si512(a0 + cpad);
  const __m512i c = _mm512_loadu_si512(a0 + 2 * cpad);
  const __m512i t0 = _mm512_unpacklo_epi8(a, b);
  const __m512i t1 = _mm512_unpackhi_epi8(a, b);
  const __m512i t2 = _mm512_unpacklo_epi8(c, zero);
  const __m512i t3 = _mm512_unpackhi_epi8(c, zero);
  a0c = _mm512_dpbusd_epi32(a0c, _mm512_unpacklo_epi16(t0, t2), w[0]);
  a1c = _mm512_dpbusd_epi32(a1c, _mm512_unpackhi_epi16(t0, t2), w[1]);
  a2c = _mm512_dpbusd_epi32(a2c, _mm512_unpacklo_epi16(t1, t3), w[2]);
  a3c = _mm512_dpbusd_epi32(a3c, _mm512_unpackhi_epi16(t1, t3), w[3]);
}

static void runRowsDirect(const Prepared& p, Prepared::Scratch& s, const std::int8_t* in,
                          std::int8_t* out, int y0, int y1) {
  const Layer& L = *p.L;
  const std::size_t rowBytes = static_cast<std::size_t>(L.W + 2) * p.cpad;
  if (s.row.size() < 3 * rowBytes)
    s.row.resize(3 * rowBytes);
  s.rowOf[0] = s.rowOf[1] = s.rowOf[2] = -1;
  const __m512i zpOut = p.zpOut.v, lo = p.lo.v, hi = p.hi.v;
  const int tail = p.tail;
  const __mmask64 tailMask = p.tailMask;
  const int cpad = p.cpad;
  for (int y = y0; y < y1; ++y) {
    const std::uint8_t* rows[3];
    for (int ky = 0; ky < 3; ++ky) {
      const int r = y * L.stride + ky;
      const int slot = r % 3;
      std::uint8_t* dst = s.row.data() + slot * rowBytes;
      if (s.rowOf[slot] != r) {
        buildRow(p, dst, in, r);
        s.rowOf[slot] = r;
      }
      rows[ky] = dst;
    }
    std::int8_t* o = out + static_cast<std::size_t>(y) * L.Wo * L.C;
    const int step = L.stride * cpad;
    for (int x = 0; x < L.Wo; ++x) {
      for (int g = 0; g < p.groups; ++g) {
        const __m512i* wq = &p.wq[static_cast<std::size_t>(g) * 12].v;
        const __m512i* bq = &p.bias[g * 4].v;
        const __m512* sq = &p.scale[g * 4].v;
        __m512i a0 = bq[0], a1 = bq[1], a2 = bq[2], a3 = bq[3];
        const std::size_t off = static_cast<std::size_t>(x) * step + 64 * g;
        tapRow(rows[0] + off, cpad, wq, a0, a1, a2, a3);
        tapRow(rows[1] + off, cpad, wq + 4, a0, a1, a2, a3);
        tapRow(rows[2] + off, cpad, wq + 8, a0, a1, a2, a3);
        requantizeStore(a0, a1, a2, a3, sq, zpOut, lo, hi,
                        o + static_cast<std::size_t>(x) * L.C + 64 * g,
                        g + 1 < p.groups || tail == 64, tailMask);
      }
    }
  }
}

static bool gDirect = false;  // "direct"
static void runKernel(Prepared& p, const std::int8_t* in, std::int8_t* out, int threads) {
  const int Ho = p.L->Ho;
  if (threads == 1) {
    (gDirect ? runRowsDirect : runRows)(p, p.scratch[0], in, out, 0, Ho);
    return;
  }
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const int n = omp_get_num_threads();
    const int y0 = Ho * t / n, y1 = Ho * (t + 1) / n;
    (gDirect ? runRowsDirect : runRows)(p, p.scratch[t], in, out, y0, y1);
  }
}

static double medianMs(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int main(int argc, char** argv) {
  const std::string kernel = argc > 1 ? argv[1] : "quads";
  const std::string model = argc > 2 ? argv[2] : "bench";
  const int threads = argc > 3 ? std::atoi(argv[3]) : 1;
  const int reps = argc > 4 ? std::atoi(argv[4]) : 30;
  if ((kernel != "quads" && kernel != "direct" && kernel != "multiply") ||
      (model != "bench" && model != "detector") || threads < 1 || reps < 1) {
    std::fprintf(stderr,
                 "usage: depthwise_vnni_probe quads|direct|multiply [bench|detector] [threads] "
                 "[repetitions]\n");
    return 2;
  }
  if (!__builtin_cpu_supports("avx512vnni") || !__builtin_cpu_supports("avx512bw")) {
    std::fprintf(stderr, "depthwise_vnni_probe: this CPU has no AVX512-VNNI / AVX512BW\n");
    return 2;
  }
  gDirect = kernel == "direct";
  gSkipBuild = kernel == "multiply";
  omp_set_num_threads(threads);
  struct Shape {
    int C, H, W, stride;
  };
  // The depthwise layers (channels, input height and width, stride) of the bench model
  // (tools/engine/make_test_models.py --bench) and of models/detector/detector_int8.onnx.
  std::vector<Shape> shapes = {{32, 256, 256, 1},  {96, 256, 256, 2}, {144, 128, 128, 1},
                               {144, 128, 128, 2}, {192, 64, 64, 1},  {192, 64, 64, 1},
                               {192, 64, 64, 2},   {384, 32, 32, 1},  {384, 32, 32, 1},
                               {384, 32, 32, 1},   {384, 32, 32, 1},  {576, 32, 32, 1},
                               {576, 32, 32, 1},   {576, 32, 32, 2},  {960, 16, 16, 1},
                               {960, 16, 16, 1},   {960, 16, 16, 1}};
  if (model == "detector")
    shapes = {{48, 256, 336, 2}, {72, 128, 168, 1}, {72, 128, 168, 2}, {96, 64, 84, 1},
              {128, 64, 84, 2},  {256, 32, 42, 1},  {256, 32, 42, 1},  {256, 32, 42, 2},
              {384, 16, 21, 1},  {48, 64, 84, 1},   {48, 128, 168, 1}, {48, 128, 168, 1},
              {48, 128, 168, 1}, {48, 128, 168, 1}, {48, 128, 168, 1}};
  std::mt19937 rng(7);
  double totalOurs = 0, totalDnnl = 0, totalMacs = 0;
  bool allExact = true;
  for (const auto& sh : shapes) {
    Layer L;
    L.C = sh.C;
    L.H = sh.H;
    L.W = sh.W;
    L.stride = sh.stride;
    L.Ho = (L.H + 2 - 3) / L.stride + 1;
    L.Wo = (L.W + 2 - 3) / L.stride + 1;
    L.zpIn = static_cast<int>(rng() % 200) - 100;
    L.zpOut = static_cast<int>(rng() % 60) - 30;
    L.outMin = L.zpOut;
    L.outMax = 127;  // a fused Relu
    L.w.resize(static_cast<std::size_t>(L.C) * 9);
    for (auto& v : L.w)
      v = static_cast<std::int8_t>(static_cast<int>(rng() % 255) - 127);
    L.bias.resize(L.C);
    L.scale.resize(L.C);
    for (int c = 0; c < L.C; ++c) {
      L.bias[c] = static_cast<int>(rng() % 20001) - 10000;
      L.scale[c] = 0.0005f + 0.002f * static_cast<float>(rng() % 1000) / 1000.0f;
    }
    std::vector<std::int8_t> in(static_cast<std::size_t>(L.H) * L.W * L.C);
    for (auto& v : in)
      v = static_cast<std::int8_t>(static_cast<int>(rng() % 256) - 128);
    const std::size_t outSize = static_cast<std::size_t>(L.Ho) * L.Wo * L.C;
    std::vector<std::int8_t> ref(outSize), ours(outSize), dn(outSize);
    reference(L, in.data(), ref.data());
    Prepared p = prepare(L, threads);
    runKernel(p, in.data(), ours.data(), threads);
    const bool exact = ref == ours;
    allExact &= exact;

    // oneDNN
    using namespace dnnl;
    using tag = memory::format_tag;
    using dt = memory::data_type;
    engine eng(engine::kind::cpu, 0);
    stream strm(eng);
    memory::desc srcMd({1, L.C, L.H, L.W}, dt::s8, tag::nhwc);
    memory::desc dstMd({1, L.C, L.Ho, L.Wo}, dt::s8, tag::nhwc);
    memory::desc userW({L.C, 1, 1, 3, 3}, dt::s8, tag::goihw);
    memory::desc anyW({L.C, 1, 1, 3, 3}, dt::s8, tag::any);
    memory::desc biasMd({L.C}, dt::s32, tag::x);
    primitive_attr attr;
    attr.set_output_scales(1 << 1, L.scale);
    attr.set_zero_points(DNNL_ARG_SRC, 0, {DNNL_RUNTIME_S32_VAL});
    attr.set_zero_points(DNNL_ARG_DST, 0, {DNNL_RUNTIME_S32_VAL});
    post_ops ops;
    ops.append_eltwise(1.0f, algorithm::eltwise_clip, static_cast<float>(L.outMin - L.zpOut),
                       static_cast<float>(L.outMax - L.zpOut));
    attr.set_post_ops(ops);
    convolution_forward::desc d(prop_kind::forward_inference, algorithm::convolution_direct, srcMd,
                                anyW, biasMd, dstMd, {L.stride, L.stride}, {0, 0}, {1, 1}, {1, 1});
    convolution_forward::primitive_desc pd(d, attr, eng);
    memory uw(userW, eng, L.w.data());
    memory wm(pd.weights_desc(), eng);
    reorder(uw, wm).execute(strm, uw, wm);
    memory bm(biasMd, eng, L.bias.data());
    memory sm(srcMd, eng, in.data());
    memory dm(dstMd, eng, dn.data());
    memory zpi({{1}, dt::s32, tag::x}, eng);
    *static_cast<int*>(zpi.get_data_handle()) = L.zpIn;
    memory zpo({{1}, dt::s32, tag::x}, eng);
    *static_cast<int*>(zpo.get_data_handle()) = L.zpOut;
    convolution_forward conv(pd);
    std::unordered_map<int, memory> args = {{DNNL_ARG_SRC, sm},
                                            {DNNL_ARG_WEIGHTS, wm},
                                            {DNNL_ARG_BIAS, bm},
                                            {DNNL_ARG_DST, dm},
                                            {DNNL_ARG_ATTR_ZERO_POINTS | DNNL_ARG_SRC, zpi},
                                            {DNNL_ARG_ATTR_ZERO_POINTS | DNNL_ARG_DST, zpo}};
    conv.execute(strm, args);
    strm.wait();
    int maxDiff = 0;
    for (std::size_t i = 0; i < outSize; ++i)
      maxDiff = std::max(maxDiff, std::abs(dn[i] - ref[i]));

    std::vector<double> tOurs, tDnnl;
    for (int r = 0; r < reps; ++r) {
      auto t0 = std::chrono::steady_clock::now();
      runKernel(p, in.data(), ours.data(), threads);
      auto t1 = std::chrono::steady_clock::now();
      conv.execute(strm, args);
      strm.wait();
      auto t2 = std::chrono::steady_clock::now();
      tOurs.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      tDnnl.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    }
    const double mo = medianMs(tOurs), md = medianMs(tDnnl);
    const double macs = 9.0 * outSize;
    totalOurs += mo;
    totalDnnl += md;
    totalMacs += macs;
    std::printf(
        "C %4d %3dx%-3d s%d  ours %.3f ms (%5.1f GMAC/s)  oneDNN %.3f ms (%5.1f)  x%.2f  exact %s  "
        "oneDNN-ref max diff %d  [%s]\n",
        L.C, L.H, L.W, L.stride, mo, macs / mo / 1e6, md, macs / md / 1e6, md / mo,
        exact ? "yes" : "NO", maxDiff, pd.impl_info_str());
  }
  std::printf(
      "total: ours %.3f ms (%.1f GMAC/s), oneDNN %.3f ms (%.1f GMAC/s), x%.2f, all exact %s, "
      "threads %d\n",
      totalOurs, totalMacs / totalOurs / 1e6, totalDnnl, totalMacs / totalDnnl / 1e6,
      totalDnnl / totalOurs, allExact ? "yes" : "NO", threads);
  return allExact || gSkipBuild ? 0 : 1;
}
