// inference/onnx_qdq: the QDQ patterns the Parser folds (onnx_parser.hpp): an activation's
// QuantizeLinear -> DequantizeLinear pair becomes one quantized tensor, a weight's
// DequantizeLinear (of int8, or of a fake-quant QuantizeLinear of floats) becomes int8 weights
// with per-channel scales, a bias's DequantizeLinear(int32) becomes float biases, and Relu/Clip
// behind a node become its output clamp.
#include <algorithm>
#include <cmath>
#include <limits>

#include "inference/onnx_parser.hpp"

namespace vp::inference::onnx_detail {

QuantParams Parser::scalarQuant(const onnx::NodeProto& node) const {
  if (node.input_size() < 2 || node.input(1).empty())
    failNode(node, "missing scale");
  const auto* scaleT = constant(node.input(1));
  if (scaleT == nullptr) {
    failNode(node, "scale '" + node.input(1) + "' is not an initializer or constant");
  }
  const auto scale = floats(node, *scaleT, "scale");
  if (scale.size() != 1) {
    failNode(node, "activation scale has " + std::to_string(scale.size()) +
                       " values, expected one (per-tensor)");
  }
  if (!(scale[0] > 0.0F) || !std::isfinite(scale[0])) {
    failNode(node, "scale must be positive and finite");
  }
  if (node.input_size() < 3 || node.input(2).empty()) {
    failNode(node, "missing zero point (the uint8 default is not supported; int8 required)");
  }
  const auto* zpT = constant(node.input(2));
  if (zpT == nullptr) {
    failNode(node, "zero point '" + node.input(2) + "' is not an initializer or constant");
  }
  if (zpT->data_type() != onnx::TensorProto_DataType_INT8) {
    failNode(node, "zero point must be int8 (uint8 activations are not supported)");
  }
  const auto zp = ints(node, *zpT, "zero point");
  if (zp.size() != 1)
    failNode(node, "zero point must be a scalar");
  if (zp[0] < -128 || zp[0] > 127)
    failNode(node, "zero point out of int8 range");
  return QuantParams{scale[0], static_cast<int>(zp[0])};
}

const onnx::NodeProto* Parser::producerNode(const std::string& value) const {
  auto it = producer_.find(value);
  return it == producer_.end() ? nullptr : &model_.graph().node(it->second);
}

const std::vector<int>& Parser::consumersOf(const std::string& value) const {
  static const std::vector<int> kNone;
  auto it = consumers_.find(value);
  return it == consumers_.end() ? kNone : it->second;
}

int Parser::defineActivation(const onnx::NodeProto& owner, const std::string& floatValue,
                             TensorShape shape, int reuse) {
  if (graphOutputs_.count(floatValue) != 0) {
    failNode(owner, "output '" + floatValue +
                        "' is a graph output without QuantizeLinear/DequantizeLinear");
  }
  const auto& cons = consumersOf(floatValue);
  if (cons.size() != 1 || model_.graph().node(cons[0]).op_type() != "QuantizeLinear") {
    failNode(owner, "output '" + floatValue +
                        "' must feed exactly one QuantizeLinear (QDQ form: every activation is "
                        "QuantizeLinear -> DequantizeLinear)");
  }
  const auto& q = model_.graph().node(cons[0]);
  const QuantParams quant = scalarQuant(q);
  const std::string& qOut = q.output(0);
  if (graphOutputs_.count(qOut) != 0) {
    failNode(q, "int8 graph outputs are not supported (output a DequantizeLinear)");
  }
  const auto& dqs = consumersOf(qOut);
  if (dqs.empty())
    failNode(q, "output has no DequantizeLinear consumer");
  int id = reuse;
  if (id < 0) {
    id = static_cast<int>(g_.tensors.size());
    g_.tensors.push_back(GraphTensor{});
    aliasNames_.emplace_back();
  }
  auto& tensor = g_.tensors[static_cast<std::size_t>(id)];
  tensor.shape = shape;
  tensor.quant = quant;
  floatNames_[floatValue] = id;
  for (const int di : dqs) {
    const auto& dq = model_.graph().node(di);
    if (dq.op_type() != "DequantizeLinear") {
      failNode(dq, "consumes int8 tensor '" + qOut + "' (only DequantizeLinear may)");
    }
    const QuantParams dqQuant = scalarQuant(dq);
    if (!sameQuant(dqQuant, quant)) {
      failNode(dq, "scale/zero point " + formatQuant(dqQuant) +
                       " differ from its QuantizeLinear's " + formatQuant(quant));
    }
    aliases_[dq.output(0)] = id;
    aliasNames_[static_cast<std::size_t>(id)].push_back(dq.output(0));
    tensor.name = dq.output(0);
  }
  return id;
}

int Parser::activation(const onnx::NodeProto& node, int inputIndex) const {
  if (node.input_size() <= inputIndex || node.input(inputIndex).empty()) {
    failNode(node, "missing input " + std::to_string(inputIndex));
  }
  const std::string& name = node.input(inputIndex);
  auto it = aliases_.find(name);
  if (it != aliases_.end())
    return it->second;
  if (constant(name) != nullptr) {
    failNode(node, "input '" + name + "' is a constant; an activation tensor is expected");
  }
  const auto* p = producerNode(name);
  if (p == nullptr && !isGraphInput(name))
    failNode(node, "input '" + name + "' is undefined");
  failNode(node, "input '" + name +
                     "' is not a dequantized activation (expected QuantizeLinear -> "
                     "DequantizeLinear in front of every compute operator)");
}

bool Parser::isGraphInput(const std::string& name) const {
  for (const auto& in : model_.graph().input()) {
    if (in.name() == name)
      return true;
  }
  return false;
}

std::size_t Parser::useCount(int id) const {
  std::size_t n = 0;
  for (const auto& alias : aliasNames_[static_cast<std::size_t>(id)]) {
    n += consumersOf(alias).size();
    n += graphOutputs_.count(alias);
  }
  return n;
}

Parser::Weights Parser::weights(const onnx::NodeProto& node, const std::string& name, int axis,
                                const std::string& axisWord) const {
  const auto* dq = producerNode(name);
  if (dq == nullptr || dq->op_type() != "DequantizeLinear") {
    if (constant(name) != nullptr) {
      failNode(node, "weight '" + name +
                         "' is a float initializer; expected int8 weights "
                         "behind a DequantizeLinear");
    }
    failNode(node, "weight '" + name + "' must come from DequantizeLinear (QDQ form)");
  }
  const auto* src = constant(dq->input(0));
  const onnx::NodeProto* fakeQ = nullptr;
  if (src == nullptr) {
    fakeQ = producerNode(dq->input(0));
    if (fakeQ == nullptr || fakeQ->op_type() != "QuantizeLinear" ||
        constant(fakeQ->input(0)) == nullptr) {
      failNode(node, "weight '" + name +
                         "' is neither DequantizeLinear(int8 initializer) nor "
                         "DequantizeLinear(QuantizeLinear(float initializer))");
    }
    src = constant(fakeQ->input(0));
  }
  Weights w;
  w.dims.assign(src->dims().begin(), src->dims().end());
  if (w.dims.size() != 4) {
    failNode(node, "weight '" + name + "' has " + std::to_string(w.dims.size()) +
                       " dimensions, expected 4");
  }
  const auto channels = w.dims[static_cast<std::size_t>(axis)];
  // Scales and zero points of the DequantizeLinear.
  if (dq->input_size() < 2 || dq->input(1).empty())
    failNode(node, "weight scale missing");
  const auto* scaleT = constant(dq->input(1));
  if (scaleT == nullptr)
    failNode(node, "weight scale '" + dq->input(1) + "' is not constant");
  auto scales = floats(node, *scaleT, "weight scale");
  if (scales.size() != 1 && static_cast<std::int64_t>(scales.size()) != channels) {
    failNode(node, "weight scale has " + std::to_string(scales.size()) + " values, expected " +
                       std::to_string(channels) + " (" + axisWord + ")");
  }
  if (scales.size() > 1) {
    std::int64_t dqAxis = attrInt(*dq, "axis", 1);
    if (dqAxis < 0)
      dqAxis += 4;
    if (dqAxis != axis) {
      failNode(node, "weight DequantizeLinear axis is " + std::to_string(dqAxis) + ", expected " +
                         std::to_string(axis) + " (" + axisWord + ")");
    }
  }
  for (const float s : scales) {
    if (!(s > 0.0F) || !std::isfinite(s)) {
      failNode(node, "weight scale must be positive and finite");
    }
  }
  if (dq->input_size() >= 3 && !dq->input(2).empty()) {
    const auto* zpT = constant(dq->input(2));
    if (zpT == nullptr)
      failNode(node, "weight zero point is not constant");
    for (const auto z : ints(node, *zpT, "weight zero point")) {
      if (z != 0)
        failNode(node, "weight zero point is nonzero (symmetric int8 weights only)");
    }
    if (zpT->data_type() != onnx::TensorProto_DataType_INT8) {
      failNode(node, "weight zero point must be int8");
    }
  }
  if (scales.size() == 1)
    scales.assign(static_cast<std::size_t>(channels), scales[0]);
  w.scales = scales;

  // Stride between consecutive `axis` indices and the run length inside it.
  std::int64_t inner = 1;
  for (std::size_t d = static_cast<std::size_t>(axis) + 1; d < 4; ++d)
    inner *= w.dims[d];
  const auto channelOf = [&](std::size_t i) {
    return static_cast<std::size_t>((static_cast<std::int64_t>(i) / inner) % channels);
  };
  if (fakeQ == nullptr) {
    if (src->data_type() != onnx::TensorProto_DataType_INT8) {
      failNode(node, "weight initializer '" + src->name() + "' must be int8");
    }
    const auto v = ints(node, *src, "weight");
    w.values.reserve(v.size());
    for (const auto x : v)
      w.values.push_back(static_cast<std::int8_t>(x));
  } else {
    // torch fake-quant export: quantize the float weights here with the same params.
    const auto qScales = constant(fakeQ->input(1));
    if (qScales == nullptr ||
        floats(node, *qScales, "weight scale") != floats(node, *scaleT, "weight scale")) {
      failNode(node, "weight QuantizeLinear and DequantizeLinear scales differ");
    }
    const auto v = floats(node, *src, "weight");
    w.values.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const float q = std::nearbyint(v[i] / w.scales[channelOf(i)]);
      w.values.push_back(static_cast<std::int8_t>(std::clamp(q, -128.0F, 127.0F)));
    }
  }
  return w;
}

std::vector<float> Parser::bias(const onnx::NodeProto& node, int channels) const {
  if (node.input_size() < 3 || node.input(2).empty()) {
    return std::vector<float>(static_cast<std::size_t>(channels), 0.0F);
  }
  const std::string& name = node.input(2);
  std::vector<float> b;
  if (const auto* t = constant(name); t != nullptr) {
    b = floats(node, *t, "bias");
  } else {
    const auto* dq = producerNode(name);
    const onnx::TensorProto* src =
        dq != nullptr && dq->op_type() == "DequantizeLinear" ? constant(dq->input(0)) : nullptr;
    if (src == nullptr || src->data_type() != onnx::TensorProto_DataType_INT32) {
      failNode(node, "bias '" + name +
                         "' must be a float initializer or DequantizeLinear(int32 initializer)");
    }
    const auto q = ints(node, *src, "bias");
    const auto* scaleT = dq->input_size() > 1 ? constant(dq->input(1)) : nullptr;
    if (scaleT == nullptr)
      failNode(node, "bias scale missing or not constant");
    const auto s = floats(node, *scaleT, "bias scale");
    if (s.size() != 1 && s.size() != q.size()) {
      failNode(node, "bias scale has " + std::to_string(s.size()) + " values, expected " +
                         std::to_string(q.size()));
    }
    if (dq->input_size() > 2 && !dq->input(2).empty()) {
      const auto* zpT = constant(dq->input(2));
      if (zpT == nullptr)
        failNode(node, "bias zero point is not constant");
      for (const auto z : ints(node, *zpT, "bias zero point")) {
        if (z != 0)
          failNode(node, "bias zero point is nonzero");
      }
    }
    for (std::size_t i = 0; i < q.size(); ++i) {
      b.push_back(static_cast<float>(q[i]) * s[s.size() == 1 ? 0 : i]);
    }
  }
  if (static_cast<int>(b.size()) != channels) {
    failNode(node, "bias has " + std::to_string(b.size()) + " values, expected " +
                       std::to_string(channels) + " (output channels)");
  }
  // A NaN or infinite bias has no int32 accumulator value (quantized at load, int8 backend).
  for (std::size_t c = 0; c < b.size(); ++c) {
    if (!std::isfinite(b[c])) {
      failNode(node,
               "bias '" + name + "' of output channel " + std::to_string(c) + " is not finite");
    }
  }
  return b;
}

int Parser::finishOutput(const onnx::NodeProto& node, GraphNode& gn, TensorShape shape,
                         bool allowClamp) {
  std::string value = node.output(0);
  for (;;) {
    const auto& cons = consumersOf(value);
    if (graphOutputs_.count(value) != 0 || cons.size() != 1)
      break;
    const auto& next = model_.graph().node(cons[0]);
    if (!isActivationOp(next.op_type()) || !next.domain().empty())
      break;
    if (!allowClamp) {
      failNode(next, "cannot be fused into " + gn.opType +
                         " (which does not requantize); put QuantizeLinear/DequantizeLinear "
                         "in between");
    }
    applyClamp(next, gn);
    fused_[static_cast<std::size_t>(cons[0])] = true;
    value = next.output(0);
  }
  return defineActivation(node, value, shape);
}

void Parser::applyClamp(const onnx::NodeProto& act, GraphNode& gn) const {
  float lo = 0.0F;
  float hi = std::numeric_limits<float>::infinity();
  if (act.op_type() == "Clip") {
    lo = -std::numeric_limits<float>::infinity();
    if (const auto* a = attr(act, "min"); a != nullptr)
      lo = a->f();
    if (const auto* a = attr(act, "max"); a != nullptr)
      hi = a->f();
    for (int i = 1; i <= 2; ++i) {
      if (act.input_size() <= i || act.input(i).empty())
        continue;
      const auto* t = constant(act.input(i));
      if (t == nullptr)
        failNode(act, "min/max must be constants");
      const auto v = floats(act, *t, i == 1 ? "min" : "max");
      if (v.size() != 1)
        failNode(act, "min/max must be scalars");
      (i == 1 ? lo : hi) = v[0];
    }
    if (!(lo <= hi))
      failNode(act, "min > max");
  }
  gn.clampMin = std::max(gn.clampMin, lo);
  gn.clampMax = std::min(gn.clampMax, hi);
  gn.opType += "+" + act.op_type();
}

}  // namespace vp::inference::onnx_detail
