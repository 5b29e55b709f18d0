// fuzz/onnx_model: the QDQ ONNX loader and the int8 engine (src/perception/inference) on
// arbitrary model bytes. The input is the model file itself.
// Contract checked: parseQdqModel() and Engine::loadFromMemory() return true, or false with a
// message naming the model; a model that loads runs once on a grey image of its input size
// (when that is small) and returns Ok with outputs of the declared sizes.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "inference/engine.hpp"
#include "inference/onnx_graph.hpp"

namespace {

constexpr const char* kTarget = "onnx_model";
constexpr const char* kName = "fuzz_model.onnx";
// Larger graphs are parsed and checked but not built: building allocates every tensor, which
// is right for a real model and only slow here.
constexpr std::size_t kMaxTensorElements = std::size_t{1} << 22;
constexpr int kMaxRunPixels = 128 * 128;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(vp::fuzz::asText(data, size));
  vp::inference::QdqGraph graph;
  std::string why;
  if (!vp::inference::parseQdqModel(bytes, kName, &graph, &why)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.starts_with(kName), kTarget,
                     "parse failed without naming the model: '" + why + "'");
    return 0;
  }
  std::size_t elements = 0;
  for (const auto& tensor : graph.tensors) {
    elements += tensor.shape.elements();
  }
  if (elements > kMaxTensorElements) {
    return 0;
  }

  vp::inference::Engine engine;
  vp::inference::EngineOptions options;  // int8, one thread
  if (!engine.loadFromMemory(bytes, kName, options, &why)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.starts_with(kName), kTarget,
                     "load failed without naming the model: '" + why + "'");
    vp::fuzz::expect(!engine.loaded(), kTarget, "a failed load left the engine loaded");
    return 0;
  }
  const vp::inference::TensorShape input = engine.inputShape();
  vp::fuzz::expect(input.n == 1 && input.c == 3 && input.w > 0 && input.h > 0, kTarget,
                   "loaded model with an input other than [1, 3, H, W]");
  if (input.w * input.h > kMaxRunPixels) {
    return 0;
  }
  const std::size_t stride = static_cast<std::size_t>(input.w) * 3;
  const std::vector<std::uint8_t> image(stride * static_cast<std::size_t>(input.h), 128);
  vp::fuzz::note(kTarget,
                 "loaded, running " + std::to_string(input.w) + " x " + std::to_string(input.h));
  const vp::inference::RunStatus status =
      engine.run(vp::inference::ImageView{image.data(), input.w, input.h, stride});
  vp::fuzz::expect(status == vp::inference::RunStatus::Ok, kTarget,
                   std::string("run() of a loaded model: ") + vp::inference::toString(status));
  for (std::size_t i = 0; i < engine.outputCount(); ++i) {
    const vp::inference::OutputTensor& out = engine.output(i);
    vp::fuzz::expect(out.data != nullptr && out.quantized != nullptr, kTarget,
                     "output '" + out.name + "' without data");
    // Touch every value: ASan reports an output buffer shorter than its shape.
    volatile float sum = 0.0F;
    for (std::size_t k = 0; k < out.shape.elements(); ++k) {
      sum = sum + out.data[k];
    }
    (void)sum;
  }
  return 0;
}
