#include "detection/vehicle_cropper.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geometry/rotated_box.hpp"
#include "preprocess/white_balance.hpp"

namespace vp::detection {

namespace {

// cv::warpAffine's fixed point: coordinates in 1/1024 px (AB_BITS), reduced to 1/32 px
// (INTER_BITS) with a rounding offset of half a 1/32 step; bilinear weights are products of
// the 5-bit fractions (sum 1024), i.e. OpenCV's 15-bit table divided by 32.
constexpr int kAffineBits = 10;
constexpr double kAffineScale = 1 << kAffineBits;
constexpr int kFractionBits = 5;
constexpr int kFractionSteps = 1 << kFractionBits;
constexpr std::int64_t kAffineRound = (1 << kAffineBits) / kFractionSteps / 2;
constexpr int kWeightBits = 2 * kFractionBits;
constexpr int kWeightRound = 1 << (kWeightBits - 1);
// Keeps absurd maps (a GSD of 1e-9) inside integer range; any such point is far outside.
constexpr double kCoordinateLimit = 1e9;

std::int64_t fixedPoint(double value) {
  return static_cast<std::int64_t>(
      std::llrint(std::clamp(value * kAffineScale, -kCoordinateLimit, kCoordinateLimit)));
}

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

bool allFinite(std::span<const float> values) {
  return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

// Type: softmax of the logits (shifted by the largest for range).
void setTypeProbabilities(std::span<const float> typeLogits, Detection* detection) {
  const float largest = *std::max_element(typeLogits.begin(), typeLogits.end());
  double total = 0.0;
  std::array<double, shape::kVehicleTypeCount> e{};
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    e[t] = std::exp(static_cast<double>(typeLogits[t]) - static_cast<double>(largest));
    total += e[t];
  }
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    detection->typeProbabilities[t] = static_cast<float>(e[t] / total);
  }
}

}  // namespace

const char* toString(SecondStageStatus status) {
  switch (status) {
    case SecondStageStatus::Ok:
      return "ok";
    case SecondStageStatus::NotInitialised:
      return "crop network not loaded";
    case SecondStageStatus::BadGsd:
      return "ground sample distance unknown or invalid";
    case SecondStageStatus::BadOutputs:
      return "crop network outputs have the wrong size or are not finite";
    case SecondStageStatus::CropFailed:
      return "crop could not be cut (frame empty or not CV_8UC3)";
    case SecondStageStatus::EngineFailed:
      return "crop network run failed";
  }
  return "unknown";
}

CropMap cropAffine(double centreU, double centreV, double angle, double gsd_m, double cropGsd_m) {
  const double k = cropGsd_m / gsd_m;
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  const double x0 = (kCropWidth_px - 1) / 2.0;
  const double y0 = (kCropHeight_px - 1) / 2.0;
  CropMap map;
  map(0, 0) = k * c;
  map(0, 1) = -k * s;
  map(1, 0) = k * s;
  map(1, 1) = k * c;
  // t = centre - A (x0, y0), summed in numpy's order.
  map(0, 2) = centreU - (map(0, 0) * x0 + map(0, 1) * y0);
  map(1, 2) = centreV - (map(1, 0) * x0 + map(1, 1) * y0);
  return map;
}

bool cutCrop(const cv::Mat& frame, const CropMap& map, cv::Mat& crop) {
  if (frame.empty() || frame.type() != CV_8UC3 || crop.empty() || crop.type() != CV_8UC3) {
    return false;
  }
  const int width = frame.cols;
  const int height = frame.rows;
  const std::size_t step = frame.step[0];
  const std::uint8_t* data = frame.data;
  for (int y = 0; y < crop.rows; ++y) {
    const std::int64_t rowX = fixedPoint(map(0, 1) * y + map(0, 2)) + kAffineRound;
    const std::int64_t rowY = fixedPoint(map(1, 1) * y + map(1, 2)) + kAffineRound;
    std::uint8_t* out = crop.ptr<std::uint8_t>(y);
    for (int x = 0; x < crop.cols; ++x, out += 3) {
      const std::int64_t fx = (rowX + fixedPoint(map(0, 0) * x)) >> (kAffineBits - kFractionBits);
      const std::int64_t fy = (rowY + fixedPoint(map(1, 0) * x)) >> (kAffineBits - kFractionBits);
      const auto sx =
          static_cast<int>(std::clamp<std::int64_t>(fx >> kFractionBits, INT16_MIN, INT16_MAX));
      const auto sy =
          static_cast<int>(std::clamp<std::int64_t>(fy >> kFractionBits, INT16_MIN, INT16_MAX));
      const auto ax = static_cast<int>(fx & (kFractionSteps - 1));
      const auto ay = static_cast<int>(fy & (kFractionSteps - 1));
      const int w00 = (kFractionSteps - ax) * (kFractionSteps - ay);
      const int w01 = ax * (kFractionSteps - ay);
      const int w10 = (kFractionSteps - ax) * ay;
      const int w11 = ax * ay;
      int x0 = sx;
      int x1 = sx + 1;
      int y0 = sy;
      int y1 = sy + 1;
      if (!(static_cast<unsigned>(sx) < static_cast<unsigned>(width - 1) &&
            static_cast<unsigned>(sy) < static_cast<unsigned>(height - 1))) {
        // BORDER_REPLICATE: neighbours outside the frame take the nearest edge pixel.
        x0 = std::clamp(x0, 0, width - 1);
        x1 = std::clamp(x1, 0, width - 1);
        y0 = std::clamp(y0, 0, height - 1);
        y1 = std::clamp(y1, 0, height - 1);
      }
      const std::uint8_t* p00 =
          data + static_cast<std::size_t>(y0) * step + static_cast<std::size_t>(x0) * 3;
      const std::uint8_t* p01 =
          data + static_cast<std::size_t>(y0) * step + static_cast<std::size_t>(x1) * 3;
      const std::uint8_t* p10 =
          data + static_cast<std::size_t>(y1) * step + static_cast<std::size_t>(x0) * 3;
      const std::uint8_t* p11 =
          data + static_cast<std::size_t>(y1) * step + static_cast<std::size_t>(x1) * 3;
      for (int c = 0; c < 3; ++c) {
        const int sum = p00[c] * w00 + p01[c] * w01 + p10[c] * w10 + p11[c] * w11;
        out[c] = static_cast<std::uint8_t>((sum + kWeightRound) >> kWeightBits);
      }
    }
  }
  return true;
}

SecondStageStatus applyCropOutputs(const CropNetOutputs& outputs, double gsd_m,
                                   const SecondStageOptions& options, Detection* detection) {
  if (!(gsd_m > 0.0) || !std::isfinite(gsd_m)) {
    return SecondStageStatus::BadGsd;
  }
  if (outputs.typeLogits.size() != static_cast<std::size_t>(shape::kVehicleTypeCount) ||
      outputs.shape.size() > static_cast<std::size_t>(shape::kMaxShapeComponents) ||
      outputs.refine.size() != static_cast<std::size_t>(kRefineCount) ||
      !allFinite(outputs.typeLogits) || !allFinite(outputs.shape) || !allFinite(outputs.refine) ||
      !std::isfinite(outputs.flipLogit) ||
      (outputs.hasVehicleLogit && !std::isfinite(outputs.vehicleLogit))) {
    return SecondStageStatus::BadOutputs;
  }
  Detection& d = *detection;
  setTypeProbabilities(outputs.typeLogits, &d);

  // Shape: the ASM describes cars; a vehicle most likely Large gets none.
  d.gamma = shape::ShapeParams{};
  const bool large = topTwoTypes(d).first == shape::VehicleType::Large;
  if (!large || options.shapeForLargeVehicles) {
    d.gamma.count = static_cast<int>(outputs.shape.size());
    std::copy(outputs.shape.begin(), outputs.shape.end(), d.gamma.gamma.begin());
  }

  // Refinement in the crop frame of the first-stage pose (inverse of crops.refine_target).
  const double angle0 = d.box.angle;
  double angle = angle0;
  if (options.applyRefine) {
    std::array<double, kRefineCount> r{};
    for (int i = 0; i < kRefineCount; ++i) {
      r[i] = static_cast<double>(outputs.refine[i]) * kRefineScale[i] + kRefineOffset[i];
    }
    const bool keepLength = large && !options.refineLargeVehicleLength;
    if (keepLength) {
      r[0] = 0.0;                   // along-axis centre: the first stage's
      r[3] = d.box.length * gsd_m;  // length: the first stage's
    }
    const double c = std::cos(angle0);
    const double s = std::sin(angle0);
    d.box.cx += (c * r[0] - s * r[1]) / gsd_m;
    d.box.cy += (s * r[0] + c * r[1]) / gsd_m;
    angle += r[2];
    if (options.refineSize && r[3] > 0.0 && r[4] > 0.0) {
      d.box.length = r[3] / gsd_m;
      d.box.width = r[4] / gsd_m;
    }
  }

  // Front/back: logit > 0 <=> probability > 0.5 (Predictor's rule).
  d.flipProbability =
      static_cast<float>(1.0 / (1.0 + std::exp(-static_cast<double>(outputs.flipLogit))));
  if (options.applyFlip && outputs.flipLogit > 0.0F) {
    angle += geometry::kPi;
  }
  d.box.angle = geometry::wrapTwoPi(angle);
  d.vehicleProbability =
      outputs.hasVehicleLogit
          ? static_cast<float>(1.0 / (1.0 + std::exp(-static_cast<double>(outputs.vehicleLogit))))
          : std::numeric_limits<float>::quiet_NaN();
  return SecondStageStatus::Ok;
}

bool VehicleCropper::init(const std::string& cropModelPath,
                          const inference::EngineOptions& engineOptions,
                          const SecondStageOptions& options, std::string* why) {
  std::string detail;
  if (!engine_.load(cropModelPath, engineOptions, &detail)) {
    return fail(why, "crop model: " + detail);
  }
  const inference::TensorShape input = engine_.inputShape();
  if (input.h != kCropHeight_px || input.w != kCropWidth_px || input.c != 3) {
    return fail(why, cropModelPath + ": input is " + std::to_string(input.c) + "x" +
                         std::to_string(input.h) + "x" + std::to_string(input.w) +
                         ", the crop network needs 3x" + std::to_string(kCropHeight_px) + "x" +
                         std::to_string(kCropWidth_px));
  }
  // The verifier outputs are optional (crop networks before them lack them): `present` says
  // whether the model has one; a required output has none.
  struct Wanted {
    const char* name;
    std::size_t* index;
    int minChannels;
    int maxChannels;
    bool* present;
  };
  const Wanted wanted[] = {
      {"type_logits", &typeIndex_, shape::kVehicleTypeCount, shape::kVehicleTypeCount, nullptr},
      {"shape", &shapeIndex_, 0, shape::kMaxShapeComponents, nullptr},
      {"flip_logit", &flipIndex_, 1, 1, nullptr},
      {"refine", &refineIndex_, kRefineCount, kRefineCount, nullptr},
      {"vehicle_logit", &vehicleIndex_, 1, 1, &hasVerifier_},
      {"vehicle_logit_edge", &edgeVehicleIndex_, 1, 1, &hasEdgeVerifier_},
  };
  for (const Wanted& w : wanted) {
    bool found = false;
    for (std::size_t i = 0; i < engine_.outputCount(); ++i) {
      const inference::OutputTensor& out = engine_.output(i);
      if (out.name != w.name) {
        continue;
      }
      if (out.shape.h != 1 || out.shape.w != 1 || out.shape.c < w.minChannels ||
          out.shape.c > w.maxChannels) {
        return fail(why, cropModelPath + ": output '" + w.name + "' is " +
                             std::to_string(out.shape.c) + "x" + std::to_string(out.shape.h) + "x" +
                             std::to_string(out.shape.w) + ", expected " +
                             std::to_string(w.minChannels) +
                             (w.maxChannels != w.minChannels ? ".." + std::to_string(w.maxChannels)
                                                             : std::string()) +
                             " channels x 1 x 1");
      }
      *w.index = i;
      found = true;
    }
    if (w.present != nullptr) {
      *w.present = found;
    } else if (!found) {
      return fail(why, cropModelPath + ": no output named '" + w.name +
                           "' (the crop network needs type_logits, shape, flip_logit, refine)");
    }
  }
  if (hasEdgeVerifier_ && !hasVerifier_) {
    return fail(why, cropModelPath +
                         ": output 'vehicle_logit_edge' without 'vehicle_logit' (the border's "
                         "verifier comes beside the verifier)");
  }
  shapeCount_ = engine_.output(shapeIndex_).shape.c;
  options_ = options;
  crop_.create(kCropHeight_px, kCropWidth_px, CV_8UC3);
  crop_.setTo(cv::Scalar::all(0));
  mirrored_.create(kCropHeight_px, kCropWidth_px, CV_8UC3);
  return true;
}

void VehicleCropper::setFrameGain(float gain) {
  if (gain == frameGain_) {
    return;
  }
  frameGain_ = gain;
  gainTable_ = preprocess::gainTable(gain);  // the preprocessor's rounding, byte for byte
}

bool VehicleCropper::cut(const cv::Mat& frame, const CropMap& map, cv::Mat& crop) const {
  if (!cutCrop(frame, map, crop)) {
    return false;
  }
  if (frameGain_ != 1.0F) {
    // The frame's pixels still lack the exposure gain the working image got (setFrameGain).
    for (int v = 0; v < crop.rows; ++v) {
      std::uint8_t* row = crop.ptr<std::uint8_t>(v);
      for (int i = 0; i < crop.cols * crop.channels(); ++i) {
        row[i] = gainTable_[row[i]];
      }
    }
  }
  return true;
}

SecondStageStatus VehicleCropper::classify(const cv::Mat& frame, double gsd_m, Detection* detection,
                                           bool keepBox) {
  if (!initialised()) {
    return SecondStageStatus::NotInitialised;
  }
  if (!(gsd_m > 0.0) || !std::isfinite(gsd_m)) {
    return SecondStageStatus::BadGsd;
  }
  const geometry::RotatedBox& box = detection->box;
  if (!cut(frame, cropAffine(box.cx, box.cy, box.angle, gsd_m), crop_)) {
    return SecondStageStatus::CropFailed;
  }
  const inference::ImageView view{crop_.data, crop_.cols, crop_.rows, crop_.step[0]};
  if (engine_.run(view) != inference::RunStatus::Ok) {
    return SecondStageStatus::EngineFailed;
  }
  // The engine reuses its output buffers: keep the first run's values (sizes checked at init),
  // since the mirrored and the end crops run it again.
  const std::span<const float> firstShape = values(shapeIndex_);
  std::copy(firstShape.begin(), firstShape.end(), shape_.begin());
  const std::span<const float> firstTypes = values(typeIndex_);
  std::copy(firstTypes.begin(), firstTypes.end(), typeLogits_.begin());
  const std::span<const float> firstRefine = values(refineIndex_);
  std::copy(firstRefine.begin(), firstRefine.end(), refine_.begin());
  CropNetOutputs outputs;
  outputs.typeLogits = typeLogits_;
  outputs.shape = std::span<const float>(shape_.data(), firstShape.size());
  outputs.flipLogit = values(flipIndex_)[0];
  outputs.refine = refine_;
  // A vehicle cut by the border takes the border's own verifier where the model has one.
  const std::size_t verifierIndex = keepBox && hasEdgeVerifier_ && options_.frameEdgeOwnVerifier
                                        ? edgeVehicleIndex_
                                        : vehicleIndex_;
  outputs.hasVehicleLogit = hasVerifier_;
  outputs.vehicleLogit = hasVerifier_ ? values(verifierIndex)[0] : 0.0F;
  if (options_.mirrorAverage) {
    const SecondStageStatus status = mirrorAverage(verifierIndex, &outputs);
    if (status != SecondStageStatus::Ok) {
      return status;
    }
  }
  SecondStageOptions applied = options_;
  applied.applyRefine = options_.applyRefine && !keepBox;
  const auto top = std::max_element(typeLogits_.begin(), typeLogits_.end()) - typeLogits_.begin();
  if (options_.largeVehicleEnds && top == static_cast<std::ptrdiff_t>(shape::VehicleType::Large)) {
    // The box is still the first stage's: applyCropOutputs() below refines it.
    const SecondStageStatus status =
        endsFlipLogit(frame, gsd_m, detection->box, &outputs.flipLogit);
    if (status != SecondStageStatus::Ok) {
      return status;
    }
    return applyCropOutputs(outputs, gsd_m, applied, detection);
  }
  if (!options_.turnAverage) {
    return applyCropOutputs(outputs, gsd_m, applied, detection);
  }
  // Type, shape and refinement as usual, the heading kept on the first stage's side; then the
  // front/back from a crop at the refined box and its turned copy (see the contract).
  SecondStageOptions refineOnly = applied;
  refineOnly.applyFlip = false;
  const SecondStageStatus refined = applyCropOutputs(outputs, gsd_m, refineOnly, detection);
  if (refined != SecondStageStatus::Ok) {
    return refined;
  }
  float flipLogit = 0.0F;
  std::array<float, shape::kVehicleTypeCount> turnedTypeLogits{};
  const SecondStageStatus turned =
      turnedFlipLogit(frame, gsd_m, detection->box, &flipLogit,
                      options_.turnTypeAverage ? &turnedTypeLogits : nullptr);
  if (turned != SecondStageStatus::Ok) {
    return turned;
  }
  if (options_.turnTypeAverage) {
    const float w = options_.turnTypeWeight;
    for (std::size_t t = 0; t < typeLogits_.size(); ++t) {
      typeLogits_[t] = (1.0F - w) * typeLogits_[t] + w * turnedTypeLogits[t];
    }
    setTypeProbabilities(typeLogits_, detection);
  }
  detection->flipProbability =
      static_cast<float>(1.0 / (1.0 + std::exp(-static_cast<double>(flipLogit))));
  if (options_.applyFlip && flipLogit > 0.0F) {
    detection->box.angle = geometry::wrapTwoPi(detection->box.angle + geometry::kPi);
  }
  return SecondStageStatus::Ok;
}

SecondStageStatus VehicleCropper::endsFlipLogit(const cv::Mat& frame, double gsd_m,
                                                const geometry::RotatedBox& box, float* flipLogit) {
  if (!initialised()) {
    return SecondStageStatus::NotInitialised;
  }
  if (!(gsd_m > 0.0) || !std::isfinite(gsd_m)) {
    return SecondStageStatus::BadGsd;
  }
  const double halfWindow_px = 0.5 * kCropWidth_px * kCropGsd_m / gsd_m;
  const double offset_px = std::max(0.0, 0.5 * box.length - halfWindow_px);
  const double c = std::cos(box.angle);
  const double s = std::sin(box.angle);
  std::array<float, 2> flips{};
  for (int end = 0; end < 2; ++end) {  // 0: ahead, looking ahead; 1: behind, looking back
    const double sign = end == 0 ? 1.0 : -1.0;
    const double angle = end == 0 ? box.angle : geometry::wrapTwoPi(box.angle + geometry::kPi);
    if (!cut(frame,
             cropAffine(box.cx + sign * offset_px * c, box.cy + sign * offset_px * s, angle, gsd_m),
             mirrored_)) {
      return SecondStageStatus::CropFailed;
    }
    const inference::ImageView view{mirrored_.data, mirrored_.cols, mirrored_.rows,
                                    mirrored_.step[0]};
    if (engine_.run(view) != inference::RunStatus::Ok) {
      return SecondStageStatus::EngineFailed;
    }
    flips[static_cast<std::size_t>(end)] = engine_.output(flipIndex_).data[0];
  }
  if (!std::isfinite(flips[0]) || !std::isfinite(flips[1])) {
    return SecondStageStatus::BadOutputs;
  }
  *flipLogit = 0.5F * (flips[0] - flips[1]);
  return SecondStageStatus::Ok;
}

SecondStageStatus VehicleCropper::turnedFlipLogit(
    const cv::Mat& frame, double gsd_m, const geometry::RotatedBox& box, float* flipLogit,
    std::array<float, shape::kVehicleTypeCount>* typeLogits) {
  if (!initialised()) {
    return SecondStageStatus::NotInitialised;
  }
  if (!(gsd_m > 0.0) || !std::isfinite(gsd_m)) {
    return SecondStageStatus::BadGsd;
  }
  if (!cut(frame, cropAffine(box.cx, box.cy, box.angle, gsd_m), crop_)) {
    return SecondStageStatus::CropFailed;
  }
  cv::flip(crop_, mirrored_, -1);  // both axes: the crop cut at angle + pi, pixel for pixel
  if (typeLogits != nullptr) {
    typeLogits->fill(0.0F);
  }
  std::array<float, 2> flips{};
  const std::array<const cv::Mat*, 2> crops{&crop_, &mirrored_};
  for (std::size_t i = 0; i < crops.size(); ++i) {
    const inference::ImageView view{crops[i]->data, crops[i]->cols, crops[i]->rows,
                                    crops[i]->step[0]};
    if (engine_.run(view) != inference::RunStatus::Ok) {
      return SecondStageStatus::EngineFailed;
    }
    flips[i] = engine_.output(flipIndex_).data[0];
    if (typeLogits != nullptr) {
      const std::span<const float> types = values(typeIndex_);
      for (std::size_t t = 0; t < typeLogits->size(); ++t) {
        (*typeLogits)[t] += 0.5F * types[t];  // the mean of the two runs
      }
    }
  }
  if (!std::isfinite(flips[0]) || !std::isfinite(flips[1]) ||
      (typeLogits != nullptr && !allFinite(std::span<const float>(*typeLogits)))) {
    return SecondStageStatus::BadOutputs;
  }
  *flipLogit = 0.5F * (flips[0] - flips[1]);
  return SecondStageStatus::Ok;
}

std::span<const float> VehicleCropper::values(std::size_t index) const {
  const inference::OutputTensor& out = engine_.output(index);
  return {out.data, out.shape.elements()};
}

SecondStageStatus VehicleCropper::mirrorAverage(std::size_t verifierIndex,
                                                CropNetOutputs* outputs) {
  cv::flip(crop_, mirrored_, 0);
  const inference::ImageView mirroredView{mirrored_.data, mirrored_.cols, mirrored_.rows,
                                          mirrored_.step[0]};
  if (engine_.run(mirroredView) != inference::RunStatus::Ok) {
    return SecondStageStatus::EngineFailed;
  }
  const std::span<const float> typeLogits = values(typeIndex_);
  const std::span<const float> refine = values(refineIndex_);
  if (hasVerifier_) {  // a mirrored vehicle is still a vehicle: both runs' logits averaged
    outputs->vehicleLogit = 0.5F * (outputs->vehicleLogit + values(verifierIndex)[0]);
  }
  for (std::size_t t = 0; t < typeLogits_.size(); ++t) {
    typeLogits_[t] = 0.5F * (typeLogits_[t] + typeLogits[t]);
  }
  // Mirrored: the offset across the axis (dv) and the angle change turn sign.
  constexpr std::array<float, kRefineCount> kMirrorSign = {1.0F, -1.0F, -1.0F, 1.0F, 1.0F};
  if (options_.mirrorRefine) {
    for (std::size_t i = 0; i < refine_.size(); ++i) {
      refine_[i] = 0.5F * (refine_[i] + kMirrorSign[i] * refine[i]);
    }
  }
  // The ASM's components are left-right symmetric (cars are; DefaultAsm test): a mirrored car
  // has the same gamma, so the two runs' shapes are averaged as they are.
  const std::span<const float> shape = values(shapeIndex_);
  for (std::size_t i = 0; i < outputs->shape.size(); ++i) {
    shape_[i] = 0.5F * (shape_[i] + shape[i]);
  }
  return SecondStageStatus::Ok;
}

}  // namespace vp::detection
