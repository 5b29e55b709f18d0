// perception/footprint_type: the lifted footprint's size as evidence on a car's type.
//
// Contract: apply() looks at each lifted observation (liftStatus Ok) that is not cut by the
// frame's border (atFrameEdge false, its footprint would be short) and whose most likely type is
// a car (not Large), and adds to each car type's log-probability
//   lengthWeight[t] * clamp((L - referenceLength_m) / lengthScale_m)
//   + aspectWeight[t] * clamp((ln(L / W) - ln(referenceAspect)) / aspectScale)
// (L, W: the footprint's length and width on the ground, m; clamp to +-maxTerm: beyond the range
// the weights were fitted on, e.g. a 6 m delivery van, a longer footprint says no more), then
// renormalises the six car types so that their total, and the Large probability, stay as they were.
// An observation whose most likely type changes is lifted again with the frame's Lifter and camera
// pose (its shape height places the box and its ASM keypoints stand on the ground), as the lane
// prior does for a turned one. Observations not lifted, at the frame's edge, most likely Large or
// with a degenerate footprint are left as they were. Why: the crop network sees each vehicle at a
// fixed 6 cm/px and should know its size, yet confuses compacts with estates;
// the footprint's length and aspect ratio separate that pair better than its logits alone (SUV and
// van carry no weight by default: there the footprint mostly shifted their boundary). The
// weights are fitted to one crop network (`tools/detector/fit_footprint_type.py` on its application
// runs over the tuning renders, which prints this file's defaults); another crop network needs its
// own. apply() works in place, never allocates and never throws; it is const.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>

#include "lifting/lifting.hpp"
#include "perception/detection_lifter.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::perception {

struct FootprintTypeOptions {
  bool enabled = true;  // perception.footprint_type
  // Per type (shape::VehicleType order; Large's are not used): log-probability change per
  // lengthScale_m of footprint length above referenceLength_m, and per aspectScale of
  // ln(length / width) above ln(referenceAspect). Fitted for the shipped crop network (v13) on
  // its application runs over the tuning renders (multinomial log-loss over the car types,
  // L2 0.01; fit_footprint_type.py prints these two lines). SUV and van keep 0: between those
  // two the footprint mostly shifted the boundary with the held-out sets' mix, not the evidence.
  std::array<double, shape::kVehicleTypeCount> lengthWeight{-0.1296, -0.0561, -0.0046, -0.0002,
                                                            0.0,     0.0,     0.0};
  std::array<double, shape::kVehicleTypeCount> aspectWeight{-0.0641, -0.4401, -0.0029, 0.0065,
                                                            0.0,     0.0,     0.0};
  double referenceLength_m = 4.6;  // m
  double lengthScale_m = 0.4;      // m, > 0
  double referenceAspect = 2.35;   // length / width, > 0
  double aspectScale = 0.1;        // of ln(length / width), > 0
  // Each term is clamped to +-maxTerm scales: about the tuning renders' 0.5-99.5 % range
  // (length 3.6-5.6 m).
  double maxTerm = 2.5;  // > 0
};

struct FootprintTypeScreening {
  std::size_t weighed = 0;  // observations whose type probabilities the footprint moved
  std::size_t retyped = 0;  // of those, whose most likely type changed (lifted again)
};

class FootprintType {
 public:
  // Borrows the DetectionLifter the frames are lifted with (must outlive this). False + *why for
  // a non-positive scale or reference, or a weight that is not finite.
  bool init(const FootprintTypeOptions& options, const DetectionLifter* lifter,
            std::string* why = nullptr);
  bool active() const { return active_; }

  // Moves, in place, the type probabilities of the observations the contract names. lifter and
  // cameraPose: those the observations were lifted with.
  FootprintTypeScreening apply(std::span<VehicleObservation> observations,
                               const lifting::Lifter& lifter,
                               const lifting::CameraPoseWorld& cameraPose) const;

 private:
  FootprintTypeOptions options_{};
  const DetectionLifter* lifter_ = nullptr;
  bool active_ = false;
};

}  // namespace vp::perception
