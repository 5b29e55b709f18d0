// The float XNNPACK backend (contract in xnnpack_backend.hpp): the graph walk of
// xnnpack_graph.hpp with F32 operators, the weights dequantized and the Q/DQ pairs dropped.
#include <cmath>

#include "inference/xnnpack_backend.hpp"
#include "inference/xnnpack_graph.hpp"

namespace vp::inference {
namespace {

class XnnpackFp32Backend final : public XnnpackGraphBackend<float> {
 private:
  float outMin(const GraphNode& node) const override { return node.clampMin; }
  float outMax(const GraphNode& node) const override { return node.clampMax; }

  // The float weights: w times its output channel's scale.
  static auto dequantizer(const GraphNode& node) {
    return [&node](std::int8_t w, int o) {
      return static_cast<float>(w) * node.weightScales[toSize(o)];
    };
  }

  bool addConv(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto kernel = convKernel(node, dequantizer(node));
    xnn_operator_t op = nullptr;
    const auto status = createConvolution(xnn_create_convolution2d_nhwc_f32, node, kernel.data(),
                                          node.bias.data(), node.clampMin, node.clampMax, 0U, &op);
    return addOperator(node, "convolution2d_nhwc_f32", status, op, why,
                       xnn_setup_convolution2d_nhwc_f32, 1U, toSize(in.shape.h), toSize(in.shape.w),
                       inBuf(node), outBuf(node), pool());
  }

  bool addDeconv(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto kernel = deconvKernel(node, dequantizer(node));
    xnn_operator_t op = nullptr;
    const auto status = createConvolution(xnn_create_deconvolution2d_nhwc_f32, node, kernel.data(),
                                          node.bias.data(), node.clampMin, node.clampMax, 0U, &op);
    return addOperator(node, "deconvolution2d_nhwc_f32", status, op, why,
                       xnn_setup_deconvolution2d_nhwc_f32, 1U, toSize(in.shape.h),
                       toSize(in.shape.w), static_cast<std::uint32_t>(node.adjustH),
                       static_cast<std::uint32_t>(node.adjustW), inBuf(node), outBuf(node), pool());
  }

  bool addBinary(const GraphNode& node, std::string* why) override {
    const bool add = node.kind == OpKind::Add;
    xnn_operator_t op = nullptr;
    const auto status = (add ? xnn_create_add_nd_f32 : xnn_create_multiply_nd_f32)(
        node.clampMin, node.clampMax, 0U, &op);
    const auto sa = nhwc(tensor(node.inputs[0]).shape);
    const auto sb = nhwc(tensor(node.inputs[1]).shape);
    return addOperator(node, add ? "add_nd_f32" : "multiply_nd_f32", status, op, why,
                       add ? xnn_setup_add_nd_f32 : xnn_setup_multiply_nd_f32, 4U, sa.data(), 4U,
                       sb.data(), inBuf(node), data(node.inputs[1]), outBuf(node), pool());
  }

  bool addGlobalAveragePool(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status =
        xnn_create_global_average_pooling_nwc_f32(c, c, c, node.clampMin, node.clampMax, 0U, &op);
    return addOperator(node, "global_average_pooling_nwc_f32", status, op, why,
                       xnn_setup_global_average_pooling_nwc_f32, 1U, pixels(in.shape), inBuf(node),
                       outBuf(node), pool());
  }

  // The node's clamp from `src` into its output (in place when src is the output).
  bool addClamp(const GraphNode& node, const float* src, std::string* why) {
    const auto& in = tensor(node.inputs[0]);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status = xnn_create_clamp_nc_f32(c, c, c, node.clampMin, node.clampMax, 0U, &op);
    return addOperator(node, "clamp_nc_f32", status, op, why, xnn_setup_clamp_nc_f32,
                       pixels(in.shape), src, outBuf(node), pool());
  }

  bool addElementwise(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    if (node.kind == OpKind::Clamp)
      return addClamp(node, inBuf(node), why);
    if (node.kind == OpKind::Tanh) {
      Step step;
      step.floatInput = inBuf(node);
      step.floatOutput = outBuf(node);
      step.function = FloatFunction::Tanh;
      step.clampMin = node.clampMin;
      step.clampMax = node.clampMax;
      step.count = in.shape.elements();
      addStep(std::move(step), "vp tanh loop (XNNPACK snapshot has no tanh_nc_f32)");
      return true;
    }
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status = xnn_create_sigmoid_nc_f32(c, c, c, 0U, &op);
    if (!addOperator(node, "sigmoid_nc_f32", status, op, why, xnn_setup_sigmoid_nc_f32,
                     pixels(in.shape), inBuf(node), outBuf(node), pool())) {
      return false;
    }
    // A fused clamp behind the sigmoid runs in place on its output.
    const bool clamped = std::isfinite(node.clampMin) || std::isfinite(node.clampMax);
    return !clamped || addClamp(node, outBuf(node), why);
  }
};

}  // namespace

std::unique_ptr<InferenceBackend> createXnnpackFp32Backend(const QdqGraph& graph, int threads,
                                                           bool planMemory, std::string* why) {
  return makeBackend<XnnpackFp32Backend>(graph, threads, planMemory, why);
}

}  // namespace vp::inference
