#include "synthetic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "geometry/rotated_box.hpp"

namespace vp::tracking::test {
namespace {

constexpr double kLaneOffset_m = 1.75;
constexpr double kKerbOffset_m = 5.5;

enum class Manoeuvre { Straight, Left, Right };

struct Vehicle {
  TruthObject truth;
  double wheelbase = 2.7;
  double rearToCentre = 1.35;
  double laneSpeed = 10.0;
  Manoeuvre manoeuvre = Manoeuvre::Straight;
  double turnRadius = 10.0;
  double turnStart = 0.0;  // along-road coordinate of the rear axle where steering begins
  double turned = 0.0;     // yaw accumulated in the turn, rad
  bool turning = false;
  bool turnDone = false;
  double approachHeading = 0.0;
  int occlusionStart = -1;  // frame index (may be negative: before the recording)
  int occlusionEnd = -1;
};

double alongRoad(const Vehicle& v) {
  const Eigen::Vector2d f(std::cos(v.approachHeading), std::sin(v.approachHeading));
  return v.truth.rearAxle.dot(f);
}

void setBody(Vehicle& v, std::mt19937& rng, const shape::ActiveShapeModel* asmModel) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  TruthObject& t = v.truth;
  t.type = u(rng) < 0.05 ? shape::VehicleType::Large
                         : static_cast<shape::VehicleType>(static_cast<int>(u(rng) * 6.0) % 6);
  if (t.type == shape::VehicleType::Large || asmModel == nullptr) {
    const bool large = t.type == shape::VehicleType::Large;
    t.length_m = large ? 10.0 : 4.5;
    t.width_m = large ? 2.5 : 1.8;
    v.wheelbase = large ? 6.0 : 2.7;
    v.rearToCentre = large ? 2.5 : 1.3;
    t.shape = {};
    return;
  }
  const shape::TypePrior& prior = asmModel->typePrior(t.type);
  t.shape.count = asmModel->componentCount();
  for (int s = 0; s < t.shape.count; ++s) {
    const double mean = prior.sampleCount > 0 ? prior.mean[static_cast<std::size_t>(s)] : 0.0;
    t.shape.gamma[static_cast<std::size_t>(s)] = static_cast<float>(mean + 0.5 * n(rng));
  }
  const shape::KeypointModel model = asmModel->shape(t.shape);
  const Eigen::Vector3d size = shape::boundingBoxSize(model);
  t.length_m = size.x();
  t.width_m = size.y();
  const auto& w = shape::wheelCentreKeypoints();
  const double front = 0.5 * (model(0, w[0]) + model(0, w[1]));
  const double rear = 0.5 * (model(0, w[2]) + model(0, w[3]));
  v.wheelbase = front - rear;
  v.rearToCentre = -rear;
}

void updateCentre(Vehicle& v) {
  v.truth.centre =
      v.truth.rearAxle + v.rearToCentre * Eigen::Vector2d(std::cos(v.truth.heading_rad),
                                                          std::sin(v.truth.heading_rad));
}

// One bicycle step of a moving vehicle: steering from its manoeuvre, speed towards the
// lane speed (6 m/s through a turn).
void advance(Vehicle& v, double dt) {
  TruthObject& t = v.truth;
  const double s = alongRoad(v);
  if (v.manoeuvre != Manoeuvre::Straight && !v.turning && !v.turnDone && s >= v.turnStart) {
    v.turning = true;
  }
  double delta = 0.0;
  if (v.turning) {
    delta = std::atan(v.wheelbase / v.turnRadius) * (v.manoeuvre == Manoeuvre::Left ? 1.0 : -1.0);
  }
  const double target =
      (v.manoeuvre != Manoeuvre::Straight && !v.turnDone && s > v.turnStart - 25.0) ? 6.0
                                                                                    : v.laneSpeed;
  const double accel =
      t.speed_mps > target + 0.05 ? -2.0 : (t.speed_mps < target - 0.05 ? 1.5 : 0.0);
  t.speed_mps = std::max(0.0, t.speed_mps + accel * dt);
  const double yawRate = t.speed_mps * std::tan(delta) / v.wheelbase;
  const double dPsi = yawRate * dt;
  const double mid = t.heading_rad + 0.5 * dPsi;
  t.rearAxle += t.speed_mps * dt * Eigen::Vector2d(std::cos(mid), std::sin(mid));
  t.heading_rad += dPsi;
  t.yawRate_radps = yawRate;
  if (v.turning) {
    v.turned += std::abs(dPsi);
    if (v.turned >= 0.5 * geometry::kPi) {
      v.turning = false;
      v.turnDone = true;
      t.heading_rad =
          v.approachHeading + (v.manoeuvre == Manoeuvre::Left ? 0.5 : -0.5) * geometry::kPi;
      v.approachHeading = t.heading_rad;
      t.yawRate_radps = 0.0;
    }
  }
  t.heading_rad = geometry::wrapTwoPi(t.heading_rad);
  updateCentre(v);
}

}  // namespace

std::vector<SceneFrame> makeIntersection(const SceneParams& p,
                                         const shape::ActiveShapeModel* asmModel) {
  std::mt19937 rng(p.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  const double dt = 1.0 / p.frameRate_hz;
  constexpr int kSubsteps = 10;
  int nextId = 1;
  std::vector<Vehicle> vehicles;

  auto assignOcclusion = [&](Vehicle& v, int fromFrame, int span) {
    if (u(rng) < p.occlusionShare) {
      v.occlusionStart = fromFrame + static_cast<int>(u(rng) * span);
      v.occlusionEnd = v.occlusionStart + 3 + static_cast<int>(u(rng) * 13.0);
    }
  };

  // Parked cars along the right kerb of each approach, either way round.
  for (int a = 0; a < 4; ++a) {
    const double psi = a * 0.5 * geometry::kPi;
    const Eigen::Vector2d f(std::cos(psi), std::sin(psi));
    const Eigen::Vector2d left(-f.y(), f.x());
    for (int k = 0; k < p.parkedPerKerb; ++k) {
      Vehicle v;
      setBody(v, rng, asmModel);
      v.truth.id = nextId++;
      v.truth.parked = true;
      v.truth.speed_mps = 0.0;
      v.truth.heading_rad = geometry::wrapTwoPi(psi + (u(rng) < 0.5 ? 0.0 : geometry::kPi));
      const Eigen::Vector2d centre = (-60.0 + 8.0 * k) * f - kKerbOffset_m * left;
      v.truth.rearAxle = centre - v.rearToCentre * Eigen::Vector2d(std::cos(v.truth.heading_rad),
                                                                   std::sin(v.truth.heading_rad));
      updateCentre(v);
      assignOcclusion(v, 0, p.frames);
      vehicles.push_back(v);
    }
  }

  std::array<double, 4> laneSpeed{};
  std::array<double, 4> nextArrival{};
  for (int a = 0; a < 4; ++a) {
    laneSpeed[static_cast<std::size_t>(a)] = 8.0 + 5.0 * u(rng);
    nextArrival[static_cast<std::size_t>(a)] = 0.0;
  }
  std::exponential_distribution<double> gap(1.0 / p.meanArrivalGap_s);
  std::poisson_distribution<int> falsePositives(p.falsePositivesPerFrame);

  const int warmupFrames = static_cast<int>(15.0 * p.frameRate_hz);
  std::vector<SceneFrame> frames;
  frames.reserve(static_cast<std::size_t>(p.frames));
  for (int k = -warmupFrames; k < p.frames; ++k) {
    const double time = k * dt;
    for (int a = 0; a < 4; ++a) {
      auto& next = nextArrival[static_cast<std::size_t>(a)];
      if (time - (-warmupFrames * dt) < next) {
        continue;
      }
      next += std::max(1.5, gap(rng));
      Vehicle v;
      setBody(v, rng, asmModel);
      v.truth.id = nextId++;
      v.approachHeading = a * 0.5 * geometry::kPi;
      const Eigen::Vector2d f(std::cos(v.approachHeading), std::sin(v.approachHeading));
      const Eigen::Vector2d left(-f.y(), f.x());
      v.truth.heading_rad = v.approachHeading;
      v.truth.rearAxle = -(p.halfSize_m + 8.0) * f - kLaneOffset_m * left;
      v.laneSpeed = laneSpeed[static_cast<std::size_t>(a)];
      v.truth.speed_mps = v.laneSpeed;
      const double r = u(rng);
      if (r < 0.5 * p.turnShare) {
        v.manoeuvre = Manoeuvre::Left;
        v.turnRadius = 9.0 + 5.0 * u(rng);
        v.turnStart = kLaneOffset_m - v.turnRadius;
      } else if (r < p.turnShare) {
        v.manoeuvre = Manoeuvre::Right;
        v.turnRadius = 5.0 + 3.0 * u(rng);
        v.turnStart = -kLaneOffset_m - v.turnRadius;
      }
      updateCentre(v);
      assignOcclusion(v, k + static_cast<int>(p.frameRate_hz),
                      static_cast<int>(8.0 * p.frameRate_hz));
      vehicles.push_back(v);
    }
    for (Vehicle& v : vehicles) {
      if (!v.truth.parked) {
        for (int s = 0; s < kSubsteps; ++s) {
          advance(v, dt / kSubsteps);
        }
      }
    }
    std::erase_if(vehicles, [&](const Vehicle& v) {
      return v.truth.centre.cwiseAbs().maxCoeff() > p.halfSize_m + 12.0;
    });
    if (k < 0) {
      continue;
    }

    SceneFrame frame;
    frame.timestamp_ns = static_cast<std::int64_t>(std::llround(time * 1e9));
    for (Vehicle& v : vehicles) {
      if (v.truth.centre.cwiseAbs().maxCoeff() > p.halfSize_m) {
        continue;
      }
      TruthObject t = v.truth;
      t.visible = !(k >= v.occlusionStart && k < v.occlusionEnd);
      frame.truth.push_back(t);
      if (!t.visible || u(rng) < p.missRate) {
        continue;
      }
      WorldDetection d;
      d.timestamp_ns = frame.timestamp_ns;
      d.centreEnu = t.centre + p.positionNoise_m * Eigen::Vector2d(n(rng), n(rng));
      double heading = t.heading_rad + p.headingNoise_rad * n(rng);
      if (u(rng) < p.flipRate) {
        heading += geometry::kPi;
      }
      d.headingEnu_rad = geometry::wrapTwoPi(heading);
      d.headingKnown = true;
      d.length_m = t.length_m + p.sizeNoise_m * n(rng);
      d.width_m = t.width_m + p.sizeNoise_m * n(rng);
      d.score =
          static_cast<float>(u(rng) < p.lowScoreRate ? 0.15 + 0.3 * u(rng) : 0.55 + 0.4 * u(rng));
      std::array<double, shape::kVehicleTypeCount> logits{};
      double total = 0.0;
      for (std::size_t c = 0; c < logits.size(); ++c) {
        logits[c] =
            n(rng) + (static_cast<int>(c) == static_cast<int>(t.type) ? p.typeLogitBias : 0.0);
        total += std::exp(logits[c]);
      }
      for (std::size_t c = 0; c < logits.size(); ++c) {
        d.typeProbabilities[c] = static_cast<float>(std::exp(logits[c]) / total);
      }
      d.shape = t.shape;
      for (int s = 0; s < d.shape.count; ++s) {
        d.shape.gamma[static_cast<std::size_t>(s)] += static_cast<float>(p.gammaNoise * n(rng));
      }
      frame.detections.push_back(d);
    }
    const int nFalse = falsePositives(rng);
    for (int i = 0; i < nFalse; ++i) {
      WorldDetection d;
      d.timestamp_ns = frame.timestamp_ns;
      d.centreEnu =
          Eigen::Vector2d((2.0 * u(rng) - 1.0) * p.halfSize_m, (2.0 * u(rng) - 1.0) * p.halfSize_m);
      d.headingEnu_rad = geometry::kTwoPi * u(rng);
      d.length_m = 4.5 + 0.3 * n(rng);
      d.width_m = 1.8 + 0.1 * n(rng);
      d.score = static_cast<float>(0.1 + 0.6 * u(rng));
      double total = 0.0;
      std::array<double, shape::kVehicleTypeCount> logits{};
      for (double& l : logits) {
        l = n(rng);
        total += std::exp(l);
      }
      for (std::size_t c = 0; c < logits.size(); ++c) {
        d.typeProbabilities[c] = static_cast<float>(std::exp(logits[c]) / total);
      }
      frame.detections.push_back(d);
    }
    std::shuffle(frame.detections.begin(), frame.detections.end(), rng);
    frames.push_back(std::move(frame));
  }
  return frames;
}

std::vector<WorldDetection> makeConvoyFrame(int count, int frame, double frameRate_hz) {
  std::vector<WorldDetection> out(static_cast<std::size_t>(count));
  const double t = frame / frameRate_hz;
  for (int i = 0; i < count; ++i) {
    WorldDetection& d = out[static_cast<std::size_t>(i)];
    d.timestamp_ns = static_cast<std::int64_t>(std::llround(t * 1e9));
    // 20 lanes, 10 cars per lane 12 m apart.
    const int lane = i % 20;
    const int slot = i / 20;
    d.centreEnu = Eigen::Vector2d(-100.0 + 12.0 * slot + 10.0 * t, -50.0 + 5.0 * lane);
    d.headingEnu_rad = 0.0;
    d.length_m = 4.5;
    d.width_m = 1.8;
    d.score = 0.9f;
    d.typeProbabilities.fill(0.05f);
    d.typeProbabilities[3] = 0.7f;
  }
  return out;
}

}  // namespace vp::tracking::test
