// tools/simulator/surface_model: the scene's digital surface model (DSM): the DTM's grid with the
// buildings standing on it (walls, flat or gabled roofs with the renderer's eaves overhang,
// raised roof fixtures such as HVAC units and dormers), written as dsm.tif beside a sequence's
// dtm.tif. Trees, street furniture and vehicles are left out: the surface prior
// (perception/surface_prior.hpp) is about structures vehicles cannot stand on, or decks they can.
#pragma once

#include "scene.hpp"
#include "terrain/terrain_model.hpp"
#include "world.hpp"

namespace vp::sim {

// The DTM's grid (same samples, CRS and NoData) with each sample inside a building raised to the
// building's roof (or fixture top) at that point, the same heights the renderer draws.
terrain::TerrainGrid surfaceGrid(const SceneSpec& scene, const World& world);

// The roof height (ENU z) of the building at east/north p, or a value below -1e8 when p lies
// outside its footprint (gabled roofs: with the eaves overhang).
double roofZ(const Building& building, const World& world, const Eigen::Vector2d& p);

}  // namespace vp::sim
