// preprocess/working_scale: which working scale a frame gets when the drone's height changes.
//
// Contract: the detector was trained on frames brought to about 12 cm per working pixel; a
// frame of g metres per pixel should therefore be downscaled by g / 0.12. The preprocessor
// cannot build new resize tables in the loop (fixed memory), so it prepares a ladder of scales
// at start-up - the configured working scale times powers of kScaleStep, within
// [minScale, maxScale] - and the loop picks a rung. chooseRung() moves to the rung nearest the
// ideal scale (in log space) only when the ideal lies more than `hysteresis` rungs away from
// the current one, so a drone hovering near the midpoint between two rungs does not make the
// scale flicker. fewerTilesRung() then may step down from that rung to a coarser one that cuts
// the working image into fewer detector tiles, as long as a working pixel stays within a given
// ratio of the trained size (the detector is trained on 8-18 cm working pixels). Pure
// functions, no allocation.
#pragma once

#include <cstddef>
#include <span>

namespace vp::preprocess {

// Metres per working pixel the detector is trained at: a 2592 px frame from ~90 m, downscaled
// 4x (tools/detector/README.md, docs/model_card.md).
inline constexpr double kDetectorWorkingGsd_m = 0.12;

// Ratio of neighbouring rungs: 2^(1/8), about 9 %: within the detector's tolerance of scale
// (it is trained with +-20 % scale augmentation, tools/detector/README.md).
inline constexpr double kScaleStep = 1.0905077326652577;  // 2^(1/8)
// Most rungs a ladder may have (from 1/16 to 1 at kScaleStep: 33).
inline constexpr std::size_t kMaxScaleRungs = 33;
// A move to another rung needs the ideal scale this many rungs away from the current one.
inline constexpr double kScaleHysteresis_rungs = 0.75;

// The ladder anchor * kScaleStep^k for every integer k with minScale <= scale <= maxScale
// (and <= 1), ascending, into `out`; returns how many were written (0 when the anchor is not
// within [minScale, maxScale] or out is too small for them all). The anchor itself is always
// a rung, so a fixed-scale configuration's numbers are reproduced exactly.
std::size_t buildScaleLadder(double anchor, double minScale, double maxScale,
                             std::span<double> out);

// The rung for an ideal scale, starting from rung `current`: `current` unless the ideal lies
// more than hysteresis_rungs rungs away, else the nearest rung (clamped to the ladder). A
// non-finite or non-positive ideal keeps `current`.
std::size_t chooseRung(std::span<const double> ladder, std::size_t current, double idealScale,
                       double hysteresis_rungs = kScaleHysteresis_rungs);

// The rung the detector runs at when the ideal one is `ideal`: among the rungs k <= ideal whose
// working pixel is at most maxGsdRatio times the ideal rung's (ladder[ideal] / ladder[k] <=
// maxGsdRatio), the one with the fewest tiles (tileCounts[k]); of those the finest. It depends
// on `ideal` alone, so chooseRung()'s hysteresis covers it too. maxGsdRatio <= 1, or sizes that
// differ, give `ideal`.
std::size_t fewerTilesRung(std::span<const double> ladder, std::span<const std::size_t> tileCounts,
                           std::size_t ideal, double maxGsdRatio);

}  // namespace vp::preprocess
