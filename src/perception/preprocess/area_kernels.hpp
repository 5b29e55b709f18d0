// preprocess/area_kernels: the inner loops of AreaResizer (internal to vp_preprocess).
//
// Contract: each function is one pass over one row in the scratch layouts of area_resizer.cpp;
// buffers written through vector stores have at least 16 values of slack past n (the resizer
// pads them) and the caller guarantees it. Every function gives the same values whichever
// instruction set runs it (SSE2 on x86-64, AVX2 when the CPU has it, portable scalar code
// otherwise): the float arithmetic is done in the same order, element by element, and
// rounding is to nearest, half to even (the default floating-point environment), as lrint.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace vp::preprocess::kernels {

// The instruction sets the kernels may use, in order. By default the best the build and the
// CPU allow; limitIsa() lowers it (tests run every variant against the scalar code) and
// returns what is in force. Not meant to change while a resize runs.
enum class Isa { Scalar = 0, Sse2 = 1, Avx2 = 2 };
Isa activeIsa();
Isa limitIsa(Isa limit);

// out[i] = saturate(round(in[i] * gains[i % 3])) for i < n: WhiteBalancer's tables.
void applyGains(const std::uint8_t* in, std::uint8_t* out, std::size_t n,
                const std::array<float, 3>& gains);

// sum[i] = (first ? 0 : sum[i]) + the rows' values i, for i < n (count rows).
void accumulateColumns16(const std::uint8_t* const* rows, int count, std::uint16_t* sum,
                         std::size_t n, bool first);

// In place: sum[3 fx d + c] becomes the sum of the fx pixels' column sums of block d, channel
// c (n = source row values; sum holds 3 fx zeros of slack past n). log2fx >= 0 when fx is a
// power of two.
void blockSums16(std::uint16_t* sum, std::size_t n, int fx, int log2fx);

// How a block sum becomes a mean: OpenCV's 2 x 2 half up, a power-of-two area half to even
// by shifts, any other area float(sum) * (1 / area) rounded half to even.
struct BlockRounding {
  enum class Kind { HalfUpShift, HalfEvenShift, Float } kind = Kind::Float;
  int shift = 0;
  float inverseArea = 1.0F;
};
BlockRounding blockRounding(int fx, int fy);

// out[3 d + c] = mean of block d, channel c, from blockSums16's layout (n values of sum;
// outValues = 3 x width); `rounded` is scratch of n + 16 bytes.
void roundBlocks16(const std::uint16_t* sum, std::size_t n, std::uint8_t* rounded,
                   std::uint8_t* out, std::size_t outValues, int fx, const BlockRounding& rounding);
// The same from 32-bit column sums (not yet summed across the block).
void roundBlocks32(const std::uint32_t* columnSums, std::uint8_t* out, std::size_t outValues,
                   int fx, const BlockRounding& rounding);

// out[i] = float(in[i]) for i < n.
void toFloat(const std::uint8_t* in, float* out, std::size_t n);

// out[3 d + c] = sum over t < taps, in order, of row[3 (first[d] + t) + c] * weights[d taps + t]
// (starting from 0), for d < width. row holds 3 taps + 4 zeros of slack past its values.
// pairWeights: the same weights for pixels 2p, 2p + 1 as 8 floats per tap (4 x w(2p, t), 4 x
// w(2p + 1, t)), taps of pair p from 8 p taps on (AreaResizer builds them).
void horizontalTaps(const float* row, float* out, int width, const int* first, const float* weights,
                    const float* pairWeights, int taps);

// sum[i] = (first ? 0 : sum[i]) + weight * values[i] for i < n.
void accumulateWeighted(const float* values, float* sum, std::size_t n, float weight, bool first);

// out[i] = saturate(round(sum[i])) for i < n.
void roundToBytes(const float* sum, std::uint8_t* out, std::size_t n);

}  // namespace vp::preprocess::kernels
