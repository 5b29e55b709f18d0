// inference/onnx_operators: one graph node per supported ONNX operator (onnx_parser.hpp):
// dispatch, window attributes (strides, dilations, pads, auto_pad), and for each operator its
// checks and NCHW shape inference (docs/inference.md lists the supported operators).
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "inference/onnx_parser.hpp"

namespace vp::inference::onnx_detail {

GraphNode Parser::makeNode(const onnx::NodeProto& node, OpKind kind) const {
  GraphNode gn;
  gn.kind = kind;
  gn.name = node.name().empty() ? node.output(0) : node.name();
  gn.opType = node.op_type();
  return gn;
}

void Parser::push(GraphNode gn) {
  producerOf_[gn.output] = static_cast<int>(g_.nodes.size());
  g_.nodes.push_back(std::move(gn));
}

const TensorShape& Parser::shapeOf(int id) const {
  return g_.tensors[static_cast<std::size_t>(id)].shape;
}

void Parser::windowAttributes(const onnx::NodeProto& node, GraphNode& gn, const TensorShape& in,
                              bool allowSame) const {
  const auto strides = attrInts(node, "strides", 2, 1);
  const auto dilations = attrInts(node, "dilations", 2, 1);
  gn.strideH = strides[0];
  gn.strideW = strides[1];
  gn.dilationH = dilations[0];
  gn.dilationW = dilations[1];
  if (gn.strideH < 1 || gn.strideW < 1 || gn.dilationH < 1 || gn.dilationW < 1) {
    failNode(node, "strides and dilations must be >= 1");
  }
  const std::string autoPad = attrString(node, "auto_pad", "NOTSET");
  if (autoPad == "NOTSET") {
    const auto pads = attrInts(node, "pads", 4, 0);
    gn.padTop = pads[0];
    gn.padLeft = pads[1];
    gn.padBottom = pads[2];
    gn.padRight = pads[3];
  } else if (autoPad == "VALID") {
    gn.padTop = gn.padLeft = gn.padBottom = gn.padRight = 0;
  } else if (allowSame && (autoPad == "SAME_UPPER" || autoPad == "SAME_LOWER")) {
    const auto same = [&](int size, int k, int s, int d, int* begin, int* end) {
      const int out = (size + s - 1) / s;
      const int total = std::max(0, (out - 1) * s + (k - 1) * d + 1 - size);
      *begin = autoPad == "SAME_UPPER" ? total / 2 : total - total / 2;
      *end = total - *begin;
    };
    same(in.h, gn.kernelH, gn.strideH, gn.dilationH, &gn.padTop, &gn.padBottom);
    same(in.w, gn.kernelW, gn.strideW, gn.dilationW, &gn.padLeft, &gn.padRight);
  } else {
    failNode(node, "auto_pad '" + autoPad + "' is not supported");
  }
}

int Parser::windowOut(int size, int padA, int padB, int k, int s, int d) {
  const int span = size + padA + padB - ((k - 1) * d + 1);
  return span < 0 ? 0 : span / s + 1;
}

void Parser::parseNode(int index) {
  const auto& node = model_.graph().node(index);
  const std::string& op = node.op_type();
  if (!node.domain().empty() && node.domain() != "ai.onnx") {
    failNode(node, "unsupported operator (domain '" + node.domain() + "')");
  }
  if (node.output_size() < 1)
    failNode(node, "has no output");
  if (op == "QuantizeLinear" || op == "DequantizeLinear" || op == "Constant")
    return;
  if (op == "Identity") {
    auto it = aliases_.find(node.input(0));
    if (it != aliases_.end()) {
      aliases_[node.output(0)] = it->second;
      aliasNames_[static_cast<std::size_t>(it->second)].push_back(node.output(0));
    }
    return;
  }
  if (op == "Conv")
    return parseConv(node);
  if (op == "ConvTranspose")
    return parseConvTranspose(node);
  if (op == "Add" || op == "Mul")
    return parseBinary(node);
  if (op == "Concat")
    return parseConcat(node);
  if (op == "Resize")
    return parseResize(node);
  if (op == "MaxPool")
    return parseMaxPool(node);
  if (op == "GlobalAveragePool")
    return parseGlobalAveragePool(node);
  if (op == "Sigmoid" || op == "Tanh")
    return parseUnary(node);
  if (isActivationOp(op))
    return parseStandaloneClamp(node);
  failNode(node, "unsupported operator (docs/inference.md lists the supported ones)");
}

void Parser::parseConv(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, OpKind::Conv);
  const int x = activation(node, 0);
  const TensorShape in = shapeOf(x);
  if (node.input_size() < 2)
    failNode(node, "missing weight input");
  const auto group = attrInt(node, "group", 1);
  if (group < 1 || group > in.c || in.c % group != 0) {
    failNode(node, "group " + std::to_string(group) + " does not divide the " +
                       std::to_string(in.c) + " input channels");
  }
  gn.group = static_cast<int>(group);
  Weights w = weights(node, node.input(1), 0, "output channels");
  const int cout = static_cast<int>(w.dims[0]);
  if (w.dims[1] * group != in.c) {
    failNode(node, "weight has " + std::to_string(w.dims[1]) + " input channels per group, " +
                       "expected " + std::to_string(in.c / group) + " (input has " +
                       std::to_string(in.c) + " channels, group " + std::to_string(group) + ")");
  }
  if (cout % group != 0)
    failNode(node, "output channels not divisible by group");
  gn.kernelH = static_cast<int>(w.dims[2]);
  gn.kernelW = static_cast<int>(w.dims[3]);
  if (const auto* ks = attr(node, "kernel_shape"); ks != nullptr) {
    if (ks->ints_size() != 2 || ks->ints(0) != gn.kernelH || ks->ints(1) != gn.kernelW) {
      failNode(node, "kernel_shape disagrees with the weight's dimensions");
    }
  }
  windowAttributes(node, gn, in, true);
  const TensorShape out{
      1, cout, windowOut(in.h, gn.padTop, gn.padBottom, gn.kernelH, gn.strideH, gn.dilationH),
      windowOut(in.w, gn.padLeft, gn.padRight, gn.kernelW, gn.strideW, gn.dilationW)};
  if (out.h < 1 || out.w < 1)
    failNode(node, "empty output (kernel larger than padded input)");
  gn.weights = std::move(w.values);
  gn.weightScales = std::move(w.scales);
  gn.bias = bias(node, cout);
  gn.inputs = {x};
  gn.macs = static_cast<std::uint64_t>(out.elements()) * static_cast<std::uint64_t>(in.c / group) *
            static_cast<std::uint64_t>(gn.kernelH * gn.kernelW);
  gn.output = finishOutput(node, gn, out, true);
  push(std::move(gn));
}

void Parser::parseConvTranspose(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, OpKind::ConvTranspose);
  const int x = activation(node, 0);
  const TensorShape in = shapeOf(x);
  if (node.input_size() < 2)
    failNode(node, "missing weight input");
  const auto group = attrInt(node, "group", 1);
  if (group < 1 || in.c % group != 0)
    failNode(node, "group does not divide input channels");
  gn.group = static_cast<int>(group);
  if (attr(node, "output_shape") != nullptr) {
    failNode(node, "attribute 'output_shape' is not supported (give pads/output_padding)");
  }
  Weights w = weights(node, node.input(1), 1, "output channels per group");
  if (w.dims[0] != in.c) {
    failNode(node, "weight has " + std::to_string(w.dims[0]) + " input channels, expected " +
                       std::to_string(in.c));
  }
  const int coutGroup = static_cast<int>(w.dims[1]);
  const int cout = coutGroup * gn.group;
  gn.kernelH = static_cast<int>(w.dims[2]);
  gn.kernelW = static_cast<int>(w.dims[3]);
  windowAttributes(node, gn, in, false);
  const auto adjust = attrInts(node, "output_padding", 2, 0);
  gn.adjustH = adjust[0];
  gn.adjustW = adjust[1];
  if (gn.adjustH >= gn.strideH || gn.adjustW >= gn.strideW) {
    failNode(node, "output_padding must be smaller than the stride");
  }
  const TensorShape out{1, cout,
                        (in.h - 1) * gn.strideH + (gn.kernelH - 1) * gn.dilationH + 1 - gn.padTop -
                            gn.padBottom + gn.adjustH,
                        (in.w - 1) * gn.strideW + (gn.kernelW - 1) * gn.dilationW + 1 - gn.padLeft -
                            gn.padRight + gn.adjustW};
  if (out.h < 1 || out.w < 1)
    failNode(node, "empty output");
  // Scales come per axis-1 index (output channel within a group): expand to all outputs.
  std::vector<float> scales;
  for (int g = 0; g < gn.group; ++g) {
    scales.insert(scales.end(), w.scales.begin(), w.scales.end());
  }
  gn.weights = std::move(w.values);
  gn.weightScales = std::move(scales);
  gn.bias = bias(node, cout);
  gn.inputs = {x};
  gn.macs = static_cast<std::uint64_t>(in.elements()) * static_cast<std::uint64_t>(coutGroup) *
            static_cast<std::uint64_t>(gn.kernelH * gn.kernelW);
  gn.output = finishOutput(node, gn, out, true);
  push(std::move(gn));
}

void Parser::parseBinary(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, node.op_type() == "Add" ? OpKind::Add : OpKind::Mul);
  if (node.input_size() != 2)
    failNode(node, "expects two inputs");
  const int a = activation(node, 0);
  const int b = activation(node, 1);
  const TensorShape sa = shapeOf(a);
  const TensorShape sb = shapeOf(b);
  const auto bc = [&](int x, int y) {
    if (x != y && x != 1 && y != 1) {
      failNode(node, "input shapes [1," + std::to_string(sa.c) + "," + std::to_string(sa.h) + "," +
                         std::to_string(sa.w) + "] and [1," + std::to_string(sb.c) + "," +
                         std::to_string(sb.h) + "," + std::to_string(sb.w) + "] do not broadcast");
    }
    return std::max(x, y);
  };
  const TensorShape out{1, bc(sa.c, sb.c), bc(sa.h, sb.h), bc(sa.w, sb.w)};
  gn.inputs = {a, b};
  if (gn.kind == OpKind::Mul)
    gn.macs = out.elements();
  gn.output = finishOutput(node, gn, out, true);
  push(std::move(gn));
}

void Parser::parseConcat(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, OpKind::Concat);
  auto axis = attrInt(node, "axis", 1);
  if (axis < 0)
    axis += 4;
  if (axis != 1)
    failNode(node, "only channel concatenation (axis 1) is supported");
  if (node.input_size() < 1)
    failNode(node, "has no inputs");
  TensorShape out{1, 0, 0, 0};
  for (int i = 0; i < node.input_size(); ++i) {
    const int t = activation(node, i);
    const auto& s = shapeOf(t);
    if (i == 0) {
      out.h = s.h;
      out.w = s.w;
    } else if (s.h != out.h || s.w != out.w) {
      failNode(node, "inputs differ in height/width");
    }
    out.c += s.c;
    gn.inputs.push_back(t);
  }
  gn.output = finishOutput(node, gn, out, false);
  const auto& oq = g_.tensors[static_cast<std::size_t>(gn.output)].quant;
  for (std::size_t i = 0; i < gn.inputs.size(); ++i) {
    const auto& iq = g_.tensors[static_cast<std::size_t>(gn.inputs[i])].quant;
    if (!sameQuant(iq, oq)) {
      failNode(node, "input '" + node.input(static_cast<int>(i)) + "' is quantized with " +
                         formatQuant(iq) + " but the output with " + formatQuant(oq) +
                         ": Concat inputs must share the output's scale and zero point "
                         "(there is no requantizing int8 concat)");
    }
  }
  push(std::move(gn));
}

void Parser::requireSameQuant(const onnx::NodeProto& node, const GraphNode& gn,
                              const std::string& why) const {
  const auto& iq = g_.tensors[static_cast<std::size_t>(gn.inputs[0])].quant;
  const auto& oq = g_.tensors[static_cast<std::size_t>(gn.output)].quant;
  if (!sameQuant(iq, oq)) {
    failNode(node, "input " + formatQuant(iq) + " and output " + formatQuant(oq) +
                       " quantization differ; " + why);
  }
}

void Parser::parseResize(const onnx::NodeProto& node) {
  const int x = activation(node, 0);
  const TensorShape in = shapeOf(x);
  const std::string mode = attrString(node, "mode", "nearest");
  const std::string ctm = attrString(node, "coordinate_transformation_mode", "half_pixel");
  GraphNode gn = makeNode(node, mode == "nearest" ? OpKind::ResizeNearest : OpKind::ResizeBilinear);
  // Output size from scales (input 2) or sizes (input 3).
  int outH = 0;
  int outW = 0;
  if (node.input_size() > 3 && !node.input(3).empty()) {
    const auto* t = constant(node.input(3));
    if (t == nullptr)
      failNode(node, "sizes must be a constant");
    const auto sizes = ints(node, *t, "sizes");
    if (sizes.size() != 4 || sizes[0] != 1 || sizes[1] != in.c) {
      failNode(node, "sizes must be [1, C, H, W]");
    }
    outH = static_cast<int>(sizes[2]);
    outW = static_cast<int>(sizes[3]);
  } else if (node.input_size() > 2 && !node.input(2).empty()) {
    const auto* t = constant(node.input(2));
    if (t == nullptr)
      failNode(node, "scales must be a constant");
    const auto scales = floats(node, *t, "scales");
    if (scales.size() != 4 || scales[0] != 1.0F || scales[1] != 1.0F) {
      failNode(node, "scales must be [1, 1, sh, sw]");
    }
    outH = static_cast<int>(std::floor(static_cast<float>(in.h) * scales[2]));
    outW = static_cast<int>(std::floor(static_cast<float>(in.w) * scales[3]));
  } else {
    failNode(node, "needs constant scales or sizes");
  }
  if (outH < in.h || outW < in.w || outH % in.h != 0 || outW % in.w != 0) {
    failNode(node, "only integer upscaling factors are supported (" + std::to_string(in.h) + "x" +
                       std::to_string(in.w) + " -> " + std::to_string(outH) + "x" +
                       std::to_string(outW) + ")");
  }
  gn.scaleH = outH / in.h;
  gn.scaleW = outW / in.w;
  if (mode == "linear" || mode == "bilinear") {
    if (ctm == "align_corners") {
      gn.alignCorners = true;
    } else if (ctm != "half_pixel" && ctm != "pytorch_half_pixel") {
      failNode(node, "coordinate_transformation_mode '" + ctm +
                         "' is not supported for linear (half_pixel, pytorch_half_pixel, "
                         "align_corners)");
    }
    gn.opType = "Resize(linear)";
  } else if (mode == "nearest") {
    const std::string nearestMode = attrString(node, "nearest_mode", "round_prefer_floor");
    const bool halfPixel = ctm == "half_pixel" || ctm == "pytorch_half_pixel";
    const bool rounding = nearestMode == "round_prefer_floor" || nearestMode == "round_prefer_ceil";
    const bool ok = (halfPixel && rounding) || (ctm == "asymmetric" && nearestMode == "floor");
    if (!ok) {
      failNode(node, "nearest with coordinate_transformation_mode '" + ctm +
                         "' and nearest_mode '" + nearestMode +
                         "' is not a pixel replication; supported: asymmetric+floor, "
                         "half_pixel+round_prefer_floor/ceil");
    }
    gn.opType = "Resize(nearest)";
  } else {
    failNode(node, "mode '" + mode + "' is not supported (linear, nearest)");
  }
  gn.inputs = {x};
  gn.output = finishOutput(node, gn, TensorShape{1, in.c, outH, outW}, false);
  requireSameQuant(node, gn, "Resize does not requantize");
  push(std::move(gn));
}

void Parser::parseMaxPool(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, OpKind::MaxPool);
  const int x = activation(node, 0);
  const TensorShape in = shapeOf(x);
  if (node.output_size() > 1 && !node.output(1).empty()) {
    failNode(node, "the Indices output is not supported");
  }
  const auto* ks = attr(node, "kernel_shape");
  if (ks == nullptr || ks->ints_size() != 2)
    failNode(node, "needs a 2-D kernel_shape");
  gn.kernelH = static_cast<int>(ks->ints(0));
  gn.kernelW = static_cast<int>(ks->ints(1));
  if (gn.kernelH < 1 || gn.kernelW < 1)
    failNode(node, "invalid kernel_shape");
  if (attrInt(node, "storage_order", 0) != 0)
    failNode(node, "storage_order 1 not supported");
  windowAttributes(node, gn, in, true);
  if ((gn.dilationH > 1 || gn.dilationW > 1) &&
      (gn.padTop | gn.padLeft | gn.padBottom | gn.padRight) != 0) {
    failNode(node, "dilated max pooling with padding is not supported");
  }
  if (gn.padTop >= gn.kernelH || gn.padBottom >= gn.kernelH || gn.padLeft >= gn.kernelW ||
      gn.padRight >= gn.kernelW) {
    failNode(node, "padding must be smaller than the kernel");
  }
  TensorShape out{1, in.c,
                  windowOut(in.h, gn.padTop, gn.padBottom, gn.kernelH, gn.strideH, gn.dilationH),
                  windowOut(in.w, gn.padLeft, gn.padRight, gn.kernelW, gn.strideW, gn.dilationW)};
  if (attrInt(node, "ceil_mode", 0) != 0) {
    const auto ceilOut = [](int size, int a, int b, int k, int s, int d) {
      const int span = size + a + b - ((k - 1) * d + 1);
      return (span + s - 1) / s + 1;
    };
    if (ceilOut(in.h, gn.padTop, gn.padBottom, gn.kernelH, gn.strideH, gn.dilationH) != out.h ||
        ceilOut(in.w, gn.padLeft, gn.padRight, gn.kernelW, gn.strideW, gn.dilationW) != out.w) {
      failNode(node, "ceil_mode 1 changes the output size here (not supported)");
    }
  }
  if (out.h < 1 || out.w < 1)
    failNode(node, "empty output");
  gn.inputs = {x};
  gn.output = finishOutput(node, gn, out, true);
  requireSameQuant(node, gn, "MaxPool does not requantize");
  push(std::move(gn));
}

void Parser::parseGlobalAveragePool(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, OpKind::GlobalAveragePool);
  const int x = activation(node, 0);
  const TensorShape in = shapeOf(x);
  gn.inputs = {x};
  gn.output = finishOutput(node, gn, TensorShape{1, in.c, 1, 1}, true);
  push(std::move(gn));
}

void Parser::parseUnary(const onnx::NodeProto& node) {
  GraphNode gn = makeNode(node, node.op_type() == "Sigmoid" ? OpKind::Sigmoid : OpKind::Tanh);
  const int x = activation(node, 0);
  gn.inputs = {x};
  gn.output = finishOutput(node, gn, shapeOf(x), true);
  push(std::move(gn));
}

void Parser::parseStandaloneClamp(const onnx::NodeProto& node) {
  const int x = activation(node, 0);
  GraphNode gn = makeNode(node, OpKind::Clamp);
  applyClamp(node, gn);
  gn.opType = node.op_type();
  // Fuse into the producer when it requantizes anyway and nobody else reads its output.
  auto p = producerOf_.find(x);
  if (p != producerOf_.end() && useCount(x) == 1) {
    GraphNode& prod = g_.nodes[static_cast<std::size_t>(p->second)];
    if (prod.kind == OpKind::Conv || prod.kind == OpKind::ConvTranspose ||
        prod.kind == OpKind::Add || prod.kind == OpKind::Mul) {
      prod.clampMin = std::max(prod.clampMin, gn.clampMin);
      prod.clampMax = std::min(prod.clampMax, gn.clampMax);
      prod.opType += "+" + node.op_type();
      // The producer now writes the activation's quantized output directly.
      finishOutputInto(node, x);
      return;
    }
  }
  gn.inputs = {x};
  gn.output = finishOutput(node, gn, shapeOf(x), true);
  push(std::move(gn));
}

void Parser::finishOutputInto(const onnx::NodeProto& node, int reuse) {
  std::string value = node.output(0);
  const auto& cons = consumersOf(value);
  if (cons.size() == 1 && isActivationOp(model_.graph().node(cons[0]).op_type())) {
    failNode(model_.graph().node(cons[0]), "chained activations without QDQ are not supported");
  }
  defineActivation(node, value, shapeOf(reuse), reuse);
}

}  // namespace vp::inference::onnx_detail
