// inference/onnx_graph: reads a QDQ ONNX file into a small, validated graph IR.
//
// Contract: parseQdqModel() parses the protobuf, checks the opset, folds the QDQ plumbing
// (activation QuantizeLinear -> DequantizeLinear pairs become tensor quantization params,
// weight DequantizeLinear chains become int8 weights with per-channel float scales, bias
// chains become float biases, Relu/Clip become output clamps where they can be fused) and
// infers every NCHW shape itself through the supported operators, checking them against the
// shapes the file declares. The result lists compute nodes in execution order; tensor 0 is
// the quantized image input. Every rejection is a message "file: node 'n' (Op): why". The
// IR is backend neutral: the XNNPACK backends consume it, the OpenCV backend uses only the
// input/output description (it rebuilds a float model from the protobuf itself). The parser
// unwinds with an internal exception that never leaves parseQdqModel() (load time only).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "inference/engine.hpp"

namespace vp::inference {

struct QuantParams {
  float scale = 1.0F;
  int zeroPoint = 0;
};

bool sameQuant(const QuantParams& a, const QuantParams& b);

struct GraphTensor {
  std::string name;  // ONNX value name of the (dequantized) activation
  TensorShape shape;
  QuantParams quant;
};

enum class OpKind {
  Conv,
  ConvTranspose,
  Add,
  Mul,
  Concat,
  ResizeBilinear,
  ResizeNearest,
  MaxPool,
  GlobalAveragePool,
  Sigmoid,
  Tanh,
  Clamp
};

struct GraphNode {
  OpKind kind = OpKind::Conv;
  std::string name;    // ONNX node name
  std::string opType;  // after fusion, e.g. "Conv+Relu"
  std::vector<int> inputs;
  int output = -1;

  // Output clamp in real (dequantized) units, from fused Relu/Clip.
  float clampMin = -std::numeric_limits<float>::infinity();
  float clampMax = std::numeric_limits<float>::infinity();

  // Conv / ConvTranspose / MaxPool windows.
  int kernelH = 1;
  int kernelW = 1;
  int strideH = 1;
  int strideW = 1;
  int dilationH = 1;
  int dilationW = 1;
  int padTop = 0;
  int padLeft = 0;
  int padBottom = 0;
  int padRight = 0;
  int group = 1;
  int adjustH = 0;  // ConvTranspose output_padding
  int adjustW = 0;

  // Conv: [Cout][Cin/g][kh][kw]; ConvTranspose: [Cin][Cout/g][kh][kw] (ONNX layouts).
  std::vector<std::int8_t> weights;
  std::vector<float> weightScales;  // per output channel
  std::vector<float> bias;          // per output channel, float (zeros if absent)

  // Resize: integer scale factors; bilinear: align corners (else half pixel).
  int scaleH = 1;
  int scaleW = 1;
  bool alignCorners = false;

  std::uint64_t macs = 0;
};

struct GraphOutput {
  std::string name;
  int tensor = -1;
};

struct QdqGraph {
  std::string file;  // file name used in messages
  std::vector<GraphTensor> tensors;
  std::vector<GraphNode> nodes;
  std::vector<GraphOutput> outputs;
  int inputTensor = 0;
  std::string inputName;
  InputNormalization normalization;  // from metadata_props (defaults if absent)
};

// Parses `bytes` (the file's contents); `file` names the file in messages. Returns false and
// fills *why on any rejection.
bool parseQdqModel(const std::string& bytes, const std::string& file, QdqGraph* graph,
                   std::string* why);

// Reads a whole file; false with a message when it is missing or unreadable.
bool readFileBytes(const std::string& path, std::string* bytes, std::string* why);

}  // namespace vp::inference
