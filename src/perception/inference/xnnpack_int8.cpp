// The int8 XNNPACK backend (contract in xnnpack_backend.hpp): the graph walk of
// xnnpack_graph.hpp with QS8/QC8/S8 operators on the model's quantization, and 256-entry
// tables where XNNPACK has no kernel for it.
#include "inference/xnnpack_int8.hpp"

#include "inference/xnnpack_backend.hpp"

namespace vp::inference {

std::unique_ptr<InferenceBackend> createXnnpackInt8Backend(const QdqGraph& graph, int threads,
                                                           bool planMemory, std::string* why) {
  return makeBackend<XnnpackInt8Backend>(graph, threads, planMemory, why);
}

}  // namespace vp::inference
