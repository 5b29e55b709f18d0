#include "tracking/association.hpp"

#include <cmath>

#include <Eigen/Cholesky>

#include "geometry/rotated_box.hpp"

namespace vp::tracking {

bool Associator::init(int maxTracks, int maxDetections, const AssociationParams& params,
                      AssignmentSolver* solver) {
  if (maxTracks <= 0 || maxDetections <= 0 || !(params.lowScore <= params.highScore)) {
    return false;
  }
  params_ = params;
  solver_ = solver;
  maxTracks_ = maxTracks;
  maxDetections_ = maxDetections;
  costs_.assign(static_cast<std::size_t>(maxTracks) * static_cast<std::size_t>(maxDetections),
                kInfeasibleCost);
  rows_.assign(static_cast<std::size_t>(maxTracks), -1);
  cols_.assign(static_cast<std::size_t>(maxDetections), -1);
  assignment_.assign(static_cast<std::size_t>(maxTracks), -1);
  return hungarian_.init(maxTracks, maxDetections);
}

float Associator::pairCost(const TrackView& track, const WorldDetection& detection) const {
  const Eigen::Vector2d d = detection.centreEnu - track.centre;
  const double dist2 = d.squaredNorm();
  if (dist2 > params_.maxDistance_m * params_.maxDistance_m) {
    return kInfeasibleCost;
  }
  if (detection.headingKnown &&
      geometry::axisAngleDifference(detection.headingEnu_rad, track.heading_rad) >
          params_.maxAxisAngle_rad) {
    return kInfeasibleCost;
  }
  const Eigen::LLT<Eigen::Matrix2d> llt(track.centreInnovationCov);
  if (llt.info() != Eigen::Success) {
    return kInfeasibleCost;
  }
  const double mahalanobis2 = d.dot(llt.solve(d));
  if (!(mahalanobis2 <= params_.mahalanobisGate)) {
    return kInfeasibleCost;
  }
  // The overlap term breaks ties the centre cannot: two cars side by side in a queue differ
  // little in centre distance relative to S, but much in footprint overlap.
  const geometry::RotatedBox a{track.centre.x(), track.centre.y(), track.length_m, track.width_m,
                               track.heading_rad};
  const geometry::RotatedBox b{
      detection.centreEnu.x(), detection.centreEnu.y(), detection.length_m, detection.width_m,
      detection.headingKnown ? detection.headingEnu_rad : track.heading_rad};
  const double iou = geometry::rotatedIou(a, b);
  const double cost = params_.mahalanobisWeight * mahalanobis2 / params_.mahalanobisGate +
                      params_.iouWeight * (1.0 - iou);
  return static_cast<float>(cost);
}

bool Associator::runPass(std::span<const TrackView> tracks,
                         std::span<const WorldDetection> detections, bool secondPass,
                         std::span<int> trackToDet, std::span<int> detToTrack, int* matches,
                         int* gated) {
  int nRows = 0;
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    if (trackToDet[t] < 0 && (!secondPass || tracks[t].secondPass)) {
      rows_[static_cast<std::size_t>(nRows++)] = static_cast<int>(t);
    }
  }
  int nCols = 0;
  for (std::size_t d = 0; d < detections.size(); ++d) {
    const float s = detections[d].score;
    const bool inPass =
        secondPass ? (s >= params_.lowScore && s < params_.highScore) : (s >= params_.highScore);
    if (detToTrack[d] < 0 && inPass) {
      cols_[static_cast<std::size_t>(nCols++)] = static_cast<int>(d);
    }
  }
  if (nRows == 0 || nCols == 0) {
    return true;
  }
  // Rows with no feasible pair are left out of the solver: the gates make the matrix sparse
  // and the O(n^3) solver pays for every row it sees.
  int kept = 0;
  for (int r = 0; r < nRows; ++r) {
    const TrackView& track = tracks[static_cast<std::size_t>(rows_[static_cast<std::size_t>(r)])];
    float* row = costs_.data() + static_cast<std::size_t>(kept) * static_cast<std::size_t>(nCols);
    bool any = false;
    for (int c = 0; c < nCols; ++c) {
      const float cost =
          pairCost(track, detections[static_cast<std::size_t>(cols_[static_cast<std::size_t>(c)])]);
      row[c] = cost;
      if (cost < kInfeasibleCost) {
        any = true;
        ++*gated;
      }
    }
    if (any) {
      rows_[static_cast<std::size_t>(kept++)] = rows_[static_cast<std::size_t>(r)];
    }
  }
  if (kept == 0) {
    return true;
  }
  AssignmentSolver* solver = solver_ != nullptr ? solver_ : &hungarian_;
  const std::span<const float> view(
      costs_.data(), static_cast<std::size_t>(kept) * static_cast<std::size_t>(nCols));
  if (!solver->solve(view, kept, nCols,
                     std::span<int>(assignment_.data(), static_cast<std::size_t>(kept)))) {
    return false;
  }
  for (int r = 0; r < kept; ++r) {
    const int c = assignment_[static_cast<std::size_t>(r)];
    if (c < 0) {
      continue;
    }
    const int t = rows_[static_cast<std::size_t>(r)];
    const int d = cols_[static_cast<std::size_t>(c)];
    trackToDet[static_cast<std::size_t>(t)] = d;
    detToTrack[static_cast<std::size_t>(d)] = t;
    ++*matches;
  }
  return true;
}

bool Associator::associate(std::span<const TrackView> tracks,
                           std::span<const WorldDetection> detections, std::span<int> trackToDet,
                           std::span<int> detToTrack, AssociationStats* stats) {
  if (tracks.size() > static_cast<std::size_t>(maxTracks_) ||
      detections.size() > static_cast<std::size_t>(maxDetections_) ||
      trackToDet.size() < tracks.size() || detToTrack.size() < detections.size()) {
    return false;
  }
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    trackToDet[t] = -1;
  }
  for (std::size_t d = 0; d < detections.size(); ++d) {
    detToTrack[d] = -1;
  }
  AssociationStats local;
  const bool ok = runPass(tracks, detections, false, trackToDet, detToTrack,
                          &local.firstPassMatches, &local.gatedPairs) &&
                  runPass(tracks, detections, true, trackToDet, detToTrack,
                          &local.secondPassMatches, &local.gatedPairs);
  if (stats != nullptr) {
    *stats = local;
  }
  return ok;
}

}  // namespace vp::tracking
