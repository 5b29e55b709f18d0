// vp_traffic_eval on a tiny simulated intersection (a few seconds of frames, small images): the
// ground truth written as the app's trajectory file agrees exactly with the truth; tracks that
// break every half second lose every turning movement; tracks moved
// away from every vehicle count nothing and match nothing; bad input and usage are refused with
// a message.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include "output_files/trajectory_file.hpp"
#include "sequence/recorded_sequence.hpp"
#include "simulator.hpp"
#include "traffic_eval.hpp"

namespace vp::traffic_eval {
namespace {

namespace fs = std::filesystem;

class TrafficEval : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ =
        new fs::path(fs::temp_directory_path() / ("vp_traffic_eval_" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    // Seed 7 has vehicles crossing two gates on x86-64; the simulator draws other scenes from a
    // seed on CPUs whose math library rounds differently (docs/simulator.md "Determinism"), so
    // the next seeds are taken until the 15 s hold such a vehicle.
    for (const std::uint64_t seed : {7U, 8U, 9U, 10U, 11U, 12U}) {
      sim::SimOptions options;
      options.scene = sim::SceneKind::Intersection;
      options.seed = seed;
      options.frames = 150;  // 15 s at 10 Hz
      options.outDir = (*dir_ / ("intersection_" + std::to_string(seed))).string();
      options.width = 160;
      options.height = 128;
      options.png = true;
      options.supersampling = 1;
      options.asmPath = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";
      sim::Simulator simulator;
      std::string why;
      ASSERT_TRUE(simulator.init(options, &why) && simulator.write(&why)) << why;
      sequence_ = options.outDir;
      const SequenceResult perfect =
          evaluate(writeTracks("probe.csv", [](std::size_t, const sequence::ObjectTruth&,
                                               tracking::TrackState&) { return true; }));
      if (perfect.movementVehicles > 0) {
        return;
      }
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }

  static std::string sequence() { return sequence_; }

  // The ground truth as a trajectory file; edit(frame index, truth, track) may change the track
  // and returns false to leave the row out.
  static std::string writeTracks(const std::string& name,
                                 const std::function<bool(std::size_t, const sequence::ObjectTruth&,
                                                          tracking::TrackState&)>& edit) {
    sequence::SequenceReader reader;
    std::string why;
    EXPECT_TRUE(reader.open(sequence(), &why)) << why;
    const std::string path = (*dir_ / name).string();
    output_files::TrajectoryFileWriter writer;
    EXPECT_TRUE(writer.open(path, output_files::TrajectoryFileInfo{3}, &why)) << why;
    for (std::size_t i = 0; i < reader.frames().size(); ++i) {
      const sequence::FrameRecord& frame = reader.frames()[i];
      for (const sequence::ObjectTruth& object : reader.objects(frame.frameId)) {
        tracking::TrackState t;
        t.id = static_cast<std::uint32_t>(object.trackId);
        t.status = tracking::TrackStatus::Confirmed;
        t.timestamp_ns = frame.timestamp_ns;
        t.centreEnu = object.positionEnu.head<2>();
        t.rearAxleEnu = t.centreEnu;
        t.headingEnu_rad =
            std::fmod(object.headingEnu_rad + 4.0 * std::numbers::pi, 2.0 * std::numbers::pi);
        t.speed_mps = object.speed_mps;
        t.length_m = object.dimensions_m.x();
        t.width_m = object.dimensions_m.y();
        t.type = object.type;
        t.typeProbabilities[static_cast<std::size_t>(object.type)] = 1.0F;
        if (!edit(i, object, t)) {
          continue;
        }
        EXPECT_TRUE(writer.writeRow(frame.frameId, t, nullptr, &why)) << why;
      }
      EXPECT_TRUE(writer.commit());
    }
    EXPECT_TRUE(writer.close(&why)) << why;
    return path;
  }

  static SequenceResult evaluate(const std::string& tracks) {
    SequenceResult result;
    std::string why;
    EXPECT_TRUE(evaluateSequence({sequence(), tracks}, EvalOptions{}, &result, &why)) << why;
    return result;
  }

  static fs::path* dir_;
  static std::string sequence_;  // the chosen sequence
};

fs::path* TrafficEval::dir_ = nullptr;
std::string TrafficEval::sequence_;

TEST_F(TrafficEval, PerfectTracksAgreeWithTheTruth) {
  const SequenceResult r =
      evaluate(writeTracks("perfect.csv", [](std::size_t, const sequence::ObjectTruth&,
                                             tracking::TrackState&) { return true; }));
  EXPECT_EQ(r.frames, 150U);
  EXPECT_GT(r.truthTotal, 0U) << "the sequence has gate crossings";
  EXPECT_GT(r.movementVehicles, 0U) << "and vehicles crossing two gates";
  EXPECT_GT(r.queuePeriods, 0U);
  EXPECT_EQ(r.measuredTotal, r.truthTotal);
  EXPECT_EQ(r.measuredCounts, r.truthCounts);
  EXPECT_EQ(r.movementAgreeing, r.movementVehicles);
  EXPECT_EQ(r.queueAgreeing, r.queuePeriods);
  EXPECT_NEAR(r.queueAbsError_m, 0.0, 0.05);
  const Acceptance a = accept(r);
  EXPECT_TRUE(a.pass());
  EXPECT_EQ(a.countError, 0.0);
  std::ostringstream text;
  printResult(r, true, text);
  EXPECT_EQ(r.typeCellError, 0U);
  EXPECT_EQ(r.directionCellError, 0U);
  EXPECT_NE(text.str().find("relative error of the totals 0.0 %, by gate and direction 0.0 %, by "
                            "gate, direction and type 0.0 %"),
            std::string::npos)
      << text.str();
}

// A track published under a wrong type keeps the totals and the counts by direction, and moves
// its crossings to another type's cell: each adds 2 to the by-type error, which fails the counts.
TEST_F(TrafficEval, AWrongTypeIsACountErrorByType) {
  const SequenceResult r = evaluate(writeTracks(
      "retyped.csv", [](std::size_t, const sequence::ObjectTruth&, tracking::TrackState& t) {
        t.type =
            t.type == shape::VehicleType::Van ? shape::VehicleType::Sedan : shape::VehicleType::Van;
        t.typeProbabilities.fill(0.0F);
        t.typeProbabilities[static_cast<std::size_t>(t.type)] = 1.0F;
        return true;
      }));
  ASSERT_GT(r.truthTotal, 0U);
  EXPECT_EQ(r.measuredTotal, r.truthTotal);
  EXPECT_EQ(r.directionCellError, 0U);
  EXPECT_EQ(r.typeCellError, 2 * r.truthTotal);
  const Acceptance a = accept(r);
  EXPECT_EQ(a.countError, 0.0);
  EXPECT_DOUBLE_EQ(a.typeError, 2.0);
  EXPECT_FALSE(a.countsPass);
  // Sedans and vans are both cars in seed 002's categories: no error by category.
  EXPECT_EQ(r.categoryCellError, 0U);
  EXPECT_EQ(a.categoryError, 0.0);
}

TEST_F(TrafficEval, ACarCountedAsATransporterIsACountErrorByCategory) {
  const SequenceResult r = evaluate(writeTracks(
      "large.csv", [](std::size_t, const sequence::ObjectTruth&, tracking::TrackState& t) {
        t.type = t.type == shape::VehicleType::Large ? shape::VehicleType::Sedan
                                                     : shape::VehicleType::Large;
        t.typeProbabilities.fill(0.0F);
        t.typeProbabilities[static_cast<std::size_t>(t.type)] = 1.0F;
        return true;
      }));
  ASSERT_GT(r.truthTotal, 0U);
  EXPECT_EQ(r.directionCellError, 0U);
  EXPECT_EQ(r.categoryCellError, 2 * r.truthTotal);
  EXPECT_DOUBLE_EQ(accept(r).categoryError, 2.0);
  std::ostringstream text;
  printResult(r, false, text);
  EXPECT_NE(text.str().find("seed 002's category (car; transporter: large): 200.0 %"),
            std::string::npos)
      << text.str();
}

TEST_F(TrafficEval, BrokenTracksLoseTheTurningMovements) {
  const SequenceResult perfect =
      evaluate(writeTracks("whole.csv", [](std::size_t, const sequence::ObjectTruth&,
                                           tracking::TrackState&) { return true; }));
  ASSERT_GT(perfect.movementVehicles, 0U);
  // Every track breaks every 0.5 s (a new id): none lives long enough to cross two gates, while
  // the crossings inside each piece are still counted.
  const SequenceResult broken = evaluate(writeTracks(
      "broken.csv", [](std::size_t i, const sequence::ObjectTruth&, tracking::TrackState& t) {
        t.id += 100000 * static_cast<std::uint32_t>(i / 5 + 1);
        return true;
      }));
  EXPECT_EQ(broken.movementVehicles, perfect.movementVehicles);
  EXPECT_EQ(broken.movementUnmatched, 0U);
  EXPECT_EQ(broken.movementAgreeing, 0U);
  EXPECT_FALSE(accept(broken).movementsPass);
  EXPECT_LE(broken.measuredTotal, perfect.measuredTotal);  // a break on a crossing loses it
}

TEST_F(TrafficEval, TracksAwayFromTheVehiclesCountAndMatchNothing) {
  const SequenceResult r = evaluate(writeTracks(
      "moved.csv", [](std::size_t, const sequence::ObjectTruth&, tracking::TrackState& t) {
        t.centreEnu.x() += 500.0;
        t.rearAxleEnu = t.centreEnu;
        return true;
      }));
  ASSERT_GT(r.truthTotal, 0U);
  EXPECT_EQ(r.measuredTotal, 0U);
  EXPECT_EQ(r.movementUnmatched, r.movementVehicles);
  const Acceptance a = accept(r);
  EXPECT_EQ(a.countError, 1.0);
  EXPECT_FALSE(a.countsPass);
}

TEST_F(TrafficEval, TheCommandReportsAndRefusesBadInput) {
  const std::string tracks = writeTracks("cli.csv", [](std::size_t, const sequence::ObjectTruth&,
                                                       tracking::TrackState&) { return true; });
  std::ostringstream out;
  std::ostringstream err;
  EXPECT_EQ(runTrafficEval({"--sequence", sequence(), "--tracks", tracks, "--details",
                            "--require-acceptance", "--period", "5"},
                           out, err),
            0)
      << err.str();
  EXPECT_NE(out.str().find(fs::path(sequence()).filename().string() + ": 150 frames"),
            std::string::npos)
      << out.str();
  EXPECT_NE(out.str().find("gate counts (gate direction type: truth measured)"), std::string::npos);
  EXPECT_NE(out.str().find("turning movements: "), std::string::npos);
  EXPECT_NE(out.str().find("queue length: "), std::string::npos);

  std::ostringstream err2;
  EXPECT_EQ(runTrafficEval({"--sequence", sequence()}, out, err2), 2);
  EXPECT_NE(err2.str().find("has no --tracks FILE"), std::string::npos) << err2.str();
  std::ostringstream err3;
  EXPECT_EQ(runTrafficEval({"--sequence", sequence(), "--tracks", tracks, "--site",
                            sequence() + "/missing.geojson"},
                           out, err3),
            1);
  EXPECT_NE(err3.str().find("missing.geojson: cannot open the site file"), std::string::npos)
      << err3.str();
  std::ostringstream err4;
  EXPECT_EQ(
      runTrafficEval({"--sequence", sequence(), "--tracks", tracks, "--period", "-1"}, out, err4),
      2);
  EXPECT_NE(err4.str().find("--period must be a positive number"), std::string::npos);
}

}  // namespace
}  // namespace vp::traffic_eval
