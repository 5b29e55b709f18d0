// io/dtm_write: writeDtmGeoTiff() and writeDtmWithWorldFile() (dtm_file.hpp) — a float32
// TIFF with GDAL_NODATA, georeferenced by GeoTIFF tags and keys or by a .tfw world file.
#include <geotiff.h>
#include <geovalues.h>
#include <xtiffio.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/dtm_file.hpp"
#include "io/dtm_tiff.hpp"

namespace vp::io {
namespace {

using dtm_detail::fail;
using dtm_detail::GtifPtr;
using dtm_detail::kTagGdalNoData;
using dtm_detail::registerTags;
using dtm_detail::TiffDiagnostics;
using dtm_detail::TiffPtr;
using terrain::GeoTransform;
using terrain::HorizontalCrs;
using terrain::TerrainGrid;

bool validateForWrite(const std::string& path, const TerrainGrid& grid, std::string* why) {
  if (grid.cols <= 0 || grid.rows <= 0 ||
      grid.heights_m.size() != static_cast<std::size_t>(grid.cols) * grid.rows) {
    return fail(why, path,
                "grid is inconsistent (" + std::to_string(grid.cols) + "x" +
                    std::to_string(grid.rows) + ", " + std::to_string(grid.heights_m.size()) +
                    " heights)");
  }
  if (grid.crs.kind == HorizontalCrs::Utm && (grid.crs.utmZone < 1 || grid.crs.utmZone > 60)) {
    return fail(why, path, "invalid UTM zone " + std::to_string(grid.crs.utmZone));
  }
  return true;
}

std::string formatNoData(float value) {
  if (std::isnan(value)) {
    return "nan";
  }
  char text[64];
  // 9 significant digits round-trip any float.
  std::snprintf(text, sizeof(text), "%.9g", static_cast<double>(value));
  return text;
}

// Opens `path` for writing and writes the float32 raster (plus GDAL_NODATA); `tags` adds
// the georeferencing before the image data.
template <class Tags>
bool writeRaster(const std::string& path, const TerrainGrid& grid, Tags&& tags, std::string* why) {
  registerTags();
  TiffDiagnostics diagnostics;
  TiffPtr tif(XTIFFOpen(path.c_str(), "w"));
  if (!tif) {
    return fail(why, path, "cannot create TIFF" + TiffDiagnostics::detail());
  }
  TIFF* t = tif.get();
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, static_cast<std::uint32_t>(grid.cols));
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, static_cast<std::uint32_t>(grid.rows));
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 32);
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, TIFFDefaultStripSize(t, 0));
  if (grid.noData) {
    const std::string text = formatNoData(*grid.noData);
    TIFFSetField(t, kTagGdalNoData, text.c_str());
  }
  if (!tags(t)) {
    return fail(why, path, "cannot write the GeoTIFF keys" + TiffDiagnostics::detail());
  }
  std::vector<float> row(static_cast<std::size_t>(grid.cols));
  for (int r = 0; r < grid.rows; ++r) {
    std::copy_n(grid.heights_m.begin() + static_cast<std::ptrdiff_t>(r) * grid.cols, grid.cols,
                row.begin());
    if (TIFFWriteScanline(t, row.data(), static_cast<std::uint32_t>(r), 0) < 0) {
      return fail(why, path, "cannot write row " + std::to_string(r) + TiffDiagnostics::detail());
    }
  }
  if (TIFFFlush(t) != 1) {
    return fail(why, path, "cannot write TIFF" + TiffDiagnostics::detail());
  }
  tif.reset();
  if (TiffDiagnostics::anyError()) {
    return fail(why, path, "cannot write TIFF" + TiffDiagnostics::detail());
  }
  return true;
}

}  // namespace

bool writeDtmGeoTiff(const std::string& path, const terrain::TerrainGrid& grid, std::string* why) {
  if (!validateForWrite(path, grid, why)) {
    return false;
  }
  const GeoTransform& g = grid.transform;
  // PixelIsArea: the tags place the outer corner of the first pixel, half a pixel from its
  // centre along both axes.
  const double cornerX = g.x0 - 0.5 * (g.dxCol + g.dxRow);
  const double cornerY = g.y0 - 0.5 * (g.dyCol + g.dyRow);
  const auto tags = [&](TIFF* t) {
    // Tiepoint + scale only express a north-up, unflipped grid (scales are positive);
    // anything else goes into a ModelTransformation.
    if (g.dxRow == 0.0 && g.dyCol == 0.0 && g.dxCol > 0.0 && g.dyRow < 0.0) {
      double tie[6] = {0.0, 0.0, 0.0, cornerX, cornerY, 0.0};
      double scale[3] = {g.dxCol, -g.dyRow, 0.0};
      TIFFSetField(t, TIFFTAG_GEOTIEPOINTS, 6, tie);
      TIFFSetField(t, TIFFTAG_GEOPIXELSCALE, 3, scale);
    } else {
      double matrix[16] = {g.dxCol, g.dxRow, 0.0, cornerX,  //
                           g.dyCol, g.dyRow, 0.0, cornerY,  //
                           0.0,     0.0,     0.0, 0.0,      //
                           0.0,     0.0,     0.0, 1.0};
      TIFFSetField(t, TIFFTAG_GEOTRANSMATRIX, 16, matrix);
    }
    GtifPtr gtif(GTIFNew(t));
    if (!gtif) {
      return false;
    }
    GTIF* k = gtif.get();
    if (grid.crs.kind == HorizontalCrs::Utm) {
      GTIFKeySet(k, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
      GTIFKeySet(k, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
      GTIFKeySet(k, ProjectedCSTypeGeoKey, TYPE_SHORT, 1,
                 (grid.crs.utmNorth ? 32600 : 32700) + grid.crs.utmZone);
    } else {
      GTIFKeySet(k, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeGeographic);
      GTIFKeySet(k, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsArea);
      GTIFKeySet(k, GeographicTypeGeoKey, TYPE_SHORT, 1, 4326);
    }
    return GTIFWriteKeys(k) == 1;
  };
  return writeRaster(path, grid, tags, why);
}

bool writeDtmWithWorldFile(const std::string& path, const terrain::TerrainGrid& grid,
                           std::string* why) {
  if (!validateForWrite(path, grid, why)) {
    return false;
  }
  if (!writeRaster(
          path, grid, [](TIFF*) { return true; }, why)) {
    return false;
  }
  std::filesystem::path world(path);
  world.replace_extension(".tfw");
  std::ofstream out(world);
  const GeoTransform& g = grid.transform;
  char text[256];
  std::snprintf(text, sizeof(text), "%.17g\n%.17g\n%.17g\n%.17g\n%.17g\n%.17g\n", g.dxCol, g.dyCol,
                g.dxRow, g.dyRow, g.x0, g.y0);
  out << text;
  out.close();
  if (!out) {
    return fail(why, world.string(), "cannot write world file");
  }
  return true;
}

}  // namespace vp::io
