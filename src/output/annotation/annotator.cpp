#include "annotation/annotator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "geometry/rotated_box.hpp"

namespace vp::annotation {

namespace {

constexpr int kShiftBits = 4;  // cv::line fixed-point fraction bits: 1/16 px positions
constexpr double kShiftScale = 1 << kShiftBits;
constexpr double kMaxCoordinate_px = 30000.0;  // keeps the fixed-point coordinates in int range
constexpr int kRearAxleDotRadius_px = 3;
constexpr double kArrowHeadShare = 0.3;  // arrow head length / arrow length
constexpr int kLabelGap_px = 2;          // between the box and its label

cv::Scalar scalar(Bgr c) {
  return {double(c.b), double(c.g), double(c.r)};
}

bool usable(const Eigen::Vector2d& p) {
  return p.allFinite();
}

cv::Point fixedPoint(const Eigen::Vector2d& p) {
  const double x = std::clamp(p.x(), -kMaxCoordinate_px, kMaxCoordinate_px);
  const double y = std::clamp(p.y(), -kMaxCoordinate_px, kMaxCoordinate_px);
  return {static_cast<int>(std::lround(x * kShiftScale)),
          static_cast<int>(std::lround(y * kShiftScale))};
}

// Grows `bounds` by the segment a-b drawn `thickness` wide (anti-aliasing adds a pixel).
void extend(cv::Rect2d& bounds, const Eigen::Vector2d& a, const Eigen::Vector2d& b, int thickness) {
  const double pad = 0.5 * thickness + 2.0;
  const double x0 = std::min(a.x(), b.x()) - pad;
  const double y0 = std::min(a.y(), b.y()) - pad;
  const double x1 = std::max(a.x(), b.x()) + pad;
  const double y1 = std::max(a.y(), b.y()) + pad;
  if (bounds.width <= 0.0) {
    bounds = cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
    return;
  }
  const double bx1 = std::max(bounds.x + bounds.width, x1);
  const double by1 = std::max(bounds.y + bounds.height, y1);
  bounds.x = std::min(bounds.x, x0);
  bounds.y = std::min(bounds.y, y0);
  bounds.width = bx1 - bounds.x;
  bounds.height = by1 - bounds.y;
}

void drawSegment(cv::Mat& image, const Eigen::Vector2d& a, const Eigen::Vector2d& b, Bgr colour,
                 int thickness, cv::Rect2d& bounds) {
  if (!usable(a) || !usable(b)) {
    return;
  }
  // Anti-aliased lines only 1 px wide: OpenCV 4.6 draws the round caps of thicker
  // anti-aliased lines through ellipse2Poly into a std::vector (16 allocations per line,
  // measured in tests/annotation); thick 8-connected lines allocate nothing.
  const int lineType = thickness == 1 ? cv::LINE_AA : cv::LINE_8;
  cv::line(image, fixedPoint(a), fixedPoint(b), scalar(colour), thickness, lineType, kShiftBits);
  extend(bounds, a, b, thickness);
}

cv::Rect clipped(const cv::Rect2d& bounds, const cv::Mat& image) {
  if (bounds.width <= 0.0) {
    return {};
  }
  const int x0 = static_cast<int>(std::floor(std::max(bounds.x, 0.0)));
  const int y0 = static_cast<int>(std::floor(std::max(bounds.y, 0.0)));
  const int x1 = static_cast<int>(
      std::ceil(std::min(bounds.x + bounds.width, static_cast<double>(image.cols))));
  const int y1 = static_cast<int>(
      std::ceil(std::min(bounds.y + bounds.height, static_cast<double>(image.rows))));
  if (x1 <= x0 || y1 <= y0) {
    return {};
  }
  return {x0, y0, x1 - x0, y1 - y0};
}

}  // namespace

bool Annotator::init(const AnnotationStyle& style, std::string* why) {
  const auto fail = [why](const std::string& message) {
    if (why != nullptr) {
      *why = "annotator: " + message;
    }
    return false;
  };
  initialised_ = false;
  if (style.lineThickness_px < 1 || style.lineThickness_px > 8) {
    return fail("lineThickness_px must be in 1..8, got " + std::to_string(style.lineThickness_px));
  }
  if (style.wireframeThickness_px < 1 || style.wireframeThickness_px > 8) {
    return fail("wireframeThickness_px must be in 1..8, got " +
                std::to_string(style.wireframeThickness_px));
  }
  if (!(style.fontScale >= 0.2 && style.fontScale <= 4.0)) {
    return fail("fontScale must be in 0.2..4, got " + std::to_string(style.fontScale));
  }
  style_ = style;

  // Distinct mesh edges (each interior edge is shared by two triangles).
  std::map<std::pair<int, int>, bool> seen;
  edgeCount_ = 0;
  for (const shape::Triangle& t : shape::mesh()) {
    for (int i = 0; i < 3; ++i) {
      const int a = t.v[static_cast<std::size_t>(i)];
      const int b = t.v[static_cast<std::size_t>((i + 1) % 3)];
      const std::pair<int, int> key = a < b ? std::make_pair(a, b) : std::make_pair(b, a);
      if (seen.emplace(key, true).second) {
        if (edgeCount_ == kMaxWireframeEdges) {
          return fail("the mesh has more than kMaxWireframeEdges edges");
        }
        edges_[static_cast<std::size_t>(edgeCount_++)] = {static_cast<std::uint8_t>(key.first),
                                                          static_cast<std::uint8_t>(key.second)};
      }
    }
  }

  // Glyph atlas: one cell per printable character, coverage 0..255 (anti-aliased).
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  int baseline = 0;
  const cv::Size tall = cv::getTextSize("Ag|", font, style.fontScale, 1, &baseline);
  glyphHeight_ = tall.height + baseline + 2;
  glyphCellWidth_ = 0;
  for (int g = 0; g < kGlyphCount; ++g) {
    const std::string text(1, static_cast<char>(kFirstGlyph + g));
    const cv::Size size = cv::getTextSize(text, font, style.fontScale, 1, &baseline);
    glyphWidth_[static_cast<std::size_t>(g)] = size.width + 1;
    glyphCellWidth_ = std::max(glyphCellWidth_, size.width + 2);
  }
  atlas_ = cv::Mat::zeros(glyphHeight_, glyphCellWidth_ * kGlyphCount, CV_8UC1);
  for (int g = 0; g < kGlyphCount; ++g) {
    cv::Mat cell = atlas_.colRange(g * glyphCellWidth_, (g + 1) * glyphCellWidth_);
    cv::putText(cell, std::string(1, static_cast<char>(kFirstGlyph + g)),
                cv::Point(0, tall.height + 1), font, style.fontScale, cv::Scalar(255), 1,
                cv::LINE_AA);
  }
  initialised_ = true;
  return true;
}

cv::Size Annotator::textSize(const char* text) const {
  int width = 0;
  for (int i = 0; text[i] != '\0' && i < kMaxLabelChars; ++i) {
    int g = static_cast<unsigned char>(text[i]) - kFirstGlyph;
    if (g < 0 || g >= kGlyphCount) {
      g = '?' - kFirstGlyph;
    }
    width += glyphWidth_[static_cast<std::size_t>(g)];
  }
  return {width, glyphHeight_};
}

cv::Rect Annotator::drawText(cv::Mat& image, const char* text, cv::Point topLeft,
                             Bgr colour) const {
  if (!initialised_ || image.empty() || image.type() != CV_8UC3) {
    return {};
  }
  int x = topLeft.x;
  for (int i = 0; text[i] != '\0' && i < kMaxLabelChars; ++i) {
    int g = static_cast<unsigned char>(text[i]) - kFirstGlyph;
    if (g < 0 || g >= kGlyphCount) {
      g = '?' - kFirstGlyph;
    }
    const int width = glyphWidth_[static_cast<std::size_t>(g)];
    for (int row = 0; row < glyphHeight_; ++row) {
      const int y = topLeft.y + row;
      if (y < 0 || y >= image.rows) {
        continue;
      }
      const std::uint8_t* coverage = atlas_.ptr<std::uint8_t>(row) + g * glyphCellWidth_;
      cv::Vec3b* pixels = image.ptr<cv::Vec3b>(y);
      for (int col = 0; col < width; ++col) {
        const int px = x + col;
        const int a = coverage[col];
        if (a == 0 || px < 0 || px >= image.cols) {
          continue;
        }
        cv::Vec3b& p = pixels[px];
        p[0] = static_cast<std::uint8_t>((p[0] * (255 - a) + colour.b * a + 127) / 255);
        p[1] = static_cast<std::uint8_t>((p[1] * (255 - a) + colour.g * a + 127) / 255);
        p[2] = static_cast<std::uint8_t>((p[2] * (255 - a) + colour.r * a + 127) / 255);
      }
    }
    x += width;
  }
  return {topLeft.x, topLeft.y, x - topLeft.x, glyphHeight_};
}

cv::Rect Annotator::drawObservation(cv::Mat& image,
                                    const perception::VehicleObservation& observation, int trackId,
                                    const lifting::Lifter* lifter,
                                    const lifting::CameraPoseWorld* cameraPose) const {
  if (!initialised_ || image.empty() || image.type() != CV_8UC3) {
    return {};
  }
  const geometry::RotatedBox& box = observation.detection.box;
  if (!std::isfinite(box.cx) || !std::isfinite(box.cy) || !std::isfinite(box.angle) ||
      !std::isfinite(box.length) || !std::isfinite(box.width)) {
    return {};
  }
  const bool lifted = observation.liftStatus == perception::LiftStatus::Ok;
  cv::Rect2d bounds(0.0, 0.0, 0.0, 0.0);

  // ASM wireframe first, so the box and the arrow stay visible on top of it.
  if (style_.drawWireframe && lifted && observation.hasKeypoints && lifter != nullptr &&
      cameraPose != nullptr) {
    std::array<Eigen::Vector2d, shape::kKeypointCount> pixels;
    for (int k = 0; k < shape::kKeypointCount; ++k) {
      const auto p = lifter->worldToPixel(*cameraPose, observation.keypointsEnu.col(k));
      pixels[static_cast<std::size_t>(k)] = p ? *p : Eigen::Vector2d(std::nan(""), std::nan(""));
    }
    for (int e = 0; e < edgeCount_; ++e) {
      const auto& edge = edges_[static_cast<std::size_t>(e)];
      drawSegment(image, pixels[edge[0]], pixels[edge[1]], kWireframeColour,
                  style_.wireframeThickness_px, bounds);
    }
  }
  if (lifted && observation.hasRearAxle && lifter != nullptr && cameraPose != nullptr) {
    const auto p = lifter->worldToPixel(*cameraPose, observation.rearAxleEnu);
    if (p && p->allFinite()) {
      // A closed 1 px-wide ring of short segments: cv::circle with a thickness allocates.
      constexpr int kSegments = 8;
      for (int i = 0; i < kSegments; ++i) {
        const double a0 = geometry::kTwoPi * i / kSegments;
        const double a1 = geometry::kTwoPi * (i + 1) / kSegments;
        const Eigen::Vector2d q0 =
            *p + kRearAxleDotRadius_px * Eigen::Vector2d(std::cos(a0), std::sin(a0));
        const Eigen::Vector2d q1 =
            *p + kRearAxleDotRadius_px * Eigen::Vector2d(std::cos(a1), std::sin(a1));
        drawSegment(image, q0, q1, kRearAxleColour, 2, bounds);
      }
    }
  }

  // Rotated box.
  const std::array<Eigen::Vector2d, 4> corners = geometry::corners(box);
  const Bgr boxColour = lifted ? kLiftedBoxColour : kNotLiftedBoxColour;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    drawSegment(image, corners[i], corners[(i + 1) % corners.size()], boxColour,
                style_.lineThickness_px, bounds);
  }

  // Driving direction: centre -> middle of the front edge.
  const Eigen::Vector2d centre(box.cx, box.cy);
  const Eigen::Vector2d front = 0.5 * (corners[0] + corners[1]);
  if (observation.detection.directionKnown) {
    drawSegment(image, centre, front, kDirectionColour, style_.lineThickness_px, bounds);
    const Eigen::Vector2d back = (centre - front) * kArrowHeadShare;
    const Eigen::Vector2d side(-back.y(), back.x());
    drawSegment(image, front, front + back + 0.5 * side, kDirectionColour, style_.lineThickness_px,
                bounds);
    drawSegment(image, front, front + back - 0.5 * side, kDirectionColour, style_.lineThickness_px,
                bounds);
  } else {
    const Eigen::Vector2d rear = 0.5 * (corners[2] + corners[3]);
    drawSegment(image, rear, front, kUnknownDirectionColour, style_.lineThickness_px, bounds);
  }

  // Label above the box's top corner (below it when that leaves the image).
  if (style_.drawLabels) {
    float probability = 0.0F;
    const shape::VehicleType type = perception::mostLikelyType(observation.detection, &probability);
    char text[kMaxLabelChars + 1];
    int n = std::snprintf(text, sizeof(text), "%s %d%%", shape::toString(type),
                          static_cast<int>(std::lround(100.0 * static_cast<double>(probability))));
    if (trackId >= 0 && n > 0 && n < kMaxLabelChars) {
      n += std::snprintf(text + n, sizeof(text) - static_cast<std::size_t>(n), " #%d", trackId);
    }
    if (!lifted && n > 0 && n < kMaxLabelChars) {
      std::snprintf(text + n, sizeof(text) - static_cast<std::size_t>(n), " [%s]",
                    perception::toString(observation.liftStatus));
    }
    double minX = corners[0].x();
    double minY = corners[0].y();
    double maxY = corners[0].y();
    for (const Eigen::Vector2d& c : corners) {
      minX = std::min(minX, c.x());
      minY = std::min(minY, c.y());
      maxY = std::max(maxY, c.y());
    }
    const cv::Size size = textSize(text);
    const double pad = 0.5 * style_.lineThickness_px + kLabelGap_px;
    double top = minY - pad - size.height;
    if (top < 0.0) {
      top = maxY + pad;
    }
    const cv::Point topLeft(
        static_cast<int>(std::lround(std::clamp(minX, -kMaxCoordinate_px, kMaxCoordinate_px))),
        static_cast<int>(std::lround(std::clamp(top, -kMaxCoordinate_px, kMaxCoordinate_px))));
    // Black background, then the text.
    const cv::Rect area = clipped(cv::Rect2d(topLeft.x, topLeft.y, size.width, size.height), image);
    for (int y = area.y; y < area.y + area.height; ++y) {
      cv::Vec3b* row = image.ptr<cv::Vec3b>(y);
      for (int x = area.x; x < area.x + area.width; ++x) {
        row[x] =
            cv::Vec3b(kLabelBackgroundColour.b, kLabelBackgroundColour.g, kLabelBackgroundColour.r);
      }
    }
    drawText(image, text, topLeft, kLabelTextColour);
    extend(bounds, Eigen::Vector2d(topLeft.x, topLeft.y),
           Eigen::Vector2d(topLeft.x + size.width, topLeft.y + size.height), 0);
  }
  return clipped(bounds, image);
}

bool Annotator::drawFrame(cv::Mat& image,
                          std::span<const perception::VehicleObservation> observations,
                          std::span<const int> trackIds, const lifting::Lifter* lifter,
                          const lifting::CameraPoseWorld* cameraPose) const {
  if (!initialised_ || image.empty() || image.type() != CV_8UC3 ||
      (!trackIds.empty() && trackIds.size() != observations.size())) {
    return false;
  }
  for (std::size_t i = 0; i < observations.size(); ++i) {
    drawObservation(image, observations[i], trackIds.empty() ? -1 : trackIds[i], lifter,
                    cameraPose);
  }
  return true;
}

}  // namespace vp::annotation
