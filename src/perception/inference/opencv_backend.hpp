// inference/opencv_backend: the float reference, OpenCV DNN on the QDQ model with Q/DQ folded.
//
// Contract: createOpenCvBackend() rewrites the ONNX protobuf (`bytes`) into a float model in
// memory: weight/bias DequantizeLinear chains (int8 initializer or fake-quant
// QuantizeLinear(float initializer)) become dequantized float initializers, activation
// QuantizeLinear -> DequantizeLinear pairs are bypassed (the input QuantizeLinear too), then
// hands the serialized model to cv::dnn::readNetFromONNX with the OPENCV backend on the CPU.
// The graph IR (already validated) supplies the output names and shapes. The input is a
// preallocated NCHW float blob; outputs are copied NCHW -> NHWC into preallocated buffers.
// OpenCV allocates inside forward(): this backend is a reference, not for the real-time
// path. Threads: cv::setNumThreads(threads) is process-wide (it changes OpenCV for everyone).
#pragma once

#include <memory>
#include <string>

#include "inference/backend.hpp"
#include "inference/onnx_graph.hpp"

namespace vp::inference {

std::unique_ptr<InferenceBackend> createOpenCvBackend(const std::string& bytes,
                                                      const QdqGraph& graph, int threads,
                                                      std::string* why);

}  // namespace vp::inference
