// inference/onnx_graph: parseQdqModel() and the Parser's walk over the model (onnx_parser.hpp):
// model-level checks (opset, vp.input.* metadata), the image input, the graph outputs and the
// shapes the file declares. The QDQ folding and the operators live in onnx_qdq.cpp,
// onnx_operators.cpp and onnx_values.cpp.
#include "inference/onnx_graph.hpp"

#include <onnx/onnx_pb.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "inference/onnx_parser.hpp"

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

namespace onnx_detail {

void Parser::parse() {
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

std::string Parser::nodeLabel(const onnx::NodeProto& node) const {
  const std::string name = node.name().empty() ? "<unnamed>" : node.name();
  return g_.file + ": node '" + name + "' (" + node.op_type() + ")";
}

void Parser::failNode(const onnx::NodeProto& node, const std::string& msg) const {
  throw LoadError(nodeLabel(node) + ": " + msg);
}

void Parser::checkOpset() {
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

std::vector<float> Parser::parseTriple(const std::string& text, bool* ok) {
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

void Parser::readMetadata() {
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
      auto& target = prop.key() == "vp.input.mean" ? g_.normalization.mean : g_.normalization.scale;
      for (std::size_t c = 0; c < 3; ++c)
        target[c] = v[c];
      if (prop.key() == "vp.input.scale" &&
          std::any_of(v.begin(), v.end(), [](float s) { return s == 0.0F; })) {
        fail("metadata 'vp.input.scale' has a zero entry");
      }
    }
  }
}

void Parser::parseInput() {
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

void Parser::parseOutputs() {
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

void Parser::checkShape(const onnx::ValueInfoProto& vi, const TensorShape& s) const {
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

void Parser::checkValueInfo() const {
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

}  // namespace onnx_detail

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
    onnx_detail::Parser parser(model, graph);
    parser.parse();
  } catch (const onnx_detail::LoadError& e) {
    *why = e.what();
    return false;
  } catch (const std::exception& e) {
    *why = file + ": " + e.what();
    return false;
  }
  return true;
}

}  // namespace vp::inference
