// The int8 XNNPACK backend (contract in xnnpack_backend.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "inference/xnnpack_backend.hpp"
#include "inference/xnnpack_runtime.hpp"

namespace vp::inference {
namespace {

std::int8_t quantizeValue(float v, const QuantParams& q) {
  if (std::isnan(v))
    return static_cast<std::int8_t>(q.zeroPoint);
  const float scaled = v / q.scale;
  if (scaled <= -256.0F)
    return -128;
  if (scaled >= 256.0F)
    return 127;
  const float r = std::nearbyint(scaled) + static_cast<float>(q.zeroPoint);
  return static_cast<std::int8_t>(std::clamp(r, -128.0F, 127.0F));
}

std::size_t pixels(const TensorShape& s) {
  return static_cast<std::size_t>(s.h) * static_cast<std::size_t>(s.w);
}
std::size_t toSize(int v) {
  return static_cast<std::size_t>(v);
}

class XnnpackInt8Backend final : public InferenceBackend {
 public:
  bool build(const QdqGraph& graph, int threads, std::string* why) {
    if (!initializeXnnpack(why)) {
      *why = graph.file + ": " + *why;
      return false;
    }
    graph_ = &graph;
    pool_ = makeThreadPool(threads);
    buffers_.reserve(graph.tensors.size());
    for (const auto& t : graph.tensors) {
      buffers_.push_back(makeTensorBuffer<std::int8_t>(t.shape.elements()));
    }
    inputTensor_ = graph.inputTensor;
    for (const auto& node : graph.nodes) {
      kernel_.clear();
      if (!addNode(node, why))
        return false;
      layers_.push_back(LayerInfo{node.name, node.opType, kernel_, node.macs});
    }
    outputData_.reserve(graph.outputs.size());
    for (const auto& out : graph.outputs) {
      const auto& t = graph.tensors[toSize(out.tensor)];
      outputData_.emplace_back(t.shape.elements(), 0.0F);
      OutputTensor ot;
      ot.name = out.name;
      ot.shape = t.shape;
      ot.data = outputData_.back().data();
      ot.quantized = buffers_[toSize(out.tensor)].data();
      ot.scale = t.quant.scale;
      ot.zeroPoint = t.quant.zeroPoint;
      outputs_.push_back(ot);
    }
    graph_ = nullptr;
    return true;
  }

  InputLayout inputLayout() const override { return InputLayout::Int8Nhwc; }
  void* inputData() override { return buffers_[toSize(inputTensor_)].data(); }

  bool run() override {
    for (const auto& step : steps_) {
      if (!step.run(pool_.get()))
        return false;
    }
    for (std::size_t o = 0; o < outputs_.size(); ++o) {
      const std::int8_t* q = outputs_[o].quantized;
      float* f = outputData_[o].data();
      const float scale = outputs_[o].scale;
      const int zp = outputs_[o].zeroPoint;
      const std::size_t n = outputData_[o].size();
      for (std::size_t i = 0; i < n; ++i)
        f[i] = static_cast<float>(q[i] - zp) * scale;
    }
    return true;
  }

  const std::vector<OutputTensor>& outputs() const override { return outputs_; }
  const std::vector<LayerInfo>& layers() const override { return layers_; }

 private:
  const GraphTensor& tensor(int id) const { return graph_->tensors[toSize(id)]; }
  std::int8_t* data(int id) { return buffers_[toSize(id)].data(); }

  bool fail(const GraphNode& node, const std::string& msg, std::string* why) const {
    *why = graph_->file + ": node '" + node.name + "' (" + node.opType + "): " + msg;
    return false;
  }
  bool created(xnn_status status, const char* function, const GraphNode& node, XnnOperator& op,
               xnn_operator_t raw, std::string* why) {
    op.reset(raw);
    if (status != xnn_status_success) {
      return fail(node, std::string(function) + " failed: " + xnnStatusText(status), why);
    }
    return true;
  }
  bool setUp(xnn_status status, const char* function, const GraphNode& node, std::string* why) {
    if (status != xnn_status_success) {
      return fail(node, std::string(function) + " failed: " + xnnStatusText(status), why);
    }
    return true;
  }
  void addKernel(const std::string& name) {
    if (kernel_.empty()) {
      kernel_ = name;
    } else if (kernel_.find(name) == std::string::npos) {
      kernel_ += " + " + name;
    }
  }

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

  std::int8_t outMin(const GraphNode& node) const {
    return quantizeValue(node.clampMin, tensor(node.output).quant);
  }
  std::int8_t outMax(const GraphNode& node) const {
    return quantizeValue(node.clampMax, tensor(node.output).quant);
  }

  static std::vector<std::int32_t> quantizeBias(const std::vector<float>& bias, float inputScale,
                                                const std::vector<float>& weightScales) {
    std::vector<std::int32_t> q(bias.size());
    for (std::size_t c = 0; c < bias.size(); ++c) {
      const double v =
          std::nearbyint(static_cast<double>(bias[c]) /
                         (static_cast<double>(inputScale) * static_cast<double>(weightScales[c])));
      q[c] = static_cast<std::int32_t>(std::clamp(v, -2147483647.0, 2147483647.0));
    }
    return q;
  }

  bool addConv(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const int cin = in.shape.c;
    const int cout = out.shape.c;
    const int cinG = cin / node.group;
    const int coutG = cout / node.group;
    // ONNX OIHW -> XNNPACK [O][kh][kw][I/g].
    std::vector<std::int8_t> kernel(node.weights.size());
    const int kh = node.kernelH;
    const int kw = node.kernelW;
    for (int o = 0; o < cout; ++o) {
      for (int i = 0; i < cinG; ++i) {
        for (int y = 0; y < kh; ++y) {
          for (int x = 0; x < kw; ++x) {
            kernel[toSize(((o * kh + y) * kw + x) * cinG + i)] =
                node.weights[toSize(((o * cinG + i) * kh + y) * kw + x)];
          }
        }
      }
    }
    const auto bias = quantizeBias(node.bias, in.quant.scale, node.weightScales);
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = xnn_create_convolution2d_nhwc_qc8(
        static_cast<std::uint32_t>(node.padTop), static_cast<std::uint32_t>(node.padRight),
        static_cast<std::uint32_t>(node.padBottom), static_cast<std::uint32_t>(node.padLeft),
        static_cast<std::uint32_t>(kh), static_cast<std::uint32_t>(kw),
        static_cast<std::uint32_t>(node.strideH), static_cast<std::uint32_t>(node.strideW),
        static_cast<std::uint32_t>(node.dilationH), static_cast<std::uint32_t>(node.dilationW),
        static_cast<std::uint32_t>(node.group), toSize(cinG), toSize(coutG), toSize(cin),
        toSize(cout), static_cast<std::int8_t>(in.quant.zeroPoint), in.quant.scale,
        node.weightScales.data(), kernel.data(), bias.data(),
        static_cast<std::int8_t>(out.quant.zeroPoint), out.quant.scale, outMin(node), outMax(node),
        0, &raw);
    if (!created(status, "xnn_create_convolution2d_nhwc_qc8", node, step.op, raw, why)) {
      return false;
    }
    if (!setUp(xnn_setup_convolution2d_nhwc_qc8(step.op.get(), 1, toSize(in.shape.h),
                                                toSize(in.shape.w), data(node.inputs[0]),
                                                data(node.output), pool_.get()),
               "xnn_setup_convolution2d_nhwc_qc8", node, why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    addKernel("xnn convolution2d_nhwc_qc8");
    return true;
  }

  bool addDeconv(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const int cin = in.shape.c;
    const int cout = out.shape.c;
    const int cinG = cin / node.group;
    const int coutG = cout / node.group;
    const int kh = node.kernelH;
    const int kw = node.kernelW;
    // Per-tensor kernel scale: requantize per-channel weights to the largest channel scale.
    const float kernelScale = *std::max_element(node.weightScales.begin(), node.weightScales.end());
    const bool perTensor = std::all_of(node.weightScales.begin(), node.weightScales.end(),
                                       [&](float s) { return s == kernelScale; });
    // ONNX [Cin][Cout/g][kh][kw] -> XNNPACK [g][Cout/g][kh][kw][Cin/g].
    std::vector<std::int8_t> kernel(node.weights.size());
    for (int g = 0; g < node.group; ++g) {
      for (int j = 0; j < coutG; ++j) {
        const float ratio = node.weightScales[toSize(g * coutG + j)] / kernelScale;
        for (int i = 0; i < cinG; ++i) {
          for (int y = 0; y < kh; ++y) {
            for (int x = 0; x < kw; ++x) {
              const std::int8_t w =
                  node.weights[toSize((((g * cinG + i) * coutG + j) * kh + y) * kw + x)];
              const float q =
                  perTensor ? static_cast<float>(w) : std::nearbyint(static_cast<float>(w) * ratio);
              kernel[toSize((((g * coutG + j) * kh + y) * kw + x) * cinG + i)] =
                  static_cast<std::int8_t>(std::clamp(q, -127.0F, 127.0F));
            }
          }
        }
      }
    }
    const std::vector<float> scales(toSize(cout), kernelScale);
    const auto bias = quantizeBias(node.bias, in.quant.scale, scales);
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = xnn_create_deconvolution2d_nhwc_qs8(
        static_cast<std::uint32_t>(node.padTop), static_cast<std::uint32_t>(node.padRight),
        static_cast<std::uint32_t>(node.padBottom), static_cast<std::uint32_t>(node.padLeft),
        static_cast<std::uint32_t>(kh), static_cast<std::uint32_t>(kw),
        static_cast<std::uint32_t>(node.strideH), static_cast<std::uint32_t>(node.strideW),
        static_cast<std::uint32_t>(node.dilationH), static_cast<std::uint32_t>(node.dilationW),
        static_cast<std::uint32_t>(node.group), toSize(cinG), toSize(coutG), toSize(cin),
        toSize(cout), static_cast<std::int8_t>(in.quant.zeroPoint), in.quant.scale, kernelScale,
        kernel.data(), bias.data(), static_cast<std::int8_t>(out.quant.zeroPoint), out.quant.scale,
        outMin(node), outMax(node), 0, &raw);
    if (!created(status, "xnn_create_deconvolution2d_nhwc_qs8", node, step.op, raw, why)) {
      return false;
    }
    if (!setUp(
            xnn_setup_deconvolution2d_nhwc_qs8(
                step.op.get(), 1, toSize(in.shape.h), toSize(in.shape.w),
                static_cast<std::uint32_t>(node.adjustH), static_cast<std::uint32_t>(node.adjustW),
                data(node.inputs[0]), data(node.output), pool_.get()),
            "xnn_setup_deconvolution2d_nhwc_qs8", node, why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    addKernel(perTensor ? "xnn deconvolution2d_nhwc_qs8"
                        : "xnn deconvolution2d_nhwc_qs8 (per-channel scales requantized to "
                          "per-tensor)");
    return true;
  }

  static std::array<std::size_t, 4> nhwc(const TensorShape& s) {
    return {toSize(s.n), toSize(s.h), toSize(s.w), toSize(s.c)};
  }

  bool addBinary(const GraphNode& node, std::string* why) {
    const auto& a = tensor(node.inputs[0]);
    const auto& b = tensor(node.inputs[1]);
    const auto& out = tensor(node.output);
    const bool add = node.kind == OpKind::Add;
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = (add ? xnn_create_add_nd_qs8 : xnn_create_multiply_nd_qs8)(
        static_cast<std::int8_t>(a.quant.zeroPoint), a.quant.scale,
        static_cast<std::int8_t>(b.quant.zeroPoint), b.quant.scale,
        static_cast<std::int8_t>(out.quant.zeroPoint), out.quant.scale, outMin(node), outMax(node),
        0, &raw);
    const char* createName = add ? "xnn_create_add_nd_qs8" : "xnn_create_multiply_nd_qs8";
    if (!created(status, createName, node, step.op, raw, why))
      return false;
    const auto sa = nhwc(a.shape);
    const auto sb = nhwc(b.shape);
    const auto setupStatus = (add ? xnn_setup_add_nd_qs8 : xnn_setup_multiply_nd_qs8)(
        step.op.get(), 4, sa.data(), 4, sb.data(), data(node.inputs[0]), data(node.inputs[1]),
        data(node.output), pool_.get());
    if (!setUp(setupStatus, add ? "xnn_setup_add_nd_qs8" : "xnn_setup_multiply_nd_qs8", node,
               why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    addKernel(add ? "xnn add_nd_qs8" : "xnn multiply_nd_qs8");
    return true;
  }

  // One strided copy of `batch` rows of `channels` bytes.
  bool addCopy(const GraphNode& node, std::size_t channels, std::size_t inStride,
               std::size_t outStride, std::size_t batch, const std::int8_t* src, std::int8_t* dst,
               std::string* why) {
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = xnn_create_copy_nc_x8(channels, inStride, outStride, 0, &raw);
    if (!created(status, "xnn_create_copy_nc_x8", node, step.op, raw, why)) {
      return false;
    }
    if (!setUp(xnn_setup_copy_nc_x8(step.op.get(), batch, src, dst, pool_.get()),
               "xnn_setup_copy_nc_x8", node, why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    return true;
  }

  bool addConcat(const GraphNode& node, std::string* why) {
    const auto& out = tensor(node.output);
    std::size_t offset = 0;
    for (const int input : node.inputs) {
      const auto& in = tensor(input);
      if (!addCopy(node, toSize(in.shape.c), toSize(in.shape.c), toSize(out.shape.c),
                   pixels(in.shape), data(input), data(node.output) + offset, why)) {
        return false;
      }
      offset += toSize(in.shape.c);
    }
    addKernel("xnn copy_nc_x8 (into channel slices)");
    return true;
  }

  bool addResizeBilinear(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = xnn_create_resize_bilinear2d_nhwc_s8(
        c, c, c, node.alignCorners ? XNN_FLAG_ALIGN_CORNERS : 0U, &raw);
    if (!created(status, "xnn_create_resize_bilinear2d_nhwc_s8", node, step.op, raw, why)) {
      return false;
    }
    if (!setUp(xnn_setup_resize_bilinear2d_nhwc_s8(
                   step.op.get(), 1, toSize(in.shape.h), toSize(in.shape.w), toSize(out.shape.h),
                   toSize(out.shape.w), data(node.inputs[0]), data(node.output), pool_.get()),
               "xnn_setup_resize_bilinear2d_nhwc_s8", node, why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    addKernel("xnn resize_bilinear2d_nhwc_s8");
    return true;
  }

  // Integer nearest upscaling: widen each row into a scratch buffer (kw strided copies), then
  // replicate the widened rows (kh strided copies).
  bool addResizeNearest(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    const auto kh = toSize(node.scaleH);
    const auto kw = toSize(node.scaleW);
    const auto rowBytes = toSize(out.shape.w) * c;
    scratch_.push_back(makeTensorBuffer<std::int8_t>(toSize(in.shape.h) * rowBytes));
    std::int8_t* wide = scratch_.back().data();
    for (std::size_t dx = 0; dx < kw; ++dx) {
      if (!addCopy(node, c, c, kw * c, pixels(in.shape), data(node.inputs[0]), wide + dx * c,
                   why)) {
        return false;
      }
    }
    for (std::size_t dy = 0; dy < kh; ++dy) {
      if (!addCopy(node, rowBytes, rowBytes, kh * rowBytes, toSize(in.shape.h), wide,
                   data(node.output) + dy * rowBytes, why)) {
        return false;
      }
    }
    addKernel("xnn copy_nc_x8 (pixel replication)");
    return true;
  }

  bool addMaxPool(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = xnn_create_max_pooling2d_nhwc_s8(
        static_cast<std::uint32_t>(node.padTop), static_cast<std::uint32_t>(node.padRight),
        static_cast<std::uint32_t>(node.padBottom), static_cast<std::uint32_t>(node.padLeft),
        static_cast<std::uint32_t>(node.kernelH), static_cast<std::uint32_t>(node.kernelW),
        static_cast<std::uint32_t>(node.strideH), static_cast<std::uint32_t>(node.strideW),
        static_cast<std::uint32_t>(node.dilationH), static_cast<std::uint32_t>(node.dilationW), c,
        c, c, outMin(node), outMax(node), 0, &raw);
    if (!created(status, "xnn_create_max_pooling2d_nhwc_s8", node, step.op, raw, why)) {
      return false;
    }
    if (!setUp(xnn_setup_max_pooling2d_nhwc_s8(step.op.get(), 1, toSize(in.shape.h),
                                               toSize(in.shape.w), data(node.inputs[0]),
                                               data(node.output), pool_.get()),
               "xnn_setup_max_pooling2d_nhwc_s8", node, why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    addKernel("xnn max_pooling2d_nhwc_s8");
    return true;
  }

  bool addGlobalAveragePool(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    Step step;
    xnn_operator_t raw = nullptr;
    const auto status = xnn_create_global_average_pooling_nwc_qs8(
        c, c, c, static_cast<std::int8_t>(in.quant.zeroPoint), in.quant.scale,
        static_cast<std::int8_t>(out.quant.zeroPoint), out.quant.scale, outMin(node), outMax(node),
        0, &raw);
    if (!created(status, "xnn_create_global_average_pooling_nwc_qs8", node, step.op, raw, why)) {
      return false;
    }
    if (!setUp(xnn_setup_global_average_pooling_nwc_qs8(step.op.get(), 1, pixels(in.shape),
                                                        data(node.inputs[0]), data(node.output),
                                                        pool_.get()),
               "xnn_setup_global_average_pooling_nwc_qs8", node, why)) {
      return false;
    }
    steps_.push_back(std::move(step));
    addKernel("xnn global_average_pooling_nwc_qs8");
    return true;
  }

  // Sigmoid / Tanh / Relu / Clip: XNNPACK when it has the kernel for these quantization
  // params, else a 256-entry table computed here (exact: out = Q(f(DQ(in)))).
  bool addElementwise(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    const auto n = in.shape.elements();
    Step step;
    xnn_operator_t raw = nullptr;
    xnn_status status = xnn_status_unsupported_parameter;
    const char* name = "";
    const auto inZp = static_cast<std::int8_t>(in.quant.zeroPoint);
    const auto outZp = static_cast<std::int8_t>(out.quant.zeroPoint);
    if (node.kind == OpKind::Sigmoid) {
      status = xnn_create_sigmoid_nc_qs8(c, c, c, inZp, in.quant.scale, outZp, out.quant.scale,
                                         outMin(node), outMax(node), 0, &raw);
      name = "sigmoid_nc_qs8";
    } else if (node.kind == OpKind::Tanh) {
      status = xnn_create_tanh_nc_qs8(c, c, c, inZp, in.quant.scale, outZp, out.quant.scale,
                                      outMin(node), outMax(node), 0, &raw);
      name = "tanh_nc_qs8";
    } else if (sameQuant(in.quant, out.quant)) {
      status = xnn_create_clamp_nc_s8(c, c, c, outMin(node), outMax(node), 0, &raw);
      name = "clamp_nc_s8";
    }
    if (status == xnn_status_success) {
      step.op.reset(raw);
      const std::int8_t* src = data(node.inputs[0]);
      std::int8_t* dst = data(node.output);
      const auto batch = pixels(in.shape);
      xnn_status setupStatus = xnn_status_success;
      if (node.kind == OpKind::Sigmoid) {
        setupStatus = xnn_setup_sigmoid_nc_qs8(step.op.get(), batch, src, dst, pool_.get());
      } else if (node.kind == OpKind::Tanh) {
        setupStatus = xnn_setup_tanh_nc_qs8(step.op.get(), batch, src, dst, pool_.get());
      } else {
        setupStatus = xnn_setup_clamp_nc_s8(step.op.get(), batch, src, dst, pool_.get());
      }
      if (!setUp(setupStatus, name, node, why))
        return false;
      steps_.push_back(std::move(step));
      addKernel(std::string("xnn ") + name);
      return true;
    }
    if (raw != nullptr)
      xnn_delete_operator(raw);
    for (int q = -128; q <= 127; ++q) {
      const float x = static_cast<float>(q - in.quant.zeroPoint) * in.quant.scale;
      float y = x;
      if (node.kind == OpKind::Sigmoid)
        y = 1.0F / (1.0F + std::exp(-x));
      if (node.kind == OpKind::Tanh)
        y = std::tanh(x);
      y = std::clamp(y, node.clampMin, node.clampMax);
      step.lut[toSize(q + 128)] = quantizeValue(y, out.quant);
    }
    step.lutInput = data(node.inputs[0]);
    step.lutOutput = data(node.output);
    step.count = n;
    steps_.push_back(std::move(step));
    addKernel(node.kind == OpKind::Clamp ? "vp lut_s8 (requantizing clamp)"
                                         : "vp lut_s8 (256-entry table)");
    return true;
  }

  const QdqGraph* graph_ = nullptr;
  ThreadPool pool_;
  std::vector<std::vector<std::int8_t>> buffers_;
  std::vector<std::vector<std::int8_t>> scratch_;
  std::vector<Step> steps_;
  std::vector<std::vector<float>> outputData_;
  std::vector<OutputTensor> outputs_;
  std::vector<LayerInfo> layers_;
  std::string kernel_;
  int inputTensor_ = 0;
};

}  // namespace

std::unique_ptr<InferenceBackend> createXnnpackInt8Backend(const QdqGraph& graph, int threads,
                                                           std::string* why) {
  auto backend = std::make_unique<XnnpackInt8Backend>();
  if (!backend->build(graph, threads, why))
    return nullptr;
  return backend;
}

}  // namespace vp::inference
