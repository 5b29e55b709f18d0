// inference/xnnpack_runtime: what both XNNPACK backends share.
//
// Contract: initializeXnnpack() calls xnn_initialize(nullptr) once per process (thread-safe,
// the default allocator) and reports its status on every call. XnnOperator and ThreadPool
// own an operator / a pthreadpool (nullptr pool = run on the calling thread). Step is one
// unit of run(): an XNNPACK operator, a small loop of our own (a 256-entry int8 table or an
// element-wise float function) or an ExternalStep of another library (oneDNN), over
// preallocated buffers; running a step never allocates.
// xnnStatusText() turns a status into words for load errors.
#pragma once

#include <pthreadpool.h>
#include <xnnpack.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vp::inference {

bool initializeXnnpack(std::string* why);
const char* xnnStatusText(xnn_status status);

struct XnnOperatorDeleter {
  void operator()(xnn_operator_t op) const { xnn_delete_operator(op); }
};
using XnnOperator = std::unique_ptr<xnn_operator, XnnOperatorDeleter>;

struct ThreadPoolDeleter {
  void operator()(pthreadpool_t pool) const { pthreadpool_destroy(pool); }
};
using ThreadPool = std::unique_ptr<pthreadpool, ThreadPoolDeleter>;
ThreadPool makeThreadPool(int threads);  // nullptr for threads <= 1

enum class FloatFunction { Tanh };

// A unit of run() owned by something else than XNNPACK (the oneDNN convolutions of the
// DnnlInt8 backend); run() must not allocate and reports failure as false.
class ExternalStep {
 public:
  virtual ~ExternalStep() = default;
  virtual bool run() = 0;
};

struct Step {
  XnnOperator op;                    // when set, the step is xnn_run_operator(op)
  ExternalStep* external = nullptr;  // else when set, the step is external->run() (not owned)
  // Otherwise an int8 table lookup (lut) or a float function over `count` elements.
  const std::int8_t* lutInput = nullptr;
  std::int8_t* lutOutput = nullptr;
  std::array<std::int8_t, 256> lut{};
  const float* floatInput = nullptr;
  float* floatOutput = nullptr;
  FloatFunction function = FloatFunction::Tanh;
  float clampMin = 0.0F;
  float clampMax = 0.0F;
  std::size_t count = 0;

  bool run(pthreadpool_t pool) const;
};

// A zero-initialised buffer with XNN_EXTRA_BYTES of readable slack behind the data.
template <class T>
std::vector<T> makeTensorBuffer(std::size_t elements) {
  return std::vector<T>(elements + (XNN_EXTRA_BYTES + sizeof(T) - 1) / sizeof(T), T{});
}

}  // namespace vp::inference
