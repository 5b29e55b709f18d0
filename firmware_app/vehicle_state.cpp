#include "vehicle_state.hpp"

#include <cmath>
#include <numbers>

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
  if (track.type != shape::VehicleType::Large) {
    state.shape = track.shape;
    if (shapeModel != nullptr) {
      const shape::VehicleGeometry geometry =
          shape::vehicleGeometry(*shapeModel, track.type, track.shape);
      state.height_m = static_cast<float>(geometry.size_m.z());
    }
  }
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
