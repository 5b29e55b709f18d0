// tests/perception/surface_prior: the surface model's prior on lifted detections. A flat DTM and a
// DSM raised over two blocks: a deck (6 m, under a drivable area of the site) and a roof (9 m, no
// area). Vehicles stand on the deck, on the roof and on the ground; the camera looks 10 degrees off
// nadir, so the DTM lift of a raised vehicle lands metres away from it. The prior lifts the deck's
// vehicle onto the deck (within 0.3 m of its true footprint centre, in 3D), drops (or flags) the
// roof's and leaves the ground's untouched; without a site the deck is a structure too; without a
// DSM nothing changes; screen() allocates nothing.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "perception/footprint_projection.hpp"
#include "perception/surface_prior.hpp"
#include "site/site.hpp"
#include "test_scene.hpp"

namespace vp::perception {
namespace {

using testworld::kGround_m;

constexpr double kDeck_m = 6.0;
constexpr double kRoof_m = 9.0;

// East/north rectangle (m from the origin).
struct Block {
  double east0, east1, north0, north1;
  bool contains(double e, double n) const {
    return e >= east0 && e <= east1 && n >= north0 && n <= north1;
  }
};
constexpr Block kDeck{5.0, 35.0, -35.0, -10.0};
constexpr Block kRoof{-35.0, -10.0, 10.0, 35.0};

// The DTM's grid (flat, 1 m cells) with the two blocks raised; the DTM's own grid is the same
// without them. planeDtm's samples lie at whole metres east/north of the origin's UTM point,
// which the world frame's east/north follow to within the meridian convergence (< 1 cm here).
terrain::TerrainGrid surface(bool withBlocks) {
  const double half = 120.0;
  terrain::TerrainGrid grid = test::planeDtm(testworld::kOrigin, kGround_m, 0.0, 0.0, half, 1.0);
  if (!withBlocks) {
    return grid;
  }
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const double e = -half + c;
      const double n = half - r;
      float& h = grid.heights_m[static_cast<std::size_t>(r * grid.cols + c)];
      if (kDeck.contains(e, n)) {
        h += static_cast<float>(kDeck_m);
      } else if (kRoof.contains(e, n)) {
        h += static_cast<float>(kRoof_m);
      }
    }
  }
  return grid;
}

site::Site deckSite() {
  site::Site site("test site");
  site::Feature deck;
  deck.kind = site::FeatureKind::Drivable;
  deck.id = "deck";
  const std::array<Eigen::Vector2d, 4> ring = {Eigen::Vector2d(kDeck.east0 - 1, kDeck.north0 - 1),
                                               Eigen::Vector2d(kDeck.east1 + 1, kDeck.north0 - 1),
                                               Eigen::Vector2d(kDeck.east1 + 1, kDeck.north1 + 1),
                                               Eigen::Vector2d(kDeck.east0 - 1, kDeck.north1 + 1)};
  site.append(deck, ring);
  // The ground around (where the ground vehicle drives).
  site::Feature road;
  road.kind = site::FeatureKind::Drivable;
  road.id = "road";
  const std::array<Eigen::Vector2d, 4> square = {Eigen::Vector2d(5, 5), Eigen::Vector2d(30, 5),
                                                 Eigen::Vector2d(30, 30), Eigen::Vector2d(5, 30)};
  site.append(road, square);
  return site;
}

struct Fixture {
  testworld::Scene scene{surface(false), camera::LensModel::Pinhole};
  terrain::TerrainModel dsm;
  lifting::Lifter dsmLifter;
  lifting::CameraPoseWorld pose;
  std::vector<shape::GroundFootprint> truth;  // ground, deck, roof
  std::vector<VehicleObservation> observations;

  Fixture() {
    std::string why;
    EXPECT_TRUE(dsm.init(surface(true), scene.frame, &why)) << why;
    EXPECT_TRUE(dsmLifter.initOnSurface(scene.lifter, dsm, &why)) << why;
    const auto camera = scene.lifter.cameraPose(testworld::hoveringPose(30.0, -80.0));
    EXPECT_TRUE(camera.hasValue());
    pose = *camera;
    int i = 0;
    for (const Eigen::Vector2d& at :
         {Eigen::Vector2d(15, 15), Eigen::Vector2d(20, -22), Eigen::Vector2d(-22, 22)}) {
      shape::GroundFootprint f;
      const auto onSurface = dsm.groundPointEnu(at.x(), at.y());
      EXPECT_TRUE(onSurface.hasValue());
      f.centreEnu = *onSurface;
      f.headingEnu_rad = 0.4 + i++;
      f.length_m = 4.5;
      f.width_m = 1.8;
      truth.push_back(f);
    }
    // A perfect detector's boxes of the vehicles where they stand (on the DSM), lifted as the
    // pipeline lifts them: on the DTM.
    std::vector<detection::Detection> detections;
    for (const shape::GroundFootprint& f : truth) {
      const auto box = footprintToImageBox(dsmLifter, pose, dsm, f);
      EXPECT_TRUE(box.hasValue());
      detection::Detection d;
      d.box = *box;
      d.score = 0.9F;
      d.typeProbabilities.fill(0.02F);
      d.typeProbabilities[0] = 0.88F;
      detections.push_back(d);
    }
    observations.resize(detections.size());
    FrameCameraPose camera2;
    camera2.status = LiftStatus::Ok;
    camera2.pose = pose;
    const FrameLiftSummary s =
        scene.detectionLifter.liftFrame(scene.lifter, 1000, camera2, detections, observations);
    EXPECT_EQ(s.lifted, 3U);
  }

  SurfacePrior prior(const site::Site* site, site::OffRoadPolicy policy, bool withDsm = true) {
    site::SiteOptions options;
    options.onStructure = policy;
    SurfacePrior p;
    std::string why;
    EXPECT_TRUE(p.init(scene.terrain, withDsm ? &dsm : nullptr, scene.lifter, scene.frame,
                       scene.asmModel, DetectionLifterOptions{.boxHeightShare = 0.0}, site, options,
                       &why))
        << why;
    return p;
  }
};

TEST(SurfacePrior, DeckVehiclesAreLiftedOntoTheDeckAndRoofVehiclesDropped) {
  Fixture f;
  // On the DTM the raised vehicles land away from where they stand (the test means something).
  EXPECT_GT((f.observations[1].ground.centreEnu - f.truth[1].centreEnu).norm(), 1.0);
  EXPECT_LT((f.observations[0].ground.centreEnu - f.truth[0].centreEnu).norm(), 0.3);

  const site::Site site = deckSite();
  const SurfacePrior prior = f.prior(&site, site::OffRoadPolicy::Drop);
  ASSERT_TRUE(prior.active());
  std::array<VehicleObservation, 3> out{};
  test::AllocationCounter allocations;
  const SurfaceScreening s = prior.screen(f.pose, f.observations, out);
  allocations.stop();
  EXPECT_EQ(allocations.count(), 0U) << "screen() allocates nothing";
  EXPECT_EQ(s.onDeck, 1U);
  EXPECT_EQ(s.onStructure, 1U);
  ASSERT_EQ(s.written, 2U) << "the roof's vehicle is dropped";
  // The ground vehicle: untouched.
  EXPECT_EQ(out[0].ground.centreEnu, f.observations[0].ground.centreEnu);
  EXPECT_FALSE(out[0].onDeck);
  // The deck vehicle: on the deck, where it stands.
  EXPECT_TRUE(out[1].onDeck);
  EXPECT_EQ(out[1].liftStatus, LiftStatus::Ok);
  EXPECT_LT((out[1].ground.centreEnu - f.truth[1].centreEnu).norm(), 0.3)
      << out[1].ground.centreEnu.transpose() << " vs " << f.truth[1].centreEnu.transpose();
  const auto groundBelow = f.scene.terrain.heightAtEnu(out[1].ground.centreEnu);
  ASSERT_TRUE(groundBelow.hasValue());
  EXPECT_NEAR(out[1].ground.centreWgs84.height_m - *groundBelow, kDeck_m, 0.3);
  EXPECT_NEAR(out[1].ground.length_m, 4.5, 0.3);
  EXPECT_EQ(prior.kindAt(out[1].ground.centreEnu), SurfaceKind::Deck);
  EXPECT_EQ(&prior.standingSurface(out[1].ground.centreEnu), &f.dsm);
  EXPECT_EQ(&prior.standingSurface(out[0].ground.centreEnu), &f.scene.terrain);

  // Flag: the roof's vehicle is kept, marked.
  const SurfacePrior flag = f.prior(&site, site::OffRoadPolicy::Flag);
  const SurfaceScreening flagged = flag.screen(f.pose, f.observations, out);
  ASSERT_EQ(flagged.written, 3U);
  EXPECT_EQ(flagged.onStructure, 1U);
  EXPECT_FALSE(out[0].onStructure);
  EXPECT_FALSE(out[1].onStructure);
  EXPECT_TRUE(out[2].onStructure);
  EXPECT_EQ(out[2].ground.centreEnu, f.observations[2].ground.centreEnu);

  // Keep: counted, kept unmarked.
  const SurfacePrior keep = f.prior(&site, site::OffRoadPolicy::Keep);
  const SurfaceScreening kept = keep.screen(f.pose, f.observations, out);
  EXPECT_EQ(kept.written, 3U);
  EXPECT_EQ(kept.onStructure, 1U);
  EXPECT_FALSE(out[2].onStructure);
}

TEST(SurfacePrior, CostPerObservation) {
  // One ray march over the DSM per lifted observation (two more height lookups), and a full lift
  // for a deck's vehicle: the same answer every round; the time is printed for the record, not
  // asserted (speed is the benchmarks' to show: a loaded or emulated machine is 5-20x slower).
  Fixture f;
  const site::Site site = deckSite();
  const SurfacePrior prior = f.prior(&site, site::OffRoadPolicy::Drop);
  std::array<VehicleObservation, 3> out{};
  constexpr int kRounds = 300;
  const auto start = std::chrono::steady_clock::now();
  std::size_t written = 0;
  for (int i = 0; i < kRounds; ++i) {
    written += prior.screen(f.pose, f.observations, out).written;
  }
  const double perObservation_us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count() /
      (kRounds * 3.0);
  EXPECT_EQ(written, kRounds * 2U);
  std::printf("surface prior: %.1f us per lifted observation (ground, deck, roof mix)\n",
              perObservation_us);
  RecordProperty("surface_prior_us_per_observation", std::to_string(perObservation_us));
}

TEST(SurfacePrior, WithoutASiteTheDeckIsAStructureAndWithoutADsmNothingChanges) {
  Fixture f;
  std::array<VehicleObservation, 3> out{};
  const SurfacePrior noSite = f.prior(nullptr, site::OffRoadPolicy::Drop);
  const SurfaceScreening s = noSite.screen(f.pose, f.observations, out);
  EXPECT_EQ(s.onDeck, 0U);
  EXPECT_EQ(s.onStructure, 2U);
  ASSERT_EQ(s.written, 1U);
  EXPECT_EQ(out[0].ground.centreEnu, f.observations[0].ground.centreEnu);

  const site::Site site = deckSite();
  const SurfacePrior noDsm = f.prior(&site, site::OffRoadPolicy::Drop, false);
  EXPECT_FALSE(noDsm.active());
  const SurfaceScreening none = noDsm.screen(f.pose, f.observations, out);
  EXPECT_EQ(none.written, 3U);
  EXPECT_EQ(none.onDeck + none.onStructure, 0U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(out[i].ground.centreEnu, f.observations[i].ground.centreEnu);
  }

  // Not lifted: passes unjudged.
  std::array<VehicleObservation, 1> unlifted{f.observations[2]};
  unlifted[0].liftStatus = LiftStatus::NoPose;
  const SurfacePrior prior = f.prior(&site, site::OffRoadPolicy::Drop);
  EXPECT_EQ(prior.screen(f.pose, unlifted, out).written, 1U);
}

TEST(SurfacePrior, RefusesAnUninitialisedLifterAndAStructureHeightOutOfRange) {
  Fixture f;
  SurfacePrior prior;
  std::string why;
  site::SiteOptions options;
  lifting::Lifter none;
  EXPECT_FALSE(prior.init(f.scene.terrain, &f.dsm, none, f.scene.frame, f.scene.asmModel, {},
                          nullptr, options, &why));
  EXPECT_NE(why.find("pose and the DTM"), std::string::npos) << why;
  options.maxStructureHeight_m = 0.1;
  EXPECT_FALSE(prior.init(f.scene.terrain, &f.dsm, f.scene.lifter, f.scene.frame, f.scene.asmModel,
                          {}, nullptr, options, &why));
  EXPECT_NE(why.find("largest structure height"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::perception
