// perception/surface_prior: the surface model's prior on lifted detections — a vehicle stands on
// the ground, or on a deck a drivable or parking area marks (a bridge, a parking deck), never on
// a roof.
//
// Contract: init() borrows the DTM the detections were lifted on, the surface model (DSM: ground
// plus buildings, bridges and decks, in the DTM's raster formats; terrain.dsm_path) and the site
// (null or empty: no area marks a deck), and copies the perception stage's Lifter over the DSM
// (same camera, mount and world frame). Without a DSM the prior is inactive and screen() copies
// every observation unchanged. screen() looks at each lifted observation: the viewing ray of its
// box centre (at the box height the detection was lifted at) meets the DSM; where the DSM stands
// more than maxStructureHeight_m above the DTM there, the vehicle is on a structure. When the
// site marks that point drivable or parking (Placement OnRoad) it is on a deck: the observation
// is lifted again with the Lifter over the DSM, so its footprint, keypoints and rear axle lie on
// the deck (onDeck set, counted). Otherwise it is on a structure (counted): dropped (Drop),
// kept with onStructure set (Flag), or kept unflagged (Keep). Observations that are not lifted,
// or whose ray misses the DSM (off its grid, NoData), pass unchanged. Order is kept. screen() is
// const, never allocates and never throws. standingSurface() tells the loop on which model a
// published track stands (the DSM on a marked deck, else the DTM).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include <Eigen/Core>

#include "lifting/lifting.hpp"
#include "perception/detection_lifter.hpp"
#include "site/site.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::perception {

struct SurfaceScreening {
  std::size_t written = 0;      // observations in the output
  std::size_t onDeck = 0;       // lifted again onto a deck a drivable or parking area marks
  std::size_t onStructure = 0;  // on a structure no such area marks (dropped, flagged or kept)
};

// What stands under a lifted point.
enum class SurfaceKind : std::uint8_t {
  Ground,     // the DSM is within maxStructureHeight_m of the DTM (or there is no DSM there)
  Deck,       // a structure a drivable or parking area marks
  Structure,  // a structure no such area marks (a roof)
};

class SurfacePrior {
 public:
  // dsm null: inactive (true). lifter: the perception stage's (the camera its detections are in);
  // lift: the perception stage's lift options (the box height). Fails with *why when the
  // Lifter is not initialised (a fixed view lifted through ground control points has no camera
  // pose to intersect) or the options are out of range.
  bool init(const terrain::TerrainModel& dtm, const terrain::TerrainModel* dsm,
            const lifting::Lifter& lifter, const geodesy::LocalFrame& frame,
            const shape::ActiveShapeModel& shapeModel, const DetectionLifterOptions& lift,
            const site::Site* site, const site::SiteOptions& options, std::string* why);
  bool active() const { return dsm_ != nullptr; }

  // Copies the observations to keep into out (at most out.size()); cameraPose: the frame's
  // (FrameLiftSummary::cameraPose, valid when the observations were lifted).
  SurfaceScreening screen(const lifting::CameraPoseWorld& cameraPose,
                          std::span<const VehicleObservation> observations,
                          std::span<VehicleObservation> out) const;

  // What stands under the point (east/north of the world frame) and whether a track there is
  // placed on the DSM (Deck) or the DTM.
  SurfaceKind kindAt(const Eigen::Vector3d& pointEnu) const;
  const terrain::TerrainModel& standingSurface(const Eigen::Vector3d& pointEnu) const {
    return kindAt(pointEnu) == SurfaceKind::Deck ? *dsm_ : *dtm_;
  }

 private:
  const terrain::TerrainModel* dtm_ = nullptr;
  const terrain::TerrainModel* dsm_ = nullptr;
  const site::Site* site_ = nullptr;
  lifting::Lifter dsmLifter_;
  DetectionLifter dsmDetectionLifter_;
  double maxStructureHeight_m_ = 2.5;
  site::OffRoadPolicy onStructure_ = site::OffRoadPolicy::Drop;
};

}  // namespace vp::perception
