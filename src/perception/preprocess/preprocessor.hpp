// preprocess/preprocessor: turns one camera frame into the corrected full-resolution frame and
// the detector's input tiles at the working resolution, in memory fixed at init().
//
// Contract (per frame, in this order; docs/perception.md):
//  1. undistortion (optional; skipped for a pinhole camera): the BGR frame is remapped
//     through a precomputed fixed-point map (FrameRemap) into an owned buffer; frameCamera()
//     is then the pinhole camera of that undistorted frame (same intrinsics, no distortion),
//     which is what lifting must use for the detections' pixels;
//  2. white balance (optional; seed 001's near-white points, WhiteBalancer): gains estimated
//     on this frame and applied to the full-resolution frame (into the owned buffer; the
//     caller's frame is never written);
//  2b. exposure (optional, on by default; exposure.hpp): a frame darker than the detector's
//     training frames gets a gain equal on all channels, applied like the white balance's
//     gains in the same sweep. With white balance or undistortion it is multiplied into their
//     gains and written to the owned full-resolution frame too; otherwise only the working
//     image gets it (no full-size copy, no buffer for it) and output().frameGain tells readers
//     of the full-resolution frame (the crops) to apply it themselves;
//  3. area downscale by the working scale (AreaResizer, = cv::resize INTER_AREA) into the
//     working image, whose padding right/bottom (to at least the network input) holds padValue;
//     steps 2 (its gains) and 3 are one sweep over the frame's rows, split over the threads:
//     each source row is read once, balanced on the way in and, with white balance on, also
//     written to the owned full-resolution frame; no other full-size image is made;
//     the scale is workingScale, or - with workingGsd_m > 0 - the rung of a ladder of scales
//     built at init() (working_scale.hpp) that adaptToGsd() picks from the frame's ground
//     sample distance, so that a working pixel covers about workingGsd_m metres at any height;
//  4. tiles of the network input size over the working image (tiling.hpp): one tile when the
//     scaled frame fits, else overlapping tiles, each a view with its offset.
// The camera's YUYV / NV12 buffers can go straight to step 3 (process(const YuvFrame&): the
// rows are converted inside the resize sweep, without a full-size BGR frame).
// process() returns a status and never throws: an empty frame, a type other than CV_8UC3, a
// size other than the one given to init(), or the preprocessor's own output passed back in
// are refused with lastError() naming what was wrong. After init() it performs no heap
// allocation. Results (output()) stay valid until the next process(); when neither correction
// runs, output().frame is a view of the caller's frame, which must then outlive its use.
// Not thread-safe; `threads` > 1 splits the row loops over an owned pool.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"
#include "preprocess/area_resizer.hpp"
#include "preprocess/exposure.hpp"
#include "preprocess/frame_remap.hpp"
#include "preprocess/row_parallel.hpp"
#include "preprocess/tiling.hpp"
#include "preprocess/white_balance.hpp"
#include "preprocess/working_scale.hpp"

namespace vp::preprocess {

// Most tiles one frame may be cut into (fixed memory downstream).
constexpr int kMaxTiles = 64;
// Default working scale: the 2592 px wide camera frame to 648 px (~12 cm/px at 90 m), the
// resolution the detector is trained at (tools/detector/README.md).
constexpr double kDefaultWorkingScale = 648.0 / 2592.0;

// The preprocessing knobs (config: perception.*, docs/configuration.md). Defaults are the
// shipped configuration's (config/default.yaml; a test keeps the two equal).
struct PreprocessOptions {
  // Remove lens distortion (no-op for a pinhole camera). Off: the shipped detector is trained
  // on raw (distorted) frames.
  bool undistort = false;
  bool whiteBalance = false;  // seed 001 AWB (the detector is trained without it)
  WhiteBalanceOptions whiteBalanceOptions{};
  // Gain for under-exposed frames (on by default; normally exposed frames are left as they
  // are).
  ExposureOptions exposure{};
  double workingScale = kDefaultWorkingScale;  // working px per frame px, (0, 1]
  // > 0: adapt the working scale to the frame's GSD (adaptToGsd) so that one working pixel
  // covers about this many metres; workingScale is then the scale until the first GSD and the
  // anchor of the ladder. 0: workingScale for every frame. [0, 1] m.
  double workingGsd_m = kDetectorWorkingGsd_m;
  double minWorkingScale = 0.125;  // the ladder's bounds, 0 < min <= workingScale <= max <= 1
  double maxWorkingScale = 1.0;
  // With workingGsd_m > 0: a working pixel may grow up to this many metres when a coarser rung
  // than the height's needs fewer detector tiles (fewerTilesRung; the detector is trained on
  // 0.08-0.18 m working pixels). 0: always the height's rung. 0 or [workingGsd_m, 1] m.
  double maxWorkingGsd_m = 0.15;
  int networkWidth_px = 672;  // detector input (must equal the model's input)
  int networkHeight_px = 512;
  int tileOverlap_px = 96;  // working px, >= the longest vehicle at the working scale
  int padValue = 128;       // 8-bit grey of the padding (the networks' mean: input 0)
  int threads = 1;          // row-loop threads (1 = the caller's thread), [1, 16]
};

// Checks ranges; false with a message naming the option otherwise.
bool validate(const PreprocessOptions& options, std::string* why);

// Frame <-> working pixels (pixel-centre convention, docs/conventions.md):
// working = (frame + 0.5) * scale - 0.5, as tools/detector/evaluate.py maps detections back.
struct FrameGeometry {
  int frameWidth_px = 0;
  int frameHeight_px = 0;
  int workingWidth_px = 0;  // round(frame * workingScale): the scaled content, no padding
  int workingHeight_px = 0;
  double scaleX = 1.0;  // workingWidth_px / frameWidth_px
  double scaleY = 1.0;
  double workingToFrameU(double u) const { return (u + 0.5) / scaleX - 0.5; }
  double workingToFrameV(double v) const { return (v + 0.5) / scaleY - 0.5; }
};

// One detector input: a network-sized window of the working image.
struct TileView {
  const std::uint8_t* data = nullptr;  // BGR interleaved, first pixel of the tile
  std::size_t strideBytes = 0;         // bytes between rows
  TileRect rect{};                     // placement in the working image, inner edges
  int index = 0;
};

struct PreprocessTimings {
  double undistort_ms = 0.0;
  // The white balance's and the exposure's gains (and, after undistortion only, their
  // application in place).
  double whiteBalance_ms = 0.0;
  double resize_ms = 0.0;  // the resize sweep (with the gains applied on the way in)
  double total_ms = 0.0;
};

struct PreprocessedFrame {
  cv::Mat frame;  // corrected full-resolution BGR frame (detections live in its pixels)
  FrameGeometry geometry{};
  std::span<const TileView> tiles;
  WhiteBalanceGains whiteBalance{};  // gains of this frame (found = false when AWB is off)
  ExposureGain exposure{};           // this frame's exposure gain (1 when off or not dark)
  // The gain `frame`'s pixels still need to match the working image: exposure.gain when the
  // gain went into the working image only (no white balance, no undistortion), else 1.
  float frameGain = 1.0F;
  PreprocessTimings timings{};
};

// A camera frame in one of the V4L2 layouts, for the direct camera path (a view: the caller's
// buffers; yuv_rows.hpp gives the colour conversion).
struct YuvFrame {
  enum class Layout { Yuyv, Nv12 };
  Layout layout = Layout::Yuyv;
  const std::uint8_t* data = nullptr;  // YUYV pixels (2 bytes each), or NV12's Y plane
  std::size_t strideBytes = 0;         // bytes between rows (V4L2 bytesperline)
  const std::uint8_t* uv = nullptr;    // NV12: the interleaved U V plane, half the rows
  std::size_t uvStrideBytes = 0;
  int width_px = 0;
  int height_px = 0;
};

enum class PreprocessStatus {
  Ok,
  NotInitialised,
  EmptyFrame,
  WrongFrameType,  // not 8-bit, 3 channels
  WrongFrameSize,  // not the size given to init()
  FrameIsOutput,   // the frame aliases the preprocessor's own buffer
};
const char* toString(PreprocessStatus status);

class Preprocessor {
 public:
  Preprocessor() = default;
  Preprocessor(const Preprocessor&) = delete;
  Preprocessor& operator=(const Preprocessor&) = delete;

  // Start-up: validates the options, checks that frameSize equals the camera model's image
  // size, builds the undistortion map, the resize tables and the tile layout, and allocates
  // every buffer. False with *why naming the problem.
  bool init(const PreprocessOptions& options, const camera::CameraModel& camera, cv::Size frameSize,
            std::string* why = nullptr);
  bool initialised() const { return initialised_; }

  // Real-time path: no allocation, no exceptions.
  PreprocessStatus process(const cv::Mat& bgrFrame);
  // The direct camera path: the working image straight from the camera's YUYV or NV12 buffer,
  // each row converted to BGR (as the capture's full-frame conversion does, byte for byte)
  // inside the resize sweep, so no full-size BGR frame is made. The tiles equal those of
  // process() on the converted frame; output().frame is empty (nothing downstream may read
  // full-resolution BGR: no crops, no annotated video). Only without undistortion and white
  // balance (both need the full BGR frame): otherwise WrongFrameType, as for an odd width, a
  // missing UV plane or rows shorter than the width; WrongFrameSize for another size.
  PreprocessStatus process(const YuvFrame& frame);

  const PreprocessedFrame& output() const { return output_; }
  // The camera of output().frame: pinhole when undistortion runs, else the input camera.
  const camera::CameraModel& frameCamera() const { return frameCamera_; }
  const PreprocessOptions& options() const { return options_; }
  std::size_t tileCount() const { return rungs_.empty() ? 0 : rungs_[rung_].tileCount; }

  // The working scale from now on: with workingGsd_m > 0, the ladder's rung for a frame of
  // frameGsd_m metres per pixel (chooseRung: it moves only beyond the hysteresis); true when
  // the scale changed. No-op (false) with workingGsd_m = 0 or a non-positive GSD. Real-time
  // path: no allocation (every rung is built at init()).
  bool adaptToGsd(double frameGsd_m);
  double workingScale() const { return rungs_.empty() ? 0.0 : rungs_[rung_].scale; }
  // Every scale adaptToGsd() can choose, ascending (one entry with workingGsd_m = 0).
  std::span<const double> workingScales() const { return {scales_.data(), rungs_.size()}; }
  bool undistorts() const { return remapActive_; }
  // Message of the last refused frame ("" after a good one).
  const char* lastError() const { return lastError_.data(); }

 private:
  bool initialised_ = false;
  bool remapActive_ = false;
  PreprocessOptions options_{};
  camera::CameraModel frameCamera_{};
  cv::Size frameSize_{};
  FrameRemap remap_{};
  WhiteBalancer balancer_{};
  // One working scale: its resize tables, geometry and tiles over the shared working image.
  struct Rung {
    double scale = 0.0;
    FrameGeometry geometry{};
    AreaResizer resizer{};
    cv::Mat content;  // view: the scaled frame inside working_
    std::array<TileView, kMaxTiles> tiles{};
    std::size_t tileCount = 0;
  };
  bool buildRung(Rung& rung, double scale, std::string* why);
  void resize(const ResizeSource& source, const std::array<float, 3>* gains, cv::Mat* gained);
  void selectRung(std::size_t index);

  RowParallel parallel_{};
  cv::Mat corrected_;  // owned full-resolution frame (undistortion / white balance output)
  cv::Mat working_;    // working image incl. padding, sized for the largest rung
  std::array<float, 3> gains_{1.0F, 1.0F, 1.0F};  // this frame's white-balance gains
  std::vector<Rung> rungs_;
  std::array<double, kMaxScaleRungs> scales_{};
  std::size_t rung_ = 0;       // the rung in use
  std::size_t idealRung_ = 0;  // the height's rung (chooseRung's state); rung_ may be coarser
  std::array<std::size_t, kMaxScaleRungs> runRung_{};  // per height's rung: the rung run

  PreprocessedFrame output_{};
  std::array<char, 200> lastError_{};
};

}  // namespace vp::preprocess
