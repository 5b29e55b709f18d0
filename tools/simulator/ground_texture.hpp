// simulator/ground_texture: the procedural albedo of the ground (roads, markings, kerbs,
// pavements, parking lots, grass and soil) as a function of the world position.
//
// Contract: albedo() is a pure function of the ENU ground position (x, y) and the scene spec,
// so the texture is identical in every frame and from every thread. Values are linear
// reflectances in [0, 1]. Road-local features (lanes, wheel tracks, markings, slab joints)
// are laid out in each road's (along, lateral) coordinates; irregular features (tone,
// cracks, stains, grass) come from value noise seeded by the scene's style seed.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "scene.hpp"

namespace vp::sim {

enum class GroundClass { Road, Lot, Kerb, Sidewalk, Verge };

// The smooth noise fields of the texture (features of 0.2 m and more).
enum class GroundField { Macro, Fine, Oil, CrackMask, CrackRidge, Stain, Walk, Mix, Soil, Count };

class GroundTexture {
 public:
  explicit GroundTexture(const SceneSpec& scene);

  Eigen::Vector3f albedo(double x, double y, GroundClass* cls = nullptr) const;
  // Albedo at the texels * texels points (x0 + i texel_m, y0 + j texel_m), row-major into out.
  // The smooth fields come from coarse lattices (6 cm and more) interpolated bilinearly, so values
  // differ slightly from albedo() at the same point; each tile is a pure function of its
  // arguments, like albedo().
  void fillTile(double x0, double y0, double texel_m, int texels, Eigen::Vector3f* out) const;
  // One smooth field at (x, y) (metres).
  float field(GroundField f, float x, float y) const;

 private:
  // The scene's local features that can affect an area.
  struct Nearby {
    std::vector<const Patch*> patches;
    std::vector<const Manhole*> manholes;
    std::vector<std::size_t> buildings;  // aprons
  };
  Nearby nearby(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;

  template <typename Fields>
  Eigen::Vector3f albedoAt(const Eigen::Vector2d& p, Fields& fields, const Nearby& nearby,
                           GroundClass* cls) const;
  template <typename Fields>
  float roadTone(const Eigen::Vector2d& p, const Road* road, double along, double lateral,
                 bool inJunction, Fields& fields, const Nearby& nearby) const;
  // Coverage [0, 1] of painted markings of one road at (along, lateral); *yellow set when the
  // marking is yellow.
  float roadMarkings(const Road& road, double along, double lateral, bool* yellow) const;
  float lotMarkings(const ParkingLot& lot, const Eigen::Vector2d& p) const;
  template <typename Fields>
  Eigen::Vector3f sidewalk(const Eigen::Vector2d& p, double kerbDistance, Fields& fields) const;
  Eigen::Vector3f kerb(const Eigen::Vector2d& p, double kerbDistance) const;
  // Inside a traffic island, depth_m from its kerb line.
  template <typename Fields>
  Eigen::Vector3f islandAlbedo(const Island& island, const Eigen::Vector2d& p, double depth_m,
                               Fields& fields, const Nearby& nearby, GroundClass* cls) const;
  template <typename Fields>
  Eigen::Vector3f verge(const Eigen::Vector2d& p, Fields& fields, const Nearby& nearby) const;

  const SceneSpec* scene_;
  std::vector<Eigen::Vector2d> buildingAxes_;  // unit length axis of each building
  Nearby all_;
};

}  // namespace vp::sim
