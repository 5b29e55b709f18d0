// io/dtm_file (reading): loadDtm() — the float raster, the GeoTIFF georeferencing keys and
// tags, a world file beside the image when there are none, and GDAL_NODATA. Writing is in
// dtm_write.cpp, the libtiff plumbing both share in dtm_tiff.cpp.
#include "io/dtm_file.hpp"

#include <geotiff.h>
#include <geovalues.h>
#include <xtiffio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "io/dtm_tiff.hpp"

namespace vp::io {
namespace {

using dtm_detail::fail;
using dtm_detail::GtifPtr;
using dtm_detail::kTagGdalNoData;
using dtm_detail::registerTags;
using dtm_detail::TiffDiagnostics;
using dtm_detail::TiffPtr;
using terrain::CrsSpec;
using terrain::GeoTransform;
using terrain::HorizontalCrs;
using terrain::TerrainGrid;

std::string crsName(const CrsSpec& crs) {
  return terrain::toString(crs);
}

bool sameCrs(const CrsSpec& a, const CrsSpec& b) {
  if (a.kind != b.kind) {
    return false;
  }
  return a.kind == HorizontalCrs::Wgs84Geographic ||
         (a.utmZone == b.utmZone && a.utmNorth == b.utmNorth);
}

// --- Reading -----------------------------------------------------------------------------

// "12 345 678": sizes in messages, readable at a glance.
std::string grouped(std::uint64_t value) {
  std::string digits = std::to_string(value);
  for (int at = static_cast<int>(digits.size()) - 3; at > 0; at -= 3) {
    digits.insert(static_cast<std::size_t>(at), " ");
  }
  return digits;
}

// The declared raster size against the configured cap and, uncompressed, against the file:
// checked before the grid is allocated.
bool checkDeclaredSize(TIFF* tif, const std::string& path, std::uint32_t width,
                       std::uint32_t height, std::size_t bytesPerSample,
                       const DtmLoadOptions& options, std::string* why) {
  const std::uint64_t samples = static_cast<std::uint64_t>(width) * height;
  const std::string size = std::to_string(width) + " x " + std::to_string(height) + " = " +
                           grouped(samples) + " samples";
  const std::uint64_t cap = std::min(options.maxSamples, kDtmMaxSamplesLimit);
  if (samples > cap) {
    return fail(why, path,
                "raster of " + size + " exceeds terrain.max_samples " + grouped(cap) + " (" +
                    grouped(samples * sizeof(float) >> 20) + " MiB in memory)");
  }
  std::uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &compression);
  std::error_code error;
  const std::uintmax_t fileBytes = std::filesystem::file_size(path, error);
  const std::uint64_t rasterBytes = samples * bytesPerSample;
  if (compression == COMPRESSION_NONE && !error && rasterBytes > fileBytes) {
    return fail(why, path,
                "header declares an uncompressed raster of " + size + " (" + grouped(rasterBytes) +
                    " bytes), larger than the file (" + grouped(fileBytes) +
                    " bytes): truncated or corrupt");
  }
  return true;
}

bool readRaster(TIFF* tif, const std::string& path, const DtmLoadOptions& options,
                TerrainGrid& grid, std::string* why) {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint16_t samples = 1;
  std::uint16_t bits = 1;
  std::uint16_t format = SAMPLEFORMAT_UINT;
  if (TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &width) != 1 ||
      TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &height) != 1) {
    return fail(why, path, "TIFF has no image size" + TiffDiagnostics::detail());
  }
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
  if (samples != 1 || format != SAMPLEFORMAT_IEEEFP || (bits != 32 && bits != 64)) {
    const char* formatName = format == SAMPLEFORMAT_IEEEFP ? "float"
                             : format == SAMPLEFORMAT_INT  ? "signed int"
                             : format == SAMPLEFORMAT_UINT ? "unsigned int"
                                                           : "other";
    return fail(why, path,
                "not a float32 single-band TIFF (bits " + std::to_string(bits) + ", samples " +
                    std::to_string(samples) + ", sample format " + formatName + ")");
  }
  if (width < 2 || height < 2) {
    return fail(why, path,
                "unsupported image size " + std::to_string(width) + "x" + std::to_string(height) +
                    " (needs at least 2x2)");
  }
  const std::size_t bytesPerSample = bits / 8;
  if (!checkDeclaredSize(tif, path, width, height, bytesPerSample, options, why)) {
    return false;
  }
  grid.cols = static_cast<int>(width);
  grid.rows = static_cast<int>(height);
  grid.heights_m.assign(static_cast<std::size_t>(width) * height, 0.0F);

  // Copies a block (strip or tile) of bw x bh samples stored at `block` into the grid at
  // (col0, row0), clipping to the image.
  const auto copyBlock = [&](const unsigned char* block, std::uint32_t bw, std::uint32_t bh,
                             std::uint32_t col0, std::uint32_t row0) {
    for (std::uint32_t r = 0; r < bh && row0 + r < height; ++r) {
      for (std::uint32_t c = 0; c < bw && col0 + c < width; ++c) {
        const unsigned char* src = block + (static_cast<std::size_t>(r) * bw + c) * bytesPerSample;
        float value = 0.0F;
        if (bits == 32) {
          std::memcpy(&value, src, sizeof(float));
        } else {
          double wide = 0.0;
          std::memcpy(&wide, src, sizeof(double));
          value = static_cast<float>(wide);
        }
        grid.heights_m[static_cast<std::size_t>(row0 + r) * width + col0 + c] = value;
      }
    }
  };

  if (TIFFIsTiled(tif) != 0) {
    std::uint32_t tileWidth = 0;
    std::uint32_t tileHeight = 0;
    TIFFGetField(tif, TIFFTAG_TILEWIDTH, &tileWidth);
    TIFFGetField(tif, TIFFTAG_TILELENGTH, &tileHeight);
    const tmsize_t tileBytes = TIFFTileSize(tif);
    if (tileWidth == 0 || tileHeight == 0 || tileBytes <= 0 ||
        static_cast<std::size_t>(tileBytes) <
            static_cast<std::size_t>(tileWidth) * tileHeight * bytesPerSample) {
      return fail(why, path, "invalid tile layout" + TiffDiagnostics::detail());
    }
    std::vector<unsigned char> buffer(static_cast<std::size_t>(tileBytes));
    for (std::uint32_t row = 0; row < height; row += tileHeight) {
      for (std::uint32_t col = 0; col < width; col += tileWidth) {
        if (TIFFReadTile(tif, buffer.data(), col, row, 0, 0) < 0) {
          return fail(why, path,
                      "cannot read tile at column " + std::to_string(col) + ", row " +
                          std::to_string(row) + TiffDiagnostics::detail());
        }
        copyBlock(buffer.data(), tileWidth, tileHeight, col, row);
      }
    }
  } else {
    std::uint32_t rowsPerStrip = height;
    TIFFGetFieldDefaulted(tif, TIFFTAG_ROWSPERSTRIP, &rowsPerStrip);
    rowsPerStrip = std::min(std::max<std::uint32_t>(rowsPerStrip, 1), height);
    const tmsize_t stripBytes = TIFFStripSize(tif);
    if (stripBytes <= 0 || static_cast<std::size_t>(stripBytes) <
                               static_cast<std::size_t>(width) * rowsPerStrip * bytesPerSample) {
      return fail(why, path, "invalid strip layout" + TiffDiagnostics::detail());
    }
    std::vector<unsigned char> buffer(static_cast<std::size_t>(stripBytes));
    const std::uint32_t strips = TIFFNumberOfStrips(tif);
    for (std::uint32_t s = 0; s < strips; ++s) {
      const std::uint32_t row0 = s * rowsPerStrip;
      if (row0 >= height) {
        break;
      }
      const std::uint32_t rowsHere = std::min(rowsPerStrip, height - row0);
      const tmsize_t want = static_cast<tmsize_t>(width) * rowsHere * bytesPerSample;
      if (TIFFReadEncodedStrip(tif, s, buffer.data(), want) < want) {
        return fail(why, path,
                    "cannot read strip " + std::to_string(s) + " of " + std::to_string(strips) +
                        TiffDiagnostics::detail());
      }
      copyBlock(buffer.data(), width, rowsHere, 0, row0);
    }
  }
  return true;
}

// CRS from the GeoKeys; nullopt when the file has no CRS keys. Fails on unsupported CRSs.
bool readCrsKeys(GTIF* gtif, const std::string& path, std::optional<CrsSpec>& crs,
                 std::string* why) {
  crs.reset();
  if (gtif == nullptr) {
    return true;
  }
  unsigned short modelType = 0;
  unsigned short projected = 0;
  unsigned short geographic = 0;
  const bool hasModel = GTIFKeyGetSHORT(gtif, GTModelTypeGeoKey, &modelType, 0, 1) == 1;
  const bool hasProjected = GTIFKeyGetSHORT(gtif, ProjectedCSTypeGeoKey, &projected, 0, 1) == 1;
  const bool hasGeographic = GTIFKeyGetSHORT(gtif, GeographicTypeGeoKey, &geographic, 0, 1) == 1;
  const auto unsupported = [&](unsigned short code) {
    return fail(
        why, path,
        "CRS EPSG:" + std::to_string(code) + " not supported (use WGS84 UTM 326xx/327xx or 4326)");
  };
  if ((hasModel && modelType == ModelTypeProjected) || (!hasModel && hasProjected)) {
    if (!hasProjected) {
      return fail(why, path, "projected GeoTIFF without ProjectedCSTypeGeoKey not supported");
    }
    if (projected >= 32601 && projected <= 32660) {
      crs = CrsSpec{HorizontalCrs::Utm, projected - 32600, true};
      return true;
    }
    if (projected >= 32701 && projected <= 32760) {
      crs = CrsSpec{HorizontalCrs::Utm, projected - 32700, false};
      return true;
    }
    if (projected == KvUserDefined) {
      return fail(why, path,
                  "user-defined projected CRS not supported (use WGS84 UTM 326xx/327xx or 4326)");
    }
    return unsupported(projected);
  }
  if ((hasModel && modelType == ModelTypeGeographic) || (!hasModel && hasGeographic)) {
    if (hasGeographic && geographic == 4326) {
      crs = CrsSpec{HorizontalCrs::Wgs84Geographic, 0, true};
      return true;
    }
    if (!hasGeographic || geographic == KvUserDefined) {
      return fail(why, path,
                  "geographic GeoTIFF without GeographicTypeGeoKey 4326 not supported (use "
                  "WGS84 UTM 326xx/327xx or 4326)");
    }
    return unsupported(geographic);
  }
  if (hasModel) {
    return fail(why, path,
                "GeoTIFF model type " + std::to_string(modelType) +
                    " not supported (use WGS84 UTM 326xx/327xx or 4326)");
  }
  return true;
}

// Transform of the sample centres from the GeoTIFF tags; false with `found` = false when the
// file has none of them.
bool readTransformTags(TIFF* tif, GTIF* gtif, const std::string& path, GeoTransform& transform,
                       bool& found, std::string* why) {
  found = false;
  // Raster space (I, J) -> model (X, Y): X = a*I + b*J + c, Y = d*I + e*J + f.
  double a = 0.0;
  double b = 0.0;
  double c = 0.0;
  double d = 0.0;
  double e = 0.0;
  double f = 0.0;
  std::uint16_t count = 0;
  double* values = nullptr;
  if (TIFFGetField(tif, TIFFTAG_GEOTRANSMATRIX, &count, &values) == 1 && values != nullptr) {
    if (count < 16) {
      return fail(why, path, "ModelTransformation tag has " + std::to_string(count) + " values");
    }
    a = values[0];
    b = values[1];
    c = values[3];
    d = values[4];
    e = values[5];
    f = values[7];
    found = true;
  } else {
    std::uint16_t tieCount = 0;
    double* tie = nullptr;
    std::uint16_t scaleCount = 0;
    double* scale = nullptr;
    const bool hasTie =
        TIFFGetField(tif, TIFFTAG_GEOTIEPOINTS, &tieCount, &tie) == 1 && tie != nullptr;
    const bool hasScale =
        TIFFGetField(tif, TIFFTAG_GEOPIXELSCALE, &scaleCount, &scale) == 1 && scale != nullptr;
    if (!hasTie && !hasScale) {
      return true;
    }
    if (!hasTie || tieCount < 6) {
      return fail(why, path, "ModelPixelScale without a ModelTiepoint");
    }
    if (!hasScale || scaleCount < 2) {
      return fail(why, path,
                  "ModelTiepoint without ModelPixelScale (tiepoint grids are not supported)");
    }
    // Tiepoint (I, J, K, X, Y, Z); Y grows upwards while J grows downwards.
    a = scale[0];
    e = -scale[1];
    c = tie[3] - tie[0] * a;
    f = tie[4] - tie[1] * e;
    found = true;
  }
  // PixelIsArea (the default): raster (0, 0) is the outer corner of the first pixel, whose
  // centre is (0.5, 0.5). PixelIsPoint: raster (0, 0) is the first sample itself.
  unsigned short rasterType = RasterPixelIsArea;
  if (gtif != nullptr) {
    GTIFKeyGetSHORT(gtif, GTRasterTypeGeoKey, &rasterType, 0, 1);
  }
  const double offset = rasterType == RasterPixelIsPoint ? 0.0 : 0.5;
  transform.x0 = c + offset * (a + b);
  transform.dxCol = a;
  transform.dxRow = b;
  transform.y0 = f + offset * (d + e);
  transform.dyCol = d;
  transform.dyRow = e;
  return true;
}

std::optional<std::filesystem::path> findWorldFile(const std::filesystem::path& image) {
  for (const char* ext : {".tfw", ".tifw", ".wld", ".TFW", ".TIFW", ".WLD"}) {
    std::filesystem::path candidate = image;
    candidate.replace_extension(ext);
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec)) {
      return candidate;
    }
  }
  return std::nullopt;
}

bool readWorldFile(const std::filesystem::path& file, GeoTransform& transform, std::string* why) {
  std::ifstream in(file);
  if (!in) {
    return fail(why, file.string(), "cannot open world file");
  }
  // Lines: A (x per col), D (y per col), B (x per row), E (y per row), C, F (centre of the
  // first pixel).
  double v[6] = {};
  for (double& value : v) {
    std::string line;
    if (!(in >> line)) {
      return fail(why, file.string(), "malformed world file (needs six numbers)");
    }
    char* end = nullptr;
    value = std::strtod(line.c_str(), &end);
    if (end == line.c_str() || *end != '\0' || !std::isfinite(value)) {
      return fail(why, file.string(), "malformed world file (bad number '" + line + "')");
    }
  }
  transform = GeoTransform{v[4], v[0], v[2], v[5], v[1], v[3]};
  return true;
}

}  // namespace

bool loadDtm(const std::string& path, const std::optional<terrain::CrsSpec>& crsForWorldFile,
             terrain::TerrainGrid& grid, std::string* why, const DtmLoadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return fail(why, path, "file not found");
  }
  registerTags();
  TiffDiagnostics diagnostics;
  TiffPtr tif(XTIFFOpen(path.c_str(), "r"));
  if (!tif) {
    return fail(why, path, "cannot open as TIFF" + TiffDiagnostics::detail());
  }
  TerrainGrid loaded;
  if (!readRaster(tif.get(), path, options, loaded, why)) {
    return false;
  }

  GtifPtr gtif(GTIFNew(tif.get()));
  std::optional<CrsSpec> tagCrs;
  if (!readCrsKeys(gtif.get(), path, tagCrs, why)) {
    return false;
  }
  bool hasTransformTags = false;
  if (!readTransformTags(tif.get(), gtif.get(), path, loaded.transform, hasTransformTags, why)) {
    return false;
  }

  if (hasTransformTags) {
    if (!tagCrs) {
      // Placed by tags but without CRS keys: as with a world file, the caller names the CRS.
      if (!crsForWorldFile) {
        return fail(why, path,
                    "GeoTIFF tags give no CRS (no GeoKeys): configure one (e.g. utm:16N or "
                    "wgs84)");
      }
      tagCrs = crsForWorldFile;
    }
    if (crsForWorldFile && !sameCrs(*crsForWorldFile, *tagCrs)) {
      return fail(why, path,
                  "CRS from the GeoTIFF keys (" + crsName(*tagCrs) +
                      ") differs from the configured CRS (" + crsName(*crsForWorldFile) + ")");
    }
    loaded.crs = *tagCrs;
  } else {
    const std::optional<std::filesystem::path> world = findWorldFile(path);
    if (!world) {
      return fail(why, path, "no georeferencing (no GeoTIFF tags and no world file)");
    }
    if (!readWorldFile(*world, loaded.transform, why)) {
      return false;
    }
    if (tagCrs) {
      if (crsForWorldFile && !sameCrs(*crsForWorldFile, *tagCrs)) {
        return fail(why, path,
                    "CRS from the GeoTIFF keys (" + crsName(*tagCrs) +
                        ") differs from the configured CRS (" + crsName(*crsForWorldFile) + ")");
      }
      loaded.crs = *tagCrs;
    } else if (crsForWorldFile) {
      loaded.crs = *crsForWorldFile;
    } else {
      return fail(why, path,
                  "georeferenced by world file " + world->filename().string() +
                      ", which has no CRS: configure one (e.g. utm:16N or wgs84)");
    }
  }

  char* noDataText = nullptr;
  if (TIFFGetField(tif.get(), kTagGdalNoData, &noDataText) == 1 && noDataText != nullptr) {
    char* end = nullptr;
    const double value = std::strtod(noDataText, &end);
    while (end != nullptr && (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r')) {
      ++end;
    }
    if (end == noDataText || (end != nullptr && *end != '\0')) {
      return fail(why, path, std::string("GDAL_NODATA '") + noDataText + "' is not a number");
    }
    loaded.noData = static_cast<float>(value);
  }
  grid = std::move(loaded);
  return true;
}

}  // namespace vp::io
