#include "preprocess/tiling.hpp"

namespace vp::preprocess {

namespace {

// Start of tile i of n along an axis: evenly spread over [0, content - tile], rounded down so
// the step never exceeds tile - overlap (the overlap is kept).
int tileStart(int i, int n, int content, int tile) {
  if (n <= 1) {
    return 0;
  }
  return static_cast<int>(static_cast<long long>(i) * (content - tile) / (n - 1));
}

}  // namespace

int tilesAlongAxis(int content, int tile, int overlap) {
  if (content <= 0 || tile <= 0 || overlap < 0 || overlap >= tile) {
    return 0;
  }
  if (content <= tile) {
    return 1;
  }
  const int step = tile - overlap;
  return (content - overlap + step - 1) / step;
}

std::size_t layoutTiles(int contentWidth, int contentHeight, int tileWidth, int tileHeight,
                        int overlap, std::span<TileRect> tiles) {
  const int nx = tilesAlongAxis(contentWidth, tileWidth, overlap);
  const int ny = tilesAlongAxis(contentHeight, tileHeight, overlap);
  if (nx == 0 || ny == 0) {
    return 0;
  }
  const auto count = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  if (count > tiles.size()) {
    return 0;
  }
  std::size_t k = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i, ++k) {
      TileRect& t = tiles[k];
      t.x0_px = tileStart(i, nx, contentWidth, tileWidth);
      t.y0_px = tileStart(j, ny, contentHeight, tileHeight);
      t.width_px = tileWidth;
      t.height_px = tileHeight;
      t.innerLeft = i > 0;
      t.innerRight = i + 1 < nx;
      t.innerTop = j > 0;
      t.innerBottom = j + 1 < ny;
    }
  }
  return count;
}

}  // namespace vp::preprocess
