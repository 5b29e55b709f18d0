// perception/surface_prior: each lifted observation's viewing ray against the surface model.
#include "perception/surface_prior.hpp"

namespace vp::perception {

bool SurfacePrior::init(const terrain::TerrainModel& dtm, const terrain::TerrainModel* dsm,
                        const lifting::Lifter& lifter, const geodesy::LocalFrame& frame,
                        const shape::ActiveShapeModel& shapeModel,
                        const DetectionLifterOptions& lift, const site::Site* site,
                        const site::SiteOptions& options, std::string* why) {
  dtm_ = &dtm;
  dsm_ = nullptr;
  site_ = site != nullptr && !site->empty() ? site : nullptr;
  if (dsm == nullptr) {
    return true;
  }
  if (!(options.maxStructureHeight_m >= site::kMinStructureHeight_m &&
        options.maxStructureHeight_m <= site::kMaxStructureHeight_m)) {
    if (why != nullptr) {
      *why = "surface prior: the largest structure height must be in [" +
             std::to_string(site::kMinStructureHeight_m) + ", " +
             std::to_string(site::kMaxStructureHeight_m) + "] m, got " +
             std::to_string(options.maxStructureHeight_m);
    }
    return false;
  }
  if (!lifter.initialised()) {
    if (why != nullptr) {
      *why =
          "surface prior: the surface model needs detections lifted with the pose and the DTM "
          "(a fixed view placed by ground control points has no viewing rays to follow)";
    }
    return false;
  }
  std::string problem;
  if (!dsmLifter_.initOnSurface(lifter, *dsm, &problem) ||
      !dsmDetectionLifter_.init(*dsm, frame, shapeModel, lift, &problem)) {
    if (why != nullptr) {
      *why = "surface prior: " + problem;
    }
    return false;
  }
  dsm_ = dsm;
  maxStructureHeight_m_ = options.maxStructureHeight_m;
  onStructure_ = options.onStructure;
  return true;
}

SurfaceKind SurfacePrior::kindAt(const Eigen::Vector3d& pointEnu) const {
  if (dsm_ == nullptr) {
    return SurfaceKind::Ground;
  }
  const auto surface = dsm_->heightAtEnu(pointEnu);
  const auto ground = dtm_->heightAtEnu(pointEnu);
  if (!surface || !ground || !(*surface - *ground > maxStructureHeight_m_)) {
    return SurfaceKind::Ground;
  }
  if (site_ != nullptr && site_->classify(pointEnu.head<2>()) == site::Placement::OnRoad) {
    return SurfaceKind::Deck;
  }
  return SurfaceKind::Structure;
}

SurfaceScreening SurfacePrior::screen(const lifting::CameraPoseWorld& cameraPose,
                                      std::span<const VehicleObservation> observations,
                                      std::span<VehicleObservation> out) const {
  SurfaceScreening result;
  for (const VehicleObservation& observation : observations) {
    SurfaceKind kind = SurfaceKind::Ground;
    if (active() && observation.liftStatus == LiftStatus::Ok) {
      // What the box centre's ray meets first: the surface the vehicle stands on, seen from the
      // camera (the DTM point behind a roof can lie beyond the building on an oblique view).
      const detection::Detection& d = observation.detection;
      const auto hit = dsmLifter_.pixelToGroundBelow(cameraPose, {d.box.cx, d.box.cy},
                                                     dsmDetectionLifter_.boxHeight_m(d));
      if (hit) {
        kind = kindAt(*hit);
      }
    }
    if (kind == SurfaceKind::Structure) {
      ++result.onStructure;
      if (onStructure_ == site::OffRoadPolicy::Drop) {
        continue;
      }
    }
    if (result.written == out.size()) {
      continue;  // counted all the same
    }
    VehicleObservation& kept = out[result.written++];
    if (kind == SurfaceKind::Deck) {
      kept = VehicleObservation{};
      kept.timestamp_ns = observation.timestamp_ns;
      kept.detection = observation.detection;
      dsmDetectionLifter_.liftObservation(dsmLifter_, cameraPose, kept);
      if (kept.liftStatus == LiftStatus::Ok) {
        kept.offSite = observation.offSite;
        kept.onDeck = true;
        ++result.onDeck;
        continue;
      }
      // The deck's footprint reaches off the DSM (its edge): the ground lift stands.
    }
    kept = observation;
    kept.onStructure = kind == SurfaceKind::Structure && onStructure_ == site::OffRoadPolicy::Flag;
  }
  return result;
}

}  // namespace vp::perception
