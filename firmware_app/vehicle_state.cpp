#include "vehicle_state.hpp"

#include <cmath>
#include <numbers>

#include "shape/vehicle_geometry.hpp"

namespace vp::app {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kNsPerSecond = 1e9;
constexpr double kHeadingProbeM = 10.0;  // forward point for the true-north azimuth, m

double wrapTwoPi(double angle) {
  double wrapped = std::fmod(angle, kTwoPi);
  if (wrapped < 0.0) {
    wrapped += kTwoPi;
  }
  return wrapped >= kTwoPi ? 0.0 : wrapped;
}

}  // namespace

messages::VehicleState toVehicleState(const tracking::TrackState& track, double trackAge_s,
                                      std::uint32_t droneId, std::int64_t toUtcOffsetNs,
                                      const geodesy::LocalFrame& frame,
                                      const terrain::TerrainModel* terrain,
                                      const shape::ActiveShapeModel* shapeModel) {
  messages::VehicleState state;
  state.droneId = droneId;
  state.trackId = track.id;
  state.measurementTimeNs = track.timestampNs + toUtcOffsetNs;
  state.trackAge_s = static_cast<float>(trackAge_s);

  Eigen::Vector3d centre(track.centreEnu.x(), track.centreEnu.y(), 0.0);
  if (terrain != nullptr) {
    const auto ground = terrain->groundPointEnu(centre.x(), centre.y());
    if (ground) {
      centre = *ground;
    }
  }
  state.position = frame.toGeodetic(centre);
  state.enu_m = {centre.x(), centre.y(), centre.z()};
  const double heading = wrapTwoPi(track.headingEnuRad);
  state.headingEnu_rad = heading;
  const Eigen::Vector3d ahead =
      centre + kHeadingProbeM * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0);
  double northDeg = geodesy::azimuthDeg(state.position, frame.toGeodetic(ahead));
  northDeg = std::fmod(northDeg, 360.0);
  if (northDeg < 0.0) {
    northDeg += 360.0;
  }
  state.headingTrueNorth_deg = northDeg >= 360.0 ? 0.0 : northDeg;

  state.speed_mps = static_cast<float>(track.speedMps);
  state.velocityEnu_mps = {static_cast<float>(track.speedMps * std::cos(heading)),
                           static_cast<float>(track.speedMps * std::sin(heading))};
  state.yawRate_radps = static_cast<float>(track.yawRateRadps);
  state.acceleration_mps2 = static_cast<float>(track.accelerationMps2);
  state.length_m = static_cast<float>(track.lengthM);
  state.width_m = static_cast<float>(track.widthM);
  state.type = track.type;
  state.typeProbability = track.typeProbabilities;
  if (track.type != shape::VehicleType::Large) {
    state.shape = track.shape;
    if (shapeModel != nullptr) {
      const shape::VehicleGeometry geometry =
          shape::vehicleGeometry(*shapeModel, track.type, track.shape);
      state.height_m = static_cast<float>(geometry.sizeM.z());
    }
  }
  const auto positionVariance = static_cast<float>(track.positionSigmaM * track.positionSigmaM);
  state.poseCovariance = {positionVariance, 0.0F, 0.0F, positionVariance, 0.0F, 0.0F};
  state.speedVariance_m2ps2 = static_cast<float>(track.speedSigmaMps * track.speedSigmaMps);
  state.detectionConfidence = 0.0F;  // not reported (see the contract)
  state.status = track.status;
  return state;
}

double TrackAges::ageOf(std::uint32_t trackId, std::int64_t timestampNs) {
  for (std::size_t i = 0; i < count_; ++i) {
    if (entries_[i].id == trackId) {
      return static_cast<double>(timestampNs - entries_[i].firstNs) / kNsPerSecond;
    }
  }
  if (count_ < entries_.size()) {
    entries_[count_++] = Entry{trackId, timestampNs};
  }
  return 0.0;
}

void TrackAges::retain(std::span<const tracking::TrackState> live) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    bool alive = false;
    for (const tracking::TrackState& track : live) {
      alive = alive || track.id == entries_[i].id;
    }
    if (alive) {
      entries_[kept++] = entries_[i];
    }
  }
  count_ = kept;
}

}  // namespace vp::app
