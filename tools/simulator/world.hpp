// simulator/world: the georeferenced world of a sequence: the ENU frame at the origin, the
// generated terrain (flat, sloped or undulating), its DTM grid in the UTM zone of the
// origin (written as GeoTIFF for the recording), and the terrain model used to place
// everything on the ground.
//
// Contract: the terrain is defined by its ellipsoidal height as a function of the ENU
// horizontal position, h(x, y) = origin height + relief(x, y). The DTM samples that function
// at the centres of a UTM-aligned grid (0.5 or 1 m cells); groundZ() queries the resulting
// TerrainModel (bilinear in the DTM, Earth curvature included), so objects stand exactly on
// the DTM the application will load. Building is start-up work (allocates, ~1 s).
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>

#include "geodesy/geodesy.hpp"
#include "sim_random.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::sim {

enum class ReliefKind { Flat, Slope, Undulating };

struct TerrainSpec {
  ReliefKind kind = ReliefKind::Flat;
  Eigen::Vector2d gradient{0, 0};  // rise per metre east / north
  // (kx, ky, amplitude m) of the undulations (Eigen does not zero-initialise: done explicitly).
  std::array<Eigen::Vector3d, 3> waves{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                       Eigen::Vector3d::Zero()};
  std::array<double, 3> phases{};
  double cell_m = 0.5;
};

TerrainSpec drawTerrain(Rng& rng);
const char* toString(ReliefKind kind);

// Origin: a site near Madison, WI (the real data's city) moved by up to ~1 km per seed.
geodesy::GeodeticPoint drawOrigin(Rng& rng);

class World {
 public:
  // Builds the DTM covering the square centre +- halfSize_m (ENU) and the terrain model.
  bool build(const geodesy::GeodeticPoint& origin, const TerrainSpec& spec,
             const Eigen::Vector2d& centre, double halfSize_m, std::string* why);

  const geodesy::LocalFrame& frame() const { return frame_; }
  const terrain::TerrainModel& terrain() const { return terrain_; }
  const TerrainSpec& spec() const { return spec_; }
  // ENU z of the ground under (x, y); falls back to the analytic relief off the DTM.
  double groundZ(double x, double y) const;
  // Ground point (ENU) under (x, y).
  Eigen::Vector3d ground(double x, double y) const { return {x, y, groundZ(x, y)}; }

 private:
  double relief(double x, double y) const;

  geodesy::LocalFrame frame_{};
  terrain::TerrainModel terrain_{};
  TerrainSpec spec_{};
};

}  // namespace vp::sim
