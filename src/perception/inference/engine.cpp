// The engine facade (contract in engine.hpp): load = read + parse/validate + backend + input
// table; run = image -> table -> backend.
#include "inference/engine.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "inference/backend.hpp"
#include "inference/dnnl_int8.hpp"
#include "inference/model_checksum.hpp"
#include "inference/onnx_graph.hpp"
#include "inference/opencv_backend.hpp"
#include "inference/xnnpack_backend.hpp"

namespace vp::inference {

const char* toString(Backend backend) {
  switch (backend) {
    case Backend::XnnpackInt8:
      return "int8";
    case Backend::XnnpackFp32:
      return "fp32";
    case Backend::OpenCvFp32:
      return "opencv";
    case Backend::DnnlInt8:
      return "int8-dnnl";
    case Backend::Auto:
      return "auto";
  }
  return "?";
}

std::optional<Backend> backendFromString(const std::string& name) {
  if (name == "int8")
    return Backend::XnnpackInt8;
  if (name == "fp32")
    return Backend::XnnpackFp32;
  if (name == "opencv")
    return Backend::OpenCvFp32;
  if (name == "int8-dnnl")
    return Backend::DnnlInt8;
  if (name == "auto")
    return Backend::Auto;
  return std::nullopt;
}

Backend resolveAutoBackend() {
  return dnnlInt8Available() && cpuHasVnni() ? Backend::DnnlInt8 : Backend::XnnpackInt8;
}

const char* toString(RunStatus status) {
  switch (status) {
    case RunStatus::Ok:
      return "ok";
    case RunStatus::NotLoaded:
      return "not loaded";
    case RunStatus::WrongImageSize:
      return "wrong image size";
    case RunStatus::BackendFailure:
      return "backend failure";
  }
  return "?";
}

class Engine::Impl {
 public:
  bool load(const std::string& path, const EngineOptions& options, std::string* why) {
    std::string bytes;
    if (!readFileBytes(path, &bytes, why))
      return false;
    const ChecksumResult checksum = verifyModelChecksum(path, bytes, why);
    if (checksum == ChecksumResult::Mismatch || checksum == ChecksumResult::Malformed)
      return false;
    return loadBytes(bytes, path, options, why);
  }

  bool loadBytes(const std::string& bytes, const std::string& path, const EngineOptions& options,
                 std::string* why) {
    if (!parseQdqModel(bytes, path, &graph_, why))
      return false;
    if (options.threads < 1) {
      *why = path + ": threads must be >= 1 (got " + std::to_string(options.threads) + ")";
      return false;
    }
    const Backend kind = options.backend == Backend::Auto ? resolveAutoBackend() : options.backend;
    switch (kind) {
      case Backend::Auto:
      case Backend::XnnpackInt8:
        backend_ = createXnnpackInt8Backend(graph_, options.threads, options.planMemory, why);
        break;
      case Backend::XnnpackFp32:
        backend_ = createXnnpackFp32Backend(graph_, options.threads, options.planMemory, why);
        break;
      case Backend::OpenCvFp32:
        backend_ = createOpenCvBackend(bytes, graph_, options.threads, why);
        break;
      case Backend::DnnlInt8:
        backend_ = createDnnlInt8Backend(graph_, options.threads, options.planMemory, why);
        break;
    }
    if (!backend_)
      return false;
    backendKind_ = kind;
    normalization_ = options.normalization.value_or(graph_.normalization);
    inputShape_ = graph_.tensors[static_cast<std::size_t>(graph_.inputTensor)].shape;
    buildInputTable(options.imageOrder);
    totalMacs_ = 0;
    for (const auto& layer : backend_->layers())
      totalMacs_ += layer.macs;
    return true;
  }

  // Per model channel c: the image channel it reads and the 256-entry table.
  void buildInputTable(ChannelOrder imageOrder) {
    const auto& quant = graph_.tensors[static_cast<std::size_t>(graph_.inputTensor)].quant;
    for (std::size_t c = 0; c < 3; ++c) {
      source_[c] = imageOrder == normalization_.modelOrder ? c : 2 - c;
      for (std::size_t v = 0; v < 256; ++v) {
        const float x = (static_cast<float>(v) - normalization_.mean[c]) * normalization_.scale[c];
        floatTable_[c][v] = x;
        const float q = std::nearbyint(x / quant.scale) + static_cast<float>(quant.zeroPoint);
        int8Table_[c][v] = static_cast<std::int8_t>(std::clamp(q, -128.0F, 127.0F));
      }
    }
  }

  RunStatus run(const ImageView& image) {
    if (!backend_)
      return RunStatus::NotLoaded;
    const int w = inputShape_.w;
    const int h = inputShape_.h;
    if (image.data == nullptr || image.width != w || image.height != h ||
        image.strideBytes < static_cast<std::size_t>(3 * w)) {
      return RunStatus::WrongImageSize;
    }
    const std::size_t s0 = source_[0];
    const std::size_t s1 = source_[1];
    const std::size_t s2 = source_[2];
    const auto width = static_cast<std::size_t>(w);
    const auto height = static_cast<std::size_t>(h);
    switch (backend_->inputLayout()) {
      case InputLayout::Int8Nhwc: {
        auto* out = static_cast<std::int8_t*>(backend_->inputData());
        for (std::size_t y = 0; y < height; ++y) {
          const std::uint8_t* row = image.data + y * image.strideBytes;
          std::int8_t* dst = out + y * width * 3;
          for (std::size_t x = 0; x < width; ++x) {
            const std::uint8_t* px = row + 3 * x;
            dst[3 * x] = int8Table_[0][px[s0]];
            dst[3 * x + 1] = int8Table_[1][px[s1]];
            dst[3 * x + 2] = int8Table_[2][px[s2]];
          }
        }
        break;
      }
      case InputLayout::FloatNhwc: {
        auto* out = static_cast<float*>(backend_->inputData());
        for (std::size_t y = 0; y < height; ++y) {
          const std::uint8_t* row = image.data + y * image.strideBytes;
          float* dst = out + y * width * 3;
          for (std::size_t x = 0; x < width; ++x) {
            const std::uint8_t* px = row + 3 * x;
            dst[3 * x] = floatTable_[0][px[s0]];
            dst[3 * x + 1] = floatTable_[1][px[s1]];
            dst[3 * x + 2] = floatTable_[2][px[s2]];
          }
        }
        break;
      }
      case InputLayout::FloatNchw: {
        auto* out = static_cast<float*>(backend_->inputData());
        const std::size_t plane = width * height;
        for (std::size_t y = 0; y < height; ++y) {
          const std::uint8_t* row = image.data + y * image.strideBytes;
          float* dst = out + y * width;
          for (std::size_t x = 0; x < width; ++x) {
            const std::uint8_t* px = row + 3 * x;
            dst[x] = floatTable_[0][px[s0]];
            dst[plane + x] = floatTable_[1][px[s1]];
            dst[2 * plane + x] = floatTable_[2][px[s2]];
          }
        }
        break;
      }
    }
    return backend_->run() ? RunStatus::Ok : RunStatus::BackendFailure;
  }

  QdqGraph graph_;
  std::unique_ptr<InferenceBackend> backend_;
  Backend backendKind_ = Backend::XnnpackInt8;
  InputNormalization normalization_;
  TensorShape inputShape_;
  std::uint64_t totalMacs_ = 0;
  std::array<std::size_t, 3> source_{0, 1, 2};
  std::array<std::array<std::int8_t, 256>, 3> int8Table_{};
  std::array<std::array<float, 256>, 3> floatTable_{};
};

Engine::Engine() : impl_(std::make_unique<Impl>()) {}
Engine::~Engine() = default;
Engine::Engine(Engine&&) noexcept = default;
Engine& Engine::operator=(Engine&&) noexcept = default;

bool Engine::load(const std::string& onnxPath, const EngineOptions& options, std::string* why) {
  std::string ignored;
  std::string& message = why != nullptr ? *why : ignored;
  auto fresh = std::make_unique<Impl>();
  if (!fresh->load(onnxPath, options, &message)) {
    impl_ = std::make_unique<Impl>();
    return false;
  }
  impl_ = std::move(fresh);
  return true;
}

bool Engine::loadFromMemory(const std::string& onnxBytes, const std::string& name,
                            const EngineOptions& options, std::string* why) {
  std::string ignored;
  std::string& message = why != nullptr ? *why : ignored;
  auto fresh = std::make_unique<Impl>();
  if (!fresh->loadBytes(onnxBytes, name, options, &message)) {
    impl_ = std::make_unique<Impl>();
    return false;
  }
  impl_ = std::move(fresh);
  return true;
}

bool Engine::loaded() const {
  return impl_ && impl_->backend_ != nullptr;
}

TensorShape Engine::inputShape() const {
  return impl_ ? impl_->inputShape_ : TensorShape{};
}

const InputNormalization& Engine::normalization() const {
  static const InputNormalization kDefault;
  return impl_ ? impl_->normalization_ : kDefault;
}

Backend Engine::backend() const {
  return impl_ ? impl_->backendKind_ : Backend::XnnpackInt8;
}

const std::vector<LayerInfo>& Engine::layers() const {
  static const std::vector<LayerInfo> kNone;
  return loaded() ? impl_->backend_->layers() : kNone;
}

std::uint64_t Engine::totalMacs() const {
  return impl_ ? impl_->totalMacs_ : 0;
}

ActivationMemory Engine::activationMemory() const {
  return loaded() ? impl_->backend_->activationMemory() : ActivationMemory{};
}

RunStatus Engine::run(const ImageView& image) {
  if (!impl_)
    return RunStatus::NotLoaded;
  return impl_->run(image);
}

std::size_t Engine::outputCount() const {
  return loaded() ? impl_->backend_->outputs().size() : 0;
}

const OutputTensor& Engine::output(std::size_t index) const {
  return impl_->backend_->outputs().at(index);
}

}  // namespace vp::inference
