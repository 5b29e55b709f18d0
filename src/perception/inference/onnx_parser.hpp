// inference/onnx_parser: the QDQ ONNX parser behind parseQdqModel() (onnx_graph.hpp), private
// to src/perception/inference.
//
// One Parser walks one ModelProto into a QdqGraph. Its members are defined in four files, one
// job each (the banners below say which member lives where):
//   onnx_graph.cpp      the walk itself, model-level checks (opset, metadata), the image input,
//                       the graph outputs and the declared-shape checks; parseQdqModel()
//   onnx_values.cpp     reading initializer / Constant tensors and node attributes
//   onnx_qdq.cpp        the QDQ patterns: activation Q -> DQ pairs, int8 weight and int32 bias
//                       chains, Relu/Clip fused into a node's output
//   onnx_operators.cpp  one graph node per supported operator, with its shape inference
// Every rejection unwinds as a LoadError, which parseQdqModel() turns into its message.
#pragma once

#include <onnx/onnx_pb.h>

#include <cstddef>
#include <cstdint>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "inference/onnx_graph.hpp"

namespace vp::inference::onnx_detail {

inline constexpr int kMinOpset = 13;

// Thrown inside the parser only; parseQdqModel() turns it into a return value.
struct LoadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline std::string formatQuant(const QuantParams& q) {
  std::ostringstream s;
  s.precision(9);
  s << "(scale " << q.scale << ", zero point " << q.zeroPoint << ")";
  return s.str();
}

// More elements than any tensor the engine can hold (and than a model file's values can be).
inline constexpr std::int64_t kMaxTensorElements = std::int64_t{1} << 31;

// The element count of t's dims; -1 when a dim is negative or the product exceeds
// kMaxTensorElements (checked before multiplying: hostile dims must not overflow).
inline std::int64_t elementCount(const onnx::TensorProto& t) {
  std::int64_t n = 1;
  for (const auto d : t.dims()) {
    if (d < 0 || (d > 0 && n > kMaxTensorElements / d))
      return -1;
    n *= d;
  }
  return n;
}

inline bool isActivationOp(const std::string& op) {
  return op == "Relu" || op == "Clip";
}

class Parser {
 public:
  Parser(const onnx::ModelProto& model, QdqGraph* graph) : model_(model), g_(*graph) {}

  void parse();

 private:
  // ==== onnx_graph.cpp: model level, the graph input and outputs ======================
  // ---- messages ---------------------------------------------------------------------------
  std::string nodeLabel(const onnx::NodeProto& node) const;
  [[noreturn]] void failNode(const onnx::NodeProto& node, const std::string& msg) const;
  [[noreturn]] void fail(const std::string& msg) const { throw LoadError(g_.file + ": " + msg); }

  // ---- model level ------------------------------------------------------------------------
  void checkOpset();
  static std::vector<float> parseTriple(const std::string& text, bool* ok);
  void readMetadata();

  // ---- input -----------------------------------------------------------------------------------
  void parseInput();

  // ---- outputs and declared shapes ----------------------------------------------------------
  void parseOutputs();
  void checkShape(const onnx::ValueInfoProto& vi, const TensorShape& s) const;
  void checkValueInfo() const;

  // ==== onnx_values.cpp: initializer / Constant values and node attributes ============
  // ---- constants ----------------------------------------------------------------------------
  const onnx::TensorProto* constant(const std::string& name) const;
  std::vector<float> floats(const onnx::NodeProto& node, const onnx::TensorProto& t,
                            const std::string& what) const;
  std::vector<std::int64_t> ints(const onnx::NodeProto& node, const onnx::TensorProto& t,
                                 const std::string& what) const;

  // ---- attributes ---------------------------------------------------------------------------
  static const onnx::AttributeProto* attr(const onnx::NodeProto& node, const std::string& name);
  static std::int64_t attrInt(const onnx::NodeProto& node, const std::string& name,
                              std::int64_t fallback);
  static std::string attrString(const onnx::NodeProto& node, const std::string& name,
                                const std::string& fallback);
  std::vector<int> attrInts(const onnx::NodeProto& node, const std::string& name,
                            std::size_t expected, int fallback) const;

  // ==== onnx_qdq.cpp: the QDQ patterns around compute nodes ===========================
  // ---- quantization params -------------------------------------------------------------------
  // Scalar (scale, zero point) of a QuantizeLinear / DequantizeLinear node.
  QuantParams scalarQuant(const onnx::NodeProto& node) const;

  // ---- activations ----------------------------------------------------------------------------
  const onnx::NodeProto* producerNode(const std::string& value) const;
  const std::vector<int>& consumersOf(const std::string& value) const;
  // `floatValue` (output of `owner`, after any fused activations) must feed exactly one
  // QuantizeLinear whose output feeds DequantizeLinear nodes only: registers their outputs as
  // the float aliases of a new (or the given) tensor and returns its index.
  int defineActivation(const onnx::NodeProto& owner, const std::string& floatValue,
                       TensorShape shape, int reuse = -1);
  int activation(const onnx::NodeProto& node, int inputIndex) const;
  bool isGraphInput(const std::string& name) const;
  // Number of node inputs (plus graph outputs) that read any alias of tensor `id`.
  std::size_t useCount(int id) const;

  // ---- weights --------------------------------------------------------------------------------
  struct Weights {
    std::vector<std::int64_t> dims;
    std::vector<std::int8_t> values;
    std::vector<float> scales;  // per `axis` channel (broadcast from a scalar)
  };
  Weights weights(const onnx::NodeProto& node, const std::string& name, int axis,
                  const std::string& axisWord) const;
  std::vector<float> bias(const onnx::NodeProto& node, int channels) const;

  // ---- output side: fused activations then the QuantizeLinear ------------------------------
  // Follows Relu/Clip directly behind `node`'s output (fusing them into `gn`'s clamp when
  // `allowClamp`), then defines the output tensor.
  int finishOutput(const onnx::NodeProto& node, GraphNode& gn, TensorShape shape, bool allowClamp);
  void applyClamp(const onnx::NodeProto& act, GraphNode& gn) const;
  // ==== onnx_operators.cpp: one graph node per supported operator =====================
  // ---- graph nodes ---------------------------------------------------------------------------
  GraphNode makeNode(const onnx::NodeProto& node, OpKind kind) const;
  void push(GraphNode gn);
  const TensorShape& shapeOf(int id) const;

  // ---- pads / windows ------------------------------------------------------------------------
  void windowAttributes(const onnx::NodeProto& node, GraphNode& gn, const TensorShape& in,
                        bool allowSame) const;
  static int windowOut(int size, int padA, int padB, int k, int s, int d);

  // ---- per operator -----------------------------------------------------------------------------
  void parseNode(int index);
  void parseConv(const onnx::NodeProto& node);
  void parseConvTranspose(const onnx::NodeProto& node);
  void parseBinary(const onnx::NodeProto& node);
  void parseConcat(const onnx::NodeProto& node);
  void requireSameQuant(const onnx::NodeProto& node, const GraphNode& gn,
                        const std::string& why) const;
  void parseResize(const onnx::NodeProto& node);
  void parseMaxPool(const onnx::NodeProto& node);
  void parseGlobalAveragePool(const onnx::NodeProto& node);
  void parseUnary(const onnx::NodeProto& node);
  void parseStandaloneClamp(const onnx::NodeProto& node);
  void finishOutputInto(const onnx::NodeProto& node, int reuse);

  // ---- parse state --------------------------------------------------------------------------
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

}  // namespace vp::inference::onnx_detail
