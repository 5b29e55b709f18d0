#include "traffic.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPathStep_m = 0.25;
constexpr int kSubSteps = 5;
constexpr double kMaxSteer_rad = 0.6;
constexpr double kLateralAccel_mps2 = 2.5;
constexpr double kAllRedS = 2.0;

Eigen::Vector2d unit(double a) {
  return {std::cos(a), std::sin(a)};
}

double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                       const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 1e-12 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double boxDistance(const Patch& r, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = p - r.centre;
  const double qx = std::fabs(d.dot(r.dir)) - r.halfLength_m;
  const double qy = std::fabs(d.x() * -r.dir.y() + d.y() * r.dir.x()) - r.halfWidth_m;
  return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
}

double exponential(Rng& rng, double rate) {
  return -std::log(1.0 - rng.uniform()) / rate;
}

}  // namespace

BicycleState stepBicycle(const BicycleState& s, double v, double delta, double wheelbase_m,
                         double dt) {
  const double omega = v * std::tan(delta) / wheelbase_m;
  BicycleState out;
  out.psi = s.psi + omega * dt;
  if (std::fabs(omega) < 1e-9) {
    out.x = s.x + v * std::cos(s.psi) * dt;
    out.y = s.y + v * std::sin(s.psi) * dt;
  } else {
    const double r = v / omega;  // signed turn radius L / tan(delta)
    out.x = s.x + r * (std::sin(out.psi) - std::sin(s.psi));
    out.y = s.y - r * (std::cos(out.psi) - std::cos(s.psi));
  }
  return out;
}

LanePath::LanePath(std::vector<Eigen::Vector2d> points) {
  // Resample at a fixed step so arc-length lookups are index arithmetic.
  double carried = 0.0;
  points_.push_back(points.front());
  for (std::size_t i = 1; i < points.size(); ++i) {
    const Eigen::Vector2d a = points[i - 1];
    const Eigen::Vector2d b = points[i];
    const double len = (b - a).norm();
    double t = kPathStep_m - carried;
    while (t <= len) {
      points_.push_back(a + (b - a) * (t / len));
      t += kPathStep_m;
    }
    carried = len - (t - kPathStep_m);
  }
  s_.resize(points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i) {
    s_[i] = static_cast<double>(i) * kPathStep_m;
  }
  radius_.assign(points_.size(), 1e9);
  const std::size_t k = 4;
  for (std::size_t i = k; i + k < points_.size(); ++i) {
    const Eigen::Vector2d a = points_[i - k] - points_[i];
    const Eigen::Vector2d b = points_[i + k] - points_[i];
    const Eigen::Vector2d c = points_[i + k] - points_[i - k];
    const double cross = std::fabs(a.x() * b.y() - a.y() * b.x());
    radius_[i] = cross > 1e-9 ? a.norm() * b.norm() * c.norm() / (2.0 * cross) : 1e9;
  }
}

Eigen::Vector2d LanePath::at(double s) const {
  if (s <= 0.0) {
    return points_.front() + s * unit(headingAt(0.0));
  }
  const double f = s / kPathStep_m;
  const auto i = static_cast<std::size_t>(f);
  if (i + 1 >= points_.size()) {
    return points_.back() + (s - length()) * unit(headingAt(length()));
  }
  const double t = f - static_cast<double>(i);
  return points_[i] * (1.0 - t) + points_[i + 1] * t;
}

double LanePath::headingAt(double s) const {
  const auto n = points_.size();
  auto i = static_cast<std::size_t>(std::clamp(s / kPathStep_m, 0.0, static_cast<double>(n - 2)));
  i = std::min(i, n - 2);
  const Eigen::Vector2d d = points_[i + 1] - points_[i];
  return std::atan2(d.y(), d.x());
}

double LanePath::project(const Eigen::Vector2d& p, double sFrom, double sTo) const {
  const auto n = static_cast<long>(points_.size());
  const long i0 = std::clamp(static_cast<long>(sFrom / kPathStep_m), 0L, n - 1);
  const long i1 = std::clamp(static_cast<long>(sTo / kPathStep_m) + 1, 0L, n - 1);
  double best = 1e18;
  long bestIndex = i0;
  for (long i = i0; i <= i1; ++i) {
    const double d = (points_[static_cast<std::size_t>(i)] - p).squaredNorm();
    if (d < best) {
      best = d;
      bestIndex = i;
    }
  }
  // Refine on the neighbouring segments.
  double s = static_cast<double>(bestIndex) * kPathStep_m;
  for (const long j : {bestIndex - 1, bestIndex}) {
    if (j < 0 || j + 1 >= n) {
      continue;
    }
    const Eigen::Vector2d a = points_[static_cast<std::size_t>(j)];
    const Eigen::Vector2d ab = points_[static_cast<std::size_t>(j + 1)] - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    if ((a + t * ab - p).squaredNorm() <= best + 1e-12) {
      best = (a + t * ab - p).squaredNorm();
      s = (static_cast<double>(j) + t) * kPathStep_m;
    }
  }
  return s;
}

double LanePath::curveSpeedLimit(double s, double ahead) const {
  const auto n = points_.size();
  const auto i0 =
      static_cast<std::size_t>(std::clamp(s / kPathStep_m, 0.0, static_cast<double>(n - 1)));
  const auto i1 = static_cast<std::size_t>(
      std::clamp((s + ahead) / kPathStep_m, 0.0, static_cast<double>(n - 1)));
  double r = 1e9;
  for (std::size_t i = i0; i <= i1; ++i) {
    r = std::min(r, radius_[i]);
  }
  return std::sqrt(kLateralAccel_mps2 * r);
}

Eigen::Vector2d SimVehicle::centre() const {
  return Eigen::Vector2d(rear.x, rear.y) - model->rearAxleXM * unit(rear.psi);
}

bool Traffic::green(int group) const {
  if (group < 0) {
    return true;
  }
  const TrafficParams& t = scene_->traffic;
  const double available = t.signalCycleS - 4.0 * kAllRedS;
  const std::array<double, 4> durations = {0.35 * available, 0.15 * available, 0.35 * available,
                                           0.15 * available};
  double phase = std::fmod(timeS_ + t.signalOffsetS, t.signalCycleS);
  for (int g = 0; g < 4; ++g) {
    if (phase < durations[static_cast<std::size_t>(g)]) {
      return g == group;
    }
    phase -= durations[static_cast<std::size_t>(g)] + kAllRedS;
    if (phase < 0.0) {
      return false;  // all red
    }
  }
  return false;
}

void Traffic::buildPaths(const SceneSpec& scene, double halfLength) {
  const bool junction = scene.kind == SceneKind::Intersection;
  for (std::size_t ri = 0; ri < scene.roads.size(); ++ri) {
    const Road& r = scene.roads[ri];
    for (const bool forward : {true, false}) {
      const Eigen::Vector2d d = forward ? r.dir : Eigen::Vector2d(-r.dir);
      const int lanes = forward ? r.lanesForward : r.lanesBackward;
      const double tc = d.dot(scene.viewCentre - r.centre);
      for (int k = 0; k < lanes; ++k) {
        const Eigen::Vector2d pE = r.centre + r.laneOffset_m(forward, k) * r.leftNormal();
        std::vector<int> entry;
        const double t0 = (junction ? 0.0 : tc) - halfLength;
        const double t1 = (junction ? 0.0 : tc) + halfLength;
        {
          LanePath straight({pE + t0 * d, pE + t1 * d});
          if (junction) {
            straight.signalGroup = static_cast<int>(ri) * 2;
            straight.stopS = -r.stopDistance_m - t0;
          }
          entry.push_back(static_cast<int>(paths_.size()));
          paths_.push_back(std::move(straight));
        }
        if (junction) {
          const Road& q = scene.roads[1 - ri];
          for (const bool right : {true, false}) {
            if ((right && k != lanes - 1) || (!right && k != 0)) {
              continue;
            }
            const Eigen::Vector2d side =
                right ? Eigen::Vector2d(d.y(), -d.x()) : Eigen::Vector2d(-d.y(), d.x());
            const bool qForward = q.dir.dot(side) > 0.0;
            const Eigen::Vector2d dq = qForward ? q.dir : Eigen::Vector2d(-q.dir);
            const int qLanes = qForward ? q.lanesForward : q.lanesBackward;
            const Eigen::Vector2d pX =
                q.centre + q.laneOffset_m(qForward, right ? qLanes - 1 : 0) * q.leftNormal();
            // Intersection of the entry and exit lane lines.
            Eigen::Matrix2d m;
            m << d.x(), -dq.x(), d.y(), -dq.y();
            const Eigen::Vector2d ts = m.colPivHouseholderQr().solve(pX - pE);
            const Eigen::Vector2d meet = pE + ts.x() * d;
            const double phi = std::atan2(d.x() * dq.y() - d.y() * dq.x(), d.dot(dq));
            const double halfTan = std::tan(0.5 * std::fabs(phi));
            double radius = right ? std::max(4.5, scene.cornerRadius_m + 1.5) : 14.0;
            const double maxTangent = ts.x() + r.stopDistance_m - 1.0;
            radius = std::max(4.2, std::min(radius, maxTangent / halfTan));
            const double tangent = radius * halfTan;
            const Eigen::Vector2d a = meet - tangent * d;
            const Eigen::Vector2d b = meet + tangent * dq;
            const Eigen::Vector2d normal =
                phi > 0 ? Eigen::Vector2d(-d.y(), d.x()) : Eigen::Vector2d(d.y(), -d.x());
            const Eigen::Vector2d c = a + radius * normal;
            const double theta0 = std::atan2(a.y() - c.y(), a.x() - c.x());
            std::vector<Eigen::Vector2d> pts = {pE + t0 * d};
            const int arcSteps = 40;
            for (int i = 0; i <= arcSteps; ++i) {
              const double th = theta0 + phi * i / arcSteps;
              pts.emplace_back(c + radius * unit(th));
            }
            const double exitFrom = dq.dot(b - q.centre);
            pts.push_back(b + (halfLength - exitFrom) * dq);
            LanePath turn(std::move(pts));
            turn.signalGroup = static_cast<int>(ri) * 2 + (right ? 0 : 1);
            turn.stopS = -r.stopDistance_m - t0;
            entry.push_back(static_cast<int>(paths_.size()));
            paths_.push_back(std::move(turn));
          }
        }
        entries_.push_back(std::move(entry));
      }
    }
  }
}

void Traffic::placeParked(const SceneSpec& scene, Rng& rng) {
  const auto park = [&](const Eigen::Vector2d& centre, double heading) {
    SimVehicle v;
    v.model = factory_->makeCar(rng, factory_->drawCarType(rng));
    v.parked = true;
    v.trackId = nextTrackId_++;
    const Eigen::Vector2d rear = centre + v.model->rearAxleXM * unit(heading);
    v.rear = BicycleState{rear.x(), rear.y(), heading};
    vehicles_.push_back(std::move(v));
  };
  for (const Road& r : scene.roads) {
    const double tc = r.along(scene.viewCentre);
    for (const bool right : {true, false}) {
      const double width = right ? r.parkingRight_m : r.parkingLeft_m;
      if (width <= 0.0) {
        continue;
      }
      const double slot = 6.5;
      const double first = slot * std::floor((tc - 0.6 * scene.extent_m) / slot) + 0.5 * slot;
      for (double a = first; a < tc + 0.6 * scene.extent_m; a += slot) {
        if (scene.kind == SceneKind::Intersection && std::fabs(a) < r.stopDistance_m + 4.0) {
          continue;
        }
        if (r.crosswalkCentre_m < 1e8 && scene.kind != SceneKind::Intersection &&
            std::fabs(a - r.crosswalkCentre_m) < 0.5 * r.crosswalkWidth_m + 4.0) {
          continue;
        }
        const double kerbLateral = right ? -r.rightHalf_m() : r.leftHalf_m();
        const Eigen::Vector2d kerbPoint = r.centre + a * r.dir + kerbLateral * r.leftNormal();
        bool blocked = false;
        for (const Patch& p : scene.paved) {
          blocked = blocked || boxDistance(p, kerbPoint) < 0.5;
        }
        if (blocked || !rng.chance(scene.traffic.kerbParkingOccupancy)) {
          continue;
        }
        // Draw the car first so its width sets the distance to the kerb.
        const double heading =
            std::atan2(r.dir.y(), r.dir.x()) + (right ? 0.0 : kPi) + rng.normal(0.0, 0.015);
        const double alongJitter = rng.uniform(-0.6, 0.6);
        const double kerbGap = rng.uniform(0.1, 0.4);
        SimVehicle v;
        v.model = factory_->makeCar(rng, factory_->drawCarType(rng));
        if (v.model->frontXM - v.model->rearXM > slot - 0.8) {
          continue;
        }
        v.parked = true;
        v.trackId = nextTrackId_++;
        const double lateral = right ? kerbLateral + kerbGap + v.model->halfWidth_m
                                     : kerbLateral - kerbGap - v.model->halfWidth_m;
        const Eigen::Vector2d c = r.centre + (a + alongJitter) * r.dir + lateral * r.leftNormal();
        const Eigen::Vector2d rear = c + v.model->rearAxleXM * unit(heading);
        v.rear = BicycleState{rear.x(), rear.y(), heading};
        vehicles_.push_back(std::move(v));
      }
    }
  }
  for (const ParkingLot& lot : scene.lots) {
    for (const Eigen::Vector3d& bay : lot.bays) {
      if (!rng.chance(scene.traffic.lotOccupancy)) {
        continue;
      }
      const double heading = bay.z() + (rng.chance(0.15) ? kPi : 0.0) + rng.normal(0.0, 0.03);
      const Eigen::Vector2d c = Eigen::Vector2d(bay.x(), bay.y()) +
                                rng.uniform(-0.15, 0.15) * lot.dir +
                                rng.uniform(-0.2, 0.2) * unit(bay.z());
      park(c, heading);
    }
  }
}

void Traffic::init(const SceneSpec& scene, const VehicleFactory& factory, double pathHalfLength_m,
                   double warmUpS, double frameIntervalS, Rng& rng) {
  scene_ = &scene;
  factory_ = &factory;
  frameIntervalS_ = frameIntervalS;
  buildPaths(scene, pathHalfLength_m);
  placeParked(scene, rng);
  const int warmFrames = static_cast<int>(warmUpS / frameIntervalS);
  timeS_ = -warmFrames * frameIntervalS;
  for (std::size_t e = 0; e < entries_.size(); ++e) {
    nextArrivalS_.push_back(timeS_ + exponential(rng, scene.traffic.arrivalRatePerLane_hz));
  }
  for (int i = 0; i < warmFrames; ++i) {
    step(rng);
  }
  timeS_ = 0.0;
}

void Traffic::spawn(Rng& rng) {
  for (std::size_t e = 0; e < entries_.size(); ++e) {
    if (timeS_ < nextArrivalS_[e]) {
      continue;
    }
    const LanePath& first = paths_[static_cast<std::size_t>(entries_[e][0])];
    const Eigen::Vector2d start = first.at(0.0);
    bool free = true;
    for (const SimVehicle& v : vehicles_) {
      if ((v.centre() - start).norm() < 16.0) {
        free = false;
      }
    }
    if (!free) {
      continue;  // stays pending until the entry clears
    }
    nextArrivalS_[e] = timeS_ + exponential(rng, scene_->traffic.arrivalRatePerLane_hz);
    std::vector<double> weights;
    for (std::size_t i = 0; i < entries_[e].size(); ++i) {
      weights.push_back(i == 0 ? 0.6 : 0.2);
    }
    SimVehicle v;
    v.path = entries_[e][static_cast<std::size_t>(rng.weighted(weights))];
    v.model = rng.chance(scene_->traffic.largeVehicleShare)
                  ? factory_->makeLarge(rng)
                  : factory_->makeCar(rng, factory_->drawCarType(rng));
    v.trackId = nextTrackId_++;
    const double large = v.model->type == shape::VehicleType::Large ? 0.85 : 1.0;
    v.desiredSpeed_mps =
        std::min(15.0, scene_->traffic.speedLimit_mps * rng.uniform(0.8, 1.15) * large);
    v.headwayS = rng.uniform(1.1, 1.9);
    const LanePath& path = paths_[static_cast<std::size_t>(v.path)];
    v.s = 0.0;
    const Eigen::Vector2d p = path.at(0.0);
    v.rear = BicycleState{p.x(), p.y(), path.headingAt(0.0)};
    v.speed_mps = 0.8 * v.desiredSpeed_mps;
    vehicles_.push_back(std::move(v));
  }
}

double Traffic::gapAhead(std::size_t index, double* leaderSpeed) const {
  const SimVehicle& me = vehicles_[index];
  const LanePath& path = paths_[static_cast<std::size_t>(me.path)];
  const double frontDist = me.model->frontXM - me.model->rearAxleXM;
  const double hw = me.model->halfWidth_m;
  const double sFront = me.s + frontDist;
  const double horizon = 55.0;
  double gap = 1e9;
  *leaderSpeed = 0.0;
  const Eigen::Vector2d myCentre = me.centre();
  for (std::size_t j = 0; j < vehicles_.size(); ++j) {
    if (j == index) {
      continue;
    }
    const SimVehicle& o = vehicles_[j];
    const Eigen::Vector2d oc = o.centre();
    if ((oc - myCentre).norm() > horizon + 15.0) {
      continue;
    }
    const Eigen::Vector2d f = unit(o.rear.psi);
    const Eigen::Vector2d a = oc + (o.model->rearXM + o.model->halfWidth_m) * f;
    const Eigen::Vector2d b = oc + (o.model->frontXM - o.model->halfWidth_m) * f;
    const double reach = hw + o.model->halfWidth_m + 0.25;
    for (double s = sFront; s < sFront + std::min(gap, horizon); s += 0.5) {
      if (segmentDistance(path.at(s), a, b) < reach) {
        const double g = s - sFront + hw;
        if (g < gap) {
          gap = g;
          *leaderSpeed = std::max(0.0, o.speed_mps * std::cos(o.rear.psi - path.headingAt(s)));
        }
        break;
      }
    }
  }
  if (path.signalGroup >= 0 && !me.committed && !green(path.signalGroup)) {
    const double stopGap = path.stopS - sFront;
    if (stopGap > -0.5 && stopGap < gap) {
      gap = std::max(stopGap, 0.01);
      *leaderSpeed = 0.0;
    }
  }
  return gap;
}

void Traffic::step(Rng& rng) {
  spawn(rng);
  // Decide accelerations on the state at the start of the frame (IDM).
  std::vector<double> accel(vehicles_.size(), 0.0);
  for (std::size_t i = 0; i < vehicles_.size(); ++i) {
    SimVehicle& v = vehicles_[i];
    if (v.parked) {
      continue;
    }
    const LanePath& path = paths_[static_cast<std::size_t>(v.path)];
    const double frontDist = v.model->frontXM - v.model->rearAxleXM;
    if (path.signalGroup >= 0 && !v.committed) {
      const double stopGap = path.stopS - (v.s + frontDist);
      if (stopGap < 0.0 && green(path.signalGroup)) {
        v.committed = true;
      } else if (!green(path.signalGroup) && stopGap > 0.0 && stopGap < 20.0 &&
                 v.speed_mps * v.speed_mps / (2.0 * stopGap) > 4.5) {
        v.committed = true;  // too late to stop comfortably: clears on amber
      } else if (stopGap < -0.5) {
        v.committed = true;
      }
    }
    double leaderSpeed = 0.0;
    const double gap = gapAhead(i, &leaderSpeed);
    const bool large = v.model->type == shape::VehicleType::Large;
    const double aMax = large ? 1.0 : 1.6;
    const double bComfort = 2.0;
    const double lookAhead = std::max(10.0, v.speed_mps * v.speed_mps / (2.0 * 1.5) + 5.0);
    const double v0 = std::max(
        1.0, std::min(v.desiredSpeed_mps, path.curveSpeedLimit(v.s + frontDist * 0.5, lookAhead)));
    const double sStar =
        2.0 + std::max(0.0, v.speed_mps * v.headwayS + v.speed_mps * (v.speed_mps - leaderSpeed) /
                                                           (2.0 * std::sqrt(aMax * bComfort)));
    double a = aMax * (1.0 - std::pow(v.speed_mps / v0, 4.0) -
                       (sStar / std::max(gap, 0.1)) * (sStar / std::max(gap, 0.1)));
    if (gap < 0.3) {
      a = -8.0;
    }
    accel[i] = std::clamp(a, -8.0, aMax);
  }
  const double dt = frameIntervalS_ / kSubSteps;
  for (int sub = 0; sub < kSubSteps; ++sub) {
    for (std::size_t i = 0; i < vehicles_.size(); ++i) {
      SimVehicle& v = vehicles_[i];
      if (v.parked) {
        continue;
      }
      const LanePath& path = paths_[static_cast<std::size_t>(v.path)];
      const double wheelbase = v.model->wheelbase_m;
      v.s = path.project({v.rear.x, v.rear.y}, v.s - 1.0, v.s + 3.0);
      // Pure pursuit on the rear axle: the arc through the look-ahead point.
      const double lookAhead = std::clamp(2.0 + 0.45 * v.speed_mps, 3.5, 10.0);
      const Eigen::Vector2d target = path.at(v.s + lookAhead);
      const Eigen::Vector2d rel = target - Eigen::Vector2d(v.rear.x, v.rear.y);
      const double alpha = std::atan2(rel.y(), rel.x()) - v.rear.psi;
      const double ld = std::max(rel.norm(), 1.0);
      double steer = std::atan(2.0 * wheelbase * std::sin(alpha) / ld);
      steer = std::clamp(steer, -kMaxSteer_rad, kMaxSteer_rad);
      const double maxChange = 1.0 * dt;
      v.steer_rad = std::clamp(steer, v.steer_rad - maxChange, v.steer_rad + maxChange);
      v.speed_mps = std::clamp(v.speed_mps + accel[i] * dt, 0.0, 15.0);
      v.rear = stepBicycle(v.rear, v.speed_mps, v.steer_rad, wheelbase, dt);
      v.yawRate_radps = v.speed_mps * std::tan(v.steer_rad) / wheelbase;
    }
  }
  // Vehicles past the end of their path have left the scene.
  std::erase_if(vehicles_, [this](const SimVehicle& v) {
    return !v.parked && v.s > paths_[static_cast<std::size_t>(v.path)].length() - 2.0;
  });
  timeS_ += frameIntervalS_;
}

}  // namespace vp::sim
