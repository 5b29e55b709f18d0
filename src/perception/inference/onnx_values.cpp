// inference/onnx_values: the Parser's access to the model's data (onnx_parser.hpp): initializers
// and Constant nodes (through Identity), decoded as float or integer values with their element
// counts checked against their dims, and node attributes with their fallbacks.
#include <cstring>

#include "inference/onnx_parser.hpp"

namespace vp::inference::onnx_detail {

const onnx::TensorProto* Parser::constant(const std::string& name) const {
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

std::vector<float> Parser::floats(const onnx::NodeProto& node, const onnx::TensorProto& t,
                                  const std::string& what) const {
  if (t.data_type() != onnx::TensorProto_DataType_FLOAT) {
    failNode(node, what + " '" + t.name() + "' must be float");
  }
  if (t.data_location() == onnx::TensorProto_DataLocation_EXTERNAL) {
    failNode(node, what + " '" + t.name() + "' uses external data (not supported)");
  }
  const auto n = elementCount(t);
  if (n < 0) {
    failNode(node, what + " '" + t.name() + "' has invalid dims (negative, or over 2^31 values)");
  }
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

std::vector<std::int64_t> Parser::ints(const onnx::NodeProto& node, const onnx::TensorProto& t,
                                       const std::string& what) const {
  if (t.data_location() == onnx::TensorProto_DataLocation_EXTERNAL) {
    failNode(node, what + " '" + t.name() + "' uses external data (not supported)");
  }
  const auto n = elementCount(t);
  if (n < 0) {
    failNode(node, what + " '" + t.name() + "' has invalid dims (negative, or over 2^31 values)");
  }
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

const onnx::AttributeProto* Parser::attr(const onnx::NodeProto& node, const std::string& name) {
  for (const auto& a : node.attribute()) {
    if (a.name() == name)
      return &a;
  }
  return nullptr;
}

std::int64_t Parser::attrInt(const onnx::NodeProto& node, const std::string& name,
                             std::int64_t fallback) {
  const auto* a = attr(node, name);
  return a != nullptr ? a->i() : fallback;
}

std::string Parser::attrString(const onnx::NodeProto& node, const std::string& name,
                               const std::string& fallback) {
  const auto* a = attr(node, name);
  return a != nullptr ? a->s() : fallback;
}

std::vector<int> Parser::attrInts(const onnx::NodeProto& node, const std::string& name,
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

}  // namespace vp::inference::onnx_detail
