// tests/firmware_app/app_site_test: the site map in the loop. A replayed simulated sequence
// carries its site.geojson (named by its rig.yaml); the truth vehicles plus one fake detection
// on a building's roof per frame (a perception seam) go through the loop: the roof detections
// are counted as off_site and dropped before the tracker while every truth vehicle is kept; with
// off_road flag they are counted and tracked (more trajectory rows); with keep nothing is counted;
// a bad site file stops the start-up with a message naming the key, the file and the feature.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "app.hpp"
#include "app_test_support.hpp"
#include "config/config.hpp"
#include "detection/detection.hpp"
#include "output_files/trajectory_file.hpp"
#include "rig_config/rig_config.hpp"
#include "site/site.hpp"

namespace vp::app {
namespace {

// The truth's observations and, in every frame with a lifted vehicle, a copy of the first lifted
// one moved onto the roof.
class RoofInjector final : public test::TruthPlusOnePerception {
 public:
  RoofInjector(std::unique_ptr<test::TruthPerception> truth, const Eigen::Vector2d& roof_m)
      : TruthPlusOnePerception(std::move(truth), "ground truth + a roof"), roof_m_(roof_m) {}

 protected:
  bool extra(const cv::Mat& /*bgrFrame*/, const perception::VehicleObservation& firstLifted,
             perception::VehicleObservation* roof) override {
    *roof = firstLifted;
    const Eigen::Vector3d shift(roof_m_.x() - roof->ground.centreEnu.x(),
                                roof_m_.y() - roof->ground.centreEnu.y(), 0.0);
    roof->ground.centreEnu += shift;
    for (Eigen::Vector3d& corner : roof->ground.cornersEnu) {
      corner += shift;
    }
    return true;
  }

 private:
  Eigen::Vector2d roof_m_;
};

// The centre of the sequence's first building (an exclusion area of its site file).
Eigen::Vector2d firstRoof(const std::string& dir) {
  const config::RigConfig rig = config::loadRigConfig(dir + "/rig.yaml");
  EXPECT_EQ(rig.sitePath, dir + "/site.geojson") << "rig.yaml names the sequence's site map";
  site::Site site;
  std::string why;
  EXPECT_TRUE(site::loadSite(rig.sitePath, geodesy::LocalFrame(rig.origin), &site, &why)) << why;
  for (const site::Feature& f : site.features()) {
    if (f.kind == site::FeatureKind::Exclusion) {
      return (f.min_m + f.max_m) / 2.0;
    }
  }
  ADD_FAILURE() << "no building in the site file";
  return Eigen::Vector2d::Zero();
}

struct SiteRun {
  LoopCounters counters{};
  std::uint64_t injected = 0;
  std::uint64_t truthLifted = 0;
  std::size_t trajectoryRows = 0;  // tracks' rows in the trajectory file
  std::size_t roofRows = 0;        // of those, within 3 m of the roof detection
  std::string summary;
};

// The loop on the sequence `dir` (its site, unless the configuration names one) with the truth
// vehicles of `truthDir` and one roof detection per frame; recording into `recordDir` if given.
SiteRun runWithRoof(const std::string& dir, site::OffRoadPolicy policy,
                    const std::string& truthDir = "", const std::string& recordDir = "") {
  config::AppConfig config = test::defaultConfigFor(dir);
  config.app.record.dir = recordDir;
  config.dds.enabled = false;
  config.source.paced = false;
  config.app.statsPeriod_s = 3600.0;
  config.site.offRoad = policy;
  const std::string out = test::scratchDir(std::string("site_") + site::toString(policy));
  config.app.trajectoryCsv = out + "/tracks.csv";
  auto truth = std::make_unique<test::TruthPerception>();
  std::string why;
  EXPECT_TRUE(truth->init(truthDir.empty() ? dir : truthDir, &why)) << why;
  const Eigen::Vector2d roof_m = firstRoof(dir);
  auto injector = std::make_unique<RoofInjector>(std::move(truth), roof_m);
  RoofInjector* seen = injector.get();
  SiteRun result;
  App app;
  AppSeams seams;
  seams.perception = std::move(injector);
  RunSettings run;
  run.everyFrame = true;
  run.quiet = true;
  EXPECT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  EXPECT_TRUE(app.run(&why)) << why;
  result.counters = app.counters();
  result.injected = seen->injected();
  result.truthLifted = seen->truthLifted();
  result.summary = app.summaryLine();
  output_files::TrajectoryFile tracks;
  EXPECT_TRUE(output_files::readTrajectoryFile(config.app.trajectoryCsv, &tracks, &why)) << why;
  result.trajectoryRows = tracks.rows.size();
  for (const output_files::TrajectoryRecord& row : tracks.rows) {
    result.roofRows += (row.centreEnu - roof_m).norm() < 3.0 ? 1 : 0;
  }
  return result;
}

TEST(AppSite, RoofDetectionsAreDroppedAndCountedWhileEveryTruthVehicleIsKept) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  const SiteRun drop = runWithRoof(dir, site::OffRoadPolicy::Drop);
  EXPECT_EQ(drop.counters.framesProcessed, static_cast<std::uint64_t>(test::kLoopFrames));
  ASSERT_GT(drop.injected, 0U);
  EXPECT_EQ(drop.counters.lifted, drop.truthLifted + drop.injected);
  // Exactly the roof detections: no truth vehicle is off the site.
  EXPECT_EQ(drop.counters.offSite, drop.injected);
  EXPECT_EQ(drop.roofRows, 0U) << "no track on the roof";
  EXPECT_GT(drop.trajectoryRows, 0U);
  EXPECT_NE(drop.summary.find(" off_site=" + std::to_string(drop.injected) + " "),
            std::string::npos)
      << drop.summary;

  // Flag: counted the same, but tracked, so the roof becomes one more track with rows.
  const SiteRun flag = runWithRoof(dir, site::OffRoadPolicy::Flag);
  EXPECT_EQ(flag.counters.offSite, flag.injected);
  EXPECT_GT(flag.trajectoryRows, drop.trajectoryRows);
  EXPECT_GT(flag.roofRows, 0U);

  // Keep: the prior is off; the tracker gets what it gets with flag.
  const SiteRun keep = runWithRoof(dir, site::OffRoadPolicy::Keep);
  EXPECT_EQ(keep.counters.offSite, 0U);
  EXPECT_EQ(keep.trajectoryRows, flag.trajectoryRows);
}

std::string fileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// --record copies the site file the loop runs with into the recording (site.geojson, named by
// its rig.yaml), so that the replay of the recording screens the detections with the same site:
// the roof detections are off the site again, the same number of them.
TEST(AppSite, ARecordingCarriesTheSiteAndItsReplayUsesIt) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  const std::string recording = test::scratchDir("site_recording") + "/seq";
  const SiteRun live = runWithRoof(dir, site::OffRoadPolicy::Drop, "", recording);
  ASSERT_GT(live.injected, 0U);
  EXPECT_EQ(live.counters.offSite, live.injected);
  EXPECT_TRUE(live.counters.recording);

  // The copy, byte for byte, where the recording's rig.yaml names it.
  const std::string copy = recording + "/site.geojson";
  EXPECT_EQ(fileText(copy), fileText(dir + "/site.geojson"));
  EXPECT_EQ(config::loadRigConfig(recording + "/rig.yaml").sitePath, copy);
  // The sequence's surface model likewise (dsm.tif, named by terrain.dsm_path).
  ASSERT_FALSE(config::loadRigConfig(dir + "/rig.yaml").terrain.dsmPath.empty());
  EXPECT_EQ(fileText(recording + "/dsm.tif"), fileText(dir + "/dsm.tif"));
  EXPECT_EQ(config::loadRigConfig(recording + "/rig.yaml").terrain.dsmPath, recording + "/dsm.tif");

  // The replay of the recording (no site.file in its configuration): the same roof detections
  // off the site (firstRoof() reads the recording's site), the same truth vehicles on it.
  const SiteRun replay = runWithRoof(recording, site::OffRoadPolicy::Drop, dir);
  EXPECT_EQ(replay.injected, live.injected);
  EXPECT_EQ(replay.counters.offSite, live.counters.offSite);
  EXPECT_EQ(replay.counters.lifted, live.counters.lifted);
  EXPECT_EQ(replay.roofRows, 0U);
}

// A loop without a site records none: no site.geojson, and rig.yaml names none.
TEST(AppSite, ARecordingWithoutASiteHasNoSiteFile) {
  const std::string dir = test::copySequence(test::loopSequence(), "no_site");
  std::filesystem::remove(dir + "/site.geojson");
  {
    std::string rig = fileText(dir + "/rig.yaml");
    const std::size_t at = rig.find("site:");
    ASSERT_NE(at, std::string::npos);
    rig.erase(at, rig.find('\n', rig.find("file:", at)) + 1 - at);
    std::ofstream(dir + "/rig.yaml", std::ios::trunc) << rig;
  }
  ASSERT_TRUE(config::loadRigConfig(dir + "/rig.yaml").sitePath.empty());
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.enabled = false;
  config.source.paced = false;
  const std::string recording = test::scratchDir("no_site_recording") + "/seq";
  config.app.record.dir = recording;
  App app;
  RunSettings run;
  run.quiet = true;
  run.maxFrames = 3;
  std::string why;
  ASSERT_TRUE(app.init(config, run, AppSeams{}, &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  EXPECT_FALSE(std::filesystem::exists(recording + "/site.geojson"));
  EXPECT_TRUE(config::loadRigConfig(recording + "/rig.yaml").sitePath.empty());
}

TEST(AppSite, ABadSiteFileStopsTheStartUpNamingTheFeature) {
  const std::string dir = test::copySequence(test::loopSequence(), "bad_site");
  {
    std::ofstream site(dir + "/site.geojson", std::ios::trunc);
    site << R"({"type": "FeatureCollection", "features": [
  {"type": "Feature", "properties": {"kind": "drivable", "id": "road-1", "colour": "grey"},
   "geometry": {"type": "Polygon", "coordinates": [[[11.0, 48.0], [11.001, 48.0], [11.0, 48.001], [11.0, 48.0]]]}}
]})";
  }
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.enabled = false;
  App app;
  std::string why;
  EXPECT_FALSE(app.init(config, RunSettings{}, AppSeams{}, &why));
  EXPECT_NE(why.find("site.file: " + dir +
                     "/site.geojson: feature 0 (id \"road-1\", line 2): "
                     "unknown property \"colour\""),
            std::string::npos)
      << why;
}

}  // namespace
}  // namespace vp::app
