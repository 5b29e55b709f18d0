#include "io/dtm_file.hpp"

#include <geotiff.h>
#include <geovalues.h>
#include <sys/resource.h>
#include <unistd.h>
#include <xtiffio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace vp::io {
namespace {

namespace fs = std::filesystem;
using terrain::CrsSpec;
using terrain::GeoTransform;
using terrain::HorizontalCrs;
using terrain::TerrainGrid;

// A grid whose heights vary in both directions, so a transposed or flipped read shows.
TerrainGrid makeGrid(int cols, int rows, const GeoTransform& transform, const CrsSpec& crs) {
  TerrainGrid grid;
  grid.cols = cols;
  grid.rows = rows;
  grid.transform = transform;
  grid.crs = crs;
  grid.heights_m.resize(static_cast<std::size_t>(cols) * rows);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      grid.heights_m[static_cast<std::size_t>(r) * cols + c] =
          static_cast<float>(250.0 + 0.37 * c - 1.13 * r + 0.001 * c * r);
    }
  }
  return grid;
}

const CrsSpec kUtm16N{HorizontalCrs::Utm, 16, true};
const CrsSpec kWgs84{HorizontalCrs::Wgs84Geographic, 0, true};
const GeoTransform kUtmTransform{305012.5, 5.0, 0.0, 4771044.5, 0.0, -5.0};

void expectSameTransform(const GeoTransform& a, const GeoTransform& b, double tol) {
  EXPECT_NEAR(a.x0, b.x0, tol);
  EXPECT_NEAR(a.dxCol, b.dxCol, tol);
  EXPECT_NEAR(a.dxRow, b.dxRow, tol);
  EXPECT_NEAR(a.y0, b.y0, tol);
  EXPECT_NEAR(a.dyCol, b.dyCol, tol);
  EXPECT_NEAR(a.dyRow, b.dyRow, tol);
}

void expectSameGrid(const TerrainGrid& expected, const TerrainGrid& actual, double tol = 1e-9) {
  EXPECT_EQ(actual.cols, expected.cols);
  EXPECT_EQ(actual.rows, expected.rows);
  EXPECT_EQ(actual.crs.kind, expected.crs.kind);
  if (expected.crs.kind == HorizontalCrs::Utm) {
    EXPECT_EQ(actual.crs.utmZone, expected.crs.utmZone);
    EXPECT_EQ(actual.crs.utmNorth, expected.crs.utmNorth);
  }
  expectSameTransform(expected.transform, actual.transform, tol);
  EXPECT_EQ(actual.noData.has_value(), expected.noData.has_value());
  if (expected.noData && actual.noData) {
    EXPECT_EQ(*actual.noData, *expected.noData);
  }
  ASSERT_EQ(actual.heights_m.size(), expected.heights_m.size());
  for (std::size_t i = 0; i < expected.heights_m.size(); ++i) {
    if (std::isnan(expected.heights_m[i])) {
      EXPECT_TRUE(std::isnan(actual.heights_m[i])) << i;
    } else {
      ASSERT_EQ(actual.heights_m[i], expected.heights_m[i]) << i;
    }
  }
}

class DtmFile : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("vp_dtm_file_test_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

TEST_F(DtmFile, GeoTiffRoundTripUtmWithNoData) {
  TerrainGrid grid = makeGrid(37, 23, kUtmTransform, kUtm16N);
  grid.noData = -9999.0F;
  grid.heights_m[5] = -9999.0F;
  grid.heights_m[100] = std::numeric_limits<float>::quiet_NaN();
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("dtm.tif"), grid, &why)) << why;
  TerrainGrid back;
  ASSERT_TRUE(loadDtm(file("dtm.tif"), std::nullopt, back, &why)) << why;
  expectSameGrid(grid, back);
  // The configured CRS may repeat the tags' CRS.
  ASSERT_TRUE(loadDtm(file("dtm.tif"), kUtm16N, back, &why)) << why;
}

TEST_F(DtmFile, GeoTiffRoundTripSouthernUtm) {
  const CrsSpec utm33s{HorizontalCrs::Utm, 33, false};
  const TerrainGrid grid =
      makeGrid(10, 12, GeoTransform{500001.0, 2.0, 0.0, 9000000.0, 0.0, -2.0}, utm33s);
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("south.tif"), grid, &why)) << why;
  TerrainGrid back;
  ASSERT_TRUE(loadDtm(file("south.tif"), std::nullopt, back, &why)) << why;
  expectSameGrid(grid, back);
}

TEST_F(DtmFile, GeoTiffRoundTripGeographic) {
  TerrainGrid grid = makeGrid(
      31, 17, GeoTransform{-89.4062, 1.0 / 9000.0, 0.0, 43.08, 0.0, -1.0 / 9000.0}, kWgs84);
  grid.noData = std::numeric_limits<float>::quiet_NaN();
  grid.heights_m[7] = std::numeric_limits<float>::quiet_NaN();
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("geo.tif"), grid, &why)) << why;
  TerrainGrid back;
  ASSERT_TRUE(loadDtm(file("geo.tif"), std::nullopt, back, &why)) << why;
  // NaN NoData: compared separately as NaN != NaN.
  ASSERT_TRUE(back.noData.has_value());
  EXPECT_TRUE(std::isnan(*back.noData));
  back.noData = grid.noData = std::nullopt;
  expectSameGrid(grid, back, 1e-12);
}

TEST_F(DtmFile, GeoTiffRoundTripRotatedTransform) {
  // Rotated by ~10 deg and slightly sheared: written as a ModelTransformation.
  const double c = std::cos(0.17);
  const double s = std::sin(0.17);
  const TerrainGrid grid = makeGrid(
      20, 30, GeoTransform{305000.25, 5.0 * c, 4.0 * s, 4771000.75, 5.0 * s, -4.0 * c + 0.01},
      kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("rot.tif"), grid, &why)) << why;
  TerrainGrid back;
  ASSERT_TRUE(loadDtm(file("rot.tif"), std::nullopt, back, &why)) << why;
  expectSameGrid(grid, back);
  // Axis-aligned but flipped (rows going north) cannot use tiepoint + scale either.
  const TerrainGrid flipped =
      makeGrid(8, 9, GeoTransform{305000.0, 5.0, 0.0, 4771000.0, 0.0, 5.0}, kUtm16N);
  ASSERT_TRUE(writeDtmGeoTiff(file("flip.tif"), flipped, &why)) << why;
  ASSERT_TRUE(loadDtm(file("flip.tif"), std::nullopt, back, &why)) << why;
  expectSameGrid(flipped, back);
}

TEST_F(DtmFile, WorldFileWithExplicitCrs) {
  const double c = std::cos(0.3);
  const double s = std::sin(0.3);
  TerrainGrid grid = makeGrid(
      15, 11, GeoTransform{305000.5, 5.0 * c, 5.0 * s, 4771000.5, 5.0 * s, -5.0 * c}, kUtm16N);
  grid.noData = -32768.0F;
  grid.heights_m[3] = -32768.0F;
  std::string why;
  ASSERT_TRUE(writeDtmWithWorldFile(file("plain.tif"), grid, &why)) << why;
  ASSERT_TRUE(fs::exists(file("plain.tfw")));
  TerrainGrid back;
  ASSERT_TRUE(loadDtm(file("plain.tif"), kUtm16N, back, &why)) << why;
  expectSameGrid(grid, back);

  // The other extensions are found as well.
  fs::rename(file("plain.tfw"), file("plain.wld"));
  ASSERT_TRUE(loadDtm(file("plain.tif"), kUtm16N, back, &why)) << why;
  expectSameGrid(grid, back);
  fs::rename(file("plain.wld"), file("plain.tifw"));
  ASSERT_TRUE(loadDtm(file("plain.tif"), kUtm16N, back, &why)) << why;
  expectSameGrid(grid, back);
}

TEST_F(DtmFile, WorldFileWithoutCrsIsAnError) {
  const TerrainGrid grid = makeGrid(5, 5, kUtmTransform, kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmWithWorldFile(file("nocrs.tif"), grid, &why)) << why;
  TerrainGrid back;
  EXPECT_FALSE(loadDtm(file("nocrs.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("nocrs.tif"), std::string::npos) << why;
  EXPECT_NE(why.find("world file nocrs.tfw"), std::string::npos) << why;
  EXPECT_NE(why.find("no CRS"), std::string::npos) << why;
}

TEST_F(DtmFile, MalformedWorldFile) {
  const TerrainGrid grid = makeGrid(5, 5, kUtmTransform, kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmWithWorldFile(file("bad.tif"), grid, &why)) << why;
  std::ofstream(file("bad.tfw")) << "5.0\n0.0\n0.0\n-5.0\n305000.0\n";  // five numbers
  TerrainGrid back;
  EXPECT_FALSE(loadDtm(file("bad.tif"), kUtm16N, back, &why));
  EXPECT_NE(why.find("bad.tfw"), std::string::npos) << why;
  EXPECT_NE(why.find("malformed world file"), std::string::npos) << why;
}

TEST_F(DtmFile, NoGeoreferencing) {
  const TerrainGrid grid = makeGrid(5, 5, kUtmTransform, kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmWithWorldFile(file("bare.tif"), grid, &why)) << why;
  fs::remove(file("bare.tfw"));
  TerrainGrid back;
  EXPECT_FALSE(loadDtm(file("bare.tif"), kUtm16N, back, &why));
  EXPECT_NE(why.find("bare.tif: no georeferencing (no GeoTIFF tags and no world file)"),
            std::string::npos)
      << why;
}

TEST_F(DtmFile, ConfiguredCrsMustMatchTags) {
  const TerrainGrid grid = makeGrid(5, 5, kUtmTransform, kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("tagged.tif"), grid, &why)) << why;
  TerrainGrid back;
  EXPECT_FALSE(loadDtm(file("tagged.tif"), CrsSpec{HorizontalCrs::Utm, 17, true}, back, &why));
  EXPECT_NE(why.find("tagged.tif"), std::string::npos) << why;
  EXPECT_NE(why.find("utm:16N"), std::string::npos) << why;
  EXPECT_NE(why.find("utm:17N"), std::string::npos) << why;
}

TEST_F(DtmFile, MissingFile) {
  TerrainGrid back;
  std::string why;
  EXPECT_FALSE(loadDtm(file("absent.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("absent.tif: file not found"), std::string::npos) << why;
}

TEST_F(DtmFile, TruncatedFile) {
  const TerrainGrid grid = makeGrid(64, 64, kUtmTransform, kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("cut.tif"), grid, &why)) << why;
  fs::resize_file(file("cut.tif"), fs::file_size(file("cut.tif")) / 2);
  TerrainGrid back;
  EXPECT_FALSE(loadDtm(file("cut.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("cut.tif: cannot open as TIFF (libtiff: "), std::string::npos) << why;
  // Not a TIFF at all.
  std::ofstream(file("text.tif")) << "hello, not a tiff";
  EXPECT_FALSE(loadDtm(file("text.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("text.tif: cannot open as TIFF (libtiff: "), std::string::npos) << why;
}

// Writes a TIFF with libtiff/libgeotiff directly, for layouts our writer never produces.
struct RawTiff {
  int bits = 32;
  int format = SAMPLEFORMAT_IEEEFP;
  int samples = 1;
  bool tiled = false;
  int projectedCs = 32616;
  int rasterType = RasterPixelIsArea;
  bool geoKeys = true;
};

void writeRawTiff(const std::string& path, int cols, int rows, const RawTiff& spec,
                  const std::vector<double>& values) {
  TIFF* tif = XTIFFOpen(path.c_str(), "w");
  ASSERT_NE(tif, nullptr);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<std::uint32_t>(cols));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<std::uint32_t>(rows));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, spec.samples);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, spec.bits);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, spec.format);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  double tie[6] = {0.0, 0.0, 0.0, 305000.0, 4771000.0, 0.0};
  double scale[3] = {2.0, 3.0, 0.0};
  TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
  TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
  if (spec.geoKeys) {
    GTIF* gtif = GTIFNew(tif);
    GTIFKeySet(gtif, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
    GTIFKeySet(gtif, GTRasterTypeGeoKey, TYPE_SHORT, 1, spec.rasterType);
    GTIFKeySet(gtif, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, spec.projectedCs);
    GTIFWriteKeys(gtif);
    GTIFFree(gtif);
  }

  const int bytes = spec.bits / 8 * spec.samples;
  const auto pack = [&](int c, int r, unsigned char* out) {
    const double v = values[static_cast<std::size_t>(r) * cols + c];
    for (int k = 0; k < spec.samples; ++k) {
      unsigned char* dst = out + k * (spec.bits / 8);
      if (spec.format == SAMPLEFORMAT_IEEEFP && spec.bits == 64) {
        std::memcpy(dst, &v, 8);
      } else if (spec.format == SAMPLEFORMAT_IEEEFP) {
        const auto f = static_cast<float>(v);
        std::memcpy(dst, &f, 4);
      } else {
        const auto u = static_cast<std::uint16_t>(v);
        std::memcpy(dst, &u, 2);
      }
    }
  };
  if (spec.tiled) {
    const int tile = 16;
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, tile);
    TIFFSetField(tif, TIFFTAG_TILELENGTH, tile);
    std::vector<unsigned char> buffer(static_cast<std::size_t>(tile) * tile * bytes);
    for (int r0 = 0; r0 < rows; r0 += tile) {
      for (int c0 = 0; c0 < cols; c0 += tile) {
        std::fill(buffer.begin(), buffer.end(), 0);
        for (int r = 0; r < tile && r0 + r < rows; ++r) {
          for (int c = 0; c < tile && c0 + c < cols; ++c) {
            pack(c0 + c, r0 + r, buffer.data() + (static_cast<std::size_t>(r) * tile + c) * bytes);
          }
        }
        ASSERT_GE(TIFFWriteTile(tif, buffer.data(), c0, r0, 0, 0), 0);
      }
    }
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 3);
    std::vector<unsigned char> line(static_cast<std::size_t>(cols) * bytes);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        pack(c, r, line.data() + static_cast<std::size_t>(c) * bytes);
      }
      ASSERT_GE(TIFFWriteScanline(tif, line.data(), r, 0), 0);
    }
  }
  XTIFFClose(tif);
}

std::vector<double> rampValues(int cols, int rows) {
  std::vector<double> v(static_cast<std::size_t>(cols) * rows);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      v[static_cast<std::size_t>(r) * cols + c] = 100.0 + c + 1000.0 * r + 0.25;
    }
  }
  return v;
}

TEST_F(DtmFile, TiledFloat64PixelIsPoint) {
  const int cols = 37;
  const int rows = 21;  // partial tiles on both axes
  const std::vector<double> values = rampValues(cols, rows);
  RawTiff spec;
  spec.bits = 64;
  spec.tiled = true;
  spec.rasterType = RasterPixelIsPoint;
  writeRawTiff(file("tiled.tif"), cols, rows, spec, values);
  TerrainGrid back;
  std::string why;
  ASSERT_TRUE(loadDtm(file("tiled.tif"), std::nullopt, back, &why)) << why;
  ASSERT_EQ(back.cols, cols);
  ASSERT_EQ(back.rows, rows);
  for (std::size_t i = 0; i < values.size(); ++i) {
    ASSERT_EQ(back.heights_m[i], static_cast<float>(values[i])) << i;
  }
  // PixelIsPoint: the tiepoint is the first sample's centre.
  expectSameTransform(GeoTransform{305000.0, 2.0, 0.0, 4771000.0, 0.0, -3.0}, back.transform, 1e-9);
  EXPECT_FALSE(back.noData.has_value());
}

TEST_F(DtmFile, CompressedStripsPixelIsArea) {
  const int cols = 19;
  const int rows = 8;
  const std::vector<double> values = rampValues(cols, rows);
  writeRawTiff(file("strips.tif"), cols, rows, RawTiff{}, values);
  TerrainGrid back;
  std::string why;
  ASSERT_TRUE(loadDtm(file("strips.tif"), std::nullopt, back, &why)) << why;
  for (std::size_t i = 0; i < values.size(); ++i) {
    ASSERT_EQ(back.heights_m[i], static_cast<float>(values[i])) << i;
  }
  // PixelIsArea: the tiepoint is the first pixel's corner, its centre half a pixel in.
  expectSameTransform(GeoTransform{305001.0, 2.0, 0.0, 4770998.5, 0.0, -3.0}, back.transform, 1e-9);
}

TEST_F(DtmFile, TagsWithoutGeoKeysNeedAConfiguredCrs) {
  RawTiff spec;
  spec.geoKeys = false;
  writeRawTiff(file("nokeys.tif"), 6, 4, spec, rampValues(6, 4));
  TerrainGrid back;
  std::string why;
  EXPECT_FALSE(loadDtm(file("nokeys.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("nokeys.tif: GeoTIFF tags give no CRS"), std::string::npos) << why;
  ASSERT_TRUE(loadDtm(file("nokeys.tif"), kUtm16N, back, &why)) << why;
  EXPECT_EQ(back.crs.utmZone, 16);
  expectSameTransform(GeoTransform{305001.0, 2.0, 0.0, 4770998.5, 0.0, -3.0}, back.transform, 1e-9);
}

TEST_F(DtmFile, CorruptCompressedData) {
  writeRawTiff(file("corrupt.tif"), 40, 30, RawTiff{}, rampValues(40, 30));
  {
    // libtiff writes the image data right after the 8-byte header and the directory last:
    // scribble over the deflate streams and leave the directory intact.
    std::fstream f(file("corrupt.tif"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(8);
    const std::string junk(400, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  TerrainGrid back;
  std::string why;
  EXPECT_FALSE(loadDtm(file("corrupt.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("corrupt.tif: cannot read strip 0"), std::string::npos) << why;
  EXPECT_NE(why.find("libtiff: "), std::string::npos) << why;
}

TEST_F(DtmFile, NotAFloatTiff) {
  RawTiff spec;
  spec.bits = 16;
  spec.format = SAMPLEFORMAT_UINT;
  writeRawTiff(file("dtm16.tif"), 6, 4, spec, rampValues(6, 1 + 3));
  TerrainGrid back;
  std::string why;
  EXPECT_FALSE(loadDtm(file("dtm16.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("dtm16.tif: not a float32 single-band TIFF (bits 16, samples 1"),
            std::string::npos)
      << why;
  RawTiff rgb;
  rgb.samples = 3;
  writeRawTiff(file("rgb.tif"), 6, 4, rgb, rampValues(6, 4));
  EXPECT_FALSE(loadDtm(file("rgb.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("rgb.tif: not a float32 single-band TIFF (bits 32, samples 3"),
            std::string::npos)
      << why;
}

TEST_F(DtmFile, UnsupportedEpsg) {
  RawTiff spec;
  spec.projectedCs = 3857;
  writeRawTiff(file("merc.tif"), 6, 4, spec, rampValues(6, 4));
  TerrainGrid back;
  std::string why;
  EXPECT_FALSE(loadDtm(file("merc.tif"), std::nullopt, back, &why));
  EXPECT_NE(why.find("merc.tif: CRS EPSG:3857 not supported (use WGS84 UTM 326xx/327xx or 4326)"),
            std::string::npos)
      << why;
}

TEST_F(DtmFile, WriteRejectsInconsistentGrid) {
  TerrainGrid grid = makeGrid(5, 5, kUtmTransform, kUtm16N);
  grid.heights_m.pop_back();
  std::string why;
  EXPECT_FALSE(writeDtmGeoTiff(file("x.tif"), grid, &why));
  EXPECT_NE(why.find("x.tif"), std::string::npos) << why;
  EXPECT_FALSE(writeDtmGeoTiff((dir_ / "no_such_dir" / "y.tif").string(),
                               makeGrid(5, 5, kUtmTransform, kUtm16N), &why));
  EXPECT_NE(why.find("y.tif: cannot create TIFF"), std::string::npos) << why;
}

// A 551 kB file whose header declares 65 535 x 16 000 float32 samples (4.2 GB): refused from
// the declared size, before the grid is allocated, naming the file and the sizes.
TEST_F(DtmFile, HeaderClaimingAHugeRasterIsRefusedBeforeAllocating) {
  const std::string path = file("dtm.tif");
  {
    TIFF* tif = XTIFFOpen(path.c_str(), "w");
    ASSERT_NE(tif, nullptr);
    TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, std::uint32_t{65535});
    TIFFSetField(tif, TIFFTAG_IMAGELENGTH, std::uint32_t{16000});
    TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
    TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 32);
    TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
    TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
    TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, std::uint32_t{16000});
    double tie[6] = {0.0, 0.0, 0.0, 305000.0, 4771000.0, 0.0};
    double scale[3] = {1.0, 1.0, 0.0};
    TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
    TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
    std::vector<unsigned char> strip(551 * 1000, 0);
    ASSERT_GE(TIFFWriteRawStrip(tif, 0, strip.data(), static_cast<tmsize_t>(strip.size())), 0);
    XTIFFClose(tif);
  }
  ASSERT_LT(fs::file_size(path), 560'000U);

  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  TerrainGrid grid;
  std::string why;
  // The default cap (2^26 samples) refuses it first.
  EXPECT_FALSE(loadDtm(path, kUtm16N, grid, &why));
  EXPECT_NE(why.find(path + ": raster of 65535 x 16000 = 1 048 560 000 samples exceeds "
                            "terrain.max_samples 67 108 864"),
            std::string::npos)
      << why;
  // With the cap at its largest, the file's size refuses it: the raster is not compressed.
  DtmLoadOptions options;
  options.maxSamples = kDtmMaxSamplesLimit;
  EXPECT_FALSE(loadDtm(path, kUtm16N, grid, &why, options));
  EXPECT_NE(why.find(path + ": header declares an uncompressed raster of 65535 x 16000 = "
                            "1 048 560 000 samples (4 194 240 000 bytes), larger than the file"),
            std::string::npos)
      << why;
  EXPECT_TRUE(grid.heights_m.empty());
  // Nothing near the declared 4.2 GB was touched (peak resident size grew by < 64 MB).
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 64 * 1024) << "kB";
}

TEST_F(DtmFile, MaxSamplesCapsTheRaster) {
  const TerrainGrid grid = makeGrid(64, 50, kUtmTransform, kUtm16N);
  std::string why;
  ASSERT_TRUE(writeDtmGeoTiff(file("capped.tif"), grid, &why)) << why;
  TerrainGrid back;
  DtmLoadOptions options;
  options.maxSamples = 3199;
  EXPECT_FALSE(loadDtm(file("capped.tif"), std::nullopt, back, &why, options));
  EXPECT_NE(why.find("capped.tif: raster of 64 x 50 = 3 200 samples exceeds terrain.max_samples "
                     "3 199 (0 MiB in memory)"),
            std::string::npos)
      << why;
  options.maxSamples = 3200;
  ASSERT_TRUE(loadDtm(file("capped.tif"), std::nullopt, back, &why, options)) << why;
  expectSameGrid(grid, back);
}

// The sample DTM shipped for the demo (see tests/fixtures/dtm/README.md).
TEST(DtmFixture, ShippedSampleIsReadable) {
  const std::string path = std::string(VP_FIXTURE_DIR) + "/dtm/sloped_utm16n.tif";
  TerrainGrid grid;
  std::string why;
  ASSERT_TRUE(loadDtm(path, std::nullopt, grid, &why)) << why;
  EXPECT_EQ(grid.cols, 41);
  EXPECT_EQ(grid.rows, 41);
  EXPECT_EQ(grid.crs.kind, HorizontalCrs::Utm);
  EXPECT_EQ(grid.crs.utmZone, 16);
  EXPECT_TRUE(grid.crs.utmNorth);
  expectSameTransform(GeoTransform{304410.0, 5.0, 0.0, 4771831.0, 0.0, -5.0}, grid.transform, 1e-9);
  ASSERT_TRUE(grid.noData.has_value());
  EXPECT_EQ(*grid.noData, -9999.0F);
  EXPECT_EQ(grid.heights_m[40 * 41 + 40], -9999.0F);
  // h = 260 + 0.03 e + 2 exp(-((e - 20)^2 + (n - 30)^2) / (2 * 25^2)), e/n from the centre.
  const auto formula = [](double e, double n) {
    return 260.0 + 0.03 * e +
           2.0 *
               std::exp(-((e - 20.0) * (e - 20.0) + (n - 30.0) * (n - 30.0)) / (2.0 * 25.0 * 25.0));
  };
  for (int r = 0; r < 41; ++r) {
    for (int c = 0; c < 41; ++c) {
      if (r == 40 && c == 40) {
        continue;
      }
      const double e = (c - 20) * 5.0;
      const double n = (20 - r) * 5.0;
      EXPECT_NEAR(grid.heights_m[static_cast<std::size_t>(r) * 41 + c], formula(e, n), 1e-4)
          << c << "," << r;
    }
  }
}

}  // namespace
}  // namespace vp::io
