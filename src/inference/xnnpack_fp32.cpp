// The float XNNPACK backend (contract in xnnpack_backend.hpp): the IR with dequantized
// weights, Q/DQ dropped.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "inference/xnnpack_backend.hpp"
#include "inference/xnnpack_runtime.hpp"

namespace vp::inference {
namespace {

std::size_t pixels(const TensorShape& s) {
  return static_cast<std::size_t>(s.h) * static_cast<std::size_t>(s.w);
}
std::size_t toSize(int v) {
  return static_cast<std::size_t>(v);
}

class XnnpackFp32Backend final : public InferenceBackend {
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
      buffers_.push_back(makeTensorBuffer<float>(t.shape.elements()));
    }
    inputTensor_ = graph.inputTensor;
    for (const auto& node : graph.nodes) {
      kernel_.clear();
      if (!addNode(node, why))
        return false;
      layers_.push_back(LayerInfo{node.name, node.opType, kernel_, node.macs});
    }
    for (const auto& out : graph.outputs) {
      const auto& t = graph.tensors[toSize(out.tensor)];
      OutputTensor ot;
      ot.name = out.name;
      ot.shape = t.shape;
      ot.data = buffers_[toSize(out.tensor)].data();
      outputs_.push_back(ot);
    }
    graph_ = nullptr;
    return true;
  }

  InputLayout inputLayout() const override { return InputLayout::FloatNhwc; }
  void* inputData() override { return buffers_[toSize(inputTensor_)].data(); }

  bool run() override {
    for (const auto& step : steps_) {
      if (!step.run(pool_.get()))
        return false;
    }
    return true;
  }

  const std::vector<OutputTensor>& outputs() const override { return outputs_; }
  const std::vector<LayerInfo>& layers() const override { return layers_; }

 private:
  const GraphTensor& tensor(int id) const { return graph_->tensors[toSize(id)]; }
  float* data(int id) { return buffers_[toSize(id)].data(); }

  bool fail(const GraphNode& node, const std::string& msg, std::string* why) const {
    *why = graph_->file + ": node '" + node.name + "' (" + node.opType + "): " + msg;
    return false;
  }
  bool check(xnn_status status, const char* function, const GraphNode& node,
             std::string* why) const {
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
  void push(xnn_operator_t op) {
    Step step;
    step.op.reset(op);
    steps_.push_back(std::move(step));
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

  bool addConv(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const int cin = in.shape.c;
    const int cout = out.shape.c;
    const int cinG = cin / node.group;
    const int coutG = cout / node.group;
    const int kh = node.kernelH;
    const int kw = node.kernelW;
    std::vector<float> kernel(node.weights.size());
    for (int o = 0; o < cout; ++o) {
      for (int i = 0; i < cinG; ++i) {
        for (int y = 0; y < kh; ++y) {
          for (int x = 0; x < kw; ++x) {
            kernel[toSize(((o * kh + y) * kw + x) * cinG + i)] =
                static_cast<float>(node.weights[toSize(((o * cinG + i) * kh + y) * kw + x)]) *
                node.weightScales[toSize(o)];
          }
        }
      }
    }
    xnn_operator_t op = nullptr;
    const auto status = xnn_create_convolution2d_nhwc_f32(
        static_cast<std::uint32_t>(node.padTop), static_cast<std::uint32_t>(node.padRight),
        static_cast<std::uint32_t>(node.padBottom), static_cast<std::uint32_t>(node.padLeft),
        static_cast<std::uint32_t>(kh), static_cast<std::uint32_t>(kw),
        static_cast<std::uint32_t>(node.strideH), static_cast<std::uint32_t>(node.strideW),
        static_cast<std::uint32_t>(node.dilationH), static_cast<std::uint32_t>(node.dilationW),
        static_cast<std::uint32_t>(node.group), toSize(cinG), toSize(coutG), toSize(cin),
        toSize(cout), kernel.data(), node.bias.data(), node.clampMin, node.clampMax, 0, &op);
    if (!check(status, "xnn_create_convolution2d_nhwc_f32", node, why))
      return false;
    push(op);
    if (!check(
            xnn_setup_convolution2d_nhwc_f32(op, 1, toSize(in.shape.h), toSize(in.shape.w),
                                             data(node.inputs[0]), data(node.output), pool_.get()),
            "xnn_setup_convolution2d_nhwc_f32", node, why)) {
      return false;
    }
    addKernel("xnn convolution2d_nhwc_f32");
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
    std::vector<float> kernel(node.weights.size());
    for (int g = 0; g < node.group; ++g) {
      for (int j = 0; j < coutG; ++j) {
        const float scale = node.weightScales[toSize(g * coutG + j)];
        for (int i = 0; i < cinG; ++i) {
          for (int y = 0; y < kh; ++y) {
            for (int x = 0; x < kw; ++x) {
              kernel[toSize((((g * coutG + j) * kh + y) * kw + x) * cinG + i)] =
                  static_cast<float>(
                      node.weights[toSize((((g * cinG + i) * coutG + j) * kh + y) * kw + x)]) *
                  scale;
            }
          }
        }
      }
    }
    xnn_operator_t op = nullptr;
    const auto status = xnn_create_deconvolution2d_nhwc_f32(
        static_cast<std::uint32_t>(node.padTop), static_cast<std::uint32_t>(node.padRight),
        static_cast<std::uint32_t>(node.padBottom), static_cast<std::uint32_t>(node.padLeft),
        static_cast<std::uint32_t>(kh), static_cast<std::uint32_t>(kw),
        static_cast<std::uint32_t>(node.strideH), static_cast<std::uint32_t>(node.strideW),
        static_cast<std::uint32_t>(node.dilationH), static_cast<std::uint32_t>(node.dilationW),
        static_cast<std::uint32_t>(node.group), toSize(cinG), toSize(coutG), toSize(cin),
        toSize(cout), kernel.data(), node.bias.data(), node.clampMin, node.clampMax, 0, &op);
    if (!check(status, "xnn_create_deconvolution2d_nhwc_f32", node, why))
      return false;
    push(op);
    if (!check(xnn_setup_deconvolution2d_nhwc_f32(op, 1, toSize(in.shape.h), toSize(in.shape.w),
                                                  static_cast<std::uint32_t>(node.adjustH),
                                                  static_cast<std::uint32_t>(node.adjustW),
                                                  data(node.inputs[0]), data(node.output),
                                                  pool_.get()),
               "xnn_setup_deconvolution2d_nhwc_f32", node, why)) {
      return false;
    }
    addKernel("xnn deconvolution2d_nhwc_f32");
    return true;
  }

  bool addBinary(const GraphNode& node, std::string* why) {
    const auto& a = tensor(node.inputs[0]);
    const auto& b = tensor(node.inputs[1]);
    const bool add = node.kind == OpKind::Add;
    xnn_operator_t op = nullptr;
    const auto status = (add ? xnn_create_add_nd_f32 : xnn_create_multiply_nd_f32)(
        node.clampMin, node.clampMax, 0, &op);
    if (!check(status, add ? "xnn_create_add_nd_f32" : "xnn_create_multiply_nd_f32", node, why)) {
      return false;
    }
    push(op);
    const std::array<std::size_t, 4> sa{1, toSize(a.shape.h), toSize(a.shape.w), toSize(a.shape.c)};
    const std::array<std::size_t, 4> sb{1, toSize(b.shape.h), toSize(b.shape.w), toSize(b.shape.c)};
    const auto setupStatus = (add ? xnn_setup_add_nd_f32 : xnn_setup_multiply_nd_f32)(
        op, 4, sa.data(), 4, sb.data(), data(node.inputs[0]), data(node.inputs[1]),
        data(node.output), pool_.get());
    if (!check(setupStatus, add ? "xnn_setup_add_nd_f32" : "xnn_setup_multiply_nd_f32", node,
               why)) {
      return false;
    }
    addKernel(add ? "xnn add_nd_f32" : "xnn multiply_nd_f32");
    return true;
  }

  bool addCopy(const GraphNode& node, std::size_t channels, std::size_t inStride,
               std::size_t outStride, std::size_t batch, const float* src, float* dst,
               std::string* why) {
    xnn_operator_t op = nullptr;
    if (!check(xnn_create_copy_nc_x32(channels, inStride, outStride, 0, &op),
               "xnn_create_copy_nc_x32", node, why)) {
      return false;
    }
    push(op);
    return check(xnn_setup_copy_nc_x32(op, batch, src, dst, pool_.get()), "xnn_setup_copy_nc_x32",
                 node, why);
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
    addKernel("xnn copy_nc_x32 (into channel slices)");
    return true;
  }

  bool addResizeBilinear(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    if (!check(xnn_create_resize_bilinear2d_nhwc_f32(
                   c, c, c, node.alignCorners ? XNN_FLAG_ALIGN_CORNERS : 0U, &op),
               "xnn_create_resize_bilinear2d_nhwc_f32", node, why)) {
      return false;
    }
    push(op);
    if (!check(xnn_setup_resize_bilinear2d_nhwc_f32(
                   op, 1, toSize(in.shape.h), toSize(in.shape.w), toSize(out.shape.h),
                   toSize(out.shape.w), data(node.inputs[0]), data(node.output), pool_.get()),
               "xnn_setup_resize_bilinear2d_nhwc_f32", node, why)) {
      return false;
    }
    addKernel("xnn resize_bilinear2d_nhwc_f32");
    return true;
  }

  bool addResizeNearest(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    const auto kh = toSize(node.scaleH);
    const auto kw = toSize(node.scaleW);
    const auto rowValues = toSize(out.shape.w) * c;
    scratch_.push_back(makeTensorBuffer<float>(toSize(in.shape.h) * rowValues));
    float* wide = scratch_.back().data();
    for (std::size_t dx = 0; dx < kw; ++dx) {
      if (!addCopy(node, c, c, kw * c, pixels(in.shape), data(node.inputs[0]), wide + dx * c,
                   why)) {
        return false;
      }
    }
    for (std::size_t dy = 0; dy < kh; ++dy) {
      if (!addCopy(node, rowValues, rowValues, kh * rowValues, toSize(in.shape.h), wide,
                   data(node.output) + dy * rowValues, why)) {
        return false;
      }
    }
    addKernel("xnn copy_nc_x32 (pixel replication)");
    return true;
  }

  bool addMaxPool(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status = xnn_create_max_pooling2d_nhwc_f32(
        static_cast<std::uint32_t>(node.padTop), static_cast<std::uint32_t>(node.padRight),
        static_cast<std::uint32_t>(node.padBottom), static_cast<std::uint32_t>(node.padLeft),
        static_cast<std::uint32_t>(node.kernelH), static_cast<std::uint32_t>(node.kernelW),
        static_cast<std::uint32_t>(node.strideH), static_cast<std::uint32_t>(node.strideW),
        static_cast<std::uint32_t>(node.dilationH), static_cast<std::uint32_t>(node.dilationW), c,
        c, c, node.clampMin, node.clampMax, 0, &op);
    if (!check(status, "xnn_create_max_pooling2d_nhwc_f32", node, why))
      return false;
    push(op);
    if (!check(
            xnn_setup_max_pooling2d_nhwc_f32(op, 1, toSize(in.shape.h), toSize(in.shape.w),
                                             data(node.inputs[0]), data(node.output), pool_.get()),
            "xnn_setup_max_pooling2d_nhwc_f32", node, why)) {
      return false;
    }
    addKernel("xnn max_pooling2d_nhwc_f32");
    return true;
  }

  bool addGlobalAveragePool(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    if (!check(xnn_create_global_average_pooling_nwc_f32(c, c, c, node.clampMin, node.clampMax, 0,
                                                         &op),
               "xnn_create_global_average_pooling_nwc_f32", node, why)) {
      return false;
    }
    push(op);
    if (!check(xnn_setup_global_average_pooling_nwc_f32(
                   op, 1, pixels(in.shape), data(node.inputs[0]), data(node.output), pool_.get()),
               "xnn_setup_global_average_pooling_nwc_f32", node, why)) {
      return false;
    }
    addKernel("xnn global_average_pooling_nwc_f32");
    return true;
  }

  bool addClamp(const GraphNode& node, const float* src, std::string* why) {
    const auto c = toSize(tensor(node.inputs[0]).shape.c);
    xnn_operator_t op = nullptr;
    if (!check(xnn_create_clamp_nc_f32(c, c, c, node.clampMin, node.clampMax, 0, &op),
               "xnn_create_clamp_nc_f32", node, why)) {
      return false;
    }
    push(op);
    if (!check(xnn_setup_clamp_nc_f32(op, pixels(tensor(node.inputs[0]).shape), src,
                                      data(node.output), pool_.get()),
               "xnn_setup_clamp_nc_f32", node, why)) {
      return false;
    }
    addKernel("xnn clamp_nc_f32");
    return true;
  }

  bool addElementwise(const GraphNode& node, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    const bool clamped = std::isfinite(node.clampMin) || std::isfinite(node.clampMax);
    if (node.kind == OpKind::Clamp)
      return addClamp(node, data(node.inputs[0]), why);
    if (node.kind == OpKind::Tanh) {
      Step step;
      step.floatInput = data(node.inputs[0]);
      step.floatOutput = data(node.output);
      step.function = FloatFunction::Tanh;
      step.clampMin = node.clampMin;
      step.clampMax = node.clampMax;
      step.count = in.shape.elements();
      steps_.push_back(std::move(step));
      addKernel("vp tanh loop (XNNPACK snapshot has no tanh_nc_f32)");
      return true;
    }
    xnn_operator_t op = nullptr;
    if (!check(xnn_create_sigmoid_nc_f32(c, c, c, 0, &op), "xnn_create_sigmoid_nc_f32", node,
               why)) {
      return false;
    }
    push(op);
    if (!check(xnn_setup_sigmoid_nc_f32(op, pixels(in.shape), data(node.inputs[0]),
                                        data(node.output), pool_.get()),
               "xnn_setup_sigmoid_nc_f32", node, why)) {
      return false;
    }
    addKernel("xnn sigmoid_nc_f32");
    // A fused clamp behind the sigmoid runs in place on its output.
    return !clamped || addClamp(node, data(node.output), why);
  }

  const QdqGraph* graph_ = nullptr;
  ThreadPool pool_;
  std::vector<std::vector<float>> buffers_;
  std::vector<std::vector<float>> scratch_;
  std::vector<Step> steps_;
  std::vector<OutputTensor> outputs_;
  std::vector<LayerInfo> layers_;
  std::string kernel_;
  int inputTensor_ = 0;
};

}  // namespace

std::unique_ptr<InferenceBackend> createXnnpackFp32Backend(const QdqGraph& graph, int threads,
                                                           std::string* why) {
  auto backend = std::make_unique<XnnpackFp32Backend>();
  if (!backend->build(graph, threads, why))
    return nullptr;
  return backend;
}

}  // namespace vp::inference
