// inference/xnnpack_int8: the int8 XNNPACK backend class, for the backends that replace some
// of its operators (DnnlInt8 runs the convolutions on oneDNN and keeps every other node here).
//
// Contract: XnnpackInt8Backend maps each IR node to XNNPACK QS8/QC8/S8 operators or 256-entry
// tables (xnnpack_backend.hpp); a derived class may override the per-kind hooks of
// XnnpackGraphBackend<std::int8_t> and register its own steps through addStep(). The helpers
// quantizeValue() / quantizeBias() are the int8 rounding rules both backends share, so that a
// node computed by either library sees the same quantized clamp bounds and biases.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "inference/xnnpack_graph.hpp"

namespace vp::inference {

inline std::int8_t quantizeValue(float v, const QuantParams& q) {
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

inline std::int8_t zeroPoint(const GraphTensor& t) {
  return static_cast<std::int8_t>(t.quant.zeroPoint);
}

// XNNPACK wants the bias in accumulator units: input scale x the channel's weight scale.
inline std::vector<std::int32_t> quantizeBias(const std::vector<float>& bias, float inputScale,
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

class XnnpackInt8Backend : public XnnpackGraphBackend<std::int8_t> {
 protected:
  // The fused output clamp in the output's quantized units.
  std::int8_t outMin(const GraphNode& node) const override {
    return quantizeValue(node.clampMin, tensor(node.output).quant);
  }
  std::int8_t outMax(const GraphNode& node) const override {
    return quantizeValue(node.clampMax, tensor(node.output).quant);
  }

  bool addConv(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto kernel = convKernel(node, [](std::int8_t w, int) { return w; });
    const auto bias = quantizeBias(node.bias, in.quant.scale, node.weightScales);
    xnn_operator_t op = nullptr;
    const auto status =
        createConvolution(xnn_create_convolution2d_nhwc_qc8, node, zeroPoint(in), in.quant.scale,
                          node.weightScales.data(), kernel.data(), bias.data(), zeroPoint(out),
                          out.quant.scale, outMin(node), outMax(node), 0U, &op);
    return addOperator(node, "convolution2d_nhwc_qc8", status, op, why,
                       xnn_setup_convolution2d_nhwc_qc8, 1U, toSize(in.shape.h), toSize(in.shape.w),
                       inBuf(node), outBuf(node), pool());
  }

  bool addDeconv(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    // XNNPACK's qs8 deconvolution has one kernel scale: requantize per-channel weights to the
    // largest channel scale.
    const auto& scales = node.weightScales;
    const float kernelScale = *std::max_element(scales.begin(), scales.end());
    const bool perTensor =
        std::all_of(scales.begin(), scales.end(), [&](float s) { return s == kernelScale; });
    const auto kernel = deconvKernel(node, [&](std::int8_t w, int o) {
      const float ratio = scales[toSize(o)] / kernelScale;
      const float q =
          perTensor ? static_cast<float>(w) : std::nearbyint(static_cast<float>(w) * ratio);
      return static_cast<std::int8_t>(std::clamp(q, -127.0F, 127.0F));
    });
    const std::vector<float> perChannel(toSize(out.shape.c), kernelScale);
    const auto bias = quantizeBias(node.bias, in.quant.scale, perChannel);
    xnn_operator_t op = nullptr;
    const auto status =
        createConvolution(xnn_create_deconvolution2d_nhwc_qs8, node, zeroPoint(in), in.quant.scale,
                          kernelScale, kernel.data(), bias.data(), zeroPoint(out), out.quant.scale,
                          outMin(node), outMax(node), 0U, &op);
    if (!addOperator(node, "deconvolution2d_nhwc_qs8", status, op, why,
                     xnn_setup_deconvolution2d_nhwc_qs8, 1U, toSize(in.shape.h), toSize(in.shape.w),
                     static_cast<std::uint32_t>(node.adjustH),
                     static_cast<std::uint32_t>(node.adjustW), inBuf(node), outBuf(node), pool())) {
      return false;
    }
    if (!perTensor)
      relabel("xnn deconvolution2d_nhwc_qs8 (per-channel scales requantized to per-tensor)");
    return true;
  }

  bool addBinary(const GraphNode& node, std::string* why) override {
    const auto& a = tensor(node.inputs[0]);
    const auto& b = tensor(node.inputs[1]);
    const auto& out = tensor(node.output);
    const bool add = node.kind == OpKind::Add;
    xnn_operator_t op = nullptr;
    const auto status = (add ? xnn_create_add_nd_qs8 : xnn_create_multiply_nd_qs8)(
        zeroPoint(a), a.quant.scale, zeroPoint(b), b.quant.scale, zeroPoint(out), out.quant.scale,
        outMin(node), outMax(node), 0U, &op);
    const auto sa = nhwc(a.shape);
    const auto sb = nhwc(b.shape);
    return addOperator(node, add ? "add_nd_qs8" : "multiply_nd_qs8", status, op, why,
                       add ? xnn_setup_add_nd_qs8 : xnn_setup_multiply_nd_qs8, 4U, sa.data(), 4U,
                       sb.data(), inBuf(node), data(node.inputs[1]), outBuf(node), pool());
  }

  bool addGlobalAveragePool(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    xnn_operator_t op = nullptr;
    const auto status = xnn_create_global_average_pooling_nwc_qs8(
        c, c, c, zeroPoint(in), in.quant.scale, zeroPoint(out), out.quant.scale, outMin(node),
        outMax(node), 0U, &op);
    return addOperator(node, "global_average_pooling_nwc_qs8", status, op, why,
                       xnn_setup_global_average_pooling_nwc_qs8, 1U, pixels(in.shape), inBuf(node),
                       outBuf(node), pool());
  }

  // Sigmoid / Tanh / Relu / Clip: XNNPACK when it has the kernel for these quantization
  // params, else a 256-entry table computed here (exact: out = Q(f(DQ(in)))).
  bool addElementwise(const GraphNode& node, std::string* why) override {
    const auto& in = tensor(node.inputs[0]);
    const auto& out = tensor(node.output);
    const auto c = toSize(in.shape.c);
    const bool isSigmoid = node.kind == OpKind::Sigmoid;
    const bool isTanh = node.kind == OpKind::Tanh;
    xnn_operator_t op = nullptr;
    xnn_status status = xnn_status_unsupported_parameter;
    if (isSigmoid || isTanh) {
      status = (isSigmoid ? xnn_create_sigmoid_nc_qs8 : xnn_create_tanh_nc_qs8)(
          c, c, c, zeroPoint(in), in.quant.scale, zeroPoint(out), out.quant.scale, outMin(node),
          outMax(node), 0U, &op);
    } else if (sameQuant(in.quant, out.quant)) {
      status = xnn_create_clamp_nc_s8(c, c, c, outMin(node), outMax(node), 0U, &op);
    }
    if (status == xnn_status_success) {
      return addOperator(node,
                         isSigmoid ? "sigmoid_nc_qs8"
                         : isTanh  ? "tanh_nc_qs8"
                                   : "clamp_nc_s8",
                         status, op, why,
                         isSigmoid ? xnn_setup_sigmoid_nc_qs8
                         : isTanh  ? xnn_setup_tanh_nc_qs8
                                   : xnn_setup_clamp_nc_s8,
                         pixels(in.shape), inBuf(node), outBuf(node), pool());
    }
    if (op != nullptr)
      xnn_delete_operator(op);
    Step step;
    for (int q = -128; q <= 127; ++q) {
      const float x = static_cast<float>(q - in.quant.zeroPoint) * in.quant.scale;
      float y = x;
      if (isSigmoid)
        y = 1.0F / (1.0F + std::exp(-x));
      if (isTanh)
        y = std::tanh(x);
      y = std::clamp(y, node.clampMin, node.clampMax);
      step.lut[toSize(q + 128)] = quantizeValue(y, out.quant);
    }
    step.lutInput = inBuf(node);
    step.lutOutput = outBuf(node);
    step.count = in.shape.elements();
    addStep(std::move(step), node.kind == OpKind::Clamp ? "vp lut_s8 (requantizing clamp)"
                                                        : "vp lut_s8 (256-entry table)");
    return true;
  }
};

}  // namespace vp::inference
