// DetectionDecoder: hand-made detector outputs -> exact boxes in frame pixels (as the Python
// decoder gives them), and rotated NMS within and across tiles.
#include "detection/decoder.hpp"

#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "geometry/rotated_box.hpp"
#include "synthetic_heads.hpp"

namespace vp::detection {
namespace {

// tools/detector/evaluate.py's decoding (threshold 0.3, not the shipped 0.4), which these
// tests were written against.
DecoderOptions pythonDecode() {
  DecoderOptions options;
  options.scoreThreshold = 0.3F;
  return options;
}

using test::SyntheticHeads;

preprocess::TileView tileAt(int index, int x0, int y0, int width, int height, bool innerLeft,
                            bool innerRight) {
  preprocess::TileView tile;
  tile.index = index;
  tile.rect.x0_px = x0;
  tile.rect.y0_px = y0;
  tile.rect.width_px = width;
  tile.rect.height_px = height;
  tile.rect.innerLeft = innerLeft;
  tile.rect.innerRight = innerRight;
  return tile;
}

preprocess::FrameGeometry geometryFor(int frameW, int frameH, double scale) {
  preprocess::FrameGeometry g;
  g.frameWidth_px = frameW;
  g.frameHeight_px = frameH;
  g.workingWidth_px = static_cast<int>(std::lround(frameW * scale));
  g.workingHeight_px = static_cast<int>(std::lround(frameH * scale));
  g.scaleX = static_cast<double>(g.workingWidth_px) / frameW;
  g.scaleY = static_cast<double>(g.workingHeight_px) / frameH;
  return g;
}

// The grid of evaluate.decode's docstring example, fed to the Python decoder:
//   hm (5 x 6) below; with ix, iy the cell indices (float32 numpy arrays):
//   offset = (0.1 ix - 0.25, -0.05 iy + 0.1), size = (2.5 + 0.1 ix, 1.5 + 0.05 iy),
//   a = 0.7 ix + 1.3 iy - 2, direction = 0.8 (cos a, sin a);
//   decode(out, stride=4, threshold=0.3, top_k=200) printed with %.9f.
TEST(DetectionDecoder, MatchesThePythonDecoderOnAHandMadeGrid) {
  constexpr int kW = 6;
  constexpr int kH = 5;
  const float hm[kH][kW] = {{0.10F, 0.35F, 0.20F, 0.05F, 0.50F, 0.45F},
                            {0.31F, 0.25F, 0.15F, 0.05F, 0.40F, 0.10F},
                            {0.05F, 0.10F, 0.80F, 0.30F, 0.10F, 0.05F},
                            {0.20F, 0.10F, 0.60F, 0.29F, 0.70F, 0.33F},
                            {0.90F, 0.10F, 0.05F, 0.10F, 0.32F, 0.34F}};
  SyntheticHeads heads(kW, kH);
  for (int iy = 0; iy < kH; ++iy) {
    for (int ix = 0; ix < kW; ++ix) {
      const auto x = static_cast<float>(ix);
      const auto y = static_cast<float>(iy);
      heads.heatmapAt(ix, iy) = hm[iy][ix];
      heads.offsetAt(ix, iy)[0] = 0.1F * x - 0.25F;
      heads.offsetAt(ix, iy)[1] = -0.05F * y + 0.1F;
      heads.sizeAt(ix, iy)[0] = 2.5F + 0.1F * x;
      heads.sizeAt(ix, iy)[1] = 1.5F + 0.05F * y;
      const float a = 0.7F * x + 1.3F * y - 2.0F;
      heads.directionAt(ix, iy)[0] = std::cos(a) * 0.8F;
      heads.directionAt(ix, iy)[1] = std::sin(a) * 0.8F;
    }
  }
  // (cx, cy, length, width, angle, score) from the Python decoder.
  const double expected[5][6] = {
      {0.500000000, 17.099999994, 12.182493210, 5.473947525, 3.199999634, 0.9000000},
      {9.300000012, 9.500000000, 14.879733086, 4.953032494, 2.000000000, 0.8000000},
      {18.100000024, 13.299999982, 18.174146652, 5.206979752, 4.699999754, 0.7000000},
      {18.100000024, 1.900000006, 18.174146652, 4.481688976, 0.800000072, 0.5000000},
      {4.899999976, 1.900000006, 13.463736534, 4.481688976, 4.983185355, 0.3500000}};

  DecoderOptions options = pythonDecode();
  options.nmsIou = 1.0;  // Python's decode has no box NMS: keep every peak
  DetectionDecoder decoder;
  std::string why;
  ASSERT_TRUE(decoder.init(options, kW, kH, 4, 1, &why)) << why;
  decoder.beginFrame();
  // Scale 1: frame pixels = working pixels, so the numbers compare directly.
  ASSERT_EQ(decoder.decodeTile(heads.heads(), tileAt(0, 0, 0, 24, 20, false, false),
                               geometryFor(24, 20, 1.0)),
            DecodeStatus::Ok);
  EXPECT_EQ(decoder.candidateCount(), 5U);
  std::array<Detection, 8> out{};
  ASSERT_EQ(decoder.finishFrame(out), 5U);
  for (int i = 0; i < 5; ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(out[i].box.cx, expected[i][0], 1e-5);
    EXPECT_NEAR(out[i].box.cy, expected[i][1], 1e-5);
    EXPECT_NEAR(out[i].box.length, expected[i][2], 1e-5);
    EXPECT_NEAR(out[i].box.width, expected[i][3], 1e-5);
    EXPECT_NEAR(out[i].box.angle, expected[i][4], 1e-6);
    EXPECT_NEAR(out[i].score, expected[i][5], 1e-7);
    EXPECT_TRUE(out[i].directionKnown);
    EXPECT_EQ(out[i].gamma.count, 0);
    EXPECT_FLOAT_EQ(out[i].typeProbabilities[3], 1.0F / 7.0F);
  }
}

// Vehicles in all four quadrants of the driving direction, at the default working scale
// (a 2592 x 2048 frame seen as 648 x 512 in a 672 x 512 tile).
TEST(DetectionDecoder, KnownVehiclesComeBackExactlyInFramePixels) {
  struct Vehicle {
    double u, v, length, width, angle;
    float score;
  };
  const Vehicle vehicles[] = {{400.3, 300.7, 180.0, 72.0, 0.4, 0.91F},
                              {1500.0, 1200.25, 190.0, 75.0, 2.5, 0.83F},
                              {2000.5, 600.0, 170.0, 70.0, 3.9, 0.77F},
                              {900.0, 1800.0, 200.0, 80.0, 5.8, 0.64F}};
  const preprocess::FrameGeometry geometry = geometryFor(2592, 2048, 0.25);
  SyntheticHeads heads(168, 128);
  for (const Vehicle& v : vehicles) {
    // frame -> working pixels: (f + 0.5) * scale - 0.5; sizes * scale.
    heads.addVehicle((v.u + 0.5) * 0.25 - 0.5, (v.v + 0.5) * 0.25 - 0.5, v.length * 0.25,
                     v.width * 0.25, v.angle, v.score);
  }
  DetectionDecoder decoder;
  ASSERT_TRUE(decoder.init(pythonDecode(), 168, 128, 4, 1));
  decoder.beginFrame();
  ASSERT_EQ(decoder.decodeTile(heads.heads(), tileAt(0, 0, 0, 672, 512, false, false), geometry),
            DecodeStatus::Ok);
  std::array<Detection, 8> out{};
  ASSERT_EQ(decoder.finishFrame(out), 4U);
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(out[i].box.cx, vehicles[i].u, 2e-4);
    EXPECT_NEAR(out[i].box.cy, vehicles[i].v, 2e-4);
    EXPECT_NEAR(out[i].box.length, vehicles[i].length, 1e-4);
    EXPECT_NEAR(out[i].box.width, vehicles[i].width, 1e-4);
    // Full circle: 3.9 and 5.8 rad are not folded to the other half.
    EXPECT_NEAR(out[i].box.angle, vehicles[i].angle, 1e-6);
    EXPECT_EQ(out[i].score, vehicles[i].score);
    EXPECT_EQ(out[i].tile, 0);
  }
}

TEST(DetectionDecoder, ThresholdTopKAndPlateaus) {
  SyntheticHeads heads(40, 30);
  heads.addVehicle(20, 20, 30, 12, 0.0, 0.9F);
  heads.addVehicle(80, 20, 30, 12, 1.0, 0.8F);
  heads.addVehicle(20, 80, 30, 12, 2.0, 0.7F);
  heads.addVehicle(80, 80, 30, 12, 3.0, 0.29F);  // below the 0.3 threshold
  const preprocess::FrameGeometry geometry = geometryFor(160, 120, 1.0);
  DecoderOptions options = pythonDecode();
  options.topKPerTile = 2;
  DetectionDecoder decoder;
  ASSERT_TRUE(decoder.init(options, 40, 30, 4, 1));
  decoder.beginFrame();
  ASSERT_EQ(decoder.decodeTile(heads.heads(), tileAt(0, 0, 0, 160, 120, false, false), geometry),
            DecodeStatus::Ok);
  std::array<Detection, 8> out{};
  ASSERT_EQ(decoder.finishFrame(out), 2U);  // top 2 of the 3 above the threshold
  EXPECT_EQ(out[0].score, 0.9F);
  EXPECT_EQ(out[1].score, 0.8F);

  // A plateau (two equal neighbouring maxima) gives two peaks, as hm >= max(neighbours) does
  // in Python; their boxes coincide, so NMS keeps one.
  SyntheticHeads plateau(20, 20);
  plateau.addVehicle(38, 38, 30, 12, 0.5, 0.9F);
  plateau.heatmapAt(10, 9) = 0.9F;
  std::copy_n(plateau.offsetAt(9, 9), 2, plateau.offsetAt(10, 9));
  std::copy_n(plateau.sizeAt(9, 9), 2, plateau.sizeAt(10, 9));
  std::copy_n(plateau.directionAt(9, 9), 2, plateau.directionAt(10, 9));
  DetectionDecoder second;
  ASSERT_TRUE(second.init(pythonDecode(), 20, 20, 4, 1));
  second.beginFrame();
  ASSERT_EQ(second.decodeTile(plateau.heads(), tileAt(0, 0, 0, 80, 80, false, false),
                              geometryFor(80, 80, 1.0)),
            DecodeStatus::Ok);
  EXPECT_EQ(second.candidateCount(), 2U);
  ASSERT_EQ(second.finishFrame(out), 1U);
  EXPECT_NEAR(out[0].box.cx, 38.0, 1e-4);  // the lower cell index wins the tie
}

// Working image 1296 x 1024 (frame 2592 x 2048 at scale 0.5); tile A at x 0, tile B at x 600
// (72 px overlap), both 672 x 512.
class CrossTile : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(decoder.init(pythonDecode(), 168, 128, 4, 2)); }
  std::size_t decode(const SyntheticHeads& a, const SyntheticHeads& b) {
    decoder.beginFrame();
    EXPECT_EQ(decoder.decodeTile(a.heads(), tileAt(0, 0, 0, 672, 512, false, true), geometry),
              DecodeStatus::Ok);
    EXPECT_EQ(decoder.decodeTile(b.heads(), tileAt(1, 600, 0, 672, 512, true, false), geometry),
              DecodeStatus::Ok);
    return decoder.finishFrame(out);
  }
  DetectionDecoder decoder;
  preprocess::FrameGeometry geometry = geometryFor(2592, 2048, 0.5);
  std::array<Detection, 16> out{};
};

TEST_F(CrossTile, TheSameVehicleFromTwoTilesIsKeptOnce) {
  // Working (630, 200), 40 x 16 px: whole in both tiles, seen slightly differently by each.
  SyntheticHeads a(168, 128);
  SyntheticHeads b(168, 128);
  a.addVehicle(630.0, 200.0, 40.0, 16.0, 0.2, 0.80F);
  b.addVehicle(630.4 - 600.0, 200.3, 41.0, 16.5, 0.22, 0.85F);
  ASSERT_EQ(decode(a, b), 1U);
  EXPECT_EQ(decoder.candidateCount(), 2U);
  EXPECT_EQ(decoder.cutCandidateCount(), 0U);
  EXPECT_EQ(out[0].tile, 1);  // the better score
  EXPECT_NEAR(out[0].box.cx, (630.4 + 0.5) / 0.5 - 0.5, 1e-3);
}

TEST_F(CrossTile, ACutCopyLosesToTheWholeVehicle) {
  // Working (660, 300), 40 x 16, heading along u: it reaches x = 680, past tile A's inner
  // right edge (671.5). Tile A sees only its rear part (a short box at the edge) - and is more
  // confident about it; tile B sees it whole.
  SyntheticHeads a(168, 128);
  SyntheticHeads b(168, 128);
  a.addVehicle(663.0, 300.0, 16.0, 16.0, 0.0, 0.95F);
  b.addVehicle(660.0 - 600.0, 300.0, 40.0, 16.0, 0.0, 0.80F);
  ASSERT_EQ(decode(a, b), 1U);
  EXPECT_EQ(decoder.cutCandidateCount(), 1U);
  EXPECT_EQ(out[0].tile, 1);
  EXPECT_NEAR(out[0].box.cx, (660.0 + 0.5) / 0.5 - 0.5, 1e-3);
  EXPECT_NEAR(out[0].box.length, 80.0, 1e-3);  // the whole length, in frame pixels
}

TEST_F(CrossTile, NeighbouringVehiclesInTheOverlapAreAllKept) {
  // Two cars side by side (2 px gap) in the overlap, each seen by both tiles.
  SyntheticHeads a(168, 128);
  SyntheticHeads b(168, 128);
  for (const double v : {400.0, 418.0}) {
    a.addVehicle(636.0, v, 40.0, 16.0, 0.0, v < 410.0 ? 0.9F : 0.7F);
    b.addVehicle(36.0, v, 40.0, 16.0, 0.0, v < 410.0 ? 0.85F : 0.75F);
  }
  ASSERT_EQ(decode(a, b), 2U);
  EXPECT_EQ(decoder.candidateCount(), 4U);
  EXPECT_NEAR(out[0].box.cy, (400.0 + 0.5) / 0.5 - 0.5, 1e-3);
  EXPECT_NEAR(out[1].box.cy, (418.0 + 0.5) / 0.5 - 0.5, 1e-3);
}

TEST(DetectionDecoder, OverlappingBoxesInOneTileKeepTheBest) {
  SyntheticHeads heads(60, 40);
  heads.addVehicle(100.0, 80.0, 40.0, 16.0, 0.0, 0.9F);
  heads.addVehicle(108.0, 80.0, 40.0, 16.0, 0.1, 0.6F);   // IoU ~0.6 with the first
  heads.addVehicle(100.0, 100.0, 40.0, 16.0, 0.0, 0.7F);  // beside it: IoU 0
  DetectionDecoder decoder;
  ASSERT_TRUE(decoder.init(pythonDecode(), 60, 40, 4, 1));
  decoder.beginFrame();
  ASSERT_EQ(decoder.decodeTile(heads.heads(), tileAt(0, 0, 0, 240, 160, false, false),
                               geometryFor(240, 160, 1.0)),
            DecodeStatus::Ok);
  std::array<Detection, 8> out{};
  ASSERT_EQ(decoder.finishFrame(out), 2U);
  EXPECT_EQ(out[0].score, 0.9F);
  EXPECT_EQ(out[1].score, 0.7F);
}

TEST(DetectionDecoder, CentresInThePaddingAreNotVehicles) {
  // Default working image: 648 px of content in a 672 px tile; a peak at working x 660.
  SyntheticHeads heads(168, 128);
  heads.addVehicle(660.0, 200.0, 40.0, 16.0, 0.0, 0.9F);
  heads.addVehicle(300.0, 200.0, 40.0, 16.0, 0.0, 0.8F);
  const preprocess::FrameGeometry geometry = geometryFor(2592, 2048, 0.25);
  std::array<Detection, 8> out{};
  for (const bool drop : {true, false}) {
    DecoderOptions options = pythonDecode();
    options.dropCentresOutsideFrame = drop;
    DetectionDecoder decoder;
    ASSERT_TRUE(decoder.init(options, 168, 128, 4, 1));
    decoder.beginFrame();
    ASSERT_EQ(decoder.decodeTile(heads.heads(), tileAt(0, 0, 0, 672, 512, false, false), geometry),
              DecodeStatus::Ok);
    EXPECT_EQ(decoder.finishFrame(out), drop ? 1U : 2U);
  }
}

TEST(DetectionDecoder, OutputCapacityAndStatuses) {
  SyntheticHeads heads(40, 30);
  heads.addVehicle(20, 20, 30, 12, 0.0, 0.9F);
  heads.addVehicle(80, 20, 30, 12, 1.0, 0.8F);
  heads.addVehicle(20, 80, 30, 12, 2.0, 0.7F);
  const preprocess::FrameGeometry geometry = geometryFor(160, 120, 1.0);
  const preprocess::TileView tile = tileAt(0, 0, 0, 160, 120, false, false);
  DetectionDecoder decoder;
  EXPECT_EQ(decoder.decodeTile(heads.heads(), tile, geometry), DecodeStatus::NotInitialised);
  ASSERT_TRUE(decoder.init(pythonDecode(), 40, 30, 4, 1));
  decoder.beginFrame();
  HeadTensors broken = heads.heads();
  broken.size = nullptr;
  EXPECT_EQ(decoder.decodeTile(broken, tile, geometry), DecodeStatus::MissingTensor);
  broken = heads.heads();
  broken.gridWidth = 41;
  EXPECT_EQ(decoder.decodeTile(broken, tile, geometry), DecodeStatus::GridMismatch);
  ASSERT_EQ(decoder.decodeTile(heads.heads(), tile, geometry), DecodeStatus::Ok);
  EXPECT_EQ(decoder.decodeTile(heads.heads(), tile, geometry), DecodeStatus::TooManyTiles);
  std::array<Detection, 2> two{};
  EXPECT_EQ(decoder.finishFrame(two), 2U);
  EXPECT_EQ(decoder.droppedForCapacity(), 1U);
  EXPECT_EQ(two[1].score, 0.8F);

  std::string why;
  DecoderOptions bad = pythonDecode();
  bad.scoreThreshold = 1.5F;
  EXPECT_FALSE(decoder.init(bad, 40, 30, 4, 1, &why));
  EXPECT_NE(why.find("score_threshold"), std::string::npos) << why;
  bad = pythonDecode();
  bad.nmsIou = 0.0;
  EXPECT_FALSE(validate(bad, &why));
  EXPECT_NE(why.find("nms_iou"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::detection
