// shape/mesh_builder (internal to shape and the simulator's car generator): the few triangle
// patterns the car and large-vehicle meshes are made of, written once so that every mesh gets the
// same outward winding.
//
// Contract: a body is a side profile (a simple polygon in the x-z plane, its vertices listed
// counter-clockwise in (x, z), i.e. up the front, back over the roof, down the rear, forward
// under the floor) that exists once on the left (y > 0) and once on the right (y < 0) side.
// side() takes a triangle of profile vertices in that counter-clockwise order and emits it on
// both sides with outward normals (+y on the left, -y on the right); strip() closes the body
// between the two copies of a profile edge a -> b; lightStrip() does the same with two inner
// vertices that cut a light (head or tail) into each corner of the strip. With these the mesh
// is closed and every edge is shared by exactly two triangles of opposite orientation.
#pragma once

#include <cstdint>
#include <vector>

#include "shape/vehicle_model.hpp"

namespace vp::shape::detail {

// Indices of one profile vertex on the left and on the right side.
struct Pair {
  int left = 0;
  int right = 0;
};

class MeshBuilder {
 public:
  explicit MeshBuilder(std::vector<Triangle>* out) : out_(out) {}

  void side(Pair a, Pair b, Pair c, SurfacePart part) {
    add(c.left, b.left, a.left, part);  // the left side is seen from +y: reversed in (x, z)
    add(a.right, b.right, c.right, part);
  }

  void strip(Pair a, Pair b, SurfacePart part) {
    add(a.left, b.left, b.right, part);
    add(a.left, b.right, a.right, part);
  }

  // inner.left / inner.right lie inside the strip near its left / right end.
  void lightStrip(Pair a, Pair b, Pair inner, SurfacePart light, SurfacePart rest) {
    add(a.left, b.left, inner.left, light);
    add(inner.right, b.right, a.right, light);
    add(inner.left, b.left, b.right, rest);
    add(inner.left, b.right, inner.right, rest);
    add(a.left, inner.left, inner.right, rest);
    add(a.left, inner.right, a.right, rest);
  }

 private:
  void add(int a, int b, int c, SurfacePart part) {
    out_->push_back(Triangle{{static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(b),
                              static_cast<std::uint16_t>(c)},
                             part});
  }

  std::vector<Triangle>* out_;
};

}  // namespace vp::shape::detail
