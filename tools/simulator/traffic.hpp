// simulator/traffic: vehicle motion. Moving vehicles follow lane paths (straight on, right
// and left turns at the intersection) with the kinematic bicycle model of seed 001,
//   x' = v cos psi,  y' = v sin psi,  psi' = v / L tan delta,
// at the rear-axle centre (the reference point of seed 002), steered by pure pursuit;
// their speed follows the intelligent driver model (IDM) behind the nearest obstacle on
// their path (another vehicle's footprint, or a red signal's stop line). Vehicles arrive at
// the path starts outside the view as Poisson streams and leave at the path ends, so they
// enter and leave the image. Parked vehicles stand in kerb parking lanes and lot bays.
//
// Contract: deterministic; every random decision is drawn from the Rng passed in, in a
// fixed order. Traffic::step() advances all vehicles by one frame interval in fixed
// sub-steps. Vehicles never overlap in normal operation (spacing by the IDM and the signal
// phases); the check is geometric, not guaranteed under every corner case.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "scene.hpp"
#include "sim_random.hpp"
#include "vehicles.hpp"

namespace vp::sim {

struct BicycleState {
  double x = 0.0;  // rear-axle centre, ENU m
  double y = 0.0;
  double psi = 0.0;  // heading, rad, counter-clockwise from east
};

// Exact integration over dt for constant speed v and steering angle delta (the motion is an
// arc of radius L / tan delta), so constant steering traces a circle exactly.
BicycleState stepBicycle(const BicycleState& s, double v, double delta, double wheelbase_m,
                         double dt);

class LanePath {
 public:
  LanePath() = default;
  explicit LanePath(std::vector<Eigen::Vector2d> points);  // resampled every 0.25 m

  double length() const { return s_.empty() ? 0.0 : s_.back(); }
  Eigen::Vector2d at(double s) const;
  double headingAt(double s) const;
  // Arc length of the point nearest to p, searched in [sFrom, sTo].
  double project(const Eigen::Vector2d& p, double sFrom, double sTo) const;
  // Largest speed allowed by the path's curvature within [s, s + ahead] (lateral 2.5 m/s^2).
  double curveSpeedLimit(double s, double ahead) const;
  const std::vector<Eigen::Vector2d>& points() const { return points_; }

  int signalGroup = -1;  // -1: unsignalised
  double stopS = -1.0;   // arc length of the stop line (-1: none)

 private:
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> s_;
  std::vector<double> radius_;  // curvature radius at each point (large on straights)
};

struct SimVehicle {
  int trackId = 0;
  std::shared_ptr<const VehicleModel> model;
  BicycleState rear{};
  double speed_mps = 0.0;
  double steer_rad = 0.0;
  double yawRate_radps = 0.0;
  bool parked = false;
  int path = -1;   // index into Traffic::paths(), -1 for parked vehicles
  double s = 0.0;  // arc length of the rear axle along the path
  double desiredSpeed_mps = 10.0;
  double headwayS = 1.5;
  bool committed = false;  // past the point of stopping for the signal

  double heading() const { return rear.psi; }
  // Vehicle-frame origin (footprint centre) in the ground plane.
  Eigen::Vector2d centre() const;
};

class Traffic {
 public:
  // Builds the lane paths of the scene (extending pathHalfLength_m beyond viewCentre), the
  // parked vehicles, and runs warmUpS of traffic so that the first frame is in steady state.
  void init(const SceneSpec& scene, const VehicleFactory& factory, double pathHalfLength_m,
            double warmUpS, double frameIntervalS, Rng& rng);
  // Advances by one frame interval.
  void step(Rng& rng);

  const std::vector<SimVehicle>& vehicles() const { return vehicles_; }
  const std::vector<LanePath>& paths() const { return paths_; }
  double timeS() const { return timeS_; }
  // Signal state of a group at the current time.
  bool green(int group) const;

 private:
  void buildPaths(const SceneSpec& scene, double halfLength);
  void placeParked(const SceneSpec& scene, Rng& rng);
  void spawn(Rng& rng);
  double gapAhead(std::size_t index, double* leaderSpeed) const;
  void advance(double dt);

  const SceneSpec* scene_ = nullptr;
  const VehicleFactory* factory_ = nullptr;
  std::vector<LanePath> paths_;
  std::vector<std::vector<int>> entries_;  // per entry lane, the paths starting there
  std::vector<double> nextArrivalS_;       // per entry lane
  std::vector<SimVehicle> vehicles_;
  int nextTrackId_ = 1;
  double timeS_ = 0.0;
  double frameIntervalS_ = 0.1;
};

}  // namespace vp::sim
