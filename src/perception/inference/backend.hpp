// inference/backend: the interface the engine facade drives; one implementation per Backend.
//
// Contract: a backend is built complete at load (create functions return nullptr and fill
// *why, a message naming the file and node, on failure). inputData() is the preallocated
// buffer of the image tensor in inputLayout(); the facade fills it through the input LUT and
// then calls run(), which returns false only when the underlying library reports an error.
// outputs() point into preallocated buffers, valid until the next run().
#pragma once

#include <string>
#include <vector>

#include "inference/engine.hpp"

namespace vp::inference {

enum class InputLayout { Int8Nhwc, FloatNhwc, FloatNchw };

class InferenceBackend {
 public:
  virtual ~InferenceBackend() = default;
  virtual InputLayout inputLayout() const = 0;
  virtual void* inputData() = 0;
  virtual bool run() = 0;
  virtual const std::vector<OutputTensor>& outputs() const = 0;
  virtual const std::vector<LayerInfo>& layers() const = 0;
  virtual ActivationMemory activationMemory() const { return {}; }
};

}  // namespace vp::inference
