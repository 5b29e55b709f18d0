// fuzz/dtm_file: the DTM loader (src/foundation/io: GeoTIFF tags, world file, GDAL_NODATA) and
// the terrain model built on what it loads (src/foundation/terrain). Input layout:
//   byte 0      bit 0: a CRS is configured (utm:16N) for world-file DTMs
//   bytes 1-2   world file length L (little endian; 0: no world file beside the image)
//   L bytes     the world file (dtm.tfw)
//   the rest    the TIFF (dtm.tif)
// Contract checked: loadDtm() returns true with a consistent grid, or false with a message
// naming the file; it never allocates more than maxSamples samples (the harness sets a small
// cap, so a header declaring more must be refused, not allocated); TerrainModel::init() on a
// loaded grid returns true or false, and height queries on an initialised model return a
// height or a status.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "geodesy/geodesy.hpp"
#include "io/dtm_file.hpp"
#include "terrain/terrain_model.hpp"

namespace {

namespace fs = std::filesystem;
constexpr const char* kTarget = "dtm_file";
// 2^20 samples (4 MiB): large enough for any seed, small enough to fuzz fast.
constexpr std::uint64_t kMaxSamples = std::uint64_t{1} << 20;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) {
    return 0;
  }
  const bool configureCrs = (data[0] & 1U) != 0;
  std::size_t worldLength = static_cast<std::size_t>(data[1]) | (std::size_t{data[2]} << 8);
  std::string_view rest = vp::fuzz::asText(data + 3, size - 3);
  worldLength = std::min(worldLength, rest.size());
  const fs::path tif = vp::fuzz::scratchDirectory() / "dtm.tif";
  const fs::path world = vp::fuzz::scratchDirectory() / "dtm.tfw";
  if (worldLength > 0) {
    vp::fuzz::writeFile(world, rest.substr(0, worldLength));
  } else {
    vp::fuzz::removeFile(world);
  }
  vp::fuzz::writeFile(tif, rest.substr(worldLength));

  std::optional<vp::terrain::CrsSpec> crs;
  if (configureCrs) {
    crs = vp::terrain::CrsSpec{vp::terrain::HorizontalCrs::Utm, 16, true};
  }
  vp::io::DtmLoadOptions options;
  options.maxSamples = kMaxSamples;
  vp::terrain::TerrainGrid grid;
  std::string why;
  if (!vp::io::loadDtm(tif.string(), crs, grid, &why, options)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.find("dtm.t") != std::string::npos, kTarget,
                     "loadDtm() failed without naming the file: '" + why + "'");
    return 0;
  }
  vp::fuzz::expect(grid.cols >= 2 && grid.rows >= 2 &&
                       static_cast<std::uint64_t>(grid.cols) * grid.rows <= kMaxSamples &&
                       grid.heights_m.size() == static_cast<std::size_t>(grid.cols) * grid.rows,
                   kTarget, "loaded grid has inconsistent or too large dimensions");

  // The terrain model around the grid's first sample (a frame far from the grid only makes
  // every query OutsideDtm).
  const vp::geodesy::LocalFrame frame(vp::geodesy::GeodeticPoint{43.0731, -89.4012, 260.0});
  vp::terrain::TerrainModel model;
  vp::fuzz::note(kTarget,
                 "loaded " + std::to_string(grid.cols) + " x " + std::to_string(grid.rows));
  if (!model.init(std::move(grid), frame, &why)) {
    return 0;
  }
  const auto height = model.heightAt(43.0731, -89.4012);
  if (height) {
    vp::fuzz::expect(std::isfinite(*height), kTarget, "heightAt() returned a non-finite height");
  }
  const auto ground =
      model.intersectRay(Eigen::Vector3d(0.0, 0.0, 500.0), Eigen::Vector3d(0.1, -0.2, -1.0));
  if (ground) {
    vp::fuzz::expect(ground->allFinite(), kTarget, "intersectRay() returned a non-finite point");
  }
  return 0;
}
