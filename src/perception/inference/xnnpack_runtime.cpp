#include "inference/xnnpack_runtime.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>

namespace vp::inference {

bool initializeXnnpack(std::string* why) {
  static std::once_flag once;
  static xnn_status status = xnn_status_uninitialized;
  std::call_once(once, [] { status = xnn_initialize(nullptr); });
  if (status != xnn_status_success) {
    *why = std::string("xnn_initialize failed: ") + xnnStatusText(status) +
           " (CPU without the required instruction set?)";
    return false;
  }
  return true;
}

const char* xnnStatusText(xnn_status status) {
  switch (status) {
    case xnn_status_success:
      return "success";
    case xnn_status_uninitialized:
      return "XNNPACK not initialized";
    case xnn_status_invalid_parameter:
      return "invalid parameter";
    case xnn_status_invalid_state:
      return "invalid state";
    case xnn_status_unsupported_parameter:
      return "unsupported parameter";
    case xnn_status_unsupported_hardware:
      return "unsupported hardware";
    case xnn_status_out_of_memory:
      return "out of memory";
  }
  return "unknown status";
}

ThreadPool makeThreadPool(int threads) {
  if (threads <= 1)
    return ThreadPool(nullptr);
  return ThreadPool(pthreadpool_create(static_cast<std::size_t>(threads)));
}

bool Step::run(pthreadpool_t pool) const {
  if (op)
    return xnn_run_operator(op.get(), pool) == xnn_status_success;
  if (external != nullptr)
    return external->run();
  if (lutInput != nullptr) {
    for (std::size_t i = 0; i < count; ++i) {
      lutOutput[i] = lut[static_cast<std::size_t>(static_cast<int>(lutInput[i]) + 128)];
    }
    return true;
  }
  for (std::size_t i = 0; i < count; ++i) {
    floatOutput[i] = std::clamp(std::tanh(floatInput[i]), clampMin, clampMax);
  }
  return true;
}

}  // namespace vp::inference
