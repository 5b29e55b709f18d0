// Rotated boxes: exact overlap by convex clipping, greedy rotated NMS, angle arithmetic.
//
// Numerical approach: the intersection is computed in the local frame of the larger box b
// (origin at its centre, axes along its forward and side axes). There b is the rectangle
// |x| <= L/2, |y| <= W/2, so clipping against its four half-planes needs no rotation of the
// clip lines, and translating first removes the cancellation that large pixel or metre
// coordinates would otherwise cause in the cross products. Everything lives in fixed-size
// stack arrays: nothing here allocates.
#include "geometry/rotated_box.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vp::geometry {
namespace {

// A convex polygon of at most 8 vertices: clipping a quadrilateral against one half-plane
// adds at most one vertex, so four clips take 4 vertices to at most 8.
constexpr int kMaxPolygonVertices = 8;

struct Point {
  double x;
  double y;
};

struct Polygon {
  std::array<Point, kMaxPolygonVertices> v{};
  int n = 0;
};

bool isDegenerate(const RotatedBox& box) {
  // !(x > 0) also rejects NaN; an area that underflows to 0 is as useless as a zero side.
  return !(box.length > 0.0) || !(box.width > 0.0) || !std::isfinite(box.length) ||
         !std::isfinite(box.width) || !std::isfinite(box.cx) || !std::isfinite(box.cy) ||
         !std::isfinite(box.angle) || !(box.length * box.width > 0.0);
}

// Keeps the part of `in` whose coordinate `axis` (0 = x, 1 = y) times `sign` is at most
// `limit` (Sutherland-Hodgman for one axis-aligned half-plane). A vertex within `eps` of the
// line counts as inside: it is then not replaced by a computed intersection point, which
// keeps shared edges of touching or identical boxes from producing near-duplicate vertices.
void clipHalfPlane(const Polygon& in, int axis, double sign, double limit, double eps,
                   Polygon& out) {
  out.n = 0;
  if (in.n == 0) {
    return;
  }
  auto coord = [axis, sign](const Point& p) { return sign * (axis == 0 ? p.x : p.y); };
  Point prev = in.v[static_cast<std::size_t>(in.n - 1)];
  double prevD = coord(prev) - limit;
  for (int i = 0; i < in.n; ++i) {
    const Point cur = in.v[static_cast<std::size_t>(i)];
    const double curD = coord(cur) - limit;
    const bool prevIn = prevD <= eps;
    const bool curIn = curD <= eps;
    if (prevIn != curIn) {
      // One distance is <= eps and the other > eps, so the denominator is nonzero. When the
      // inside vertex lies in (0, eps] the true crossing is just outside the edge: clamping
      // t gives that vertex again (then snapped onto the line), a harmless duplicate.
      const double t = std::clamp(prevD / (prevD - curD), 0.0, 1.0);
      Point p{prev.x + t * (cur.x - prev.x), prev.y + t * (cur.y - prev.y)};
      // Put the new vertex exactly on the clip line rather than where rounding left it.
      (axis == 0 ? p.x : p.y) = sign * limit;
      if (out.n < kMaxPolygonVertices) {
        out.v[static_cast<std::size_t>(out.n++)] = p;
      }
    }
    if (curIn && out.n < kMaxPolygonVertices) {
      out.v[static_cast<std::size_t>(out.n++)] = cur;
    }
    prev = cur;
    prevD = curD;
  }
}

double shoelace(const Polygon& poly) {
  if (poly.n < 3) {
    return 0.0;
  }
  // Relative to the first vertex: the cross products then involve edge-sized numbers only.
  const Point o = poly.v[0];
  double twice = 0.0;
  for (int i = 1; i + 1 < poly.n; ++i) {
    const Point a = poly.v[static_cast<std::size_t>(i)];
    const Point b = poly.v[static_cast<std::size_t>(i + 1)];
    twice += (a.x - o.x) * (b.y - o.y) - (b.x - o.x) * (a.y - o.y);
  }
  return 0.5 * std::abs(twice);
}

// Absolute area error the vertices' rounding can cause: each vertex is off by a few ulps of
// the largest coordinate, which moves the area by that much times the perimeter.
double roundingNoise(const Polygon& poly) {
  double maxCoord = 0.0;
  double perimeter = 0.0;
  for (int i = 0; i < poly.n; ++i) {
    const Point a = poly.v[static_cast<std::size_t>(i)];
    const Point b = poly.v[static_cast<std::size_t>((i + 1) % poly.n)];
    maxCoord = std::max({maxCoord, std::abs(a.x), std::abs(a.y)});
    perimeter += std::hypot(b.x - a.x, b.y - a.y);
  }
  return 8.0 * std::numeric_limits<double>::epsilon() * maxCoord * perimeter;
}

}  // namespace

std::array<Eigen::Vector2d, 4> corners(const RotatedBox& box) {
  const Eigen::Vector2d c(box.cx, box.cy);
  const Eigen::Vector2d f(std::cos(box.angle), std::sin(box.angle));
  const Eigen::Vector2d n(-f.y(), f.x());
  const Eigen::Vector2d hf = 0.5 * box.length * f;
  const Eigen::Vector2d hn = 0.5 * box.width * n;
  return {c + hf + hn, c + hf - hn, c - hf - hn, c - hf + hn};
}

double area(const RotatedBox& box) {
  return box.length * box.width;
}

void axisAlignedHalfExtents(const RotatedBox& box, double* halfU, double* halfV) {
  const double c = std::abs(std::cos(box.angle));
  const double s = std::abs(std::sin(box.angle));
  *halfU = 0.5 * (box.length * c + box.width * s);
  *halfV = 0.5 * (box.length * s + box.width * c);
}

double intersectionArea(const RotatedBox& boxA, const RotatedBox& boxB) {
  if (isDegenerate(boxA) || isDegenerate(boxB)) {
    return 0.0;
  }
  // Clip the smaller box against the larger one's frame: the polygon being clipped then has
  // coordinates of its own size, so a tiny box inside a huge one keeps full relative
  // precision (the other way round, interpolating the huge box's edges would cost digits).
  const bool swap = area(boxA) > area(boxB);
  const RotatedBox& a = swap ? boxB : boxA;
  const RotatedBox& b = swap ? boxA : boxB;
  // Centre of a in b's frame.
  const double dx = a.cx - b.cx;
  const double dy = a.cy - b.cy;
  // Cheap rejection with circumscribed circles; also spares far-apart NMS candidates.
  const double ra = 0.5 * std::hypot(a.length, a.width);
  const double rb = 0.5 * std::hypot(b.length, b.width);
  if (std::hypot(dx, dy) >= ra + rb) {
    return 0.0;
  }
  const double cb = std::cos(b.angle);
  const double sb = std::sin(b.angle);
  const double ux = cb * dx + sb * dy;
  const double uy = -sb * dx + cb * dy;
  // a's axes relative to b's: only the angle difference matters, which keeps precision when
  // both angles are large but close.
  const double rel = a.angle - b.angle;
  const double cr = std::cos(rel);
  const double sr = std::sin(rel);
  const double hfx = 0.5 * a.length * cr;
  const double hfy = 0.5 * a.length * sr;
  const double hnx = -0.5 * a.width * sr;
  const double hny = 0.5 * a.width * cr;

  Polygon p;
  p.n = 4;
  p.v[0] = {ux + hfx + hnx, uy + hfy + hny};
  p.v[1] = {ux + hfx - hnx, uy + hfy - hny};
  p.v[2] = {ux - hfx - hnx, uy - hfy - hny};
  p.v[3] = {ux - hfx + hnx, uy - hfy + hny};

  // Scale-aware tolerance: a few ulps of the largest coordinate involved, so it means the
  // same for 1e-6 px boxes and 1e6 m boxes.
  const double scale = std::max({std::abs(ux), std::abs(uy), ra, rb});
  const double eps = 8.0 * std::numeric_limits<double>::epsilon() * scale;

  const double hl = 0.5 * b.length;
  const double hw = 0.5 * b.width;
  Polygon q;
  clipHalfPlane(p, 0, 1.0, hl, eps, q);
  clipHalfPlane(q, 0, -1.0, hl, eps, p);
  clipHalfPlane(p, 1, 1.0, hw, eps, q);
  clipHalfPlane(q, 1, -1.0, hw, eps, p);

  // An overlap below the rounding noise of its own vertices (the sliver that boxes which
  // merely touch leave) is not area. The noise is measured on the clipped polygon, not on
  // the boxes, so a tiny box nested in a huge one keeps its area.
  const double inter = shoelace(p);
  if (inter <= roundingNoise(p)) {
    return 0.0;
  }
  return std::min(inter, std::min(area(a), area(b)));
}

double rotatedIou(const RotatedBox& a, const RotatedBox& b) {
  if (isDegenerate(a) || isDegenerate(b)) {
    return 0.0;
  }
  const double inter = intersectionArea(a, b);
  const double uni = area(a) + area(b) - inter;
  if (!(uni > 0.0)) {
    return 0.0;
  }
  return std::clamp(inter / uni, 0.0, 1.0);
}

double wrapTwoPi(double angle) {
  double r = std::fmod(angle, kTwoPi);  // exact, in (-2pi, 2pi)
  if (r < 0.0) {
    r += kTwoPi;
  }
  // A tiny negative input (e.g. -1e-18) rounds to exactly 2pi after the addition.
  if (r >= kTwoPi) {
    r = 0.0;
  }
  return r;
}

double wrapPi(double angle) {
  // Already in range: return unchanged, so small negative differences keep their sign and
  // full precision instead of going round the circle.
  if (angle > -kPi && angle <= kPi) {
    return angle;
  }
  const double r = wrapTwoPi(angle);
  // For r in (pi, 2pi) the subtraction is exact (Sterbenz), so the result stays > -pi.
  return r > kPi ? r - kTwoPi : r;
}

double angleDifference(double a, double b) {
  return wrapPi(a - b);
}

double absAngleDifference(double a, double b) {
  return std::abs(angleDifference(a, b));
}

double axisAngleDifference(double a, double b) {
  const double d = absAngleDifference(a, b);
  return std::min(d, kPi - d);
}

// Sizes that disagree are not an error worth throwing for in the hot loop: only the first
// min(boxes.size(), scores.size(), order.size()) candidates are considered.
std::size_t rotatedNms(std::span<const RotatedBox> boxes, std::span<const float> scores,
                       double iouThreshold, std::span<std::size_t> order,
                       std::span<std::size_t> keep) {
  const std::size_t n = std::min({boxes.size(), scores.size(), order.size()});
  if (n == 0 || keep.empty()) {
    return 0;
  }
  for (std::size_t i = 0; i < n; ++i) {
    order[i] = i;
  }
  // Strict weak order even with NaN scores (they go last); ties keep the input order so the
  // result is deterministic.
  auto better = [scores](std::size_t i, std::size_t j) {
    const float si = scores[i];
    const float sj = scores[j];
    const bool nanI = std::isnan(si);
    const bool nanJ = std::isnan(sj);
    if (nanI != nanJ) {
      return nanJ;
    }
    if (!nanI && si != sj) {
      return si > sj;
    }
    return i < j;
  };
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), better);

  std::size_t kept = 0;
  for (std::size_t k = 0; k < n && kept < keep.size(); ++k) {
    const std::size_t cand = order[k];
    bool suppressed = false;
    for (std::size_t j = 0; j < kept; ++j) {
      if (rotatedIou(boxes[cand], boxes[keep[j]]) > iouThreshold) {
        suppressed = true;
        break;
      }
    }
    if (!suppressed) {
      keep[kept++] = cand;
    }
  }
  return kept;
}

}  // namespace vp::geometry
