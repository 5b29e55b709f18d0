// inference/xnnpack_backend: the graph IR on XNNPACK operators, int8 or float.
//
// Contract: createXnnpackInt8Backend() maps every IR node to XNNPACK QS8/QC8/S8/X8 operators
// (per-channel int8 convolution, per-tensor int8 deconvolution, requantizing add/multiply,
// channel-slice copies for Concat and nearest Resize, ...) or to a 256-entry table of our
// own where XNNPACK has no matching kernel (Sigmoid/Tanh whose output quantization is not
// XNNPACK's fixed one, requantizing Relu/Clip). createXnnpackFp32Backend() runs the same IR
// in float with the weights dequantized and the Q/DQ pairs dropped. Both create and set up
// every operator at load with the model's fixed input size on preallocated NHWC buffers,
// own a pthreadpool of `threads` workers (none for 1), and run() is a loop of
// xnn_run_operator() plus the output dequantization: no heap allocation.
#pragma once

#include <memory>
#include <string>

#include "inference/backend.hpp"
#include "inference/onnx_graph.hpp"

namespace vp::inference {

// planMemory: activation tensors share one arena by liveness (memory_plan.hpp), else one
// buffer each.
std::unique_ptr<InferenceBackend> createXnnpackInt8Backend(const QdqGraph& graph, int threads,
                                                           bool planMemory, std::string* why);
std::unique_ptr<InferenceBackend> createXnnpackFp32Backend(const QdqGraph& graph, int threads,
                                                           bool planMemory, std::string* why);

}  // namespace vp::inference
