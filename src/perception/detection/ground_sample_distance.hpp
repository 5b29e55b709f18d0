// detection/ground_sample_distance: metres per frame pixel at a detection, which the second
// stage needs to cut its crops at a fixed metric resolution (6 cm/px).
//
// Contract: the pipeline knows the true GSD from the drone pose and the DTM (lifting) and
// passes it per detection through a GsdProvider. Without one the detection stage uses, in
// this order, a fixed GSD from the options (e.g. camera height above ground / focal length for
// a nadir camera, nadirGsd()), else the frame's median box length taken as a nominal 4.5 m
// car - the estimate tools/detector uses for images without a known GSD ("the median box long
// side = a 4.5 m car"). Estimates are clamped to [minGsd_m, maxGsd_m]. All functions are
// allocation-free (the median works in caller-owned scratch).
#pragma once

#include <span>
#include <string>

#include "detection/detection.hpp"
#include "preprocess/working_scale.hpp"

namespace vp::detection {

// Per-detection GSD hook (e.g. from pose + DTM). Return <= 0 when unknown (the stage then
// falls back to its own estimate).
class GsdProvider {
 public:
  virtual ~GsdProvider() = default;
  virtual double groundSampleDistance_m(const Detection& detection) const = 0;
};

struct GsdOptions {
  double fixedGsd_m = 0.0;          // > 0: use this for every detection (m per frame px)
  double nominalCarLength_m = 4.5;  // the median box is taken to be this long, > 0
  double minGsd_m = 0.005;          // clamp of the estimates, 0 < min <= max
  double maxGsd_m = 0.5;
};

bool validate(const GsdOptions& options, std::string* why);

// The first stage's working resolution (preprocess/working_scale.hpp).
using preprocess::kDetectorWorkingGsd_m;

// Working scale (working px per frame px) that brings a frame of gsd_m metres per pixel to the
// detector's resolution: gsd_m / kDetectorWorkingGsd_m, at most 1 (the preprocessor only
// downscales: coarser frames are run as they are). 0 for a non-positive or non-finite gsd_m.
double workingScaleForGsd(double gsd_m);

// GSD of a nadir pinhole camera at heightAboveGround_m with focal length fPx.
double nadirGsd(double heightAboveGround_m, double focalLength_px);

// nominalCarLength_m / median box length (frame px) over the detections, clamped; 0 when
// there is none. scratch must hold detections.size() values.
double medianLengthGsd(std::span<const Detection> detections, const GsdOptions& options,
                       std::span<double> scratch);

}  // namespace vp::detection
