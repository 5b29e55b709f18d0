// tests/support/plane_dtm: a planar DTM grid around a point, for tests that need terrain with
// a known slope (lifting, perception). Header-only; links against vp_terrain / vp_geodesy.
//
// Contract: a UTM grid (the zone of `centre`) of cellM cells spanning +-halfExtentM around
// centre, heights = groundM + slopeEast * dE + slopeNorth * dN (m, ellipsoidal), north-up.
#pragma once

#include <cstddef>

#include "geodesy/geodesy.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::test {

inline terrain::TerrainGrid planeDtm(const geodesy::GeodeticPoint& centre, double groundM,
                                     double slopeEast, double slopeNorth, double halfExtentM,
                                     double cellM = 2.0) {
  const geodesy::UtmPoint utm = geodesy::toUtm(centre);
  terrain::TerrainGrid grid;
  grid.cols = grid.rows = static_cast<int>(2.0 * halfExtentM / cellM) + 1;
  grid.crs = {terrain::HorizontalCrs::Utm, utm.zone, utm.northp};
  grid.transform = {utm.eastingM - halfExtentM,  cellM, 0.0,
                    utm.northingM + halfExtentM, 0.0,   -cellM};
  grid.heightsM.resize(static_cast<std::size_t>(grid.cols * grid.rows));
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const double dE = -halfExtentM + c * cellM;
      const double dN = halfExtentM - r * cellM;
      grid.heightsM[static_cast<std::size_t>(r * grid.cols + c)] =
          static_cast<float>(groundM + slopeEast * dE + slopeNorth * dN);
    }
  }
  return grid;
}

}  // namespace vp::test
