// inference/engine: runs a quantized (QDQ) ONNX CNN on a camera-layout image, in fixed memory.
//
// Contract:
//  - load() reads an ONNX file in QDQ form (QuantizeLinear/DequantizeLinear around every
//    activation, per-channel int8 weights; docs/inference.md lists the accepted patterns and
//    the exact operator coverage) and builds one of these backends on the same file:
//      XnnpackInt8  int8 activations, per-channel int8 weights (XNNPACK QS8/QC8 kernels);
//      XnnpackFp32  the same graph in float (weights dequantized, Q/DQ pairs dropped);
//      OpenCvFp32   OpenCV DNN on the same graph with Q/DQ folded away (the reference).
//      DnnlInt8     the int8 graph with its convolutions on oneDNN (VNNI kernels), the other
//                   nodes on XNNPACK (dnnl_int8.hpp); only in builds with oneDNN (x86);
//      Auto         DnnlInt8 when the build has oneDNN and the CPU has VNNI, else XnnpackInt8:
//                   resolved in load(), backend() then names the one that runs.
//    Every problem (unsupported operator, shape mismatch, missing scale, truncated or corrupt
//    file, wrong input layout) fails load() with a message naming the file and the node.
//  - The model has one image input [1, 3, H, W] and one or more outputs. run() takes an 8-bit
//    3-channel interleaved image (BGR or RGB, any row stride) of exactly W x H, and applies
//    the model's input normalisation x = (v - mean[c]) * scale[c] and, for int8, the input
//    quantization in one pass through a per-channel 256-entry table, writing straight into
//    the first layer's input tensor. Normalisation and channel order come from the model's
//    metadata (docs/inference.md) unless the options override them.
//  - Outputs are exposed as float tensors in NHWC order (channels contiguous per pixel),
//    dequantized for the int8 backend; the raw int8 tensor and its scale/zero point are
//    also available there.
//  - Everything (tensors, scratch, operator workspaces, thread pool) is allocated in load();
//    for the XNNPACK backends run() performs no heap allocation (DnnlInt8 does: oneDNN
//    allocates inside every primitive call, see dnnl_int8.hpp). Not thread-safe: one
//    engine per thread; its own work is spread over `threads` pthreadpool workers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vp::inference {

enum class Backend { XnnpackInt8, XnnpackFp32, OpenCvFp32, DnnlInt8, Auto };
const char* toString(Backend backend);
// "int8", "fp32", "opencv", "int8-dnnl", "auto"
std::optional<Backend> backendFromString(const std::string& name);
// What Auto means on this machine and build: DnnlInt8 or XnnpackInt8 (see DnnlInt8 above).
Backend resolveAutoBackend();

enum class ChannelOrder { Bgr, Rgb };

// x = (v - mean[c]) * scale[c], c in the model's channel order, v the 8-bit pixel value.
struct InputNormalization {
  ChannelOrder modelOrder = ChannelOrder::Rgb;
  std::array<float, 3> mean{0.0F, 0.0F, 0.0F};
  std::array<float, 3> scale{1.0F / 255.0F, 1.0F / 255.0F, 1.0F / 255.0F};
};

struct EngineOptions {
  Backend backend = Backend::Auto;                  // int8-dnnl on VNNI CPUs with oneDNN, else int8
  int threads = 1;                                  // pthreadpool workers (1 = calling thread)
  ChannelOrder imageOrder = ChannelOrder::Bgr;      // layout of the images given to run()
  std::optional<InputNormalization> normalization;  // overrides the model's metadata
  // XNNPACK and oneDNN backends: activation tensors share one arena by liveness (false: one
  // buffer per tensor, for debugging and for the test that compares both; same outputs).
  bool planMemory = true;
};

struct ImageView {
  const std::uint8_t* data = nullptr;  // interleaved 3 x 8 bit
  int width = 0;
  int height = 0;
  std::size_t strideBytes = 0;  // bytes between rows (>= 3 * width)
};

struct TensorShape {
  int n = 1;
  int c = 0;
  int h = 0;
  int w = 0;
  std::size_t elements() const {
    return static_cast<std::size_t>(n) * static_cast<std::size_t>(c) * static_cast<std::size_t>(h) *
           static_cast<std::size_t>(w);
  }
};

struct OutputTensor {
  std::string name;
  TensorShape shape;                       // logical NCHW shape, as in the ONNX graph
  const float* data = nullptr;             // NHWC, shape.elements() values, valid until next run
  const std::int8_t* quantized = nullptr;  // NHWC int8 (XnnpackInt8, DnnlInt8; else nullptr)
  float scale = 1.0F;                      // quantized -> float: (q - zeroPoint) * scale
  int zeroPoint = 0;
};

// What a loaded engine holds for its activation tensors and scratch buffers (XNNPACK and
// oneDNN backends; zeros for OpenCV, which manages its own). Operator workspaces, packed
// weights and the float copies of int8 outputs are not counted.
struct ActivationMemory {
  bool planned = false;             // EngineOptions::planMemory was in effect
  std::size_t allocated_bytes = 0;  // the arena, or the sum of the separate buffers
  std::size_t separate_bytes = 0;   // one buffer per tensor, as without the plan
};

enum class RunStatus { Ok, NotLoaded, WrongImageSize, BackendFailure };
const char* toString(RunStatus status);

// One line per compute operator of the loaded graph, for reports and the coverage table.
struct LayerInfo {
  std::string nodeName;
  std::string opType;         // ONNX op type (after fusion: e.g. "Conv+Relu")
  std::string backendKernel;  // e.g. "xnn convolution2d_nhwc_qc8"
  std::uint64_t macs = 0;     // multiply-accumulates per run
};

class Engine {
 public:
  Engine();
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;
  Engine(Engine&&) noexcept;
  Engine& operator=(Engine&&) noexcept;

  // Start-up: parses, validates and builds the backend. On failure returns false, fills *why
  // ("model.onnx: node 'conv3' (Conv): ...") and leaves the engine unloaded.
  // The model file's integrity is checked first against <onnxPath>.sha256 when it exists
  // (inference/model_checksum.hpp): a mismatch fails the load, naming both digests.
  bool load(const std::string& onnxPath, const EngineOptions& options, std::string* why);
  // The same from the file's bytes (no checksum file: the caller owns the bytes); `name` stands
  // for the file in messages.
  bool loadFromMemory(const std::string& onnxBytes, const std::string& name,
                      const EngineOptions& options, std::string* why);
  bool loaded() const;

  TensorShape inputShape() const;  // [1, 3, H, W]
  const InputNormalization& normalization() const;
  Backend backend() const;
  const std::vector<LayerInfo>& layers() const;
  std::uint64_t totalMacs() const;
  ActivationMemory activationMemory() const;

  // Real-time path: no heap allocation (XNNPACK backends), no exceptions.
  RunStatus run(const ImageView& image);

  std::size_t outputCount() const;
  const OutputTensor& output(std::size_t index) const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vp::inference
