// terrain/terrain_model: the digital terrain model (DTM) and rays meeting it.
//
// Contract: a TerrainModel is a regular grid of float32 ellipsoidal heights (m) whose
// sample centres are placed by an affine geotransform in a horizontal CRS (WGS84
// geographic degrees, or a UTM zone in metres). Queries never invent heights: a point
// outside the grid or touching a NoData sample returns a status. Heights are bilinear
// between the four surrounding sample centres. Ray intersection works in the world ENU
// frame of a LocalFrame: it clips the ray to the slab between the DTM's lowest and highest
// heights, marches in steps no longer than half a cell, and refines a sign change by
// bisection to better than 0.1 mm, so steep slopes and grazing rays are handled and the
// first (nearest) crossing is returned. The grid is owned (moved in at init) and never
// reallocated; queries are const, allocation-free and thread-safe.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/expected.hpp"
#include "geodesy/geodesy.hpp"

namespace vp::terrain {

enum class HorizontalCrs { Wgs84Geographic, Utm };

struct CrsSpec {
  HorizontalCrs kind = HorizontalCrs::Utm;
  int utmZone = 0;       // 1..60, for Utm
  bool utmNorth = true;  // hemisphere, for Utm
};
// "wgs84" or "utm:<zone><N|S>" (e.g. "utm:16N"); nullopt when malformed.
std::optional<CrsSpec> crsFromString(const std::string& text);
std::string toString(const CrsSpec& crs);

// Maps sample (col, row) centres to CRS coordinates:
//   X = x0 + col * dxCol + row * dxRow,  Y = y0 + col * dyCol + row * dyRow.
// For geographic grids X is longitude (deg) and Y latitude (deg); for UTM, easting and
// northing (m). (col, row) = (0, 0) is the centre of the first stored sample.
struct GeoTransform {
  double x0 = 0.0;
  double dxCol = 1.0;
  double dxRow = 0.0;
  double y0 = 0.0;
  double dyCol = 0.0;
  double dyRow = -1.0;
};

struct TerrainGrid {
  int cols = 0;
  int rows = 0;
  std::vector<float> heights_m;  // row-major, rows * cols
  GeoTransform transform{};
  CrsSpec crs{};
  std::optional<float> noData;  // samples equal to this (or NaN) are missing
};

enum class TerrainError {
  OutsideDtm,      // the point (or the ray's ground point) lies outside the grid
  NoData,          // a sample needed for interpolation is NoData
  NoIntersection,  // the ray never meets the terrain (level or rising, or starts below it)
};
const char* toString(TerrainError error);

class TerrainModel {
 public:
  TerrainModel() = default;

  // Takes ownership of the grid; validates sizes and the geotransform (invertible).
  bool init(TerrainGrid grid, const geodesy::LocalFrame& frame, std::string* why = nullptr);

  const TerrainGrid& grid() const { return grid_; }
  float minHeight_m() const { return minHeightM_; }
  float maxHeight_m() const { return maxHeightM_; }

  // Bilinear ellipsoidal height at a WGS84 position.
  Expected<double, TerrainError> heightAt(double latitude_deg, double longitude_deg) const;
  // Height at the geodetic position of an ENU point (its own z is ignored).
  Expected<double, TerrainError> heightAtEnu(const Eigen::Vector3d& enu) const;

  // Ground point (ENU) of the given x, y: the point whose geodetic position is that of
  // (x, y, z) with z adjusted until it lies on the DTM. Used to place simulated objects.
  Expected<Eigen::Vector3d, TerrainError> groundPointEnu(double xEast_m, double yNorth_m) const;

  // First intersection of the ray origin + t * direction (t > 0, ENU, direction need not
  // be unit length) with the terrain. Errors: OutsideDtm when the crossing would lie off
  // the grid: the ray never passes over it, enters it from the side already below the
  // surface, or leaves it descending but still above the surface; NoData when the crossing
  // would lie where samples are missing; NoIntersection when a level or rising ray stays
  // above the terrain, when the origin is below the terrain, or for a zero direction. Crossings
  // of slivers shorter than half a cell (a grazing ray nicking a crest) may be missed.
  Expected<Eigen::Vector3d, TerrainError> intersectRay(const Eigen::Vector3d& originEnu,
                                                       const Eigen::Vector3d& directionEnu) const;

  // WGS84 position of the centre of sample (col, row) (height: the sample's), or OutsideDtm for
  // an index off the grid. Start-up checks (coverage()); not for the loop.
  Expected<geodesy::GeodeticPoint, TerrainError> samplePosition(int col, int row) const;
  const geodesy::LocalFrame& frame() const { return frame_; }

 private:
  TerrainGrid grid_{};
  geodesy::LocalFrame frame_{};
  GeoTransform inverse_{};  // CRS -> (col, row)
  float minHeightM_ = 0.0F;
  float maxHeightM_ = 0.0F;
  double cellSizeM_ = 1.0;  // approximate ground size of one cell, m
  // Geographic footprint (with a margin): latitude range, and longitude range relative to
  // lonRefDeg_ (UTM zone central meridian, or the grid centre), so far points are rejected
  // before any projection and grids across the antimeridian work.
  double lonRefDeg_ = 0.0;
  double latMinDeg_ = 0.0;
  double latMaxDeg_ = 0.0;
  double dLonMinDeg_ = 0.0;
  double dLonMaxDeg_ = 0.0;
  // ENU box holding the grid between its lowest and highest heights (curvature margins
  // included): rays are clipped to it before marching.
  Eigen::Vector3d boxMin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d boxMax_ = Eigen::Vector3d::Zero();
};

// How much of one model's area another one has heights for: a surface model (DSM) must cover
// the terrain model (DTM) it is compared with. The covered model's valid samples are looked at
// on a lattice (every sample up to 256 x 256, evenly spaced beyond); each is outside the cover's
// grid, on its NoData, or covered. Start-up only (allocation-free, but a few thousand lookups).
struct Coverage {
  std::size_t checked = 0;  // valid samples of the covered model looked at
  std::size_t outside = 0;  // of those, off the cover's grid
  std::size_t noData = 0;   // of those, where the cover has no data
  // East/north bounding boxes (world ENU of the covered model's frame, m) of the two kinds;
  // meaningful only when their count is not zero.
  Eigen::Vector2d outsideMin_m{0.0, 0.0};
  Eigen::Vector2d outsideMax_m{0.0, 0.0};
  Eigen::Vector2d noDataMin_m{0.0, 0.0};
  Eigen::Vector2d noDataMax_m{0.0, 0.0};
};
Coverage coverage(const TerrainModel& covered, const TerrainModel& cover);

}  // namespace vp::terrain
