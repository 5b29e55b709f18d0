// inference/dnnl_int8: the int8 backend whose convolutions run on oneDNN (VNNI kernels on
// x86 CPUs that have them), for the same QDQ files as XnnpackInt8.
//
// Contract: createDnnlInt8Backend() builds the XnnpackInt8 graph walk (xnnpack_int8.hpp) and
// replaces every Conv node by a oneDNN int8 convolution on the same NHWC int8 buffers: s8
// activations with their zero points (the input's folded into the bias when the Conv has no
// padding, else a runtime zero-point argument like the output's), per-output-channel s8
// weights reordered once into oneDNN's blocked layout, an int32 bias in accumulator units
// (the same rounding as XNNPACK's), the requantization as per-channel output scales and a
// fused Relu/Clip as an eltwise clip post-op in output units. Every other node (ConvTranspose,
// Add/Mul, pooling, Resize, Concat, tables) stays on XNNPACK: those are memory-bound and
// oneDNN would not make them faster. Everything (primitives, reordered weights, zero-point
// and scratchpad memory: user-mode scratchpad, one buffer sized for the largest convolution)
// is created at load. oneDNN runs on its OpenMP team; run() sets the calling thread's team
// size to `threads` first. The XNNPACK part runs on the calling thread alone (no pthreadpool):
// two pools that spin after their work (XNNPACK's workers and the OpenMP team) on the same cores
// made two threads several times slower than one (docs/performance.md); its primitives are
// created for that team size. run() allocates nothing: oneDNN 2.6 builds its argument map and
// execution context on the heap inside every dnnl_primitive_execute(), and each convolution's
// call runs in a scope of the backend's core::TransientArena (reserved at load), which serves
// those blocks. When the build has no oneDNN (VP_HAVE_DNNL undefined: ARM, or libdnnl-dev absent)
// the create function fails with a message saying so.
//
// dnnlInt8Available() says whether this build has oneDNN; cpuHasVnni() whether the CPU has
// the int8 dot-product instructions (AVX512-VNNI or AVX-VNNI), the condition for
// Backend::Auto to pick DnnlInt8.
#pragma once

#include <memory>
#include <string>

#include "inference/backend.hpp"
#include "inference/onnx_graph.hpp"

namespace vp::inference {

bool dnnlInt8Available();
bool cpuHasVnni();

// planMemory as for createXnnpackInt8Backend(): the convolutions' oneDNN memories are created
// on the same (planned or separate) tensor buffers.
std::unique_ptr<InferenceBackend> createDnnlInt8Backend(const QdqGraph& graph, int threads,
                                                        bool planMemory, std::string* why);

}  // namespace vp::inference
