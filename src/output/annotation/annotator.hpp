// annotation/annotator: draws a frame's vehicle observations onto its image, for operators,
// recordings and reports, in the style of seed 000's Figure 3.
//
// Contract: Annotator::init() checks the style, lists the ASM mesh's edges and pre-renders a
// glyph atlas of the printable ASCII characters with cv::putText (start-up only). The draw
// calls then write into a caller-owned 8-bit BGR cv::Mat in place and never allocate: boxes,
// arrows and the wireframe are drawn with cv::line, anti-aliased when 1 px wide and
// 8-connected when thicker (OpenCV's thick anti-aliased lines and cv::circle allocate; see
// docs/perception.md "Annotated output" for the measured counts), and text is blended from
// the atlas, because cv::putText allocates on every call. Per observation: the rotated image box
// (green when lifted to the world, orange when not), the driving direction as an arrow from the box
// centre to its front edge (yellow; a grey axis line without a head when front and back are
// undecided), a label "type NN%" with the most likely type and its probability, followed by "#id"
// when a track id is given and by the lift status when not lifted (white on black, above the box),
// and, when a camera pose is given and the observation has keypoints, the ASM wireframe: every mesh
// edge between two keypoints projected with Lifter::worldToPixel (red, as in Fig. 3), plus the
// rear-axle point (magenta dot). Drawing is clipped to the image; nothing is drawn outside the
// rectangle that drawObservation() returns. Colours are BGR constants below.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "lifting/lifting.hpp"
#include "perception/detection_lifter.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::annotation {

struct Bgr {
  std::uint8_t b = 0;
  std::uint8_t g = 0;
  std::uint8_t r = 0;
};

constexpr Bgr kLiftedBoxColour{0, 220, 0};             // green: placed in the world
constexpr Bgr kNotLiftedBoxColour{0, 140, 255};        // orange: image only (pose / DTM status)
constexpr Bgr kDirectionColour{0, 255, 255};           // yellow arrow: driving direction
constexpr Bgr kUnknownDirectionColour{160, 160, 160};  // grey axis: front/back undecided
constexpr Bgr kWireframeColour{0, 0, 255};             // red: back-projected ASM (seed 000, Fig. 3)
constexpr Bgr kRearAxleColour{255, 0, 255};            // magenta: rear-axle reference point
constexpr Bgr kLabelTextColour{255, 255, 255};         // white text
constexpr Bgr kLabelBackgroundColour{0, 0, 0};         // on black

struct AnnotationStyle {
  int lineThickness_px = 2;       // boxes and arrows, 1..8
  int wireframeThickness_px = 1;  // ASM edges, 1..8
  double fontScale = 0.5;         // cv::FONT_HERSHEY_SIMPLEX scale, 0.2..4
  bool drawLabels = true;
  bool drawWireframe = true;
};

// Upper bound on the mesh's distinct edges (each triangle adds at most three).
constexpr int kMaxWireframeEdges = 3 * 64;
constexpr int kMaxLabelChars = 63;  // longer labels are cut

class Annotator {
 public:
  Annotator() = default;

  bool init(const AnnotationStyle& style, std::string* why = nullptr);

  // Draws every observation. trackIds: empty, or one per observation (< 0 = none). lifter and
  // cameraPose (the frame's, e.g. FrameLiftSummary::cameraPose) are needed for the wireframe
  // and the rear-axle dot; pass nullptr to skip them. Returns false (drawing nothing) when
  // the image is not a non-empty CV_8UC3 Mat, trackIds has the wrong size, or init() failed.
  bool drawFrame(cv::Mat& image, std::span<const perception::VehicleObservation> observations,
                 std::span<const int> trackIds, const lifting::Lifter* lifter,
                 const lifting::CameraPoseWorld* cameraPose) const;

  // Draws one observation; returns the rectangle (image coordinates, clipped to the image)
  // that holds everything drawn, empty when nothing was drawn or the image is unusable.
  cv::Rect drawObservation(cv::Mat& image, const perception::VehicleObservation& observation,
                           int trackId, const lifting::Lifter* lifter,
                           const lifting::CameraPoseWorld* cameraPose) const;

  // Blends text from the glyph atlas with its top-left corner at `topLeft`; returns the
  // rectangle it covers (before clipping). Characters outside printable ASCII draw as '?'.
  cv::Rect drawText(cv::Mat& image, const char* text, cv::Point topLeft, Bgr colour) const;
  // Size of text drawn by drawText(), px.
  cv::Size textSize(const char* text) const;

 private:
  static constexpr int kFirstGlyph = 32;  // ' '
  static constexpr int kGlyphCount = 95;  // ' ' .. '~'

  AnnotationStyle style_{};
  bool initialised_ = false;
  std::array<std::array<std::uint8_t, 2>, kMaxWireframeEdges> edges_{};
  int edgeCount_ = 0;
  cv::Mat atlas_;  // CV_8UC1 coverage, kGlyphCount cells of glyphCellWidth_ x glyphHeight_
  std::array<int, kGlyphCount> glyphWidth_{};
  int glyphCellWidth_ = 0;
  int glyphHeight_ = 0;
};

}  // namespace vp::annotation
