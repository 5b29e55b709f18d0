// tests/firmware_app/app_surface_test: the surface model (DSM) in the loop. A replayed simulated
// intersection carries its dsm.tif (the DTM with the buildings and their roof fixtures, named by
// its rig.yaml). The truth vehicles plus, in every frame, one fake vehicle whose image box shows a
// point on a building's roof (a perception seam; lifted on the DTM as the pipeline would) go
// through the loop with the site's off-road prior off: with the DSM the roof vehicles are counted
// (on_structure) and dropped before the tracker, and no truth vehicle is touched (on-road recall
// unchanged), allocation-free; with site.on_structure: keep they are counted and tracked; without
// a DSM nothing is counted and the tracker gets what it gets with keep. A DSM that cannot be read,
// does not cover the DTM, or is missing, or one named with a fixed view placed by ground control
// points, stops the start-up with a message naming the file or the key.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app.hpp"
#include "app_test_support.hpp"
#include "config/config.hpp"
#include "detection/detection.hpp"
#include "io/dtm_file.hpp"
#include "output_files/trajectory_file.hpp"
#include "rig_config/rig_config.hpp"
#include "site/site.hpp"

namespace vp::app {
namespace {

namespace fs = std::filesystem;

// Points on the buildings' roofs of a sequence (world ENU, on the DSM), from its site file's
// exclusion areas (the simulator's building footprints) and its dsm.tif.
std::vector<Eigen::Vector3d> roofPoints(const std::string& dir) {
  const config::RigConfig rig = config::loadRigConfig(dir + "/rig.yaml");
  EXPECT_EQ(rig.terrain.dsmPath, dir + "/dsm.tif") << "rig.yaml names the sequence's DSM";
  const geodesy::LocalFrame frame(rig.origin);
  site::Site site;
  std::string why;
  EXPECT_TRUE(site::loadSite(rig.sitePath, frame, &site, &why)) << why;
  terrain::TerrainGrid dtmGrid;
  terrain::TerrainGrid dsmGrid;
  EXPECT_TRUE(io::loadDtm(rig.terrain.dtmPath, std::nullopt, dtmGrid, &why)) << why;
  EXPECT_TRUE(io::loadDtm(rig.terrain.dsmPath, std::nullopt, dsmGrid, &why)) << why;
  terrain::TerrainModel dtm;
  terrain::TerrainModel dsm;
  EXPECT_TRUE(dtm.init(std::move(dtmGrid), frame, &why)) << why;
  EXPECT_TRUE(dsm.init(std::move(dsmGrid), frame, &why)) << why;
  std::vector<Eigen::Vector3d> roofs;
  for (const site::Feature& f : site.features()) {
    if (f.kind != site::FeatureKind::Exclusion) {
      continue;
    }
    const Eigen::Vector2d centre = (f.min_m + f.max_m) / 2.0;
    const auto top = dsm.groundPointEnu(centre.x(), centre.y());
    const auto ground = dtm.heightAtEnu({centre.x(), centre.y(), 0.0});
    const auto surface = dsm.heightAtEnu({centre.x(), centre.y(), 0.0});
    if (top && ground && surface) {
      EXPECT_GT(*surface - *ground, 2.5) << "the DSM holds the building " << f.id;
      roofs.push_back(*top);
    }
  }
  EXPECT_FALSE(roofs.empty()) << "the sequence has buildings";
  return roofs;
}

// The truth's observations and, in every frame with a camera pose, one vehicle on the first roof
// point that shows in the image: its box (the first truth box's size and angle, centred on the
// roof point's pixel) lifted on the DTM, where it lands beyond the building on a tilted view.
class RoofVehicleInjector final : public test::TruthPlusOnePerception {
 public:
  RoofVehicleInjector(std::unique_ptr<test::TruthPerception> truth,
                      std::vector<Eigen::Vector3d> roofs)
      : TruthPlusOnePerception(std::move(truth), "ground truth + a roof vehicle"),
        roofs_(std::move(roofs)) {}

  Eigen::Vector2d liftedRoof() const { return liftedRoof_; }

 protected:
  bool extra(const cv::Mat& bgrFrame, const perception::VehicleObservation& firstLifted,
             perception::VehicleObservation* vehicle) override {
    const lifting::Lifter& lift = lifter();
    const double width = bgrFrame.cols;
    const double height = bgrFrame.rows;
    for (const Eigen::Vector3d& roof : roofs_) {
      const auto pixel = lift.worldToPixel(summary().cameraPose, roof);
      if (!pixel || pixel->x() < 10.0 || pixel->y() < 10.0 || pixel->x() > width - 10.0 ||
          pixel->y() > height - 10.0) {
        continue;
      }
      *vehicle = firstLifted;
      vehicle->detection.box.cx = pixel->x();
      vehicle->detection.box.cy = pixel->y();
      const auto ground = lift.boxToGround(summary().cameraPose, vehicle->detection.box, 0.0);
      if (!ground) {
        continue;
      }
      vehicle->ground = *ground;
      if (liftedRoof_.isZero()) {
        liftedRoof_ = ground->centreEnu.head<2>();
      }
      return true;
    }
    return false;
  }

 private:
  std::vector<Eigen::Vector3d> roofs_;
  Eigen::Vector2d liftedRoof_ = Eigen::Vector2d::Zero();
};

struct SurfaceRun {
  LoopCounters counters{};
  std::uint64_t injected = 0;
  std::uint64_t truthLifted = 0;
  std::size_t trajectoryRows = 0;
  std::size_t roofRows = 0;  // rows within 4 m of where the roof vehicle lands on the DTM
  std::size_t allocations = 0;
  std::string summary;
};

SurfaceRun runWithRoofVehicle(const std::string& dir, const std::vector<Eigen::Vector3d>& roofs,
                              site::OffRoadPolicy onStructure, const std::string& name) {
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.enabled = false;
  config.source.paced = false;
  config.app.statsPeriod_s = 3600.0;
  config.site.offRoad = site::OffRoadPolicy::Keep;  // the surface model alone
  config.site.onStructure = onStructure;
  config.perception.lift.boxHeightShare = 0.0;  // the truth's boxes are footprints
  const std::string out = test::scratchDir("surface_" + name);
  config.app.trajectoryCsv = out + "/tracks.csv";
  auto truth = std::make_unique<test::TruthPerception>();
  std::string why;
  EXPECT_TRUE(truth->init(dir, &why)) << why;
  auto injector = std::make_unique<RoofVehicleInjector>(std::move(truth), roofs);
  RoofVehicleInjector* seen = injector.get();
  test::AllocationWindow window(5, test::kLoopFrames);
  SurfaceRun result;
  {
    App app;
    AppSeams seams;
    seams.perception = std::move(injector);
    seams.observer = &window;
    EXPECT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    EXPECT_TRUE(app.run(&why)) << why;
    result.counters = app.counters();
    result.injected = seen->injected();
    result.truthLifted = seen->truthLifted();
    result.summary = app.summaryLine();
    output_files::TrajectoryFile tracks;
    EXPECT_TRUE(output_files::readTrajectoryFile(config.app.trajectoryCsv, &tracks, &why)) << why;
    result.trajectoryRows = tracks.rows.size();
    for (const output_files::TrajectoryRecord& row : tracks.rows) {
      result.roofRows += (row.centreEnu - seen->liftedRoof()).norm() < 4.0 ? 1 : 0;
    }
  }
  EXPECT_TRUE(window.counted());
  result.allocations = window.count();
  return result;
}

// A copy of the sequence without its DSM (file and rig.yaml key).
std::string withoutDsm(const std::string& from) {
  const std::string dir = test::copySequence(from, "no_dsm");
  fs::remove(dir + "/dsm.tif");
  std::ifstream in(dir + "/rig.yaml");
  std::stringstream kept;
  for (std::string line; std::getline(in, line);) {
    if (line.find("dsm_path:") == std::string::npos) {
      kept << line << "\n";
    }
  }
  in.close();
  std::ofstream(dir + "/rig.yaml", std::ios::trunc) << kept.str();
  return dir;
}

TEST(AppSurface, RoofVehiclesAreDroppedWithTheSurfaceModelAndNoTruthVehicleIsTouched) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  const std::vector<Eigen::Vector3d> roofs = roofPoints(dir);
  ASSERT_FALSE(roofs.empty());

  const SurfaceRun drop = runWithRoofVehicle(dir, roofs, site::OffRoadPolicy::Drop, "drop");
  EXPECT_EQ(drop.counters.framesProcessed, static_cast<std::uint64_t>(test::kLoopFrames));
  ASSERT_GT(drop.injected, 0U) << "a roof shows in the frames";
  EXPECT_EQ(drop.counters.lifted, drop.truthLifted + drop.injected);
  // Exactly the roof vehicles: every truth vehicle (on the road) stays (recall unchanged).
  EXPECT_EQ(drop.counters.onStructure, drop.injected);
  EXPECT_EQ(drop.counters.onDeck, 0U);
  EXPECT_EQ(drop.roofRows, 0U) << "no track where the roof vehicle lands on the DTM";
  EXPECT_GT(drop.trajectoryRows, 0U);
  EXPECT_NE(drop.summary.find(" on_structure=" + std::to_string(drop.injected) + " "),
            std::string::npos)
      << drop.summary;
  EXPECT_EQ(drop.allocations, 0U) << "the surface prior allocates nothing per frame";

  // Keep: counted the same, tracked.
  const SurfaceRun keep = runWithRoofVehicle(dir, roofs, site::OffRoadPolicy::Keep, "keep");
  EXPECT_EQ(keep.counters.onStructure, keep.injected);
  EXPECT_GT(keep.roofRows, 0U);
  EXPECT_GT(keep.trajectoryRows, drop.trajectoryRows);

  // Without a DSM: nothing counted, the tracker gets what it gets with keep.
  const SurfaceRun none =
      runWithRoofVehicle(withoutDsm(dir), roofs, site::OffRoadPolicy::Drop, "none");
  EXPECT_EQ(none.counters.onStructure + none.counters.onDeck, 0U);
  EXPECT_EQ(none.trajectoryRows, keep.trajectoryRows);
  EXPECT_EQ(none.roofRows, keep.roofRows);
}

std::string startUpError(const std::string& dir) {
  config::AppConfig config = test::defaultConfigFor(dir);
  config.dds.enabled = false;
  App app;
  std::string why;
  EXPECT_FALSE(app.init(config, RunSettings{}, AppSeams{}, &why));
  return why;
}

TEST(AppSurface, ADsmThatCannotBeReadOrDoesNotCoverTheDtmStopsTheStartUp) {
  const std::string source = test::loopSequence();
  ASSERT_FALSE(source.empty());
  {
    const std::string dir = test::copySequence(source, "dsm_garbage");
    std::ofstream(dir + "/dsm.tif", std::ios::trunc) << "not a TIFF";
    const std::string why = startUpError(dir);
    EXPECT_NE(why.find("terrain.dsm_path: " + dir + "/dsm.tif: "), std::string::npos) << why;
  }
  {
    // The DSM's western half only.
    const std::string dir = test::copySequence(source, "dsm_half");
    terrain::TerrainGrid grid;
    std::string why;
    ASSERT_TRUE(io::loadDtm(dir + "/dsm.tif", std::nullopt, grid, &why)) << why;
    terrain::TerrainGrid half = grid;
    half.cols = grid.cols / 2;
    half.heights_m.clear();
    for (int r = 0; r < grid.rows; ++r) {
      for (int c = 0; c < half.cols; ++c) {
        half.heights_m.push_back(grid.heights_m[static_cast<std::size_t>(r * grid.cols + c)]);
      }
    }
    ASSERT_TRUE(io::writeDtmGeoTiff(dir + "/dsm.tif", half, &why)) << why;
    why = startUpError(dir);
    EXPECT_NE(why.find("terrain.dsm_path " + dir + "/dsm.tif: does not cover the DTM"),
              std::string::npos)
        << why;
    // The part it misses: the east half (the world frame's origin sits near the DTM's centre;
    // UTM grid north is a degree or two off true north, so the cut is not a meridian).
    const auto at = why.find("lie off it (east ");
    ASSERT_NE(at, std::string::npos) << why;
    EXPECT_GT(std::stod(why.substr(at + 17)), -20.0) << why;
    EXPECT_LT(std::stod(why.substr(at + 17)), 20.0) << why;
    EXPECT_NE(why.find("32768 of 65536 DTM points checked"), std::string::npos) << why;
  }
  {
    // Named with a fixed view placed by ground control points: refused (no viewing rays).
    config::AppConfig config = test::defaultConfigFor(source);
    config.dds.enabled = false;
    config.terrain.dsmPath = source + "/dsm.tif";
    config.georef.gcpFile = source + "/gcp.csv";
    App app;
    std::string why;
    EXPECT_FALSE(app.init(config, RunSettings{}, AppSeams{}, &why));
    EXPECT_NE(why.find("terrain.dsm_path: the surface model follows viewing rays"),
              std::string::npos)
        << why;
  }
  {
    const std::string dir = test::copySequence(source, "dsm_missing");
    fs::remove(dir + "/dsm.tif");
    const std::string why = startUpError(dir);
    EXPECT_NE(why.find("terrain.dsm_path: no such file"), std::string::npos) << why;
  }
}

}  // namespace
}  // namespace vp::app
