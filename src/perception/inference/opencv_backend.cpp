#include "inference/opencv_backend.hpp"

#include <onnx/onnx_pb.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <set>
#include <unordered_map>
#include <utility>

namespace vp::inference {
namespace {

std::size_t toSize(std::int64_t v) {
  return static_cast<std::size_t>(v);
}

// Values of a (validated) constant tensor as doubles.
std::vector<double> tensorValues(const onnx::TensorProto& t) {
  std::int64_t n = 1;
  for (const auto d : t.dims())
    n *= d;
  std::vector<double> v;
  v.reserve(toSize(n));
  const std::string& raw = t.raw_data();
  const bool hasRaw = t.has_raw_data();
  switch (t.data_type()) {
    case onnx::TensorProto_DataType_FLOAT:
      if (hasRaw) {
        for (std::size_t i = 0; i + 4 <= raw.size(); i += 4) {
          float x = 0.0F;
          std::memcpy(&x, raw.data() + i, 4);
          v.push_back(x);
        }
      } else {
        for (const float x : t.float_data())
          v.push_back(x);
      }
      break;
    case onnx::TensorProto_DataType_INT8:
    case onnx::TensorProto_DataType_UINT8:
      if (hasRaw) {
        for (const char c : raw) {
          v.push_back(t.data_type() == onnx::TensorProto_DataType_INT8
                          ? static_cast<double>(static_cast<std::int8_t>(c))
                          : static_cast<double>(static_cast<std::uint8_t>(c)));
        }
      } else {
        for (const auto x : t.int32_data())
          v.push_back(x);
      }
      break;
    case onnx::TensorProto_DataType_INT32:
      if (hasRaw) {
        for (std::size_t i = 0; i + 4 <= raw.size(); i += 4) {
          std::int32_t x = 0;
          std::memcpy(&x, raw.data() + i, 4);
          v.push_back(x);
        }
      } else {
        for (const auto x : t.int32_data())
          v.push_back(x);
      }
      break;
    default:
      break;
  }
  return v;
}

class OpenCvBackend final : public InferenceBackend {
 public:
  bool build(const std::string& bytes, const QdqGraph& graph, int threads, std::string* why) {
    onnx::ModelProto model;
    if (!model.ParseFromString(bytes)) {
      *why = graph.file +
             ": not a valid ONNX model (protobuf parse failed; file truncated or "
             "corrupt?)";
      return false;
    }
    foldQdq(model, graph);
    std::string floatModel;
    if (!model.SerializeToString(&floatModel)) {
      *why = graph.file + ": could not serialize the float model for OpenCV";
      return false;
    }
    const auto& in = graph.tensors[static_cast<std::size_t>(graph.inputTensor)].shape;
    try {
      if (threads >= 1)
        cv::setNumThreads(threads);
      net_ = cv::dnn::readNetFromONNX(floatModel.data(), floatModel.size());
      net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
      net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
      const int dims[4] = {1, 3, in.h, in.w};
      blob_.create(4, dims, CV_32F);
      blob_.setTo(0.0F);
      for (const auto& out : graph.outputs)
        outNames_.push_back(out.name);
      net_.setInput(blob_);
      net_.forward(results_, outNames_);
    } catch (const cv::Exception& e) {
      *why = graph.file + ": OpenCV DNN rejected the float model: " + e.what();
      return false;
    }
    outputData_.reserve(graph.outputs.size());
    for (std::size_t i = 0; i < graph.outputs.size(); ++i) {
      const auto& t = graph.tensors[static_cast<std::size_t>(graph.outputs[i].tensor)];
      if (results_[i].total() != t.shape.elements()) {
        *why = graph.file + ": OpenCV DNN output '" + graph.outputs[i].name + "' has " +
               std::to_string(results_[i].total()) + " values, expected " +
               std::to_string(t.shape.elements());
        return false;
      }
      outputData_.emplace_back(t.shape.elements(), 0.0F);
      OutputTensor ot;
      ot.name = graph.outputs[i].name;
      ot.shape = t.shape;
      ot.data = outputData_.back().data();
      outputs_.push_back(ot);
    }
    for (const auto& node : graph.nodes) {
      layers_.push_back(
          LayerInfo{node.name, node.opType, "cv::dnn (OPENCV/CPU, float)", node.macs});
    }
    return true;
  }

  InputLayout inputLayout() const override { return InputLayout::FloatNchw; }
  void* inputData() override { return blob_.ptr<float>(); }

  bool run() override {
    try {
      net_.setInput(blob_);
      net_.forward(results_, outNames_);
    } catch (const cv::Exception&) {
      return false;
    }
    for (std::size_t i = 0; i < outputs_.size(); ++i) {
      const auto& s = outputs_[i].shape;
      const cv::Mat& m = results_[i];
      if (!m.isContinuous() || m.total() != s.elements() || m.type() != CV_32F)
        return false;
      const float* src = m.ptr<float>();
      float* dst = outputData_[i].data();
      const std::size_t hw = static_cast<std::size_t>(s.h) * static_cast<std::size_t>(s.w);
      const auto c = static_cast<std::size_t>(s.c);
      for (std::size_t ch = 0; ch < c; ++ch) {
        for (std::size_t p = 0; p < hw; ++p)
          dst[p * c + ch] = src[ch * hw + p];
      }
    }
    return true;
  }

  const std::vector<OutputTensor>& outputs() const override { return outputs_; }
  const std::vector<LayerInfo>& layers() const override { return layers_; }

 private:
  // Rewrites the QDQ model into a float one (see the header).
  static void foldQdq(onnx::ModelProto& model, const QdqGraph& qdq) {
    onnx::GraphProto* graph = model.mutable_graph();
    std::unordered_map<std::string, const onnx::TensorProto*> constants;
    for (const auto& init : graph->initializer())
      constants[init.name()] = &init;
    std::unordered_map<std::string, const onnx::NodeProto*> producer;
    for (const auto& node : graph->node()) {
      for (const auto& out : node.output())
        producer[out] = &node;
      if (node.op_type() == "Constant") {
        for (const auto& a : node.attribute()) {
          if (a.name() == "value" && a.has_t())
            constants[node.output(0)] = &a.t();
        }
      }
    }
    const auto axisOf = [](const onnx::NodeProto& node) {
      for (const auto& a : node.attribute()) {
        if (a.name() == "axis")
          return a.i();
      }
      return static_cast<std::int64_t>(1);
    };
    // Dequantized (or fake-quantized) constant of a DequantizeLinear with a constant source.
    const auto dequantize = [&](const onnx::NodeProto& dq, const onnx::TensorProto& src,
                                bool fakeQuant) {
      const auto values = tensorValues(src);
      const auto scales = tensorValues(*constants.at(dq.input(1)));
      std::vector<double> zps(scales.size(), 0.0);
      if (dq.input_size() > 2 && !dq.input(2).empty() && constants.count(dq.input(2)) != 0) {
        zps = tensorValues(*constants.at(dq.input(2)));
      }
      const auto rank = static_cast<std::int64_t>(src.dims_size());
      std::int64_t axis = axisOf(dq);
      if (axis < 0)
        axis += rank;
      std::int64_t inner = 1;
      for (std::int64_t d = axis + 1; d < rank; ++d)
        inner *= src.dims(static_cast<int>(d));
      const std::int64_t channels = scales.size() > 1 ? src.dims(static_cast<int>(axis)) : 1;
      onnx::TensorProto out;
      out.set_name(dq.output(0));
      out.set_data_type(onnx::TensorProto_DataType_FLOAT);
      for (const auto d : src.dims())
        out.add_dims(d);
      for (std::size_t i = 0; i < values.size(); ++i) {
        const auto c = toSize(channels > 1 ? (static_cast<std::int64_t>(i) / inner) % channels : 0);
        const double s = scales[c];
        const double zp = zps[zps.size() > 1 ? c : 0];
        double q = values[i];
        if (fakeQuant)
          q = std::clamp(std::nearbyint(q / s) + zp, -128.0, 127.0);
        out.add_float_data(static_cast<float>((q - zp) * s));
      }
      return out;
    };

    std::unordered_map<std::string, std::string> alias;
    std::vector<onnx::NodeProto> kept;
    std::vector<onnx::TensorProto> newConstants;
    for (const auto& node : graph->node()) {
      const std::string& op = node.op_type();
      if (op == "QuantizeLinear") {
        if (constants.count(node.input(0)) == 0)
          alias[node.output(0)] = node.input(0);
        continue;
      }
      if (op == "DequantizeLinear") {
        if (auto it = constants.find(node.input(0)); it != constants.end()) {
          newConstants.push_back(dequantize(node, *it->second, false));
          continue;
        }
        auto p = producer.find(node.input(0));
        if (p != producer.end() && p->second->op_type() == "QuantizeLinear" &&
            constants.count(p->second->input(0)) != 0) {
          newConstants.push_back(dequantize(node, *constants.at(p->second->input(0)), true));
          continue;
        }
        alias[node.output(0)] = node.input(0);
        continue;
      }
      if (op == "Identity") {
        alias[node.output(0)] = node.input(0);
        continue;
      }
      if (op == "Clip" && node.input_size() > 1) {
        // OpenCV 4.6 reads Clip's bounds only from the (opset 6) attributes.
        onnx::NodeProto clip = node;
        clip.clear_input();
        clip.add_input(node.input(0));
        for (int i = 1; i <= 2 && i < node.input_size(); ++i) {
          if (node.input(i).empty() || constants.count(node.input(i)) == 0)
            continue;
          const auto v = tensorValues(*constants.at(node.input(i)));
          if (v.empty())
            continue;
          auto* a = clip.add_attribute();
          a->set_name(i == 1 ? "min" : "max");
          a->set_type(onnx::AttributeProto_AttributeType_FLOAT);
          a->set_f(static_cast<float>(v[0]));
        }
        kept.push_back(clip);
        continue;
      }
      kept.push_back(node);
    }
    const auto base = [&](std::string name) {
      for (auto it = alias.find(name); it != alias.end(); it = alias.find(name)) {
        name = it->second;
      }
      return name;
    };
    // Graph outputs keep their names: the producing node is renamed to write them.
    std::unordered_map<std::string, std::string> claimed;
    std::vector<onnx::NodeProto> identities;
    for (const auto& out : graph->output()) {
      const std::string b = base(out.name());
      if (b == out.name())
        continue;
      if (claimed.count(b) == 0 && b != qdq.inputName && constants.count(b) == 0) {
        claimed[b] = out.name();
      } else {
        onnx::NodeProto id;
        id.set_op_type("Identity");
        id.set_name(out.name() + "_identity");
        id.add_input(b);
        id.add_output(out.name());
        identities.push_back(id);
      }
    }
    const auto finalName = [&](const std::string& name) {
      const std::string b = base(name);
      auto it = claimed.find(b);
      return it == claimed.end() ? b : it->second;
    };
    for (auto& id : identities)
      id.set_input(0, finalName(id.input(0)));
    std::set<std::string> used;
    graph->clear_node();
    for (auto node : kept) {
      for (int i = 0; i < node.input_size(); ++i) {
        if (node.input(i).empty())
          continue;
        node.set_input(i, finalName(node.input(i)));
        used.insert(node.input(i));
      }
      for (int i = 0; i < node.output_size(); ++i)
        node.set_output(i, finalName(node.output(i)));
      *graph->add_node() = node;
    }
    for (const auto& id : identities) {
      used.insert(id.input(0));
      *graph->add_node() = id;
    }
    // Initializers: the used originals plus the dequantized weights; nothing int8 remains.
    std::vector<onnx::TensorProto> inits;
    for (const auto& init : graph->initializer()) {
      if (used.count(init.name()) != 0)
        inits.push_back(init);
    }
    for (auto& c : newConstants) {
      if (used.count(c.name()) != 0)
        inits.push_back(std::move(c));
    }
    graph->clear_initializer();
    for (auto& init : inits)
      *graph->add_initializer() = std::move(init);
    // Drop Constant nodes nobody reads any more (e.g. int8 zero points).
    auto* nodes = graph->mutable_node();
    for (int i = nodes->size() - 1; i >= 0; --i) {
      const auto& n = nodes->Get(i);
      if (n.op_type() == "Constant" && used.count(n.output(0)) == 0)
        nodes->DeleteSubrange(i, 1);
    }
    // Only the image stays a graph input; shapes of intermediate values are not needed.
    onnx::ValueInfoProto image;
    for (const auto& in : graph->input()) {
      if (in.name() == qdq.inputName)
        image = in;
    }
    graph->clear_input();
    *graph->add_input() = image;
    graph->clear_value_info();
  }

  cv::dnn::Net net_;
  cv::Mat blob_;
  std::vector<cv::String> outNames_;
  std::vector<cv::Mat> results_;
  std::vector<std::vector<float>> outputData_;
  std::vector<OutputTensor> outputs_;
  std::vector<LayerInfo> layers_;
};

}  // namespace

std::unique_ptr<InferenceBackend> createOpenCvBackend(const std::string& bytes,
                                                      const QdqGraph& graph, int threads,
                                                      std::string* why) {
  auto backend = std::make_unique<OpenCvBackend>();
  if (!backend->build(bytes, graph, threads, why))
    return nullptr;
  return backend;
}

}  // namespace vp::inference
