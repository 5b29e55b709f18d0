#include "evaluation/mot_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotated_box.hpp"
#include "tracking/hungarian.hpp"

namespace vp::evaluation {

std::vector<int> matchByDistance(std::span<const Eigen::Vector2d> truth,
                                 std::span<const Eigen::Vector2d> hypotheses,
                                 std::span<const int> previous, double matchDistance_m) {
  const std::size_t nt = truth.size();
  const std::size_t nh = hypotheses.size();
  const auto dist = [&](std::size_t g, std::size_t h) { return (truth[g] - hypotheses[h]).norm(); };
  std::vector<int> gToH(nt, -1);
  std::vector<int> hToG(nh, -1);
  // 1. Keep last frame's pairs that are still within the distance.
  for (std::size_t g = 0; g < nt && g < previous.size(); ++g) {
    const int h = previous[g];
    if (h >= 0 && static_cast<std::size_t>(h) < nh && hToG[static_cast<std::size_t>(h)] < 0 &&
        dist(g, static_cast<std::size_t>(h)) <= matchDistance_m) {
      gToH[g] = h;
      hToG[static_cast<std::size_t>(h)] = static_cast<int>(g);
    }
  }
  // 2. Pair the rest by minimum total distance (float costs).
  std::vector<std::size_t> rows;
  std::vector<std::size_t> cols;
  for (std::size_t g = 0; g < nt; ++g) {
    if (gToH[g] < 0) {
      rows.push_back(g);
    }
  }
  for (std::size_t h = 0; h < nh; ++h) {
    if (hToG[h] < 0) {
      cols.push_back(h);
    }
  }
  if (rows.empty() || cols.empty()) {
    return gToH;
  }
  std::vector<float> costs(rows.size() * cols.size(), tracking::kInfeasibleCost);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < cols.size(); ++c) {
      const double d = dist(rows[r], cols[c]);
      if (d <= matchDistance_m) {
        costs[r * cols.size() + c] = static_cast<float>(d);
      }
    }
  }
  tracking::HungarianSolver solver;
  solver.init(static_cast<int>(rows.size()), static_cast<int>(cols.size()));
  std::vector<int> assign(rows.size(), -1);
  solver.solve(costs, static_cast<int>(rows.size()), static_cast<int>(cols.size()), assign);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (assign[r] >= 0) {
      gToH[rows[r]] = static_cast<int>(cols[static_cast<std::size_t>(assign[r])]);
    }
  }
  return gToH;
}

void MotAccumulator::addFrame(std::span<const MotObject> truth,
                              std::span<const MotObject> hypotheses) {
  ++sums_.frames;
  sums_.truthObjects += static_cast<int>(truth.size());
  sums_.hypotheses += static_cast<int>(hypotheses.size());
  const double tau = params_.matchDistance_m;
  const std::size_t nt = truth.size();
  const std::size_t nh = hypotheses.size();
  auto dist = [&](std::size_t g, std::size_t h) {
    return (truth[g].position - hypotheses[h].position).norm();
  };
  for (const MotObject& h : hypotheses) {
    ++hypothesisCount_[h.id];
  }
  for (std::size_t g = 0; g < nt; ++g) {
    for (std::size_t h = 0; h < nh; ++h) {
      if (dist(g, h) <= tau) {
        ++pairFrames_[{truth[g].id, hypotheses[h].id}];
      }
    }
  }

  // Last frame's pairs as indices of this frame (ids are unique within a frame).
  std::vector<int> previous(nt, -1);
  for (std::size_t g = 0; g < nt; ++g) {
    const auto prev = previousMatch_.find(truth[g].id);
    if (prev == previousMatch_.end()) {
      continue;
    }
    for (std::size_t h = 0; h < nh; ++h) {
      if (hypotheses[h].id == prev->second) {
        previous[g] = static_cast<int>(h);
        break;
      }
    }
  }
  std::vector<Eigen::Vector2d> truthPositions(nt);
  std::vector<Eigen::Vector2d> hypothesisPositions(nh);
  for (std::size_t g = 0; g < nt; ++g) {
    truthPositions[g] = truth[g].position;
  }
  for (std::size_t h = 0; h < nh; ++h) {
    hypothesisPositions[h] = hypotheses[h].position;
  }
  const std::vector<int> gToH = matchByDistance(truthPositions, hypothesisPositions, previous, tau);
  std::vector<int> hToG(nh, -1);
  for (std::size_t g = 0; g < nt; ++g) {
    if (gToH[g] >= 0) {
      hToG[static_cast<std::size_t>(gToH[g])] = static_cast<int>(g);
    }
  }

  std::map<int, int> current;
  for (std::size_t g = 0; g < nt; ++g) {
    TruthTrack& track = truthTracks_[truth[g].id];
    ++track.present;
    const int h = gToH[g];
    if (h < 0) {
      ++sums_.misses;
      track.trackedLastPresent = false;
      continue;
    }
    const MotObject& hyp = hypotheses[static_cast<std::size_t>(h)];
    ++sums_.matches;
    ++track.matched;
    distanceSum_ += dist(g, static_cast<std::size_t>(h));
    if (track.lastHypothesis >= 0 && track.lastHypothesis != hyp.id) {
      ++sums_.idSwitches;
    }
    if (track.trackedBefore && !track.trackedLastPresent) {
      ++sums_.fragmentations;
    }
    track.lastHypothesis = hyp.id;
    track.trackedBefore = true;
    track.trackedLastPresent = true;
    current[truth[g].id] = hyp.id;
    if (std::isfinite(truth[g].speed_mps) && std::isfinite(hyp.speed_mps)) {
      const double e = hyp.speed_mps - truth[g].speed_mps;
      speedSquaredSum_ += e * e;
      ++sums_.speedSamples;
    }
    if (std::isfinite(truth[g].heading_rad) && std::isfinite(hyp.heading_rad)) {
      ++sums_.headingSamples;
      if (geometry::absAngleDifference(truth[g].heading_rad, hyp.heading_rad) >
          0.5 * geometry::kPi) {
        ++sums_.headingOver90;
      }
    }
    if (truth[g].type >= 0 && hyp.type >= 0) {
      ++sums_.typeSamples;
      sums_.typeCorrect += truth[g].type == hyp.type ? 1 : 0;
    }
  }
  for (std::size_t h = 0; h < nh; ++h) {
    if (hToG[h] < 0) {
      ++sums_.falsePositives;
    }
  }
  previousMatch_ = std::move(current);
}

MotSummary MotAccumulator::summary() const {
  MotSummary s = sums_;
  s.truthTracks = static_cast<int>(truthTracks_.size());
  for (const auto& [id, t] : truthTracks_) {
    const double share = t.present > 0 ? static_cast<double>(t.matched) / t.present : 0.0;
    if (share >= params_.mostlyTrackedShare) {
      ++s.mostlyTracked;
    } else if (share <= params_.mostlyLostShare) {
      ++s.mostlyLost;
    } else {
      ++s.partiallyTracked;
    }
  }
  s.mota =
      s.truthObjects > 0
          ? 1.0 - static_cast<double>(s.misses + s.falsePositives + s.idSwitches) / s.truthObjects
          : 0.0;
  s.motp_m = s.matches > 0 ? distanceSum_ / s.matches : 0.0;
  s.speedRmse_mps = s.speedSamples > 0 ? std::sqrt(speedSquaredSum_ / s.speedSamples) : 0.0;

  // IDF1: one-to-one id mapping maximising the frames matched (Hungarian on -frames).
  std::vector<int> truthIds, hypIds;
  for (const auto& [id, t] : truthTracks_) {
    truthIds.push_back(id);
  }
  for (const auto& [id, n] : hypothesisCount_) {
    hypIds.push_back(id);
  }
  int idtp = 0;
  if (!truthIds.empty() && !hypIds.empty()) {
    std::vector<float> costs(truthIds.size() * hypIds.size(), 0.0f);
    for (const auto& [key, frames] : pairFrames_) {
      const auto g =
          std::lower_bound(truthIds.begin(), truthIds.end(), key.first) - truthIds.begin();
      const auto h = std::lower_bound(hypIds.begin(), hypIds.end(), key.second) - hypIds.begin();
      costs[static_cast<std::size_t>(g) * hypIds.size() + static_cast<std::size_t>(h)] =
          -static_cast<float>(frames);
    }
    tracking::HungarianSolver solver;
    solver.init(static_cast<int>(truthIds.size()), static_cast<int>(hypIds.size()));
    std::vector<int> assign(truthIds.size(), -1);
    solver.solve(costs, static_cast<int>(truthIds.size()), static_cast<int>(hypIds.size()), assign);
    for (std::size_t g = 0; g < truthIds.size(); ++g) {
      if (assign[g] >= 0) {
        idtp += static_cast<int>(-costs[g * hypIds.size() + static_cast<std::size_t>(assign[g])]);
      }
    }
  }
  const int denominator = s.truthObjects + s.hypotheses;
  s.idf1 = denominator > 0 ? 2.0 * idtp / denominator : 0.0;
  s.idPrecision = s.hypotheses > 0 ? static_cast<double>(idtp) / s.hypotheses : 0.0;
  s.idRecall = s.truthObjects > 0 ? static_cast<double>(idtp) / s.truthObjects : 0.0;
  return s;
}

}  // namespace vp::evaluation
