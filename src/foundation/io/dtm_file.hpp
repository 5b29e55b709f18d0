// io/dtm_file: reads and writes digital terrain models as float32 GeoTIFF.
//
// Contract: loadDtm() reads a single-band float32 (or float64, converted) TIFF. The
// georeferencing comes from the GeoTIFF tags (ModelTiepoint + ModelPixelScale, or
// ModelTransformation; GTRasterTypeGeoKey PixelIsArea/PixelIsPoint honoured; CRS from
// ProjectedCSTypeGeoKey 326zz/327zz = WGS84 UTM or GeographicTypeGeoKey 4326) or, when the
// file has none, from a world file beside it (.tfw, .tifw or .wld; its six lines place the
// centre of the first pixel), whose CRS the caller must give. NoData comes from the
// GDAL_NODATA tag (42113). Every failure returns false with a message naming the file and
// what is wrong. Start-up only: these functions allocate and do file I/O.
#pragma once

#include <optional>
#include <string>

#include "terrain/terrain_model.hpp"

namespace vp::io {

// crsForWorldFile: the CRS of a world-file-referenced DTM (ignored for GeoTIFF tags, but
// if given and different from the tags' CRS the load fails, naming both).
bool loadDtm(const std::string& path, const std::optional<terrain::CrsSpec>& crsForWorldFile,
             terrain::TerrainGrid& grid, std::string* why);

// Writes a float32 GeoTIFF with tiepoint/scale (or transformation) tags, the CRS key and
// GDAL_NODATA when the grid has one. Used by the simulator and by tests.
bool writeDtmGeoTiff(const std::string& path, const terrain::TerrainGrid& grid, std::string* why);

// Writes a plain float32 TIFF and a world file (path with extension .tfw) beside it.
bool writeDtmWithWorldFile(const std::string& path, const terrain::TerrainGrid& grid,
                           std::string* why);

}  // namespace vp::io
