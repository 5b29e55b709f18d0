// geometry/rotated_box: rotated boxes in the image plane, their exact overlap, rotated NMS
// and angle arithmetic that respects the full circle.
//
// Contract: a RotatedBox is a centre (px), a length along the driving direction, a width
// across it, and the angle of the forward (driving) axis in [0, 2*pi) measured in the
// image from the +u axis towards +v (clockwise on screen, since v points down). The
// angle is never folded to 180 degrees: front and back differ. All functions are pure,
// allocation-free (NMS works in caller-owned spans) and thread-safe.
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <Eigen/Core>

namespace vp::geometry {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;

struct RotatedBox {
  double cx = 0.0;      // centre, px (or metres when used in a ground plane)
  double cy = 0.0;      // centre, px
  double length = 0.0;  // extent along the forward axis, > 0
  double width = 0.0;   // extent across the forward axis, > 0
  double angle = 0.0;   // forward axis angle, rad, in [0, 2*pi)
};

// The four corners: with f = (cos a, sin a) and n = (-sin a, cos a),
// [0] = c + L/2 f + W/2 n, [1] = c + L/2 f - W/2 n, [2] = c - L/2 f - W/2 n,
// [3] = c - L/2 f + W/2 n (front two first; a consistent winding).
std::array<Eigen::Vector2d, 4> corners(const RotatedBox& box);

// Area of the box (length * width).
double area(const RotatedBox& box);

// Half width and half height of the box's axis-aligned bounding box.
void axisAlignedHalfExtents(const RotatedBox& box, double* halfU, double* halfV);

// Exact area of the intersection of two rotated boxes (convex polygon clipping).
double intersectionArea(const RotatedBox& a, const RotatedBox& b);

// Exact intersection over union in [0, 1]; 0 when either box is degenerate.
double rotatedIou(const RotatedBox& a, const RotatedBox& b);

// Wraps any angle (rad) into [0, 2*pi).
double wrapTwoPi(double angle);

// Wraps any angle (rad) into (-pi, pi].
double wrapPi(double angle);

// Signed smallest rotation from b to a, rad, in (-pi, pi]: respects 360 degrees, so a box
// pointing backwards differs by pi.
double angleDifference(double a, double b);

// |angleDifference(a, b)| in [0, pi]: the full-circle error of a driving direction
// ("up to 180 degrees", the measure reports use).
double absAngleDifference(double a, double b);

// Difference of the box axes ignoring direction, rad, in [0, pi/2]: how well the box is
// aligned regardless of front/back (used in reports beside the full-circle error).
double axisAngleDifference(double a, double b);

// Greedy rotated non-maximum suppression.
// boxes/scores: the candidates (same size). order: scratch of the same size, owned by the
// caller. keep: receives indices of kept boxes, best first; returns how many were kept
// (at most keep.size()). A box is suppressed when its rotated IoU with an already kept
// box exceeds iouThreshold. No heap allocation.
std::size_t rotatedNms(std::span<const RotatedBox> boxes, std::span<const float> scores,
                       double iouThreshold, std::span<std::size_t> order,
                       std::span<std::size_t> keep);

}  // namespace vp::geometry
