// simulator/ground_texture: the procedural albedo of the ground (roads, markings, kerbs,
// pavements, parking lots, grass and soil) as a function of the world position.
//
// Contract: albedo() is a pure function of the ENU ground position (x, y) and the scene spec,
// so the texture is identical in every frame and from every thread. Values are linear
// reflectances in [0, 1]. Road-local features (lanes, wheel tracks, markings, slab joints)
// are laid out in each road's (along, lateral) coordinates; irregular features (tone,
// cracks, stains, grass) come from value noise seeded by the scene's style seed.
#pragma once

#include <Eigen/Core>

#include "scene.hpp"

namespace vp::sim {

enum class GroundClass { Road, Lot, Kerb, Sidewalk, Verge };

class GroundTexture {
 public:
  explicit GroundTexture(const SceneSpec& scene) : scene_(&scene) {}

  Eigen::Vector3f albedo(double x, double y, GroundClass* cls = nullptr) const;

 private:
  float roadTone(const Eigen::Vector2d& p, const Road* road, double along, double lateral,
                 bool inJunction) const;
  // Coverage [0, 1] of painted markings of one road at (along, lateral); *yellow set when the
  // marking is yellow.
  float roadMarkings(const Road& road, double along, double lateral, bool* yellow) const;
  float lotMarkings(const ParkingLot& lot, const Eigen::Vector2d& p) const;
  Eigen::Vector3f sidewalk(const Eigen::Vector2d& p, double kerbDistance) const;
  Eigen::Vector3f verge(const Eigen::Vector2d& p) const;

  const SceneSpec* scene_;
};

}  // namespace vp::sim
