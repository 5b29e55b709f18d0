// tests/support/plane_dtm: a planar DTM grid around a point, for tests that need terrain with
// a known slope (lifting, perception). Header-only; links against vp_terrain / vp_geodesy.
//
// Contract: a UTM grid (the zone of `centre`) of cell_m cells spanning +-halfExtent_m around
// centre, heights = ground_m + slopeEast * dE + slopeNorth * dN (m, ellipsoidal), north-up.
#pragma once

#include <cstddef>

#include "geodesy/geodesy.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::test {

inline terrain::TerrainGrid planeDtm(const geodesy::GeodeticPoint& centre, double ground_m,
                                     double slopeEast, double slopeNorth, double halfExtent_m,
                                     double cell_m = 2.0) {
  const geodesy::UtmPoint utm = geodesy::toUtm(centre);
  terrain::TerrainGrid grid;
  grid.cols = grid.rows = static_cast<int>(2.0 * halfExtent_m / cell_m) + 1;
  grid.crs = {terrain::HorizontalCrs::Utm, utm.zone, utm.northp};
  grid.transform = {utm.easting_m - halfExtent_m,  cell_m, 0.0,
                    utm.northing_m + halfExtent_m, 0.0,    -cell_m};
  grid.heights_m.resize(static_cast<std::size_t>(grid.cols * grid.rows));
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const double dE = -halfExtent_m + c * cell_m;
      const double dN = halfExtent_m - r * cell_m;
      grid.heights_m[static_cast<std::size_t>(r * grid.cols + c)] =
          static_cast<float>(ground_m + slopeEast * dE + slopeNorth * dN);
    }
  }
  return grid;
}

}  // namespace vp::test
