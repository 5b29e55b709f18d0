// inference/xnnpack_graph: the graph walk both XNNPACK backends share.
//
// Contract: XnnpackGraphBackend<T> (T = std::int8_t or float) gives every graph tensor a
// zero-initialised NHWC range of T (by default in one arena shared by liveness, see
// memory_plan.hpp; `planned` false: one buffer each) and walks the nodes in order. Kinds whose int8
// and float operators differ only in the element type (Concat and nearest Resize as strided copies
// into slices, bilinear Resize, MaxPool) are built here; for the others (Conv, ConvTranspose,
// Add/Mul, GlobalAveragePool, Sigmoid/Tanh/Clamp) a per-kind hook of the derived backend
// picks the XNNPACK functions, their quantization or float parameters and the weight
// conversion, and registers the result through addOperator() / addStep(). The graph is read
// only inside build(); afterwards the backend owns everything run() touches. run() is the
// loop over the steps plus, for int8, dequantizing the outputs into preallocated floats: no
// heap allocation and no exceptions. Load errors read "file: node 'name' (OpType): why".
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "inference/backend.hpp"
#include "inference/memory_plan.hpp"
#include "inference/onnx_graph.hpp"
#include "inference/xnnpack_runtime.hpp"

namespace vp::inference {

inline std::size_t toSize(int v) {
  return static_cast<std::size_t>(v);
}
inline std::size_t pixels(const TensorShape& s) {
  return toSize(s.h) * toSize(s.w);
}
inline std::array<std::size_t, 4> nhwc(const TensorShape& s) {
  return {toSize(s.n), toSize(s.h), toSize(s.w), toSize(s.c)};
}

template <class T>
class XnnpackGraphBackend : public InferenceBackend {
  static_assert(std::is_same_v<T, std::int8_t> || std::is_same_v<T, float>);
  static constexpr bool kInt8 = std::is_same_v<T, std::int8_t>;

 public:
  bool build(const QdqGraph& graph, int threads, bool planned, std::string* why) {
    if (!initializeXnnpack(why)) {
      *why = graph.file + ": " + *why;
      return false;
    }
    graph_ = &graph;
    pool_ = makeThreadPool(threads);
    allocateActivations(graph, planned);
    inputTensor_ = graph.inputTensor;
    for (std::size_t s = 0; s < graph.nodes.size(); ++s) {
      const auto& node = graph.nodes[s];
      step_ = s;
      kernel_.clear();
      if (!addNode(node, why))
        return false;
      layers_.push_back(LayerInfo{node.name, node.opType, kernel_, node.macs});
    }
    dequantized_.reserve(graph.outputs.size());
    for (const auto& out : graph.outputs) {
      const auto& t = tensor(out.tensor);
      OutputTensor ot;
      ot.name = out.name;
      ot.shape = t.shape;
      if constexpr (kInt8) {
        dequantized_.emplace_back(t.shape.elements(), 0.0F);
        ot.data = dequantized_.back().data();
        ot.quantized = data(out.tensor);
        ot.scale = t.quant.scale;
        ot.zeroPoint = t.quant.zeroPoint;
      } else {
        ot.data = data(out.tensor);
      }
      outputs_.push_back(ot);
    }
    graph_ = nullptr;
    return true;
  }

  InputLayout inputLayout() const override {
    return kInt8 ? InputLayout::Int8Nhwc : InputLayout::FloatNhwc;
  }
  void* inputData() override { return data(inputTensor_); }

  bool run() override {
    for (const auto& step : steps_) {
      if (!step.run(pool_.get()))
        return false;
    }
    // Only int8 outputs have a dequantized copy (dequantized_ stays empty for float).
    for (std::size_t o = 0; o < dequantized_.size(); ++o) {
      const std::int8_t* q = outputs_[o].quantized;
      float* f = dequantized_[o].data();
      const float scale = outputs_[o].scale;
      const int zp = outputs_[o].zeroPoint;
      const std::size_t n = dequantized_[o].size();
      for (std::size_t i = 0; i < n; ++i)
        f[i] = static_cast<float>(q[i] - zp) * scale;
    }
    return true;
  }

  const std::vector<OutputTensor>& outputs() const override { return outputs_; }
  const std::vector<LayerInfo>& layers() const override { return layers_; }
  ActivationMemory activationMemory() const override { return memory_; }

 protected:
  // Per-kind hooks: create the node's operators on data(node.inputs) -> data(node.output).
  virtual bool addConv(const GraphNode& node, std::string* why) = 0;
  virtual bool addDeconv(const GraphNode& node, std::string* why) = 0;
  virtual bool addBinary(const GraphNode& node, std::string* why) = 0;  // Add, Mul
  virtual bool addGlobalAveragePool(const GraphNode& node, std::string* why) = 0;
  virtual bool addElementwise(const GraphNode& node, std::string* why) = 0;  // Sigmoid/Tanh/Clamp
  // The node's fused output clamp in T.
  virtual T outMin(const GraphNode& node) const = 0;
  virtual T outMax(const GraphNode& node) const = 0;

  const GraphTensor& tensor(int id) const { return graph_->tensors[toSize(id)]; }
  T* data(int id) { return tensorData_[toSize(id)]; }
  T* inBuf(const GraphNode& node) { return data(node.inputs[0]); }
  T* outBuf(const GraphNode& node) { return data(node.output); }
  pthreadpool_t pool() const { return pool_.get(); }

  bool fail(const GraphNode& node, const std::string& msg, std::string* why) const {
    *why = graph_->file + ": node '" + node.name + "' (" + node.opType + "): " + msg;
    return false;
  }

  // Takes ownership of `op` (also when `created` is a failure, so nothing leaks), binds it to
  // its buffers with setup(op, args...) and reports the node's kernel as "xnn <name>".
  template <class Setup, class... Args>
  bool addOperator(const GraphNode& node, const std::string& name, xnn_status created,
                   xnn_operator_t op, std::string* why, Setup setup, Args... args) {
    Step step;
    step.op.reset(op);
    if (created != xnn_status_success)
      return fail(node, "xnn_create_" + name + " failed: " + xnnStatusText(created), why);
    const xnn_status status = setup(op, args...);
    if (status != xnn_status_success)
      return fail(node, "xnn_setup_" + name + " failed: " + xnnStatusText(status), why);
    addStep(std::move(step), "xnn " + name);
    return true;
  }

  // Any step; a node made of several kinds of steps reports "a + b".
  void addStep(Step step, const std::string& kernel) {
    steps_.push_back(std::move(step));
    if (kernel_.empty()) {
      kernel_ = kernel;
    } else if (kernel_.find(kernel) == std::string::npos) {
      kernel_ += " + " + kernel;
    }
  }
  // For nodes whose operators alone would not say what they do (e.g. copies into slices).
  void relabel(std::string kernel) { kernel_ = std::move(kernel); }

  // XNNPACK's convolution and pooling create functions open with the same window parameters
  // (pads top/right/bottom/left, kernel, strides, dilations); `rest` follows them.
  template <class Create, class... Rest>
  static xnn_status createWindowed(Create create, const GraphNode& node, Rest... rest) {
    const auto u = [](int v) { return static_cast<std::uint32_t>(v); };
    return create(u(node.padTop), u(node.padRight), u(node.padBottom), u(node.padLeft),
                  u(node.kernelH), u(node.kernelW), u(node.strideH), u(node.strideW),
                  u(node.dilationH), u(node.dilationW), rest...);
  }
  // (De)convolutions add groups and channel counts (per group, then total) after the window.
  template <class Create, class... Rest>
  xnn_status createConvolution(Create create, const GraphNode& node, Rest... rest) const {
    const auto groups = toSize(node.group);
    const auto cin = toSize(tensor(node.inputs[0]).shape.c);
    const auto cout = toSize(tensor(node.output).shape.c);
    return createWindowed(create, node, static_cast<std::uint32_t>(node.group), cin / groups,
                          cout / groups, cin, cout, rest...);
  }

  // ONNX Conv weights [Cout][Cin/g][kh][kw] -> XNNPACK [Cout][kh][kw][Cin/g]; convert(w, o)
  // is the stored value of weight w of output channel o.
  template <class Convert>
  std::vector<T> convKernel(const GraphNode& node, Convert convert) const {
    const int cout = tensor(node.output).shape.c;
    const int cinG = tensor(node.inputs[0]).shape.c / node.group;
    const int kh = node.kernelH;
    const int kw = node.kernelW;
    std::vector<T> kernel(node.weights.size());
    for (int o = 0; o < cout; ++o) {
      for (int i = 0; i < cinG; ++i) {
        for (int y = 0; y < kh; ++y) {
          for (int x = 0; x < kw; ++x) {
            kernel[toSize(((o * kh + y) * kw + x) * cinG + i)] =
                convert(node.weights[toSize(((o * cinG + i) * kh + y) * kw + x)], o);
          }
        }
      }
    }
    return kernel;
  }
  // ONNX ConvTranspose [Cin][Cout/g][kh][kw] -> XNNPACK [g][Cout/g][kh][kw][Cin/g]; convert as
  // for convKernel().
  template <class Convert>
  std::vector<T> deconvKernel(const GraphNode& node, Convert convert) const {
    const int cinG = tensor(node.inputs[0]).shape.c / node.group;
    const int coutG = tensor(node.output).shape.c / node.group;
    const int kh = node.kernelH;
    const int kw = node.kernelW;
    std::vector<T> kernel(node.weights.size());
    for (int g = 0; g < node.group; ++g) {
      for (int j = 0; j < coutG; ++j) {
        for (int i = 0; i < cinG; ++i) {
          for (int y = 0; y < kh; ++y) {
            for (int x = 0; x < kw; ++x) {
              kernel[toSize((((g * coutG + j) * kh + y) * kw + x) * cinG + i)] =
                  convert(node.weights[toSize((((g * cinG + i) * coutG + j) * kh + y) * kw + x)],
                          g * coutG + j);
            }
          }
        }
      }
    }
    return kernel;
  }

 private:
  // The int8 or the float one of two XNNPACK functions that differ only in the element type.
  template <class Int8Version, class FloatVersion>
  static constexpr auto pick(Int8Version int8Version, FloatVersion floatVersion) {
    if constexpr (kInt8) {
      return int8Version;
    } else {
      return floatVersion;
    }
  }
  static constexpr const char* kCopy = kInt8 ? "copy_nc_x8" : "copy_nc_x32";

  bool addNode(const GraphNode& node, std::string* why) {
    switch (node.kind) {
      case OpKind::Conv:
        return addConv(node, why);
      case OpKind::ConvTranspose:
        return addDeconv(node, why);
      case OpKind::Add:
      case OpKind::Mul:
        return addBinary(node, why);
      case OpKind::Concat:
        return addConcat(node, why);
      case OpKind::ResizeBilinear:
        return addResizeBilinear(node, why);
      case OpKind::ResizeNearest:
        return addResizeNearest(node, why);
      case OpKind::MaxPool:
        return addMaxPool(node, why);
      case OpKind::GlobalAveragePool:
        return addGlobalAveragePool(node, why);
      case OpKind::Sigmoid:
      case OpKind::Tanh:
      case OpKind::Clamp:
        return addElementwise(node, why);
    }
    return fail(node, "internal: unknown node kind", why);
  }

  // One strided copy of `batch` rows of `channels` elements; copies only move bytes, so the
  // element size picks the operator.
  bool addCopy(const GraphNode& node, std::size_t channels, std::size_t inStride,
               std::size_t outStride, std::size_t batch, const T* src, T* dst, std::string* why) {
    xnn_operator_t op = nullptr;
    const auto status =
        pick(xnn_create_copy_nc_x8, xnn_create_copy_nc_x32)(channels, inStride, outStride, 0, &op);
    return addOperator(node, kCopy, status, op, why,
                       pick(xnn_setup_copy_nc_x8, xnn_setup_copy_nc_x32), batch, src, dst, pool());
  }

  // Each input is copied into its channel slice of the output pixels.
  bool addConcat(const GraphNode& node, std::string* why) {
    const auto& out = tensor(node.output);
    std::size_t offset = 0;
    for (const int input : node.inputs) {
      const auto& in = tensor(input);
      if (!addCopy(node, toSize(in.shape.c), toSize(in.shape.c), toSize(out.shape.c),
                   pixels(in.shape), data(input), outBuf(node) + offset, why)) {
        return false;
      }
      offset += toSize(in.shape.c);
    }
    relabel(std::string("xnn ") + kCopy + " (into channel slices)");
    return true;
  }

  bool addResizeBilinear(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status =
        pick(xnn_create_resize_bilinear2d_nhwc_s8, xnn_create_resize_bilinear2d_nhwc_f32)(
            c, c, c, node.alignCorners ? XNN_FLAG_ALIGN_CORNERS : 0U, &op);
    return addOperator(
        node, kInt8 ? "resize_bilinear2d_nhwc_s8" : "resize_bilinear2d_nhwc_f32", status, op, why,
        pick(xnn_setup_resize_bilinear2d_nhwc_s8, xnn_setup_resize_bilinear2d_nhwc_f32), 1U,
        toSize(in.shape.h), toSize(in.shape.w), toSize(out.shape.h), toSize(out.shape.w),
        inBuf(node), outBuf(node), pool());
  }

  bool addMaxPool(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status =
        createWindowed(pick(xnn_create_max_pooling2d_nhwc_s8, xnn_create_max_pooling2d_nhwc_f32),
                       node, c, c, c, outMin(node), outMax(node), 0U, &op);
    return addOperator(node, kInt8 ? "max_pooling2d_nhwc_s8" : "max_pooling2d_nhwc_f32", status, op,
                       why, pick(xnn_setup_max_pooling2d_nhwc_s8, xnn_setup_max_pooling2d_nhwc_f32),
                       1U, toSize(in.shape.h), toSize(in.shape.w), inBuf(node), outBuf(node),
                       pool());
  }

  // Integer nearest upscaling: widen each row into a scratch buffer (kw strided copies), then
  // replicate the widened rows (kh strided copies).
  bool addResizeNearest(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    const auto kh = toSize(node.scaleH);
    const auto kw = toSize(node.scaleW);
    const auto rowValues = toSize(out.shape.w) * c;
    T* wide = scratchData_[step_];
    for (std::size_t dx = 0; dx < kw; ++dx) {
      if (!addCopy(node, c, c, kw * c, pixels(in.shape), inBuf(node), wide + dx * c, why))
        return false;
    }
    for (std::size_t dy = 0; dy < kh; ++dy) {
      if (!addCopy(node, rowValues, rowValues, kh * rowValues, toSize(in.shape.h), wide,
                   outBuf(node) + dy * rowValues, why)) {
        return false;
      }
    }
    relabel(std::string("xnn ") + kCopy + " (pixel replication)");
    return true;
  }

  // The scratch row buffer of a nearest Resize: the input's rows widened to the output width.
  static std::size_t resizeScratchElements(const QdqGraph& graph, const GraphNode& node) {
    const auto& in = graph.tensors[toSize(node.inputs[0])].shape;
    const auto& out = graph.tensors[toSize(node.output)].shape;
    return toSize(in.h) * toSize(out.w) * toSize(in.c);
  }

  // Points every tensor (and every nearest Resize's scratch) at its memory, zero-initialised:
  // with the plan, ranges of one arena shared by liveness (memory_plan.hpp); without it, one
  // buffer each. Both reserve XNN_EXTRA_BYTES of readable slack behind every buffer.
  void allocateActivations(const QdqGraph& graph, bool planned) {
    std::vector<MemoryBlock> blocks = tensorLifetimes(graph, sizeof(T));
    const std::size_t tensorCount = blocks.size();
    std::vector<std::size_t> scratchBlock(graph.nodes.size(), 0);
    for (std::size_t s = 0; s < graph.nodes.size(); ++s) {
      const auto& node = graph.nodes[s];
      if (node.kind != OpKind::ResizeNearest)
        continue;
      scratchBlock[s] = blocks.size();
      const int step = static_cast<int>(s);
      blocks.push_back(MemoryBlock{resizeScratchElements(graph, node) * sizeof(T), step, step});
    }
    MemoryPlanOptions options;
    options.alignment_bytes = kArenaAlignment_bytes;
    options.slack_bytes = XNN_EXTRA_BYTES;
    const MemoryPlan plan = planMemory(blocks, options);
    memory_.planned = planned;
    memory_.separate_bytes = plan.separate_bytes;
    std::vector<T*> blockData(blocks.size(), nullptr);
    if (planned) {
      // The vector's zeroed bytes, the start rounded up to the alignment.
      arena_.assign(plan.arena_bytes + kArenaAlignment_bytes, std::byte{0});
      const auto address = reinterpret_cast<std::uintptr_t>(arena_.data());
      const std::size_t skip =
          (kArenaAlignment_bytes - address % kArenaAlignment_bytes) % kArenaAlignment_bytes;
      std::byte* base = arena_.data() + skip;
      for (std::size_t b = 0; b < blocks.size(); ++b)
        blockData[b] = reinterpret_cast<T*>(base + plan.offsets[b]);
      memory_.allocated_bytes = plan.arena_bytes;
    } else {
      separate_.reserve(blocks.size());
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        separate_.push_back(makeTensorBuffer<T>(blocks[b].bytes / sizeof(T)));
        blockData[b] = separate_.back().data();
      }
      memory_.allocated_bytes = plan.separate_bytes;
    }
    tensorData_.assign(blockData.begin(),
                       blockData.begin() + static_cast<std::ptrdiff_t>(tensorCount));
    scratchData_.assign(graph.nodes.size(), nullptr);
    for (std::size_t s = 0; s < graph.nodes.size(); ++s) {
      if (graph.nodes[s].kind == OpKind::ResizeNearest)
        scratchData_[s] = blockData[scratchBlock[s]];
    }
  }

  static constexpr std::size_t kArenaAlignment_bytes = 64;  // a cache line, >= any SIMD load

  const QdqGraph* graph_ = nullptr;  // only during build()
  std::size_t step_ = 0;             // the node being built's index, only during build()
  ThreadPool pool_;
  std::vector<std::byte> arena_;          // with the plan: every tensor and scratch buffer
  std::vector<std::vector<T>> separate_;  // without it: one buffer each
  std::vector<T*> tensorData_;            // per graph tensor
  std::vector<T*> scratchData_;           // per node: a nearest Resize's scratch, else nullptr
  ActivationMemory memory_;
  std::vector<Step> steps_;
  std::vector<std::vector<float>> dequantized_;  // int8 only: the float view of each output
  std::vector<OutputTensor> outputs_;
  std::vector<LayerInfo> layers_;
  std::string kernel_;  // the node being built's LayerInfo::backendKernel
  int inputTensor_ = 0;
};

// What the create functions of xnnpack_backend.hpp do: a backend only when it built completely.
template <class Backend>
std::unique_ptr<InferenceBackend> makeBackend(const QdqGraph& graph, int threads, bool planned,
                                              std::string* why) {
  auto backend = std::make_unique<Backend>();
  if (!backend->build(graph, threads, planned, why))
    return nullptr;
  return backend;
}

}  // namespace vp::inference
