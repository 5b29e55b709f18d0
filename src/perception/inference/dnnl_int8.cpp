// The DnnlInt8 backend (contract in dnnl_int8.hpp): XnnpackInt8's graph walk with the Conv
// hook replaced by oneDNN int8 convolutions on the same buffers.
#include "inference/dnnl_int8.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#endif

#ifdef VP_HAVE_DNNL
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <oneapi/dnnl/dnnl.hpp>
#include <utility>
#include <vector>

#include "core/transient_arena.hpp"
#include "inference/xnnpack_int8.hpp"
#endif

namespace vp::inference {

bool dnnlInt8Available() {
#ifdef VP_HAVE_DNNL
  return true;
#else
  return false;
#endif
}

bool cpuHasVnni() {
#if defined(__x86_64__) || defined(__i386__)
  unsigned eax = 0;
  unsigned ebx = 0;
  unsigned ecx = 0;
  unsigned edx = 0;
  // Leaf 7 sub-leaf 0: ECX bit 11 = AVX512_VNNI; sub-leaf 1: EAX bit 4 = AVX-VNNI (VEX).
  if (__get_cpuid_count(7, 0, &eax, &ebx, &ecx, &edx) == 0)
    return false;
  const bool avx512Vnni = (ecx & (1U << 11U)) != 0;
  const unsigned maxSubleaf = eax;
  bool avxVnni = false;
  if (maxSubleaf >= 1 && __get_cpuid_count(7, 1, &eax, &ebx, &ecx, &edx) != 0)
    avxVnni = (eax & (1U << 4U)) != 0;
  // The OS must also save the vector state; __builtin_cpu_supports checks XCR0 for us.
  return (avx512Vnni && __builtin_cpu_supports("avx512f")) ||
         (avxVnni && __builtin_cpu_supports("avx2"));
#else
  return false;
#endif
}

#ifndef VP_HAVE_DNNL

std::unique_ptr<InferenceBackend> createDnnlInt8Backend(const QdqGraph& graph, int /*threads*/,
                                                        bool /*planMemory*/, std::string* why) {
  *why = graph.file +
         ": backend int8-dnnl: this build has no oneDNN (libdnnl-dev was not found at "
         "configure time); use int8 or auto";
  return nullptr;
}

#else

namespace {

using dnnl::memory;
using Dims = memory::dims;

// What one dnnl_primitive_execute() allocates on the calling thread (its argument map and
// execution context: about 8 blocks, 504 bytes at most on the shipped models, the arena's
// high-water mark), with a large margin for other models and oneDNN builds.
constexpr std::size_t kArenaBytes = 64 * 1024;

// One oneDNN convolution: the primitive and its arguments as the C API takes them, built at
// load so that run() is a single dnnl_primitive_execute() call, its heap blocks served by the
// backend's arena (core/transient_arena.hpp) so that run() allocates nothing.
class DnnlConvolution final : public ExternalStep {
 public:
  DnnlConvolution(dnnl::primitive primitive, const dnnl::stream& stream,
                  std::vector<std::pair<int, memory> > args, core::TransientArena& arena)
      : primitive_(std::move(primitive)),
        stream_(stream),
        memories_(std::move(args)),
        arena_(arena) {
    for (const auto& [arg, mem] : memories_)
      cArgs_.push_back(dnnl_exec_arg_t{arg, mem.get()});
  }

  bool run() override {
    const core::TransientArena::Scope scope(arena_);
    return dnnl_primitive_execute(primitive_.get(), stream_.get(), static_cast<int>(cArgs_.size()),
                                  cArgs_.data()) == dnnl_success;
  }

 private:
  dnnl::primitive primitive_;
  dnnl::stream stream_;
  std::vector<std::pair<int, memory> > memories_;  // keeps the handles alive
  std::vector<dnnl_exec_arg_t> cArgs_;
  core::TransientArena& arena_;  // borrowed from the backend, which outlives its convolutions
};

class DnnlInt8Backend final : public XnnpackInt8Backend {
 public:
  explicit DnnlInt8Backend(int threads)
      : threads_(threads), engine_(dnnl::engine::kind::cpu, 0), stream_(engine_) {
    // oneDNN plans a primitive's work split for the OpenMP team size it sees when the primitive
    // is created (dnnl_get_max_threads()) and forks that many at execution whatever the team
    // size is then: the primitives must be created with the engine's own thread count, not
    // the process default (every core), or a one-thread engine forks a team on every call.
    omp_set_num_threads(threads_);
  }

  bool run() override {
    // oneDNN parallelises on the calling thread's OpenMP team: size it to this engine's.
    omp_set_num_threads(threads_);
    const bool ok = XnnpackInt8Backend::run();
    if (arena_.overflows() != 0 && !overflowLogged_) {
      // Still correct (the blocks came from the heap), but no longer allocation-free: say so once.
      overflowLogged_ = true;
      std::fprintf(stderr,
                   "%s: int8-dnnl: a oneDNN call needed more than its %zu-byte arena; its blocks "
                   "now come from the heap\n",
                   file_.c_str(), arena_.capacity());
    }
    return ok;
  }

  // The scratchpads of all convolutions share one buffer (they run one after the other);
  // each convolution's scratchpad memory points into it, so it is sized after the walk.
  bool finish(std::string* why) {
    try {
      scratch_ =
          memory(memory::desc({static_cast<memory::dim>(std::max<std::size_t>(scratchBytes_, 64))},
                              memory::data_type::u8, memory::format_tag::x),
                 engine_);
      for (memory& pad : scratchpads_)
        pad.set_data_handle(scratch_.get_data_handle());
    } catch (const dnnl::error& e) {
      *why = file_ + ": oneDNN scratchpad: " + e.what();
      return false;
    }
    return true;
  }

  std::string file_;

 protected:
  bool addConv(const GraphNode& node, std::string* why) override {
    try {
      return addDnnlConv(node, why);
    } catch (const dnnl::error& e) {
      return fail(node, std::string("oneDNN: ") + e.what(), why);
    }
  }

 private:
  static Dims nchw(const TensorShape& s) { return {s.n, s.c, s.h, s.w}; }

  // A one-element s32 memory holding a zero point, for the runtime zero-point argument.
  memory zeroPointMemory(int value) {
    memory m(memory::desc({1}, memory::data_type::s32, memory::format_tag::x), engine_);
    *static_cast<std::int32_t*>(m.get_data_handle()) = value;
    return m;
  }

  bool addDnnlConv(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const int groups = node.group;
    const int cout = out.shape.c;
    const int cinG = in.shape.c / groups;
    const memory::desc srcMd(nchw(in.shape), memory::data_type::s8, memory::format_tag::nhwc);
    const memory::desc dstMd(nchw(out.shape), memory::data_type::s8, memory::format_tag::nhwc);
    // ONNX [Cout][Cin/g][kh][kw] is oihw, and goihw once Cout is split into groups.
    const Dims userWeightDims = groups == 1
                                    ? Dims{cout, cinG, node.kernelH, node.kernelW}
                                    : Dims{groups, cout / groups, cinG, node.kernelH, node.kernelW};
    const memory::desc userWeightMd(
        userWeightDims, memory::data_type::s8,
        groups == 1 ? memory::format_tag::oihw : memory::format_tag::goihw);
    const memory::desc anyWeightMd(userWeightDims, memory::data_type::s8, memory::format_tag::any);
    const memory::desc biasMd({cout}, memory::data_type::s32, memory::format_tag::x);

    dnnl::primitive_attr attr;
    attr.set_scratchpad_mode(dnnl::scratchpad_mode::user);
    // acc (s32, input scale x weight scale units) -> output units.
    std::vector<float> scales(static_cast<std::size_t>(cout));
    for (int c = 0; c < cout; ++c) {
      scales[toSize(c)] = in.quant.scale * node.weightScales[toSize(c)] / out.quant.scale;
    }
    attr.set_output_scales(1 << 1, scales);
    // Without padding the input zero point is a per-channel constant of the accumulator,
    // folded into the bias (exact in int32); with padding oneDNN must know it, since the
    // padded pixels are the zero point (real 0), not int8 0.
    const bool padded =
        node.padTop != 0 || node.padLeft != 0 || node.padBottom != 0 || node.padRight != 0;
    const bool srcZeroPoint = in.quant.zeroPoint != 0 && padded;
    if (srcZeroPoint)
      attr.set_zero_points(DNNL_ARG_SRC, 0, {DNNL_RUNTIME_S32_VAL});
    if (out.quant.zeroPoint != 0)
      attr.set_zero_points(DNNL_ARG_DST, 0, {DNNL_RUNTIME_S32_VAL});
    // The fused Relu/Clip: the same quantized bounds XNNPACK uses, in the units the post-op
    // sees (scaled, before the destination zero point is added).
    if (outMin(node) > -128 || outMax(node) < 127) {
      dnnl::post_ops ops;
      const float lo = static_cast<float>(outMin(node) - out.quant.zeroPoint);
      const float hi = static_cast<float>(outMax(node) - out.quant.zeroPoint);
      ops.append_eltwise(1.0F, dnnl::algorithm::eltwise_clip, lo, hi);
      attr.set_post_ops(ops);
    }

    const dnnl::convolution_forward::desc desc(
        dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct, srcMd, anyWeightMd,
        biasMd, dstMd, Dims{node.strideH, node.strideW},
        Dims{node.dilationH - 1, node.dilationW - 1}, Dims{node.padTop, node.padLeft},
        Dims{node.padBottom, node.padRight});
    const dnnl::convolution_forward::primitive_desc pd(desc, attr, engine_);

    // Weights: reordered once into the layout the implementation chose (with its
    // compensation terms for s8 inputs and zero points).
    auto* userWeights = const_cast<std::int8_t*>(node.weights.data());
    memory userWeightMem(userWeightMd, engine_, userWeights);
    memory weightMem(pd.weights_desc(), engine_);
    dnnl::reorder(userWeightMem, weightMem).execute(stream_, userWeightMem, weightMem);
    stream_.wait();

    memory biasMem(biasMd, engine_);
    auto bias = quantizeBias(node.bias, in.quant.scale, node.weightScales);
    if (in.quant.zeroPoint != 0 && !srcZeroPoint) {
      const std::size_t perChannel = node.weights.size() / toSize(cout);
      for (std::size_t c = 0; c < toSize(cout); ++c) {
        std::int64_t sum = 0;
        for (std::size_t k = 0; k < perChannel; ++k)
          sum += node.weights[c * perChannel + k];
        const std::int64_t folded = bias[c] - static_cast<std::int64_t>(in.quant.zeroPoint) * sum;
        bias[c] = static_cast<std::int32_t>(
            std::clamp<std::int64_t>(folded, -2147483647LL, 2147483647LL));
      }
    }
    std::copy(bias.begin(), bias.end(), static_cast<std::int32_t*>(biasMem.get_data_handle()));

    // Source and destination are the graph's own tensor buffers (ranges of the planned arena
    // when memory is planned): oneDNN must work on them, not on copies.
    memory srcMem(srcMd, engine_, inBuf(node));
    memory dstMem(dstMd, engine_, outBuf(node));
    if (srcMem.get_data_handle() != inBuf(node) || dstMem.get_data_handle() != outBuf(node))
      return fail(node, "oneDNN did not keep the tensor buffers it was given", why);
    std::vector<std::pair<int, memory> > args;
    args.emplace_back(DNNL_ARG_SRC, srcMem);
    args.emplace_back(DNNL_ARG_WEIGHTS, weightMem);
    args.emplace_back(DNNL_ARG_BIAS, biasMem);
    args.emplace_back(DNNL_ARG_DST, dstMem);
    if (srcZeroPoint) {
      args.emplace_back(DNNL_ARG_ATTR_ZERO_POINTS | DNNL_ARG_SRC,
                        zeroPointMemory(in.quant.zeroPoint));
    }
    if (out.quant.zeroPoint != 0) {
      args.emplace_back(DNNL_ARG_ATTR_ZERO_POINTS | DNNL_ARG_DST,
                        zeroPointMemory(out.quant.zeroPoint));
    }
    const memory::desc scratchMd = pd.scratchpad_desc();
    if (scratchMd.get_size() > 0) {
      scratchBytes_ = std::max(scratchBytes_, scratchMd.get_size());
      // A placeholder handle; finish() points it into the shared buffer.
      memory pad(scratchMd, engine_, DNNL_MEMORY_NONE);
      scratchpads_.push_back(pad);
      args.emplace_back(DNNL_ARG_SCRATCHPAD, pad);
    }

    convolutions_.push_back(std::make_unique<DnnlConvolution>(dnnl::convolution_forward(pd),
                                                              stream_, std::move(args), arena_));
    Step step;
    step.external = convolutions_.back().get();
    addStep(std::move(step), std::string("dnnl ") + pd.impl_info_str());
    return true;
  }

  int threads_ = 1;
  bool overflowLogged_ = false;
  dnnl::engine engine_;
  dnnl::stream stream_;
  core::TransientArena arena_{kArenaBytes};  // declared before the convolutions: outlives them
  std::vector<std::unique_ptr<DnnlConvolution> > convolutions_;
  std::vector<memory> scratchpads_;
  std::size_t scratchBytes_ = 0;
  memory scratch_;
};

}  // namespace

std::unique_ptr<InferenceBackend> createDnnlInt8Backend(const QdqGraph& graph, int threads,
                                                        bool planMemory, std::string* why) {
  std::unique_ptr<DnnlInt8Backend> backend;
  try {
    backend = std::make_unique<DnnlInt8Backend>(threads);
  } catch (const dnnl::error& e) {
    *why = graph.file + ": oneDNN CPU engine: " + e.what();
    return nullptr;
  }
  backend->file_ = graph.file;
  // The XNNPACK nodes between the convolutions run on the calling thread: the OpenMP team alone
  // holds the other threads (two spinning pools on the same cores fight; header).
  if (!backend->build(graph, 1, planMemory, why) || !backend->finish(why))
    return nullptr;
  return backend;
}

#endif

}  // namespace vp::inference
