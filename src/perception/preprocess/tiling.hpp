// preprocess/tiling: cuts the working image into network-input-sized tiles that overlap.
//
// Contract: layoutTiles() covers a content area of contentWidth x contentHeight working
// pixels with tiles of exactly tileWidth x tileHeight (the detector's fixed input). Along an
// axis where the content fits in one tile there is one tile at 0 (the rest of it is padding);
// otherwise n = ceil((L - overlap) / (T - overlap)) tiles are spread evenly from 0 to L - T,
// so neighbours share at least `overlap` pixels and no tile reaches past the content. Tiles
// are listed row by row. A tile edge shared with a neighbour is "inner": a vehicle cut there
// is seen whole by the neighbour when the overlap is at least the vehicle's length. Pure,
// no allocation (the caller owns the output span).
#pragma once

#include <cstddef>
#include <span>

namespace vp::preprocess {

struct TileRect {
  int x0_px = 0;  // top-left corner in the working image
  int y0_px = 0;
  int width_px = 0;  // the network input size
  int height_px = 0;
  bool innerLeft = false;  // edges shared with an overlapping neighbour tile
  bool innerTop = false;
  bool innerRight = false;
  bool innerBottom = false;
};

// Number of tiles along one axis of length `content` for tiles of `tile` px overlapping by
// `overlap` px (0 <= overlap < tile); 0 on invalid arguments.
int tilesAlongAxis(int content, int tile, int overlap);

// Fills `tiles` and returns the count; returns 0 (and writes nothing) on invalid arguments or
// when `tiles` is too small.
std::size_t layoutTiles(int contentWidth, int contentHeight, int tileWidth, int tileHeight,
                        int overlap, std::span<TileRect> tiles);

}  // namespace vp::preprocess
