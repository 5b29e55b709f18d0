// detection/vehicle_cropper: the second stage - a rotated, direction-aligned crop of the
// full-resolution frame around each detection, the crop network on it, and its outputs
// (type, ASM shape, front/back flip, box refinement) applied to the detection.
//
// Contract (Python reference: tools/detector/crops.py and evaluate.Predictor.run_crops;
// tools/detector/model.py for the output meanings):
//  - cropAffine() is crops.crop_affine: crop pixel (x, y) -> frame pixel
//      (u, v) = (cu, cv) + k R(angle) (x - (W - 1) / 2, y - (H - 1) / 2),  k = 0.06 / gsd_m,
//    W x H = 96 x 48, so the crop's +x is the box's forward axis and +y the vehicle's right.
//  - cutCrop() samples the frame through that map exactly as cv2.warpAffine(...,
//    INTER_LINEAR | WARP_INVERSE_MAP, BORDER_REPLICATE) does (same fixed-point coordinates
//    and weights: bit-identical crops), without allocating.
//  - applyCropOutputs(): typeProbabilities = softmax(type_logits); gamma = shape (n_s values;
//    count 0 for a vehicle whose most likely type is Large unless shapeForLargeVehicles: the
//    ASM describes cars only); flipProbability = sigmoid(flip_logit) and, when > 0.5
//    (logit > 0, Predictor's rule), angle += pi; refine = raw * kRefineScale + kRefineOffset =
//    (du_m, dv_m, d_angle, length_m, width_m) in the crop frame of the first-stage pose
//    (x forward, y right): centre += R(angle0) (du, dv) / gsd, angle += d_angle, length and
//    width = metres / gsd - the inverse of crops.refine_target (the Python Predictor returns
//    refine without applying it). Non-finite or non-positive refined sizes keep the
//    first-stage values. A vehicle most likely Large keeps its first-stage length and its
//    centre along the axis (du not applied) unless refineLargeVehicleLength: the 5.76 m crop
//    window shows only part of a bus or truck, so the crop network's length for it is a guess,
//    while the first stage saw the whole vehicle.
//  - An optional output vehicle_logit (1 x 1 x 1, the verifier) gives vehicleProbability =
//    sigmoid(vehicle_logit); a model without it leaves vehicleProbability NaN. The detection
//    stage drops detections below SecondStageOptions::minVehicleProbability. A second optional
//    output vehicle_logit_edge (1 x 1 x 1; only beside vehicle_logit) is the verifier for a
//    vehicle cut by the frame's border: classify() with keepBox takes vehicleProbability from
//    it instead (the real sets label cut vehicles differently, so a verifier retrained for the
//    inside of the frame keeps the previous one's decisions at the border).
//  - With mirrorAverage, classify() runs the network a second time on the crop mirrored across
//    the vehicle's axis (rows reversed: left and right swapped, front stays front) and averages
//    the two runs' type logits (and verifier logits) and shape gamma (the ASM's components are
//    left-right symmetric, so a mirrored car has the same gamma), with mirrorRefine also their
//    refinements (du, length, width as they are; dv and d_angle negated back); the flip logit
//    comes from the crop as cut. A test-time augmentation: one more crop-network run.
//  - With turnAverage (a car; Large vehicles take their ends, below), the front/back comes from
//    a second look: type, shape and refinement are applied as above with the heading kept on
//    the first stage's side, then turnedFlipLogit() cuts a crop at the *refined* box (centred
//    and aligned on the vehicle) and runs the network on it and on its copy turned by 180 deg
//    (what cutting at angle + pi gives, pixel for pixel: x -> W-1-x, y -> H-1-y), returning
//    (flip(crop) - flip(turned)) / 2. The turned crop shows the front where the first shows
//    the rear, so the decision is equivariant by construction: turning the box by 180 deg
//    negates the logit and never changes the heading the vehicle ends with. flipProbability
//    is the sigmoid of that logit. Two more runs. With turnTypeAverage those two runs' type
//    logits are averaged too and weighted turnTypeWeight against the first look's (mirror-averaged)
//    logits (1 - turnTypeWeight), and typeProbabilities are the softmax of that mean: the refined
//    box is centred and aligned on the vehicle, so it is a second, better-posed view of the type,
//    at no extra run. The shape gamma and the Large rules keep the first look's decision.
//  - With largeVehicleEnds, a vehicle whose most likely type (after mirror averaging) is Large
//    gets its front/back from two more crops, one at each end of its box instead of its middle:
//    the 5.76 m window on the middle of a 12 m bus shows neither end. endsFlipLogit() cuts crop F
//    centred (L/2 - 2.88 m) ahead of the box centre along the box's heading, looking ahead, and
//    crop R as far behind it, looking back, and returns (flip(F) - flip(R)) / 2: > 0 when F looks
//    like a rear and R like a front, i.e. the box's heading is the vehicle's rear, the meaning
//    of flip_logit. Turning the box by 180 deg swaps F and R and negates the result. A box no
//    longer than the window cuts both crops at its centre, facing either way.
//  - VehicleCropper owns the crop engine and two crop buffers; classify() runs one detection
//    (the engine is batch 1) with no heap allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "detection/detection.hpp"
#include "geometry/rotated_box.hpp"
#include "inference/engine.hpp"

namespace vp::detection {

constexpr int kCropWidth_px = 96;    // model.CROP_W
constexpr int kCropHeight_px = 48;   // model.CROP_H
constexpr double kCropGsd_m = 0.06;  // model.CROP_GSD_M, metres per crop pixel
constexpr int kRefineCount = 5;      // du_m, dv_m, d_angle_rad, length_m, width_m
// model.REFINE_SCALE / REFINE_OFFSET: refine = raw * scale + offset.
constexpr std::array<double, kRefineCount> kRefineScale{0.5, 0.5, 0.2, 1.0, 1.0};
constexpr std::array<double, kRefineCount> kRefineOffset{0.0, 0.0, 0.0, 4.5, 1.8};

// 2 x 3 affine map crop pixel -> frame pixel.
using CropMap = Eigen::Matrix<double, 2, 3>;
CropMap cropAffine(double centreU, double centreV, double angle, double gsd_m,
                   double cropGsd_m = kCropGsd_m);

// frame: CV_8UC3; crop: preallocated CV_8UC3 (any size; 48 x 96 for the CropNet). False (and
// nothing written) on a wrong type or an empty image.
bool cutCrop(const cv::Mat& frame, const CropMap& map, cv::Mat& crop);

// Raw CropNet outputs of one crop.
struct CropNetOutputs {
  std::span<const float> typeLogits;  // shape::kVehicleTypeCount
  std::span<const float> shape;       // n_s <= shape::kMaxShapeComponents
  float flipLogit = 0.0F;
  std::span<const float> refine;  // kRefineCount (raw, before scale/offset)
  bool hasVehicleLogit = false;   // the crop network has the verifier output
  float vehicleLogit = 0.0F;
};

// Defaults are the shipped configuration's (perception.*, config/default.yaml): the choices
// of the tuning seeds (docs/model_card.md).
struct SecondStageOptions {
  bool applyFlip = true;                  // turn the heading by 180 deg when flip prob > 0.5
  bool applyRefine = true;                // centre/axis/size refinement (see the contract)
  bool refineSize = true;                 // ... including length and width (else the first stage's)
  bool shapeForLargeVehicles = false;     // keep gamma when the top type is Large
  bool refineLargeVehicleLength = false;  // apply length and du when the top type is Large
  bool mirrorAverage = true;              // type averaged with the mirrored crop's (see contract)
  bool mirrorRefine = true;               // ... and the refinement (needs mirrorAverage)
  bool largeVehicleEnds = true;           // Large: front/back from crops at both ends (contract)
  bool turnAverage = true;                // front/back from the refined box and its turn (contract)
  bool turnTypeAverage = true;            // ... and type from those runs too (needs turnAverage)
  // With turnTypeAverage: the second look's weight in the type logits' mean, the first look's
  // being 1 - turnTypeWeight. [0, 1]; 0.8: chosen on the tuning seeds (docs/model_card.md, round
  // 22: OA-1 87.2 -> 87.7 % there), since the refined box is the better-posed view.
  float turnTypeWeight = 0.8F;
  // Detections whose verifier probability is below this are dropped after the second stage;
  // 0 keeps all, and so does a crop network without the verifier output. [0, 1]. 0.5: v14's
  // verifier (two averaged), chosen on the tuning seeds (docs/model_card.md, round 27; v6-v13
  // used 0.3, chosen in round 8).
  float minVehicleProbability = 0.5F;
  // A vehicle whose first-stage box reaches the frame's border (Detection::atFrameEdge) is seen
  // in part. The crop network learnt whole vehicles: it stretches such a box to a whole car and
  // shifts it past the border, where the real sets' labels (and the pixels) end. With
  // frameEdgeKeepBox the box stays the first stage's (type, shape and front/back still from the
  // crops), and the verifier's threshold for it is frameEdgeMinVehicleProbability, [0, 1],
  // lower or higher than minVehicleProbability (the real sets label cut vehicles differently:
  // docs/model_card.md, round 21: CATS held-out P/R 97.4/89.8 -> 99.0/91.3 %; the border
  // convention).
  bool frameEdgeKeepBox = true;
  float frameEdgeMinVehicleProbability = 0.3F;
  // With frameEdgeKeepBox and a crop network that has the border's own verifier output
  // (vehicle_logit_edge, v14: v13's verifier), that output decides at the border (true) or the
  // one inside the frame does (false: with a low frameEdgeMinVehicleProbability, the convention
  // of a data set that labels the visible part of cut vehicles; docs/model_card.md, the border
  // convention).
  bool frameEdgeOwnVerifier = true;
};

enum class SecondStageStatus {
  Ok,
  NotInitialised,
  BadGsd,      // GSD not finite or <= 0: the crop scale is unknown
  BadOutputs,  // output sizes wrong or values not finite
  CropFailed,  // frame not CV_8UC3 or empty
  EngineFailed,
};
const char* toString(SecondStageStatus status);

// Applies one crop's outputs to the detection whose box was the crop pose (see contract).
SecondStageStatus applyCropOutputs(const CropNetOutputs& outputs, double gsd_m,
                                   const SecondStageOptions& options, Detection* detection);

class VehicleCropper {
 public:
  VehicleCropper() = default;
  VehicleCropper(const VehicleCropper&) = delete;
  VehicleCropper& operator=(const VehicleCropper&) = delete;

  // Start-up: loads the crop model (input 1 x 3 x 48 x 96; outputs type_logits 7, shape n_s,
  // flip_logit 1, refine 5 and optionally vehicle_logit 1 and vehicle_logit_edge 1, each 1 x 1)
  // and checks its interface; *why names the file and the offending output.
  bool init(const std::string& cropModelPath, const inference::EngineOptions& engineOptions,
            const SecondStageOptions& options, std::string* why = nullptr);
  bool initialised() const { return engine_.loaded(); }

  // Real-time: crop at the detection's box with gsd_m, run the network, apply its outputs.
  // With keepBox the box is not refined (the vehicle is cut by the frame's border) and the
  // border's verifier output decides when the model has one.
  SecondStageStatus classify(const cv::Mat& frame, double gsd_m, Detection* detection,
                             bool keepBox = false);

  // Real-time: the front/back logit of a long vehicle from crops at its two ends (contract);
  // the same statuses as classify().
  SecondStageStatus endsFlipLogit(const cv::Mat& frame, double gsd_m,
                                  const geometry::RotatedBox& box, float* flipLogit);
  // Real-time: the front/back logit from a crop at box and its turned copy (contract); with
  // typeLogits (borrowed, may be null) also the mean of the two runs' type logits.
  SecondStageStatus turnedFlipLogit(
      const cv::Mat& frame, double gsd_m, const geometry::RotatedBox& box, float* flipLogit,
      std::array<float, shape::kVehicleTypeCount>* typeLogits = nullptr);

  // Real-time: the gain the frame's pixels still need (the preprocessor's exposure gain when it
  // went into the working image only, preprocess::PreprocessedFrame::frameGain); every crop cut
  // from now on is mapped through saturate(round(v * gain)). 1: none (the default).
  void setFrameGain(float gain);

  const cv::Mat& lastCrop() const { return crop_; }  // diagnostics and tests
  int shapeCount() const { return shapeCount_; }
  bool hasVerifier() const { return hasVerifier_; }
  bool hasEdgeVerifier() const { return hasEdgeVerifier_; }

 private:
  std::span<const float> values(std::size_t outputIndex) const;  // the engine's last run
  // Runs the mirrored crop and averages into the first run's copies (contract); the verifier
  // logit from output verifierIndex, as the first run's.
  SecondStageStatus mirrorAverage(std::size_t verifierIndex, CropNetOutputs* outputs);
  // cutCrop() and then the frame gain.
  bool cut(const cv::Mat& frame, const CropMap& map, cv::Mat& crop) const;

  inference::Engine engine_;
  float frameGain_ = 1.0F;
  std::array<std::uint8_t, 256> gainTable_{};
  SecondStageOptions options_{};
  cv::Mat crop_;
  cv::Mat mirrored_;
  std::array<float, shape::kVehicleTypeCount> typeLogits_{};  // first run, kept for the mean
  std::array<float, kRefineCount> refine_{};
  std::array<float, shape::kMaxShapeComponents> shape_{};
  std::size_t typeIndex_ = 0;
  std::size_t shapeIndex_ = 0;
  std::size_t flipIndex_ = 0;
  std::size_t refineIndex_ = 0;
  std::size_t vehicleIndex_ = 0;
  std::size_t edgeVehicleIndex_ = 0;
  bool hasVerifier_ = false;
  bool hasEdgeVerifier_ = false;
  int shapeCount_ = 0;
};

}  // namespace vp::detection
