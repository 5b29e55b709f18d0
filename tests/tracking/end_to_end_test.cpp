// End-to-end: the tracker on the synthetic intersection (synthetic_scene.hpp) against its truth
// (occluded vehicles included: bridging occlusions is the tracker's job),
// beside the raw detections. Prints MOTA, MOTP, IDF1, id switches, fragmentations,
// MT/ML, speed RMSE, heading errors > 90 degrees and type OA-1 (per frame and per track).
// The parameters were tuned on seed 1 only (VP_TRACKING_SEEDS=1 to see it); the figures in
// docs/tracking.md and the bounds below come from seeds 101-103, never tuned on.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "evaluation/mot_metrics.hpp"
#include "geometry/rotated_box.hpp"
#include "seed_one_options.hpp"
#include "synthetic_scene.hpp"
#include "tracking/track_manager.hpp"

namespace vp::tracking {
namespace {

using evaluation::MotAccumulator;
using evaluation::MotObject;
using evaluation::MotSummary;

constexpr double kCoast_s = 1.0;

struct RunFigures {
  MotSummary tracker{};
  int rawHeadingOver90 = 0;
  int rawHeadingSamples = 0;
  int rawTypeCorrect = 0;
  int rawTypeSamples = 0;
  int perTrackCorrect = 0;
  int perTrackCount = 0;
};

RunFigures runScenario(unsigned seed, const shape::ActiveShapeModel* asmModel) {
  test::SceneParams params;
  params.seed = seed;
  const std::vector<test::SceneFrame> frames = test::makeIntersection(params, asmModel);
  TrackerConfig config = test::seedOneTracker();
  config.asmModel = asmModel;
  TrackManager tracker;
  EXPECT_TRUE(tracker.init(config));
  MotAccumulator mot;
  RunFigures fig;
  std::map<int, int> lastFusedType;  // truth id -> fused type of the track last matched to it
  std::map<int, int> truthType;
  for (const test::SceneFrame& frame : frames) {
    auto report = tracker.step(frame.timestamp_ns, frame.detections);
    EXPECT_TRUE(report.hasValue());
    std::vector<MotObject> truth, hyps;
    std::set<int> visibleIds;
    for (const test::TruthObject& t : frame.truth) {
      MotObject o;
      o.id = t.id;
      o.position = t.centre;
      o.speed_mps = t.speed_mps;
      o.heading_rad = t.heading_rad;
      o.type = static_cast<int>(t.type);
      truth.push_back(o);
      truthType[t.id] = o.type;
      if (t.visible) {
        visibleIds.insert(t.id);
      }
    }
    for (const TrackState& s : tracker.tracks()) {
      // Published: confirmed tracks, and lost ones coasting for at most kCoast_s (they bridge
      // misses and occlusions); the evaluation ignores hypotheses outside the area.
      const double since = static_cast<double>(s.timestamp_ns - s.lastUpdate_ns) * 1e-9;
      const bool coasting = s.status == TrackStatus::Lost && since <= kCoast_s;
      if ((s.status != TrackStatus::Confirmed && !coasting) ||
          s.centreEnu.cwiseAbs().maxCoeff() > params.halfSize_m) {
        continue;
      }
      MotObject o;
      o.id = static_cast<int>(s.id);
      o.position = s.centreEnu;
      o.speed_mps = s.speed_mps;
      o.heading_rad = s.headingEnu_rad;
      o.type = static_cast<int>(s.type);
      hyps.push_back(o);
    }
    mot.addFrame(truth, hyps);
    // Raw detections (the confident ones) and the per-track type: nearest within 1.5 m.
    for (const MotObject& t : truth) {
      if (!visibleIds.contains(t.id)) {
        continue;
      }
      const WorldDetection* best = nullptr;
      double bestDist = 1.5;
      for (const WorldDetection& d : frame.detections) {
        const double dist = (d.centreEnu - t.position).norm();
        if (d.score >= config.association.highScore && dist < bestDist) {
          bestDist = dist;
          best = &d;
        }
      }
      if (best != nullptr) {
        ++fig.rawHeadingSamples;
        fig.rawHeadingOver90 +=
            geometry::absAngleDifference(best->headingEnu_rad, t.heading_rad) > 0.5 * geometry::kPi
                ? 1
                : 0;
        const auto argmax =
            std::max_element(best->typeProbabilities.begin(), best->typeProbabilities.end()) -
            best->typeProbabilities.begin();
        ++fig.rawTypeSamples;
        fig.rawTypeCorrect += argmax == t.type ? 1 : 0;
      }
      const MotObject* nearest = nullptr;
      bestDist = 1.5;
      for (const MotObject& h : hyps) {
        const double dist = (h.position - t.position).norm();
        if (dist < bestDist) {
          bestDist = dist;
          nearest = &h;
        }
      }
      if (nearest != nullptr) {
        lastFusedType[t.id] = nearest->type;
      }
    }
  }
  fig.tracker = mot.summary();
  for (const auto& [id, type] : lastFusedType) {
    ++fig.perTrackCount;
    fig.perTrackCorrect += type == truthType[id] ? 1 : 0;
  }
  return fig;
}

double share(int a, int b) {
  return b > 0 ? static_cast<double>(a) / b : 0.0;
}

TEST(EndToEnd, SyntheticIntersection) {
  shape::ActiveShapeModel asmModel;
  std::string why;
  ASSERT_TRUE(asmModel.load(std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml", &why))
      << why;
  std::vector<unsigned> seeds = {101, 102, 103};
  if (const char* env = std::getenv("VP_TRACKING_SEEDS")) {
    seeds.clear();
    std::istringstream in(env);
    for (unsigned s = 0; in >> s;) {
      seeds.push_back(s);
    }
  }
  std::printf(
      "seed  MOTA   MOTP_m IDF1   IDSW FRAG MT/PT/ML   speedRMSE  flips>90 raw/trk      "
      "OA-1 raw-frame/trk-frame/per-track\n");
  for (unsigned seed : seeds) {
    const RunFigures f = runScenario(seed, &asmModel);
    const MotSummary& s = f.tracker;
    std::printf(
        "%-5u %.4f %.4f %.4f %4d %4d %d/%d/%d  %.3f m/s  %.4f / %.4f   %.3f / %.3f / %.3f "
        "(%d tracks, %d truth objects)\n",
        seed, s.mota, s.motp_m, s.idf1, s.idSwitches, s.fragmentations, s.mostlyTracked,
        s.partiallyTracked, s.mostlyLost, s.speedRmse_mps,
        share(f.rawHeadingOver90, f.rawHeadingSamples), share(s.headingOver90, s.headingSamples),
        share(f.rawTypeCorrect, f.rawTypeSamples), share(s.typeCorrect, s.typeSamples),
        share(f.perTrackCorrect, f.perTrackCount), f.perTrackCount, s.truthObjects);
    // Bounds reached on the evaluation seeds with margin (not tuned on them).
    EXPECT_GT(s.mota, 0.95);
    EXPECT_GT(s.idf1, 0.95);
    EXPECT_LT(s.speedRmse_mps, 0.3);
    EXPECT_LT(share(s.headingOver90, s.headingSamples),
              0.1 * share(f.rawHeadingOver90, f.rawHeadingSamples));
    EXPECT_GT(share(s.typeCorrect, s.typeSamples), share(f.rawTypeCorrect, f.rawTypeSamples) + 0.2);
  }
}

}  // namespace
}  // namespace vp::tracking
