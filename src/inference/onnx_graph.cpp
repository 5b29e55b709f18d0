#include "inference/onnx_graph.hpp"

#include <onnx/onnx_pb.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace vp::inference {

bool sameQuant(const QuantParams& a, const QuantParams& b) {
  return a.scale == b.scale && a.zeroPoint == b.zeroPoint;
}

bool readFileBytes(const std::string& path, std::string* bytes, std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *why = path + ": cannot open the model file (missing or unreadable)";
    return false;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    *why = path + ": read error";
    return false;
  }
  *bytes = buffer.str();
  return true;
}

namespace {

constexpr int kMinOpset = 13;

// Thrown inside the parser only; parseQdqModel() turns it into a return value.
struct LoadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string formatQuant(const QuantParams& q) {
  std::ostringstream s;
  s.precision(9);
  s << "(scale " << q.scale << ", zero point " << q.zeroPoint << ")";
  return s.str();
}

std::int64_t elementCount(const onnx::TensorProto& t) {
  std::int64_t n = 1;
  for (const auto d : t.dims())
    n *= d;
  return n;
}

bool isActivationOp(const std::string& op) {
  return op == "Relu" || op == "Clip";
}

class Parser {
 public:
  Parser(const onnx::ModelProto& model, QdqGraph* graph) : model_(model), g_(*graph) {}

  void parse() {
    checkOpset();
    readMetadata();
    const auto& graph = model_.graph();
    for (const auto& init : graph.initializer())
      constants_[init.name()] = &init;
    for (int i = 0; i < graph.node_size(); ++i) {
      const auto& node = graph.node(i);
      for (const auto& out : node.output()) {
        if (!out.empty())
          producer_[out] = i;
      }
      for (const auto& in : node.input()) {
        if (!in.empty())
          consumers_[in].push_back(i);
      }
      if (node.op_type() == "Constant" && node.domain().empty()) {
        for (const auto& attr : node.attribute()) {
          if (attr.name() == "value" && attr.has_t() && node.output_size() == 1) {
            constants_[node.output(0)] = &attr.t();
          }
        }
      }
    }
    for (const auto& out : graph.output())
      graphOutputs_.insert(out.name());
    fused_.assign(static_cast<std::size_t>(graph.node_size()), false);

    parseInput();
    for (int i = 0; i < graph.node_size(); ++i) {
      if (!fused_[static_cast<std::size_t>(i)])
        parseNode(i);
    }
    parseOutputs();
    checkValueInfo();
  }

 private:
  // ---- messages ---------------------------------------------------------------------------
  std::string nodeLabel(const onnx::NodeProto& node) const {
    const std::string name = node.name().empty() ? "<unnamed>" : node.name();
    return g_.file + ": node '" + name + "' (" + node.op_type() + ")";
  }
  [[noreturn]] void failNode(const onnx::NodeProto& node, const std::string& msg) const {
    throw LoadError(nodeLabel(node) + ": " + msg);
  }
  [[noreturn]] void fail(const std::string& msg) const { throw LoadError(g_.file + ": " + msg); }

  // ---- model level ------------------------------------------------------------------------
  void checkOpset() {
    int opset = -1;
    for (const auto& imp : model_.opset_import()) {
      if (imp.domain().empty() || imp.domain() == "ai.onnx")
        opset = static_cast<int>(imp.version());
    }
    if (opset < 0)
      fail("no default-domain opset import");
    if (opset < kMinOpset) {
      fail("opset " + std::to_string(opset) + " is too old: opset >= " + std::to_string(kMinOpset) +
           " is needed (per-channel QuantizeLinear/DequantizeLinear axis)");
    }
    if (!model_.has_graph() || model_.graph().node_size() == 0)
      fail("the model has no graph nodes");
  }

  static std::vector<float> parseTriple(const std::string& text, bool* ok) {
    std::vector<float> values;
    std::stringstream stream(text);
    std::string item;
    *ok = true;
    while (std::getline(stream, item, ',')) {
      try {
        std::size_t used = 0;
        const float v = std::stof(item, &used);
        if (item.find_first_not_of(" \t", used) != std::string::npos || !std::isfinite(v)) {
          *ok = false;
        }
        values.push_back(v);
      } catch (const std::exception&) {
        *ok = false;
      }
    }
    if (values.size() != 3)
      *ok = false;
    return values;
  }

  void readMetadata() {
    for (const auto& prop : model_.metadata_props()) {
      if (prop.key() == "vp.input.channel_order") {
        if (prop.value() == "rgb" || prop.value() == "RGB") {
          g_.normalization.modelOrder = ChannelOrder::Rgb;
        } else if (prop.value() == "bgr" || prop.value() == "BGR") {
          g_.normalization.modelOrder = ChannelOrder::Bgr;
        } else {
          fail("metadata 'vp.input.channel_order' is '" + prop.value() + "', expected rgb or bgr");
        }
      } else if (prop.key() == "vp.input.mean" || prop.key() == "vp.input.scale") {
        bool ok = false;
        const auto v = parseTriple(prop.value(), &ok);
        if (!ok) {
          fail("metadata '" + prop.key() + "' is '" + prop.value() +
               "', expected three comma-separated numbers");
        }
        auto& target =
            prop.key() == "vp.input.mean" ? g_.normalization.mean : g_.normalization.scale;
        for (std::size_t c = 0; c < 3; ++c)
          target[c] = v[c];
        if (prop.key() == "vp.input.scale" &&
            std::any_of(v.begin(), v.end(), [](float s) { return s == 0.0F; })) {
          fail("metadata 'vp.input.scale' has a zero entry");
        }
      }
    }
  }

  // ---- constants ----------------------------------------------------------------------------
  const onnx::TensorProto* constant(const std::string& name) const {
    auto it = constants_.find(name);
    if (it != constants_.end())
      return it->second;
    // Identity of a constant.
    auto p = producer_.find(name);
    if (p != producer_.end()) {
      const auto& node = model_.graph().node(p->second);
      if (node.op_type() == "Identity" && node.input_size() == 1)
        return constant(node.input(0));
    }
    return nullptr;
  }

  std::vector<float> floats(const onnx::NodeProto& node, const onnx::TensorProto& t,
                            const std::string& what) const {
    if (t.data_type() != onnx::TensorProto_DataType_FLOAT) {
      failNode(node, what + " '" + t.name() + "' must be float");
    }
    if (t.data_location() == onnx::TensorProto_DataLocation_EXTERNAL) {
      failNode(node, what + " '" + t.name() + "' uses external data (not supported)");
    }
    const auto n = elementCount(t);
    std::vector<float> v;
    if (t.has_raw_data()) {
      if (t.raw_data().size() != static_cast<std::size_t>(n) * sizeof(float)) {
        failNode(node, what + " '" + t.name() + "' has " +
                           std::to_string(t.raw_data().size() / sizeof(float)) +
                           " values, its dims say " + std::to_string(n));
      }
      v.resize(static_cast<std::size_t>(n));
      std::memcpy(v.data(), t.raw_data().data(), t.raw_data().size());
    } else {
      v.assign(t.float_data().begin(), t.float_data().end());
    }
    if (static_cast<std::int64_t>(v.size()) != n) {
      failNode(node, what + " '" + t.name() + "' has " + std::to_string(v.size()) +
                         " values, its dims say " + std::to_string(n));
    }
    return v;
  }

  std::vector<std::int64_t> ints(const onnx::NodeProto& node, const onnx::TensorProto& t,
                                 const std::string& what) const {
    if (t.data_location() == onnx::TensorProto_DataLocation_EXTERNAL) {
      failNode(node, what + " '" + t.name() + "' uses external data (not supported)");
    }
    const auto n = elementCount(t);
    std::vector<std::int64_t> v;
    const std::string& raw = t.raw_data();
    const bool hasRaw = t.has_raw_data();
    auto rawCount = [&](std::size_t bytes) {
      if (raw.size() != static_cast<std::size_t>(n) * bytes) {
        failNode(node, what + " '" + t.name() + "' has " + std::to_string(raw.size() / bytes) +
                           " values, its dims say " + std::to_string(n));
      }
    };
    switch (t.data_type()) {
      case onnx::TensorProto_DataType_INT8:
      case onnx::TensorProto_DataType_UINT8:
        if (hasRaw) {
          rawCount(1);
          for (const char c : raw) {
            v.push_back(t.data_type() == onnx::TensorProto_DataType_INT8
                            ? static_cast<std::int64_t>(static_cast<std::int8_t>(c))
                            : static_cast<std::int64_t>(static_cast<std::uint8_t>(c)));
          }
        } else {
          v.assign(t.int32_data().begin(), t.int32_data().end());
        }
        break;
      case onnx::TensorProto_DataType_INT32:
        if (hasRaw) {
          rawCount(4);
          for (std::size_t i = 0; i < raw.size(); i += 4) {
            std::int32_t x = 0;
            std::memcpy(&x, raw.data() + i, 4);
            v.push_back(x);
          }
        } else {
          v.assign(t.int32_data().begin(), t.int32_data().end());
        }
        break;
      case onnx::TensorProto_DataType_INT64:
        if (hasRaw) {
          rawCount(8);
          for (std::size_t i = 0; i < raw.size(); i += 8) {
            std::int64_t x = 0;
            std::memcpy(&x, raw.data() + i, 8);
            v.push_back(x);
          }
        } else {
          v.assign(t.int64_data().begin(), t.int64_data().end());
        }
        break;
      default:
        failNode(node, what + " '" + t.name() + "' has an unsupported element type");
    }
    if (static_cast<std::int64_t>(v.size()) != n) {
      failNode(node, what + " '" + t.name() + "' has " + std::to_string(v.size()) +
                         " values, its dims say " + std::to_string(n));
    }
    return v;
  }

  // ---- attributes ---------------------------------------------------------------------------
  static const onnx::AttributeProto* attr(const onnx::NodeProto& node, const std::string& name) {
    for (const auto& a : node.attribute()) {
      if (a.name() == name)
        return &a;
    }
    return nullptr;
  }
  static std::int64_t attrInt(const onnx::NodeProto& node, const std::string& name,
                              std::int64_t fallback) {
    const auto* a = attr(node, name);
    return a != nullptr ? a->i() : fallback;
  }
  static std::string attrString(const onnx::NodeProto& node, const std::string& name,
                                const std::string& fallback) {
    const auto* a = attr(node, name);
    return a != nullptr ? a->s() : fallback;
  }
  std::vector<int> attrInts(const onnx::NodeProto& node, const std::string& name,
                            std::size_t expected, int fallback) const {
    const auto* a = attr(node, name);
    if (a == nullptr)
      return std::vector<int>(expected, fallback);
    if (static_cast<std::size_t>(a->ints_size()) != expected) {
      failNode(node, "attribute '" + name + "' has " + std::to_string(a->ints_size()) +
                         " values, expected " + std::to_string(expected));
    }
    std::vector<int> v;
    for (const auto x : a->ints()) {
      if (x < 0 || x > 4096)
        failNode(node, "attribute '" + name + "' value out of range");
      v.push_back(static_cast<int>(x));
    }
    return v;
  }

  // ---- quantization params -------------------------------------------------------------------
  // Scalar (scale, zero point) of a QuantizeLinear / DequantizeLinear node.
  QuantParams scalarQuant(const onnx::NodeProto& node) const {
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

  // ---- activations ----------------------------------------------------------------------------
  const onnx::NodeProto* producerNode(const std::string& value) const {
    auto it = producer_.find(value);
    return it == producer_.end() ? nullptr : &model_.graph().node(it->second);
  }
  const std::vector<int>& consumersOf(const std::string& value) const {
    static const std::vector<int> kNone;
    auto it = consumers_.find(value);
    return it == consumers_.end() ? kNone : it->second;
  }

  // `floatValue` (output of `owner`, after any fused activations) must feed exactly one
  // QuantizeLinear whose output feeds DequantizeLinear nodes only: registers their outputs as
  // the float aliases of a new (or the given) tensor and returns its index.
  int defineActivation(const onnx::NodeProto& owner, const std::string& floatValue,
                       TensorShape shape, int reuse = -1) {
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

  int activation(const onnx::NodeProto& node, int inputIndex) const {
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

  bool isGraphInput(const std::string& name) const {
    for (const auto& in : model_.graph().input()) {
      if (in.name() == name)
        return true;
    }
    return false;
  }

  // Number of node inputs (plus graph outputs) that read any alias of tensor `id`.
  std::size_t useCount(int id) const {
    std::size_t n = 0;
    for (const auto& alias : aliasNames_[static_cast<std::size_t>(id)]) {
      n += consumersOf(alias).size();
      n += graphOutputs_.count(alias);
    }
    return n;
  }

  // ---- input -----------------------------------------------------------------------------------
  void parseInput() {
    const auto& graph = model_.graph();
    std::vector<const onnx::ValueInfoProto*> inputs;
    for (const auto& in : graph.input()) {
      if (constants_.count(in.name()) == 0)
        inputs.push_back(&in);
    }
    if (inputs.size() != 1) {
      fail("expected exactly one graph input (the image), found " + std::to_string(inputs.size()));
    }
    const auto& in = *inputs[0];
    g_.inputName = in.name();
    const std::string label = "input '" + in.name() + "'";
    if (!in.type().has_tensor_type() ||
        in.type().tensor_type().elem_type() != onnx::TensorProto_DataType_FLOAT) {
      fail(label + " must be a float tensor");
    }
    const auto& shape = in.type().tensor_type().shape();
    if (shape.dim_size() != 4)
      fail(label + " must have shape [1, 3, H, W]");
    std::array<std::int64_t, 4> dims{};
    for (int i = 0; i < 4; ++i) {
      if (!shape.dim(i).has_dim_value() || shape.dim(i).dim_value() <= 0) {
        fail(label + " has a dynamic or invalid dimension " + std::to_string(i) +
             " (static shapes only)");
      }
      dims[static_cast<std::size_t>(i)] = shape.dim(i).dim_value();
    }
    if (dims[0] != 1)
      fail(label + " has batch " + std::to_string(dims[0]) + " (must be 1)");
    if (dims[1] != 3)
      fail(label + " has " + std::to_string(dims[1]) + " channels (must be 3)");
    if (dims[2] > 16384 || dims[3] > 16384)
      fail(label + " is too large");
    const TensorShape s{1, 3, static_cast<int>(dims[2]), static_cast<int>(dims[3])};
    const auto& cons = consumersOf(in.name());
    if (cons.size() != 1 || graph.node(cons[0]).op_type() != "QuantizeLinear") {
      fail(label + " must be consumed by exactly one QuantizeLinear");
    }
    if (graphOutputs_.count(in.name()) != 0)
      fail(label + " is also a graph output");
    // The input QuantizeLinear has no owning compute node: report it as the owner.
    const auto& q = graph.node(cons[0]);
    onnx::NodeProto owner;
    owner.set_name(q.name());
    owner.set_op_type("QuantizeLinear");
    g_.inputTensor = defineActivation(owner, in.name(), s);
  }

  // ---- weights --------------------------------------------------------------------------------
  struct Weights {
    std::vector<std::int64_t> dims;
    std::vector<std::int8_t> values;
    std::vector<float> scales;  // per `axis` channel (broadcast from a scalar)
  };

  Weights weights(const onnx::NodeProto& node, const std::string& name, int axis,
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

  std::vector<float> bias(const onnx::NodeProto& node, int channels) const {
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
    return b;
  }

  // ---- output side: fused activations then the QuantizeLinear ------------------------------
  // Follows Relu/Clip directly behind `node`'s output (fusing them into `gn`'s clamp when
  // `allowClamp`), then defines the output tensor.
  int finishOutput(const onnx::NodeProto& node, GraphNode& gn, TensorShape shape, bool allowClamp) {
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

  void applyClamp(const onnx::NodeProto& act, GraphNode& gn) const {
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

  GraphNode makeNode(const onnx::NodeProto& node, OpKind kind) const {
    GraphNode gn;
    gn.kind = kind;
    gn.name = node.name().empty() ? node.output(0) : node.name();
    gn.opType = node.op_type();
    return gn;
  }

  void push(GraphNode gn) {
    producerOf_[gn.output] = static_cast<int>(g_.nodes.size());
    g_.nodes.push_back(std::move(gn));
  }

  const TensorShape& shapeOf(int id) const {
    return g_.tensors[static_cast<std::size_t>(id)].shape;
  }

  // ---- pads / windows ------------------------------------------------------------------------
  void windowAttributes(const onnx::NodeProto& node, GraphNode& gn, const TensorShape& in,
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

  static int windowOut(int size, int padA, int padB, int k, int s, int d) {
    const int span = size + padA + padB - ((k - 1) * d + 1);
    return span < 0 ? 0 : span / s + 1;
  }

  // ---- per operator -----------------------------------------------------------------------------
  void parseNode(int index) {
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

  void parseConv(const onnx::NodeProto& node) {
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
    gn.macs = static_cast<std::uint64_t>(out.elements()) *
              static_cast<std::uint64_t>(in.c / group) *
              static_cast<std::uint64_t>(gn.kernelH * gn.kernelW);
    gn.output = finishOutput(node, gn, out, true);
    push(std::move(gn));
  }

  void parseConvTranspose(const onnx::NodeProto& node) {
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
                          (in.h - 1) * gn.strideH + (gn.kernelH - 1) * gn.dilationH + 1 -
                              gn.padTop - gn.padBottom + gn.adjustH,
                          (in.w - 1) * gn.strideW + (gn.kernelW - 1) * gn.dilationW + 1 -
                              gn.padLeft - gn.padRight + gn.adjustW};
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

  void parseBinary(const onnx::NodeProto& node) {
    GraphNode gn = makeNode(node, node.op_type() == "Add" ? OpKind::Add : OpKind::Mul);
    if (node.input_size() != 2)
      failNode(node, "expects two inputs");
    const int a = activation(node, 0);
    const int b = activation(node, 1);
    const TensorShape sa = shapeOf(a);
    const TensorShape sb = shapeOf(b);
    const auto bc = [&](int x, int y) {
      if (x != y && x != 1 && y != 1) {
        failNode(node, "input shapes [1," + std::to_string(sa.c) + "," + std::to_string(sa.h) +
                           "," + std::to_string(sa.w) + "] and [1," + std::to_string(sb.c) + "," +
                           std::to_string(sb.h) + "," + std::to_string(sb.w) +
                           "] do not broadcast");
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

  void parseConcat(const onnx::NodeProto& node) {
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

  void requireSameQuant(const onnx::NodeProto& node, const GraphNode& gn,
                        const std::string& why) const {
    const auto& iq = g_.tensors[static_cast<std::size_t>(gn.inputs[0])].quant;
    const auto& oq = g_.tensors[static_cast<std::size_t>(gn.output)].quant;
    if (!sameQuant(iq, oq)) {
      failNode(node, "input " + formatQuant(iq) + " and output " + formatQuant(oq) +
                         " quantization differ; " + why);
    }
  }

  void parseResize(const onnx::NodeProto& node) {
    const int x = activation(node, 0);
    const TensorShape in = shapeOf(x);
    const std::string mode = attrString(node, "mode", "nearest");
    const std::string ctm = attrString(node, "coordinate_transformation_mode", "half_pixel");
    GraphNode gn =
        makeNode(node, mode == "nearest" ? OpKind::ResizeNearest : OpKind::ResizeBilinear);
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
      const bool rounding =
          nearestMode == "round_prefer_floor" || nearestMode == "round_prefer_ceil";
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

  void parseMaxPool(const onnx::NodeProto& node) {
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

  void parseGlobalAveragePool(const onnx::NodeProto& node) {
    GraphNode gn = makeNode(node, OpKind::GlobalAveragePool);
    const int x = activation(node, 0);
    const TensorShape in = shapeOf(x);
    gn.inputs = {x};
    gn.output = finishOutput(node, gn, TensorShape{1, in.c, 1, 1}, true);
    push(std::move(gn));
  }

  void parseUnary(const onnx::NodeProto& node) {
    GraphNode gn = makeNode(node, node.op_type() == "Sigmoid" ? OpKind::Sigmoid : OpKind::Tanh);
    const int x = activation(node, 0);
    gn.inputs = {x};
    gn.output = finishOutput(node, gn, shapeOf(x), true);
    push(std::move(gn));
  }

  void parseStandaloneClamp(const onnx::NodeProto& node) {
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

  void finishOutputInto(const onnx::NodeProto& node, int reuse) {
    std::string value = node.output(0);
    const auto& cons = consumersOf(value);
    if (cons.size() == 1 && isActivationOp(model_.graph().node(cons[0]).op_type())) {
      failNode(model_.graph().node(cons[0]), "chained activations without QDQ are not supported");
    }
    defineActivation(node, value, shapeOf(reuse), reuse);
  }

  // ---- outputs and declared shapes ----------------------------------------------------------
  void parseOutputs() {
    for (const auto& out : model_.graph().output()) {
      auto it = aliases_.find(out.name());
      if (it == aliases_.end()) {
        fail("graph output '" + out.name() +
             "' is not the output of a DequantizeLinear of an activation");
      }
      g_.outputs.push_back(GraphOutput{out.name(), it->second});
    }
    if (g_.outputs.empty())
      fail("the model has no outputs");
  }

  void checkShape(const onnx::ValueInfoProto& vi, const TensorShape& s) const {
    if (!vi.type().has_tensor_type() || !vi.type().tensor_type().has_shape())
      return;
    const auto& shape = vi.type().tensor_type().shape();
    if (shape.dim_size() == 0)
      return;
    const std::array<int, 4> ours{s.n, s.c, s.h, s.w};
    if (shape.dim_size() != 4) {
      fail("value '" + vi.name() + "' is declared with " + std::to_string(shape.dim_size()) +
           " dimensions, inferred 4");
    }
    for (int i = 0; i < 4; ++i) {
      if (shape.dim(i).has_dim_value() &&
          shape.dim(i).dim_value() != ours[static_cast<std::size_t>(i)]) {
        fail("value '" + vi.name() + "' is declared with dimension " + std::to_string(i) + " = " +
             std::to_string(shape.dim(i).dim_value()) + ", inferred " +
             std::to_string(ours[static_cast<std::size_t>(i)]));
      }
    }
  }

  void checkValueInfo() const {
    const auto check = [&](const onnx::ValueInfoProto& vi) {
      for (const auto* names : {&aliases_, &floatNames_}) {
        auto it = names->find(vi.name());
        if (it != names->end()) {
          checkShape(vi, g_.tensors[static_cast<std::size_t>(it->second)].shape);
          return;
        }
      }
    };
    for (const auto& vi : model_.graph().value_info())
      check(vi);
    for (const auto& vi : model_.graph().output())
      check(vi);
  }

  const onnx::ModelProto& model_;
  QdqGraph& g_;
  std::unordered_map<std::string, const onnx::TensorProto*> constants_;
  std::unordered_map<std::string, int> producer_;
  std::unordered_map<std::string, std::vector<int>> consumers_;
  std::set<std::string> graphOutputs_;
  std::vector<bool> fused_;
  std::unordered_map<std::string, int> aliases_;     // dequantized value -> tensor
  std::unordered_map<std::string, int> floatNames_;  // float value before Q -> tensor
  std::vector<std::vector<std::string>> aliasNames_;
  std::unordered_map<int, int> producerOf_;  // tensor -> graph node index
};

}  // namespace

bool parseQdqModel(const std::string& bytes, const std::string& file, QdqGraph* graph,
                   std::string* why) {
  onnx::ModelProto model;
  if (bytes.empty() || !model.ParseFromString(bytes)) {
    *why = file + ": not a valid ONNX model (protobuf parse failed; file truncated or corrupt?)";
    return false;
  }
  *graph = QdqGraph{};
  graph->file = file;
  try {
    Parser parser(model, graph);
    parser.parse();
  } catch (const LoadError& e) {
    *why = e.what();
    return false;
  } catch (const std::exception& e) {
    *why = file + ": " + e.what();
    return false;
  }
  return true;
}

}  // namespace vp::inference
