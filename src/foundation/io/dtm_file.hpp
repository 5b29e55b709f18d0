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
// The raster's declared size is checked before anything is allocated: at most
// DtmLoadOptions::maxSamples samples, and for an uncompressed raster no more sample bytes than
// the file holds (a damaged or hostile header cannot make the loader allocate gigabytes).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "terrain/terrain_model.hpp"

namespace vp::io {

// Default of DtmLoadOptions::maxSamples: 2^26 samples (e.g. 8192 x 8192, 256 MiB of float32
// heights), far more than a flight area at the DTM resolutions the lifting needs.
inline constexpr std::uint64_t kDefaultDtmMaxSamples = std::uint64_t{1} << 26;
// The largest value the option accepts: 2^30 samples (4 GiB of float32).
inline constexpr std::uint64_t kDtmMaxSamplesLimit = std::uint64_t{1} << 30;

// Configured by the `terrain:` section (terrain.max_samples, docs/configuration.md).
struct DtmLoadOptions {
  // Largest raster accepted, width x height samples, in [4, kDtmMaxSamplesLimit]. The grid
  // takes 4 bytes per sample in memory.
  std::uint64_t maxSamples = kDefaultDtmMaxSamples;
};

// crsForWorldFile: the CRS of a world-file-referenced DTM (ignored for GeoTIFF tags, but
// if given and different from the tags' CRS the load fails, naming both).
bool loadDtm(const std::string& path, const std::optional<terrain::CrsSpec>& crsForWorldFile,
             terrain::TerrainGrid& grid, std::string* why, const DtmLoadOptions& options = {});

// Writes a float32 GeoTIFF with tiepoint/scale (or transformation) tags, the CRS key and
// GDAL_NODATA when the grid has one. Used by the simulator and by tests.
bool writeDtmGeoTiff(const std::string& path, const terrain::TerrainGrid& grid, std::string* why);

// Writes a plain float32 TIFF and a world file (path with extension .tfw) beside it.
bool writeDtmWithWorldFile(const std::string& path, const terrain::TerrainGrid& grid,
                           std::string* why);

}  // namespace vp::io
