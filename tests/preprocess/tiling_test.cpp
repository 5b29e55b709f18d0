// Tiling: network-sized tiles cover the whole scaled frame, neighbours overlap by at least
// the requested amount, no tile reaches past the content, inner edges are flagged.
#include "preprocess/tiling.hpp"

#include <algorithm>
#include <array>
#include <vector>

#include <gtest/gtest.h>

namespace vp::preprocess {
namespace {

TEST(Tiling, TilesAlongAnAxis) {
  EXPECT_EQ(tilesAlongAxis(648, 672, 96), 1);  // default working scale: one tile
  EXPECT_EQ(tilesAlongAxis(672, 672, 96), 1);
  EXPECT_EQ(tilesAlongAxis(673, 672, 96), 2);
  EXPECT_EQ(tilesAlongAxis(1296, 672, 96), 3);  // (1296 - 96) / 576 = 2.08
  EXPECT_EQ(tilesAlongAxis(1248, 672, 96), 2);  // exactly 2 x 672 - 96
  EXPECT_EQ(tilesAlongAxis(1344, 672, 0), 2);
  EXPECT_EQ(tilesAlongAxis(100, 64, 64), 0);  // overlap must be < tile
  EXPECT_EQ(tilesAlongAxis(0, 64, 8), 0);
}

void expectCoverage(int contentW, int contentH, int tileW, int tileH, int overlap) {
  SCOPED_TRACE(std::to_string(contentW) + "x" + std::to_string(contentH) + " overlap " +
               std::to_string(overlap));
  std::array<TileRect, 64> tiles{};
  const std::size_t n = layoutTiles(contentW, contentH, tileW, tileH, overlap, tiles);
  const int nx = tilesAlongAxis(contentW, tileW, overlap);
  const int ny = tilesAlongAxis(contentH, tileH, overlap);
  ASSERT_EQ(n, static_cast<std::size_t>(nx * ny));
  std::vector<int> covered(static_cast<std::size_t>(contentW) * contentH, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const TileRect& t = tiles[k];
    EXPECT_EQ(t.width_px, tileW);
    EXPECT_EQ(t.height_px, tileH);
    EXPECT_GE(t.x0_px, 0);
    EXPECT_GE(t.y0_px, 0);
    // Inside the content wherever the content is at least a tile long.
    if (contentW >= tileW) {
      EXPECT_LE(t.x0_px + tileW, contentW);
    } else {
      EXPECT_EQ(t.x0_px, 0);
    }
    if (contentH >= tileH) {
      EXPECT_LE(t.y0_px + tileH, contentH);
    } else {
      EXPECT_EQ(t.y0_px, 0);
    }
    const int i = static_cast<int>(k) % nx;
    const int j = static_cast<int>(k) / nx;
    EXPECT_EQ(t.innerLeft, i > 0);
    EXPECT_EQ(t.innerRight, i + 1 < nx);
    EXPECT_EQ(t.innerTop, j > 0);
    EXPECT_EQ(t.innerBottom, j + 1 < ny);
    // Overlap with the right and lower neighbours.
    if (i + 1 < nx) {
      EXPECT_GE(t.x0_px + tileW - tiles[k + 1].x0_px, overlap);
    }
    if (j + 1 < ny) {
      EXPECT_GE(t.y0_px + tileH - tiles[k + static_cast<std::size_t>(nx)].y0_px, overlap);
    }
    for (int y = t.y0_px; y < std::min(t.y0_px + tileH, contentH); ++y) {
      for (int x = t.x0_px; x < std::min(t.x0_px + tileW, contentW); ++x) {
        ++covered[static_cast<std::size_t>(y) * contentW + x];
      }
    }
  }
  EXPECT_EQ(std::count(covered.begin(), covered.end(), 0), 0) << "uncovered working pixels";
}

TEST(Tiling, CoversTheFrameWithTheRequestedOverlap) {
  expectCoverage(648, 512, 672, 512, 96);    // default: one (padded) tile
  expectCoverage(1296, 1024, 672, 512, 96);  // working scale 0.5: 3 x 3
  expectCoverage(1296, 1024, 672, 512, 64);
  expectCoverage(2592, 2048, 672, 512, 128);  // full resolution: 5 x 5
  expectCoverage(1000, 400, 672, 512, 100);   // wide and short: 2 x 1, padded below
  expectCoverage(673, 513, 672, 512, 0);
}

TEST(Tiling, RefusesWhatDoesNotFit) {
  std::array<TileRect, 4> four{};
  EXPECT_EQ(layoutTiles(1296, 1024, 672, 512, 96, four), 0U);   // needs 9
  EXPECT_EQ(four[0].width_px, 0);                               // nothing written
  EXPECT_EQ(layoutTiles(1296, 1024, 672, 512, 672, four), 0U);  // overlap >= tile
}

}  // namespace
}  // namespace vp::preprocess
