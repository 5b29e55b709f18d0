#include "vehicle_state.hpp"

#include <cmath>
#include <numbers>
#include <optional>

#include "shape/vehicle_geometry.hpp"

namespace vp::app {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kNsPerSecond = 1e9;
constexpr double kHeadingProbe_m = 10.0;  // forward point for the true-north azimuth, m

double wrapTwoPi(double angle) {
  double wrapped = std::fmod(angle, kTwoPi);
  if (wrapped < 0.0) {
    wrapped += kTwoPi;
  }
  return wrapped >= kTwoPi ? 0.0 : wrapped;
}

// Rear axle and keypoints: the fused type and shape (geometry) placed at the track's centre and
// heading (shape::placeOnGround), each point on the DTM.
void placeBody(const tracking::TrackState& track, const shape::VehicleGeometry& geometry,
               const Eigen::Vector3d& centre, const geodesy::LocalFrame& frame,
               const terrain::TerrainModel* terrain, messages::VehicleState& state) {
  // Ground under a point: the DTM's height difference to the centre added to the centre's z
  // (ENU z and ellipsoidal height change alike over a car's few metres); without a DTM, or
  // off it, the centre's height (flat ground).
  std::optional<double> centreHeight;
  if (terrain != nullptr) {
    if (const auto h = terrain->heightAtEnu(centre)) {
      centreHeight = *h;
    }
  }
  const auto groundZ = [&](const Eigen::Vector2d& xy) -> std::optional<double> {
    if (centreHeight) {
      if (const auto h = terrain->heightAtEnu({xy.x(), xy.y(), centre.z()})) {
        return centre.z() + (*h - *centreHeight);
      }
    }
    return centre.z();
  };
  shape::GroundFootprint footprint;
  footprint.centreEnu = centre;
  footprint.headingEnu_rad = track.headingEnu_rad;
  // A car with a shape keeps the ASM's own plan size: M(gamma)'s length is the better estimate
  // (docs/model_card.md: box length RMS error 0.29 m, M(gamma) 0.16 m), and scaling the
  // keypoints to the fused box doubled their error against the simulator's truth (E_D2D with
  // the pose removed 0.123 -> 0.068 m, tests/firmware_app/vehicle_state_truth_test.cpp).
  footprint.length_m = geometry.hasKeypoints ? geometry.size_m.x() : track.length_m;
  footprint.width_m = geometry.hasKeypoints ? geometry.size_m.y() : track.width_m;
  shape::PlacedVehicle placed;
  if (!shape::placeOnGround(geometry, footprint, groundZ, &placed)) {
    // No size yet (or not finite): the rear axle at the reference point, no keypoints.
    state.rearAxleEnu_m = state.enu_m;
    state.rearAxlePosition = state.position;
    return;
  }
  state.rearAxleEnu_m = {placed.rearAxleEnu.x(), placed.rearAxleEnu.y(), placed.rearAxleEnu.z()};
  state.rearAxlePosition = frame.toGeodetic(placed.rearAxleEnu);
  if (placed.hasKeypoints) {
    state.keypointCount = static_cast<std::uint8_t>(shape::kKeypointCount);
    for (int k = 0; k < shape::kKeypointCount; ++k) {
      for (int a = 0; a < 3; ++a) {
        state.keypointsEnu_m[static_cast<std::size_t>(k)][static_cast<std::size_t>(a)] =
            static_cast<float>(placed.keypointsEnu(a, k));
      }
    }
  }
}

}  // namespace

messages::VehicleState toVehicleState(const tracking::TrackState& track, std::uint32_t droneId,
                                      std::int64_t toUtcOffset_ns, const geodesy::LocalFrame& frame,
                                      const terrain::TerrainModel* terrain,
                                      const shape::ActiveShapeModel* shapeModel) {
  messages::VehicleState state;
  state.droneId = droneId;
  state.trackId = track.id;
  state.measurementTime_ns = track.timestamp_ns + toUtcOffset_ns;
  state.trackAge_s =
      static_cast<float>(static_cast<double>(track.timestamp_ns - track.birth_ns) / kNsPerSecond);

  Eigen::Vector3d centre(track.centreEnu.x(), track.centreEnu.y(), 0.0);
  if (terrain != nullptr) {
    const auto ground = terrain->groundPointEnu(centre.x(), centre.y());
    if (ground) {
      centre = *ground;
    }
  }
  state.position = frame.toGeodetic(centre);
  state.enu_m = {centre.x(), centre.y(), centre.z()};
  const double heading = wrapTwoPi(track.headingEnu_rad);
  state.headingEnu_rad = heading;
  const Eigen::Vector3d ahead =
      centre + kHeadingProbe_m * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
  double north_deg = geodesy::azimuth_deg(state.position, frame.toGeodetic(ahead));
  north_deg = std::fmod(north_deg, 360.0);
  if (north_deg < 0.0) {
    north_deg += 360.0;
  }
  state.headingTrueNorth_deg = north_deg >= 360.0 ? 0.0 : north_deg;

  state.speed_mps = static_cast<float>(track.speed_mps);
  state.velocityEnu_mps = {static_cast<float>(track.speed_mps * std::cos(heading)),
                           static_cast<float>(track.speed_mps * std::sin(heading))};
  state.yawRate_radps = static_cast<float>(track.yawRate_radps);
  state.yawRateVariance_rad2ps2 =
      static_cast<float>(track.yawRateSigma_radps * track.yawRateSigma_radps);
  state.acceleration_mps2 = static_cast<float>(track.acceleration_mps2);
  state.length_m = static_cast<float>(track.length_m);
  state.width_m = static_cast<float>(track.width_m);
  state.type = track.type;
  state.typeProbability = track.typeProbabilities;
  // The ASM model of the fused type and shape, once: the height, the rear axle, the keypoints.
  shape::VehicleGeometry
      geometry;  // none (large vehicle, no ASM): the rear axle by the length rule
  geometry.type = track.type;
  if (track.type != shape::VehicleType::Large) {
    state.shape = track.shape;
    if (shapeModel != nullptr) {
      geometry = shape::vehicleGeometry(*shapeModel, track.type, track.shape);
      state.height_m = static_cast<float>(geometry.size_m.z());
    }
  }
  state.lengthVariance_m2 = static_cast<float>(track.lengthVariance_m2);
  state.widthVariance_m2 = static_cast<float>(track.widthVariance_m2);
  if (const std::optional<geodesy::UtmPoint> utm = geodesy::tryUtm(state.position)) {
    state.utmZone = static_cast<std::uint8_t>(utm->zone);
    state.utmNorthernHemisphere = utm->northp;
    state.utmEasting_m = utm->easting_m;
    state.utmNorthing_m = utm->northing_m;
  }
  placeBody(track, geometry, centre, frame, terrain, state);
  const Eigen::Matrix3d& c = track.poseCovariance;
  state.poseCovariance = {static_cast<float>(c(0, 0)), static_cast<float>(c(0, 1)),
                          static_cast<float>(c(0, 2)), static_cast<float>(c(1, 1)),
                          static_cast<float>(c(1, 2)), static_cast<float>(c(2, 2))};
  state.speedVariance_m2ps2 = static_cast<float>(track.speedSigma_mps * track.speedSigma_mps);
  state.detectionConfidence = static_cast<float>(track.score);
  state.status = track.status;
  return state;
}

}  // namespace vp::app
