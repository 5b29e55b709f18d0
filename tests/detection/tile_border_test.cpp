// Acceptance: a vehicle straddling a tile border is detected once — not twice (one
// copy per tile) and not never (the cut copy suppressing the whole one, or both dropped).
//
// A frame is rendered by the simulator (held-out seed) and cut into overlapping tiles by
// running the shipped detector at working scale 1 (1296 x 1024 -> 2 x 2 tiles of 672 x 512).
// For every ground-truth vehicle whose box crosses an inner tile edge, the reference is the
// detector run on each tile that holds it whole (one or more); whenever every such tile alone
// finds it, the whole tiled frame must report it exactly once. (One of them boxing it badly
// is the detector's error: with the v3 second stage, a car lying whole in two tiles got a
// wrong-axis top peak in one of them, which the tiled frame then kept.) This separates the tiling
// logic (what this test is about) from the detector's own recall (the model card's business).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "detection/detection.hpp"
#include "detection/detection_stage.hpp"
#include "geometry/rotated_box.hpp"
#include "preprocess/preprocessor.hpp"
#include "simulator.hpp"

namespace {

using vp::detection::Detection;
using vp::geometry::RotatedBox;

constexpr double kMatchIou = 0.5;  // seed 000's true-positive threshold

bool crossesInnerEdge(const RotatedBox& box, const vp::preprocess::TileRect& t) {
  double minU = 1e9, maxU = -1e9, minV = 1e9, maxV = -1e9;
  for (const auto& c : vp::geometry::corners(box)) {
    minU = std::min(minU, c.x());
    maxU = std::max(maxU, c.x());
    minV = std::min(minV, c.y());
    maxV = std::max(maxV, c.y());
  }
  const double right = t.x0_px + t.width_px, bottom = t.y0_px + t.height_px;
  const bool overlapsTile = maxU > t.x0_px && minU < right && maxV > t.y0_px && minV < bottom;
  return overlapsTile && ((t.innerRight && minU < right && maxU > right) ||
                          (t.innerBottom && minV < bottom && maxV > bottom) ||
                          (t.innerLeft && minU < t.x0_px && maxU > t.x0_px) ||
                          (t.innerTop && minV < t.y0_px && maxV > t.y0_px));
}

bool insideTile(const RotatedBox& box, const vp::preprocess::TileRect& t) {
  for (const auto& c : vp::geometry::corners(box)) {
    if (c.x() < t.x0_px + 1 || c.x() > t.x0_px + t.width_px - 2 || c.y() < t.y0_px + 1 ||
        c.y() > t.y0_px + t.height_px - 2)
      return false;
  }
  return true;
}

int matches(const RotatedBox& truth, const std::vector<Detection>& detections) {
  int n = 0;
  for (const Detection& d : detections)
    n += vp::geometry::rotatedIou(truth, d.box) >= kMatchIou;
  return n;
}

double bestIou(const RotatedBox& truth, const std::vector<Detection>& detections) {
  double best = 0.0;
  for (const Detection& d : detections)
    best = std::max(best, vp::geometry::rotatedIou(truth, d.box));
  return best;
}

// One 1296 x 1024 frame of a held-out simulated scene (seeds 9000-9999 are never trained on).
vp::sim::SimOptions heldOutFrame(vp::sim::SceneKind scene, std::uint64_t seed) {
  vp::sim::SimOptions sim;
  sim.scene = scene;
  sim.seed = seed;
  sim.frames = 1;
  sim.width = 1296;
  sim.height = 1024;
  sim.supersampling = 1;
  sim.threads = 2;
  return sim;
}

// Renders the frame, starts the shipped two-stage detector with the score threshold and
// preprocesses the frame at the working scale for it (gtest assertions: call under
// ASSERT_NO_FATAL_FAILURE).
void prepare(const vp::sim::SimOptions& sim, float scoreThreshold, double workingScale,
             vp::sim::Simulator& simulator, vp::sim::FrameOutput& frame,
             vp::detection::DetectionStage& stage, vp::preprocess::Preprocessor& preprocessor) {
  std::string why;
  ASSERT_TRUE(simulator.init(sim, &why)) << why;
  ASSERT_TRUE(simulator.nextFrame(frame, &why)) << why;
  vp::detection::DetectionStageOptions options;
  options.detectorModelPath = std::string(VP_SOURCE_DIR) + "/models/detector/detector_int8.onnx";
  options.cropModelPath = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";
  options.decoder.scoreThreshold = scoreThreshold;
  // One crop per vehicle and no verifier, as this test was written for.
  options.secondStage.mirrorAverage = false;
  options.secondStage.mirrorRefine = false;
  options.secondStage.largeVehicleEnds = false;
  options.secondStage.minVehicleProbability = 0.0F;
  ASSERT_TRUE(stage.init(options, vp::preprocess::kMaxTiles, &why)) << why;
  vp::preprocess::PreprocessOptions pre;
  pre.undistort = false;
  pre.workingScale = workingScale;
  pre.networkWidth_px = stage.detectorInputWidth();
  pre.networkHeight_px = stage.detectorInputHeight();
  ASSERT_TRUE(preprocessor.init(pre, simulator.camera(), frame.image.size(), &why)) << why;
  ASSERT_EQ(preprocessor.process(frame.image), vp::preprocess::PreprocessStatus::Ok);
}

TEST(TileBorder, AStraddlingVehicleIsDetectedOnceWheneverItsWholeTileFindsIt) {
  // Many cars, some across the tile borders; ~10 cm per pixel at this size (the detector's
  // working GSD), so frame pixels = working pixels and the frame needs tiles.
  vp::sim::SimOptions sim = heldOutFrame(vp::sim::SceneKind::Parking, 9101);
  sim.altitude_m = 125.0;
  sim.tilt_deg = 0.0;
  vp::sim::Simulator simulator;
  vp::sim::FrameOutput frame;
  vp::detection::DetectionStage stage;
  vp::preprocess::Preprocessor preprocessor;
  ASSERT_NO_FATAL_FAILURE(prepare(sim, 0.4F, 1.0, simulator, frame, stage, preprocessor));
  const vp::preprocess::PreprocessedFrame& tiled = preprocessor.output();
  ASSERT_GE(tiled.tiles.size(), 2U);

  std::vector<Detection> all(vp::detection::kMaxDetectionsPerFrame);
  std::size_t count = 0;
  ASSERT_EQ(stage.run(tiled, all, &count), vp::detection::DetectionStatus::Ok);
  all.resize(count);

  int straddlers = 0, referenceFound = 0, foundOnce = 0, duplicates = 0;
  for (const auto& object : frame.objects) {
    if (object.occlusion > 0.7 || object.truncation > 0.0)
      continue;
    bool straddles = false;
    for (const auto& tile : tiled.tiles)
      straddles |= crossesInnerEdge(object.imageBox, tile.rect);
    if (!straddles)
      continue;
    // The tiles that hold the vehicle whole (the overlap is wider than a car; it may lie whole
    // in more than one). Each is run alone: when one of them misses the vehicle or boxes it
    // badly, that is the detector's error, which the tiled frame may well inherit - not the
    // tiling's.
    std::vector<const vp::preprocess::TileView*> wholeTiles;
    for (const auto& tile : tiled.tiles)
      if (insideTile(object.imageBox, tile.rect))
        wholeTiles.push_back(&tile);
    if (wholeTiles.empty())
      continue;
    ++straddlers;
    bool everyWholeTileFindsIt = true;
    std::vector<Detection> alone(vp::detection::kMaxDetectionsPerFrame);
    for (const vp::preprocess::TileView* whole : wholeTiles) {
      vp::preprocess::PreprocessedFrame single = tiled;
      single.tiles = std::span<const vp::preprocess::TileView>(whole, 1);
      alone.resize(vp::detection::kMaxDetectionsPerFrame);
      std::size_t aloneCount = 0;
      ASSERT_EQ(stage.run(single, alone, &aloneCount), vp::detection::DetectionStatus::Ok);
      alone.resize(aloneCount);
      everyWholeTileFindsIt = everyWholeTileFindsIt && matches(object.imageBox, alone) > 0;
    }
    if (!everyWholeTileFindsIt)
      continue;  // the detector's miss, not the tiling's
    ++referenceFound;
    const int n = matches(object.imageBox, all);
    foundOnce += n == 1;
    duplicates += n > 1;
    EXPECT_EQ(n, 1) << "vehicle " << object.trackId << " at (" << object.imageBox.cx << ", "
                    << object.imageBox.cy << ") found " << n
                    << " times in the tiled frame (best IoU " << bestIou(object.imageBox, all)
                    << ")";
  }
  std::printf(
      "tiles %zu, straddling vehicles %d, found by every tile that holds them whole %d, "
      "found once in the tiled frame %d, twice or more %d\n",
      tiled.tiles.size(), straddlers, referenceFound, foundOnce, duplicates);
  EXPECT_GE(straddlers, 3) << "the scene must put vehicles across the tile borders";
  EXPECT_GE(referenceFound, 3);
  EXPECT_EQ(foundOnce, referenceFound);
}

}  // namespace

// A vehicle cut off by the frame's border is seen in part, so its box is biased: the detection
// stage marks it (Detection::atFrameEdge, with the share of its box inside the frame) for the
// tracker, and only such detections.
TEST(FrameBorder, DetectionsOfVehiclesCutByTheFrameBorderAreMarked) {
  // Cars drive in and out of the frame on a straight road (v5 finds two strongly cut ones in
  // seed 9105's first frame on x86-64). Marking, not recall, is tested: a low threshold keeps
  // the weak detections of cut vehicles. The simulator draws another scene from the same seed
  // on a CPU that fuses multiply-adds (aarch64, docs/simulator.md "Determinism"), so the next
  // seeds are taken until the frames hold two cut vehicles the detector finds.
  int cutFound = 0, cutMarked = 0, insideFound = 0, insideMarked = 0, insideShareNotOne = 0;
  for (const std::uint64_t seed : {9105U, 9106U, 9107U, 9108U}) {
    if (cutFound >= 2 && insideFound >= 10) {
      break;
    }
    vp::sim::Simulator simulator;
    vp::sim::FrameOutput frame;
    vp::detection::DetectionStage stage;
    vp::preprocess::Preprocessor preprocessor;
    ASSERT_NO_FATAL_FAILURE(prepare(heldOutFrame(vp::sim::SceneKind::Straight, seed), 0.1F, 0.5,
                                    simulator, frame, stage, preprocessor));
    std::vector<Detection> all(vp::detection::kMaxDetectionsPerFrame);
    std::size_t count = 0;
    ASSERT_EQ(stage.run(preprocessor.output(), all, &count), vp::detection::DetectionStatus::Ok);
    all.resize(count);

    const double w = frame.image.cols, h = frame.image.rows;
    for (const auto& object : frame.objects) {
      const RotatedBox& truth = object.imageBox;
      // The detection lying most on the vehicle (a cut vehicle's box is only its visible part,
      // so its centre can be far from the whole vehicle's): at least half of it on the truth.
      const Detection* best = nullptr;
      double bestShare = 0.5;
      for (const Detection& d : all) {
        const double share =
            vp::geometry::intersectionArea(truth, d.box) / vp::geometry::area(d.box);
        if (share > bestShare) {
          bestShare = share;
          best = &d;
        }
      }
      if (best == nullptr || object.occlusion > 0.5) {
        continue;
      }
      const double reach = truth.length;  // a car length from every border: wholly inside
      if (object.truncation > 0.1) {
        ++cutFound;
        cutMarked += best->atFrameEdge;
        // The share of the box inside the frame, for the tracker (its partial detections).
        const vp::geometry::RotatedBox image{0.5 * w - 0.5, 0.5 * h - 0.5, w, h, 0.0};
        EXPECT_NEAR(
            best->insideShare,
            vp::geometry::intersectionArea(best->box, image) / vp::geometry::area(best->box), 1e-4);
        std::printf("seed %llu cut vehicle: truncation %.2f, detection inside share %.2f\n",
                    static_cast<unsigned long long>(seed), object.truncation,
                    static_cast<double>(best->insideShare));
      } else if (object.truncation == 0.0 && truth.cx > reach && truth.cx < w - reach &&
                 truth.cy > reach && truth.cy < h - reach) {
        ++insideFound;
        insideMarked += best->atFrameEdge;
        insideShareNotOne += best->insideShare != 1.0F;
      }
    }
  }
  std::printf("frame border: %d cut vehicles found, %d marked; %d inside found, %d marked\n",
              cutFound, cutMarked, insideFound, insideMarked);
  EXPECT_GE(cutFound, 2) << "the scenes must put vehicles across the frame's border";
  EXPECT_EQ(cutMarked, cutFound);
  EXPECT_GE(insideFound, 10);
  EXPECT_EQ(insideMarked, 0);
  EXPECT_EQ(insideShareNotOne, 0);
}
