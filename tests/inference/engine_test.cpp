// Tests of inference/engine on the committed QDQ fixture models (tests/fixtures/models) and
// on variants of them edited here through ONNX's protobuf classes (bad models for the load
// errors, op swaps for the coverage table).
#include <gtest/gtest.h>
#include <onnx/onnx_pb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "inference/dnnl_int8.hpp"
#include "inference/engine.hpp"

namespace fs = std::filesystem;
using vp::inference::Backend;
using vp::inference::ChannelOrder;
using vp::inference::Engine;
using vp::inference::EngineOptions;
using vp::inference::ImageView;
using vp::inference::RunStatus;

namespace {

const fs::path kModelDir = fs::path(VP_FIXTURE_DIR) / "models";

// Bounds on ||a - b||_2 / ||b||_2 per output (b = OpenCV DNN float reference).
// The int8 bound is the models' own quantization error on these images (the engine's
// arithmetic is checked tighter against the generator's fake-quant reference below).
constexpr double kInt8RelativeError = 0.08;
constexpr double kFp32RelativeError = 1e-4;

std::vector<std::string> fixtureModels() {
  std::vector<std::string> names;
  if (!fs::exists(kModelDir))
    return names;
  for (const auto& entry : fs::directory_iterator(kModelDir)) {
    if (entry.path().extension() == ".onnx")
      names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

fs::path tempDir() {
  static const fs::path dir = [] {
    fs::path d =
        fs::temp_directory_path() / ("vp_inference_test_" + std::to_string(std::random_device{}()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

// Removes the temporary models when the test program ends.
class TempDirCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(tempDir(), ignored);
  }
};
[[maybe_unused]] auto* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new TempDirCleanup);  // gtest owns it

onnx::ModelProto readModel(const fs::path& path) {
  onnx::ModelProto model;
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(model.ParseFromIstream(&in)) << path;
  return model;
}

fs::path writeModel(const onnx::ModelProto& model, const std::string& name) {
  const fs::path path = tempDir() / name;
  std::ofstream out(path, std::ios::binary);
  model.SerializeToOstream(&out);
  return path;
}

struct Image {
  int width = 0;
  int height = 0;
  std::size_t stride = 0;
  std::vector<std::uint8_t> pixels;
  ImageView view() const { return ImageView{pixels.data(), width, height, stride}; }
};

// Smooth random colour gradients and blobs plus noise: not calibration data.
Image randomImage(int width, int height, std::uint32_t seed, std::size_t padBytes = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0F, 1.0F);
  std::normal_distribution<float> noise(0.0F, 12.0F);
  Image img;
  img.width = width;
  img.height = height;
  img.stride = static_cast<std::size_t>(3 * width) + padBytes;
  img.pixels.assign(img.stride * static_cast<std::size_t>(height), 0);
  std::array<float, 3> base{};
  std::array<float, 3> gx{};
  std::array<float, 3> gy{};
  for (int c = 0; c < 3; ++c) {
    base[static_cast<std::size_t>(c)] = 40.0F + 150.0F * u(rng);
    gx[static_cast<std::size_t>(c)] = (u(rng) - 0.5F) * 120.0F;
    gy[static_cast<std::size_t>(c)] = (u(rng) - 0.5F) * 120.0F;
  }
  const float bx = u(rng) * static_cast<float>(width);
  const float by = u(rng) * static_cast<float>(height);
  const float br = (0.1F + 0.3F * u(rng)) * static_cast<float>(std::min(width, height));
  const float bAmp = (u(rng) - 0.5F) * 200.0F;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float fx = static_cast<float>(x) / static_cast<float>(width) - 0.5F;
      const float fy = static_cast<float>(y) / static_cast<float>(height) - 0.5F;
      const float dx = static_cast<float>(x) - bx;
      const float dy = static_cast<float>(y) - by;
      const float blob = bAmp * std::exp(-(dx * dx + dy * dy) / (br * br));
      for (int c = 0; c < 3; ++c) {
        const auto cc = static_cast<std::size_t>(c);
        const float v =
            base[cc] + gx[cc] * fx + gy[cc] * fy + blob * (c == 1 ? 0.5F : 1.0F) + noise(rng);
        img.pixels[static_cast<std::size_t>(y) * img.stride + static_cast<std::size_t>(3 * x + c)] =
            static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      }
    }
  }
  return img;
}

std::unique_ptr<Engine> loadEngine(const fs::path& path, Backend backend, int threads = 1,
                                   ChannelOrder order = ChannelOrder::Bgr) {
  auto engine = std::make_unique<Engine>();
  EngineOptions options;
  options.backend = backend;
  options.threads = threads;
  options.imageOrder = order;
  std::string why;
  EXPECT_TRUE(engine->load(path.string(), options, &why)) << why;
  return engine;
}

std::string loadError(const fs::path& path, Backend backend = Backend::XnnpackInt8) {
  Engine engine;
  EngineOptions options;
  options.backend = backend;
  std::string why;
  EXPECT_FALSE(engine.load(path.string(), options, &why)) << path;
  EXPECT_FALSE(engine.loaded());
  std::printf("  load error: %s\n", why.c_str());
  return why;
}

std::vector<std::vector<float>> runOutputs(Engine& engine, const Image& img) {
  EXPECT_EQ(engine.run(img.view()), RunStatus::Ok);
  std::vector<std::vector<float>> outs;
  for (std::size_t i = 0; i < engine.outputCount(); ++i) {
    const auto& o = engine.output(i);
    outs.emplace_back(o.data, o.data + o.shape.elements());
  }
  return outs;
}

double relativeError(const std::vector<float>& a, const std::vector<float>& b) {
  double num = 0.0;
  double den = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
    num += d * d;
    den += static_cast<double>(b[i]) * static_cast<double>(b[i]);
  }
  return std::sqrt(num) / std::max(std::sqrt(den), 1e-12);
}

// ---- protobuf editing helpers ------------------------------------------------------------

onnx::NodeProto* findNode(onnx::ModelProto& model, const std::string& opType, int nth = 0) {
  for (auto& node : *model.mutable_graph()->mutable_node()) {
    if (node.op_type() == opType && nth-- == 0)
      return &node;
  }
  return nullptr;
}

onnx::NodeProto* producerOf(onnx::ModelProto& model, const std::string& value) {
  for (auto& node : *model.mutable_graph()->mutable_node()) {
    for (const auto& out : node.output()) {
      if (out == value)
        return &node;
    }
  }
  return nullptr;
}

onnx::TensorProto* initializer(onnx::ModelProto& model, const std::string& name) {
  for (auto& init : *model.mutable_graph()->mutable_initializer()) {
    if (init.name() == name)
      return &init;
  }
  return nullptr;
}

void addScalarInitializers(onnx::ModelProto& model, const std::string& prefix, float scale,
                           int zeroPoint) {
  auto* s = model.mutable_graph()->add_initializer();
  s->set_name(prefix + "_scale");
  s->set_data_type(onnx::TensorProto_DataType_FLOAT);
  s->add_float_data(scale);
  auto* z = model.mutable_graph()->add_initializer();
  z->set_name(prefix + "_zp");
  z->set_data_type(onnx::TensorProto_DataType_INT8);
  z->add_int32_data(zeroPoint);
}

// Gives the activation QuantizeLinear -> DequantizeLinear pair behind `floatValue` new params.
void setActivationQuant(onnx::ModelProto& model, const std::string& floatValue, float scale,
                        int zeroPoint) {
  const std::string prefix = "edited_" + floatValue;
  addScalarInitializers(model, prefix, scale, zeroPoint);
  for (auto& node : *model.mutable_graph()->mutable_node()) {
    if (node.op_type() == "QuantizeLinear" && node.input(0) == floatValue) {
      node.set_input(1, prefix + "_scale");
      node.set_input(2, prefix + "_zp");
      for (auto& dq : *model.mutable_graph()->mutable_node()) {
        if (dq.op_type() == "DequantizeLinear" && dq.input(0) == node.output(0)) {
          dq.set_input(1, prefix + "_scale");
          dq.set_input(2, prefix + "_zp");
        }
      }
    }
  }
}

// The dequantized value that follows the first `opType` node's output through its Q/DQ pair
// (empty when there is none).
std::string dequantizedOutputOf(onnx::ModelProto& model, const std::string& opType) {
  const onnx::NodeProto* op = findNode(model, opType);
  if (op == nullptr) {
    return {};
  }
  for (const auto& q : model.graph().node()) {
    if (q.op_type() != "QuantizeLinear" || q.input(0) != op->output(0)) {
      continue;
    }
    for (const auto& dq : model.graph().node()) {
      if (dq.op_type() == "DequantizeLinear" && dq.input(0) == q.output(0)) {
        return dq.output(0);
      }
    }
  }
  return {};
}

// Inserts `op` (+ Q/DQ with the given params, or the input's when scale <= 0) after the
// dequantized activation `value`, rewiring its consumers.
void insertActivation(onnx::ModelProto& model, const std::string& value, const std::string& op,
                      float scale, int zeroPoint) {
  auto* dq = producerOf(model, value);
  ASSERT_NE(dq, nullptr);
  std::string scaleName = dq->input(1);
  std::string zpName = dq->input(2);
  if (scale > 0.0F) {
    addScalarInitializers(model, "ins_" + value, scale, zeroPoint);
    scaleName = "ins_" + value + "_scale";
    zpName = "ins_" + value + "_zp";
  }
  const std::string y = value + "_" + op;
  for (auto& node : *model.mutable_graph()->mutable_node()) {
    for (auto& in : *node.mutable_input()) {
      if (in == value)
        in = y + "_dq";
    }
  }
  auto* graph = model.mutable_graph();
  auto* act = graph->add_node();
  act->set_op_type(op);
  act->set_name("inserted_" + op);
  act->add_input(value);
  act->add_output(y);
  auto* q = graph->add_node();
  q->set_op_type("QuantizeLinear");
  q->set_name("inserted_q");
  q->add_input(y);
  q->add_input(scaleName);
  q->add_input(zpName);
  q->add_output(y + "_q");
  auto* d = graph->add_node();
  d->set_op_type("DequantizeLinear");
  d->set_name("inserted_dq");
  d->add_input(y + "_q");
  d->add_input(scaleName);
  d->add_input(zpName);
  d->add_output(y + "_dq");
  // Keep the node list topologically sorted: move the three nodes behind the producer.
  auto* nodes = graph->mutable_node();
  int producerIndex = 0;
  for (int i = 0; i < nodes->size(); ++i) {
    if (nodes->Get(i).output(0) == value)
      producerIndex = i;
  }
  for (int k = 0; k < 3; ++k) {
    for (int i = nodes->size() - 1; i > producerIndex + 1 + k; --i)
      nodes->SwapElements(i, i - 1);
  }
}

// Variants of the fixtures for operators the fixtures do not contain.
struct Variant {
  std::string name;
  std::function<void(onnx::ModelProto&)> edit;
  std::string base;
  double int8Bound = kInt8RelativeError;
};

std::vector<Variant> variants() {
  return {
      {"nearest_resize",
       [](onnx::ModelProto& m) {
         auto* r = findNode(m, "Resize");
         ASSERT_NE(r, nullptr);
         r->clear_attribute();
         auto* a = r->add_attribute();
         a->set_name("mode");
         a->set_type(onnx::AttributeProto_AttributeType_STRING);
         a->set_s("nearest");
         a = r->add_attribute();
         a->set_name("coordinate_transformation_mode");
         a->set_type(onnx::AttributeProto_AttributeType_STRING);
         a->set_s("asymmetric");
         a = r->add_attribute();
         a->set_name("nearest_mode");
         a->set_type(onnx::AttributeProto_AttributeType_STRING);
         a->set_s("floor");
       },
       "fpn_heads"},
      {"tanh",
       [](onnx::ModelProto& m) {
         // The objectness head (a graph output): Sigmoid -> Tanh, output range [-1, 1].
         auto* s = findNode(m, "Sigmoid");
         ASSERT_NE(s, nullptr);
         s->set_op_type("Tanh");
         setActivationQuant(m, s->output(0), 2.0F / 255.0F, 0);
       },
       "fpn_heads",
       // Hand-picked output params, tanh ~4x steeper than sigmoid and outputs near 0 (small
       // norm): the relative error of this edited head is larger than the fixtures'.
       0.15},
      {"xnn_sigmoid",
       [](onnx::ModelProto& m) {
         auto* s = findNode(m, "Sigmoid");
         ASSERT_NE(s, nullptr);
         setActivationQuant(m, s->output(0), 1.0F / 256.0F, -128);
       },
       "conv_blocks"},
      {"standalone_relu",
       [](onnx::ModelProto& m) {
         const std::string value = dequantizedOutputOf(m, "MaxPool");
         ASSERT_FALSE(value.empty()) << "no MaxPool output Q/DQ";
         insertActivation(m, value, "Relu", 0.0F, 0);
       },
       "fpn_heads"},
      {"requantizing_relu",
       [](onnx::ModelProto& m) {
         const std::string value = dequantizedOutputOf(m, "GlobalAveragePool");
         ASSERT_FALSE(value.empty()) << "no GlobalAveragePool output Q/DQ";
         insertActivation(m, value, "Relu", 0.05F, -100);
       },
       "classifier"},
  };
}

// Fixtures plus the edited variants (paths of model files) with their int8 error bounds.
std::vector<std::pair<fs::path, double>> modelsWithBounds() {
  std::vector<std::pair<fs::path, double>> models;
  for (const auto& name : fixtureModels()) {
    models.emplace_back(kModelDir / (name + ".onnx"), kInt8RelativeError);
  }
  for (const auto& v : variants()) {
    const fs::path base = kModelDir / (v.base + ".onnx");
    if (!fs::exists(base))
      continue;
    auto model = readModel(base);
    v.edit(model);
    models.emplace_back(writeModel(model, v.name + ".onnx"), v.int8Bound);
  }
  return models;
}

std::vector<fs::path> allModels() {
  std::vector<fs::path> paths;
  for (const auto& [path, bound] : modelsWithBounds())
    paths.push_back(path);
  return paths;
}

}  // namespace

TEST(InferenceEngine, FixturesArePresent) {
  const auto names = fixtureModels();
  ASSERT_GE(names.size(), 3U) << "no fixture models in " << kModelDir;
}

TEST(InferenceEngine, LoadsEveryFixtureOnEveryBackend) {
  for (const auto& name : fixtureModels()) {
    for (const Backend b : {Backend::XnnpackInt8, Backend::XnnpackFp32, Backend::OpenCvFp32}) {
      auto engine = loadEngine(kModelDir / (name + ".onnx"), b);
      ASSERT_TRUE(engine->loaded()) << name;
      EXPECT_EQ(engine->backend(), b);
      EXPECT_EQ(engine->inputShape().c, 3);
      EXPECT_GT(engine->outputCount(), 0U);
      EXPECT_GT(engine->totalMacs(), 0U);
      EXPECT_FALSE(engine->layers().empty());
      std::uint64_t sum = 0;
      for (const auto& l : engine->layers())
        sum += l.macs;
      EXPECT_EQ(sum, engine->totalMacs());
    }
  }
}

// int8 and XNNPACK float against the OpenCV float reference on fresh random images.
TEST(InferenceEngine, MatchesOpenCvReference) {
  for (const auto& [path, int8Bound] : modelsWithBounds()) {
    auto reference = loadEngine(path, Backend::OpenCvFp32);
    auto int8 = loadEngine(path, Backend::XnnpackInt8);
    auto fp32 = loadEngine(path, Backend::XnnpackFp32);
    ASSERT_TRUE(reference->loaded() && int8->loaded() && fp32->loaded()) << path;
    const auto shape = reference->inputShape();
    std::map<std::string, std::pair<double, double>> worst;
    for (std::uint32_t seed = 100; seed < 106; ++seed) {
      const Image img = randomImage(shape.w, shape.h, seed);
      const auto ref = runOutputs(*reference, img);
      const auto q = runOutputs(*int8, img);
      const auto f = runOutputs(*fp32, img);
      for (std::size_t o = 0; o < ref.size(); ++o) {
        const std::string key = reference->output(o).name;
        const double eq = relativeError(q[o], ref[o]);
        const double ef = relativeError(f[o], ref[o]);
        auto& w = worst[key];
        w.first = std::max(w.first, eq);
        w.second = std::max(w.second, ef);
        EXPECT_LE(eq, int8Bound) << path.filename() << " " << key << " seed " << seed;
        EXPECT_LE(ef, kFp32RelativeError) << path.filename() << " " << key << " seed " << seed;
      }
    }
    for (const auto& [key, w] : worst) {
      std::printf("  %-22s %-14s worst rel. error vs OpenCV over 6 images: int8 %.4f  fp32 %.2e\n",
                  path.filename().string().c_str(), key.c_str(), w.first, w.second);
    }
  }
}

// The fixtures' own reference outputs (QDQ and float graphs evaluated by the generator).
TEST(InferenceEngine, MatchesGeneratorReferenceOutputs) {
  for (const auto& name : fixtureModels()) {
    const fs::path png = kModelDir / (name + "_input.png");
    if (!fs::exists(png))
      continue;
    const cv::Mat bgr = cv::imread(png.string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(bgr.empty()) << png;
    const ImageView view{bgr.data, bgr.cols, bgr.rows, bgr.step[0]};
    for (const Backend b :
         {Backend::XnnpackInt8, Backend::DnnlInt8, Backend::XnnpackFp32, Backend::OpenCvFp32}) {
      if (b == Backend::DnnlInt8 && !vp::inference::dnnlInt8Available())
        continue;  // builds without oneDNN (dnnl_int8_test.cpp says so with a skip)
      const bool int8 = b == Backend::XnnpackInt8 || b == Backend::DnnlInt8;
      const fs::path bin = kModelDir / (name + (int8 ? "_ref_int8.bin" : "_ref_fp32.bin"));
      std::ifstream in(bin, std::ios::binary);
      ASSERT_TRUE(in) << bin;
      std::vector<float> expected((fs::file_size(bin) + 3) / 4);
      in.read(reinterpret_cast<char*>(expected.data()),
              static_cast<std::streamsize>(expected.size() * 4));
      auto engine = loadEngine(kModelDir / (name + ".onnx"), b);
      ASSERT_EQ(engine->run(view), RunStatus::Ok);
      std::size_t offset = 0;
      for (std::size_t o = 0; o < engine->outputCount(); ++o) {
        const auto& out = engine->output(o);
        const std::size_t n = out.shape.elements();
        ASSERT_LE(offset + n, expected.size());
        const std::vector<float> got(out.data, out.data + n);
        const std::vector<float> want(expected.begin() + static_cast<std::ptrdiff_t>(offset),
                                      expected.begin() + static_cast<std::ptrdiff_t>(offset + n));
        double maxAbs = 0.0;
        double meanAbs = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
          const double d = std::abs(static_cast<double>(got[i] - want[i]));
          maxAbs = std::max(maxAbs, d);
          meanAbs += d / static_cast<double>(n);
        }
        const double rel = relativeError(got, want);
        const double step = static_cast<double>(out.scale);
        std::printf(
            "  %-12s %-7s %-13s vs generator: max |diff| %.5f (%.2f steps, mean %.3f) rel %.2e\n",
            name.c_str(), vp::inference::toString(b), out.name.c_str(), maxAbs,
            int8 ? maxAbs / step : 0.0, int8 ? meanAbs / step : 0.0, rel);
        if (int8) {
          // Bias/requantization rounding differ (one step in front of a steep Sigmoid is
          // several steps behind it, and 1-step flips add up over depth): at most 5 steps,
          // at most one step on average.
          EXPECT_LE(maxAbs, 5.0 * step + 1e-6) << name << out.name;
          EXPECT_LE(meanAbs, 1.0 * step) << name << out.name;
        } else {
          EXPECT_LE(rel, kFp32RelativeError) << name << out.name;
        }
        offset += n;
      }
      EXPECT_EQ(offset, expected.size());
    }
  }
}

// Dims whose product overflows 64 bits (a fuzzing finding): refused with a message, computed
// without overflow.
TEST(InferenceEngine, HostileTensorDimsAreRefused) {
  onnx::ModelProto model = readModel(kModelDir / "classifier.onnx");
  onnx::TensorProto* scale = nullptr;
  for (auto& tensor : *model.mutable_graph()->mutable_initializer()) {
    if (tensor.data_type() == onnx::TensorProto::FLOAT && tensor.dims_size() == 1 &&
        tensor.dims(0) > 1) {
      scale = &tensor;
      break;
    }
  }
  ASSERT_NE(scale, nullptr);
  const std::string name = scale->name();
  scale->clear_dims();
  scale->add_dims(2222574027840000);
  scale->add_dims(4567);
  Engine engine;
  std::string why;
  EXPECT_FALSE(engine.load(writeModel(model, "hostile_dims.onnx").string(), {}, &why));
  EXPECT_NE(why.find("'" + name + "' has invalid dims (negative, or over 2^31 values)"),
            std::string::npos)
      << why;
  scale->set_dims(1, -3);
  EXPECT_FALSE(engine.load(writeModel(model, "negative_dims.onnx").string(), {}, &why));
  EXPECT_NE(why.find("has invalid dims"), std::string::npos) << why;
}

// A NaN bias (a fuzzing finding: its int32 quantization was undefined) is a load error.
TEST(InferenceEngine, NonFiniteBiasIsRefused) {
  onnx::ModelProto model = readModel(kModelDir / "classifier.onnx");
  std::string biasName;
  for (const auto& node : model.graph().node()) {
    if (node.op_type() == "Conv" && node.input_size() > 2) {
      biasName = node.input(2);
      break;
    }
  }
  onnx::TensorProto* bias = nullptr;
  for (auto& tensor : *model.mutable_graph()->mutable_initializer()) {
    if (tensor.name() == biasName && tensor.data_type() == onnx::TensorProto::FLOAT) {
      bias = &tensor;
    }
  }
  ASSERT_NE(bias, nullptr) << "no float Conv bias in classifier.onnx";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (bias->has_raw_data()) {
    std::memcpy(bias->mutable_raw_data()->data() + sizeof(float), &nan, sizeof(float));
  } else {
    bias->set_float_data(1, nan);
  }
  for (const Backend backend : {Backend::XnnpackInt8, Backend::XnnpackFp32}) {
    Engine engine;
    std::string why;
    EngineOptions options;
    options.backend = backend;
    EXPECT_FALSE(engine.load(writeModel(model, "nan_bias.onnx").string(), options, &why));
    EXPECT_NE(why.find("bias '" + biasName + "' of output channel 1 is not finite"),
              std::string::npos)
        << why;
  }
}

TEST(InferenceEngine, NoHeapAllocationPerRun) {
  std::printf("  counting %s\n", vp::test::AllocationCounter::countsMalloc()
                                     ? "the malloc family (interposed)"
                                     : "operator new only (AddressSanitizer build)");
  {
    vp::test::AllocationCounter sanity;
    void* (*volatile allocate)(std::size_t) = std::malloc;
    void* p = allocate(64);
    std::free(p);
    auto* volatile object = new std::string(100, 'x');
    delete object;
    sanity.stop();
    ASSERT_GE(sanity.count(), 1U) << "the allocation counter sees nothing";
  }
  const auto models = allModels();
  for (std::size_t m = 0; m < models.size(); ++m) {
    const auto& path = models[m];
    for (const Backend b : {Backend::XnnpackInt8, Backend::XnnpackFp32}) {
      for (const int threads : {1, 2}) {
        // Two workers on every fixture; the edited variants once (their ops are the same).
        if (threads == 2 && m >= fixtureModels().size())
          continue;
        auto engine = loadEngine(path, b, threads);
        ASSERT_TRUE(engine->loaded());
        const auto s = engine->inputShape();
        const Image img = randomImage(s.w, s.h, 7, 5);
        ASSERT_EQ(engine->run(img.view()), RunStatus::Ok);  // warm-up
        ASSERT_EQ(engine->run(img.view()), RunStatus::Ok);
        vp::test::AllocationCounter counter;
        for (int i = 0; i < 3; ++i)
          engine->run(img.view());
        counter.stop();
        EXPECT_EQ(counter.count(), 0U)
            << path.filename() << " " << vp::inference::toString(b) << " threads " << threads;
      }
    }
  }
}

// The activation memory plan on every fixture and edited variant (nearest Resize with its
// scratch buffer, Tanh, tables, MaxPool, ...): the same outputs as one buffer per tensor, also
// on the second of two different images (the arena then holds the first one's values).
// The shipped models: memory_plan_test.cpp.
TEST(InferenceEngine, MemoryPlanChangesNoOutput) {
  for (const auto& path : allModels()) {
    for (const Backend b : {Backend::XnnpackInt8, Backend::XnnpackFp32}) {
      auto planned = loadEngine(path, b);
      auto separate = std::make_unique<Engine>();
      EngineOptions options;
      options.backend = b;
      options.planMemory = false;
      std::string why;
      ASSERT_TRUE(separate->load(path.string(), options, &why)) << why;
      ASSERT_TRUE(planned->loaded());
      EXPECT_TRUE(planned->activationMemory().planned);
      EXPECT_LT(planned->activationMemory().allocated_bytes,
                separate->activationMemory().allocated_bytes)
          << path.filename();
      const auto s = planned->inputShape();
      for (const std::uint32_t seed : {21U, 22U}) {
        const Image img = randomImage(s.w, s.h, seed);
        EXPECT_EQ(runOutputs(*planned, img), runOutputs(*separate, img))
            << path.filename() << " " << vp::inference::toString(b) << " image " << seed;
      }
    }
  }
}

TEST(InferenceEngine, MultiThreadedMatchesSingleThreaded) {
  for (const auto& name : fixtureModels()) {
    const fs::path path = kModelDir / (name + ".onnx");
    auto one = loadEngine(path, Backend::XnnpackInt8, 1);
    auto two = loadEngine(path, Backend::XnnpackInt8, 2);
    const auto s = one->inputShape();
    const Image img = randomImage(s.w, s.h, 11);
    EXPECT_EQ(runOutputs(*one, img), runOutputs(*two, img)) << name;
  }
}

TEST(InferenceEngine, WrongImageSizeAndNotLoaded) {
  Engine empty;
  const Image tiny = randomImage(8, 8, 1);
  EXPECT_EQ(empty.run(tiny.view()), RunStatus::NotLoaded);
  EXPECT_FALSE(empty.loaded());
  EXPECT_EQ(empty.outputCount(), 0U);

  auto engine = loadEngine(kModelDir / "fpn_heads.onnx", Backend::XnnpackInt8);
  const auto s = engine->inputShape();
  EXPECT_EQ(engine->run(randomImage(s.w - 1, s.h, 1).view()), RunStatus::WrongImageSize);
  EXPECT_EQ(engine->run(randomImage(s.h, s.w, 1).view()), RunStatus::WrongImageSize);
  Image bad = randomImage(s.w, s.h, 1);
  ImageView v = bad.view();
  v.strideBytes = static_cast<std::size_t>(3 * s.w - 1);
  EXPECT_EQ(engine->run(v), RunStatus::WrongImageSize);
  v = bad.view();
  v.data = nullptr;
  EXPECT_EQ(engine->run(v), RunStatus::WrongImageSize);
  EXPECT_EQ(engine->run(bad.view()), RunStatus::Ok);
}

// Swapping the image's channels and the option gives the same result; padded rows too.
TEST(InferenceEngine, ChannelOrderAndStride) {
  for (const auto& name : fixtureModels()) {
    const fs::path path = kModelDir / (name + ".onnx");
    for (const Backend b : {Backend::XnnpackInt8, Backend::XnnpackFp32, Backend::OpenCvFp32}) {
      auto bgrEngine = loadEngine(path, b, 1, ChannelOrder::Bgr);
      auto rgbEngine = loadEngine(path, b, 1, ChannelOrder::Rgb);
      const auto s = bgrEngine->inputShape();
      const Image bgr = randomImage(s.w, s.h, 21, 7);
      Image rgb = bgr;
      for (int y = 0; y < s.h; ++y) {
        for (int x = 0; x < s.w; ++x) {
          auto* px = &rgb.pixels[static_cast<std::size_t>(y) * rgb.stride +
                                 static_cast<std::size_t>(3 * x)];
          std::swap(px[0], px[2]);
        }
      }
      const auto a = runOutputs(*bgrEngine, bgr);
      EXPECT_EQ(a, runOutputs(*rgbEngine, rgb)) << name << " " << vp::inference::toString(b);
      Image dense = randomImage(s.w, s.h, 21, 0);
      EXPECT_EQ(a, runOutputs(*bgrEngine, dense)) << name << " stride";
      // A different image really changes the output (the test above is not vacuous).
      EXPECT_NE(a, runOutputs(*bgrEngine, randomImage(s.w, s.h, 22))) << name;
    }
  }
}

TEST(InferenceEngine, NormalizationFromMetadataAndOverride) {
  auto engine = loadEngine(kModelDir / "fpn_heads.onnx", Backend::XnnpackInt8);
  EXPECT_EQ(engine->normalization().modelOrder, ChannelOrder::Bgr);
  EXPECT_NEAR(engine->normalization().mean[0], 127.5F, 1e-4F);
  auto classifier = loadEngine(kModelDir / "classifier.onnx", Backend::XnnpackInt8);
  EXPECT_EQ(classifier->normalization().modelOrder, ChannelOrder::Rgb);
  EXPECT_NEAR(classifier->normalization().mean[2], 103.53F, 1e-3F);

  Engine overridden;
  EngineOptions options;
  vp::inference::InputNormalization norm;
  norm.modelOrder = ChannelOrder::Rgb;
  norm.mean = {10.0F, 20.0F, 30.0F};
  options.normalization = norm;
  std::string why;
  ASSERT_TRUE(overridden.load((kModelDir / "fpn_heads.onnx").string(), options, &why)) << why;
  EXPECT_EQ(overridden.normalization().modelOrder, ChannelOrder::Rgb);
  EXPECT_EQ(overridden.normalization().mean[1], 20.0F);
}

TEST(InferenceEngine, Int8OutputsExposeQuantizedTensors) {
  auto engine = loadEngine(kModelDir / "conv_blocks.onnx", Backend::XnnpackInt8);
  const auto s = engine->inputShape();
  ASSERT_EQ(engine->run(randomImage(s.w, s.h, 3).view()), RunStatus::Ok);
  const auto& out = engine->output(0);
  ASSERT_NE(out.quantized, nullptr);
  for (std::size_t i = 0; i < out.shape.elements(); ++i) {
    EXPECT_EQ(out.data[i], static_cast<float>(out.quantized[i] - out.zeroPoint) * out.scale);
  }
  auto fp32 = loadEngine(kModelDir / "conv_blocks.onnx", Backend::XnnpackFp32);
  EXPECT_EQ(fp32->output(0).quantized, nullptr);
}

// ---- load errors ---------------------------------------------------------------------------

TEST(InferenceEngineErrors, MissingFile) {
  const std::string why = loadError(tempDir() / "does_not_exist.onnx");
  EXPECT_NE(why.find("does_not_exist.onnx"), std::string::npos);
}

TEST(InferenceEngineErrors, TruncatedFile) {
  const fs::path src = kModelDir / "conv_blocks.onnx";
  const fs::path dst = tempDir() / "truncated.onnx";
  fs::copy_file(src, dst, fs::copy_options::overwrite_existing);
  fs::resize_file(dst, fs::file_size(src) / 2);
  const std::string why = loadError(dst);
  EXPECT_NE(why.find("truncated.onnx"), std::string::npos);
  fs::resize_file(dst, 0);
  EXPECT_NE(loadError(dst).find("not a valid ONNX model"), std::string::npos);
}

TEST(InferenceEngineErrors, CorruptBytes) {
  const fs::path src = kModelDir / "conv_blocks.onnx";
  std::ifstream in(src, std::ios::binary);
  std::ostringstream buffer;
  buffer << in.rdbuf();
  std::string bytes = buffer.str();
  for (std::size_t i = 0; i < 64; ++i)
    bytes[i * 7 % 200] = static_cast<char>(0xff);
  const fs::path dst = tempDir() / "corrupt.onnx";
  std::ofstream(dst, std::ios::binary) << bytes;
  const std::string why = loadError(dst);
  EXPECT_NE(why.find("corrupt.onnx"), std::string::npos);
  EXPECT_NE(why.find("not a valid ONNX model"), std::string::npos);
}

TEST(InferenceEngineErrors, UnsupportedOperator) {
  auto model = readModel(kModelDir / "conv_blocks.onnx");
  auto* node = findNode(model, "Sigmoid");
  ASSERT_NE(node, nullptr);
  node->set_op_type("Softplus");
  const std::string nodeName = node->name();
  const auto path = writeModel(model, "unsupported_op.onnx");
  for (const Backend b : {Backend::XnnpackInt8, Backend::OpenCvFp32}) {
    const std::string why = loadError(path, b);
    EXPECT_NE(why.find("unsupported_op.onnx: node '" + nodeName + "' (Softplus)"),
              std::string::npos);
    EXPECT_NE(why.find("unsupported operator"), std::string::npos);
  }
}

TEST(InferenceEngineErrors, ConcatWithMismatchedScales) {
  auto model = readModel(kModelDir / "fpn_heads.onnx");
  auto* concat = findNode(model, "Concat");
  ASSERT_NE(concat, nullptr);
  const std::string concatName = concat->name();
  // Give the first input's Q/DQ pair its own scale.
  auto* dq = producerOf(model, concat->input(0));
  ASSERT_NE(dq, nullptr);
  auto* q = producerOf(model, dq->input(0));
  ASSERT_NE(q, nullptr);
  const float scale = initializer(model, dq->input(1))->float_data_size() > 0
                          ? initializer(model, dq->input(1))->float_data(0)
                          : 0.05F;
  setActivationQuant(model, q->input(0), scale * 1.5F + 0.01F, 0);
  const std::string why = loadError(writeModel(model, "concat_scales.onnx"));
  EXPECT_NE(why.find("concat_scales.onnx: node '" + concatName + "' (Concat)"), std::string::npos);
  EXPECT_NE(why.find("must share the output's scale and zero point"), std::string::npos);
}

TEST(InferenceEngineErrors, MissingScale) {
  auto model = readModel(kModelDir / "conv_blocks.onnx");
  // Remove the scale initializer of the first activation QuantizeLinear after a Conv.
  auto* conv = findNode(model, "Conv");
  ASSERT_NE(conv, nullptr);
  onnx::NodeProto* q = nullptr;
  for (auto& node : *model.mutable_graph()->mutable_node()) {
    if (node.op_type() == "QuantizeLinear" && node.input(0) != "input" && q == nullptr &&
        initializer(model, node.input(0)) == nullptr) {
      q = &node;
    }
  }
  ASSERT_NE(q, nullptr);
  const std::string missing = q->input(1) + "_gone";
  q->set_input(1, missing);
  const std::string why = loadError(writeModel(model, "missing_scale.onnx"));
  EXPECT_NE(why.find("missing_scale.onnx: node '" + q->name() + "' (QuantizeLinear)"),
            std::string::npos);
  EXPECT_NE(why.find(missing), std::string::npos);

  // A scale input left empty.
  auto model2 = readModel(kModelDir / "conv_blocks.onnx");
  auto* dq = findNode(model2, "DequantizeLinear", 3);
  ASSERT_NE(dq, nullptr);
  dq->set_input(1, "");
  EXPECT_NE(loadError(writeModel(model2, "empty_scale.onnx")).find("empty_scale.onnx: node '"),
            std::string::npos);
}

TEST(InferenceEngineErrors, WeightScaleCount) {
  auto model = readModel(kModelDir / "conv_blocks.onnx");
  auto* conv = findNode(model, "Conv", 1);
  ASSERT_NE(conv, nullptr);
  auto* wdq = producerOf(model, conv->input(1));
  ASSERT_NE(wdq, nullptr);
  auto* scale = initializer(model, wdq->input(1));
  ASSERT_NE(scale, nullptr);
  const auto channels = scale->dims(0);
  // Drop the last channel's scale (and zero point).
  std::vector<float> values;
  if (scale->has_raw_data()) {
    values.resize(static_cast<std::size_t>(channels));
    std::memcpy(values.data(), scale->raw_data().data(), values.size() * 4);
  } else {
    values.assign(scale->float_data().begin(), scale->float_data().end());
  }
  scale->clear_raw_data();
  scale->clear_float_data();
  for (std::int64_t i = 0; i + 1 < channels; ++i)
    scale->add_float_data(values[static_cast<std::size_t>(i)]);
  scale->set_dims(0, channels - 1);
  const std::string why = loadError(writeModel(model, "weight_scales.onnx"));
  EXPECT_NE(why.find("weight_scales.onnx: node '" + conv->name() + "' (Conv): weight scale has " +
                     std::to_string(channels - 1) + " values, expected " +
                     std::to_string(channels) + " (output channels)"),
            std::string::npos);
}

TEST(InferenceEngineErrors, DynamicOrBatchedInput) {
  auto model = readModel(kModelDir / "classifier.onnx");
  model.mutable_graph()
      ->mutable_input(0)
      ->mutable_type()
      ->mutable_tensor_type()
      ->mutable_shape()
      ->mutable_dim(0)
      ->set_dim_param("N");
  EXPECT_NE(loadError(writeModel(model, "dynamic.onnx")).find("dynamic"), std::string::npos);
  auto batched = readModel(kModelDir / "classifier.onnx");
  batched.mutable_graph()
      ->mutable_input(0)
      ->mutable_type()
      ->mutable_tensor_type()
      ->mutable_shape()
      ->mutable_dim(0)
      ->set_dim_value(2);
  EXPECT_NE(loadError(writeModel(batched, "batched.onnx")).find("batch 2"), std::string::npos);
}

TEST(InferenceEngineErrors, OldOpset) {
  auto model = readModel(kModelDir / "classifier.onnx");
  for (auto& imp : *model.mutable_opset_import()) {
    if (imp.domain().empty())
      imp.set_version(11);
  }
  EXPECT_NE(loadError(writeModel(model, "opset11.onnx")).find("opset 11"), std::string::npos);
}

// ---- operator coverage: every kernel of docs/inference.md's table is exercised ----------

TEST(InferenceEngine, OperatorCoverageMatchesDocs) {
  std::ifstream doc(fs::path(VP_SOURCE_DIR) / "docs" / "inference.md");
  ASSERT_TRUE(doc) << "docs/inference.md";
  // Rows of the table under "## Operator coverage": | `Op` | `int8 kernel` | `fp32 kernel` | ...
  std::vector<std::array<std::string, 3>> rows;
  std::string line;
  bool inSection = false;
  while (std::getline(doc, line)) {
    if (line.rfind("## ", 0) == 0)
      inSection = line.find("Operator coverage") != std::string::npos;
    if (!inSection || line.rfind("| `", 0) != 0)
      continue;
    std::array<std::string, 3> cells;
    std::stringstream ss(line.substr(1));
    for (auto& cell : cells) {
      std::getline(ss, cell, '|');
      const auto a = cell.find('`');
      const auto b = cell.find('`', a + 1);
      cell = a == std::string::npos || b == std::string::npos ? "" : cell.substr(a + 1, b - a - 1);
    }
    rows.push_back(cells);
  }
  ASSERT_GE(rows.size(), 10U) << "coverage table not found";

  std::set<std::string> opTypes;
  std::string int8Kernels;
  std::string fp32Kernels;
  for (const auto& path : allModels()) {
    for (const Backend b : {Backend::XnnpackInt8, Backend::XnnpackFp32}) {
      auto engine = loadEngine(path, b);
      for (const auto& l : engine->layers()) {
        (b == Backend::XnnpackInt8 ? int8Kernels : fp32Kernels) += l.backendKernel + "\n";
        std::stringstream ops(l.opType);
        std::string op;
        while (std::getline(ops, op, '+'))
          opTypes.insert(op.substr(0, op.find('(')));
      }
    }
  }
  for (const auto& [op, int8Kernel, fp32Kernel] : rows) {
    EXPECT_TRUE(opTypes.count(op) != 0) << "op " << op << " not exercised by any test model";
    EXPECT_NE(int8Kernels.find(int8Kernel), std::string::npos) << op << ": " << int8Kernel;
    EXPECT_NE(fp32Kernels.find(fp32Kernel), std::string::npos) << op << ": " << fp32Kernel;
  }
}
