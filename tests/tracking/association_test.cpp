// Tests for tracking/hungarian and tracking/association: the solver against brute force on
// random small matrices (with infeasible entries), each gate, and the ByteTrack second pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include "geometry/rotated_box.hpp"
#include "seed_one_options.hpp"
#include "tracking/association.hpp"
#include "tracking/hungarian.hpp"

namespace vp::tracking {
namespace {

// Best (most pairs, then least cost) assignment by enumerating column permutations.
std::pair<int, double> bruteForce(const std::vector<float>& c, int rows, int cols) {
  const int n = std::max(rows, cols);
  std::vector<int> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), 0);
  int bestPairs = -1;
  double bestCost = 0.0;
  do {
    int pairs = 0;
    double cost = 0.0;
    for (int r = 0; r < rows; ++r) {
      const int col = perm[static_cast<std::size_t>(r)];
      if (col < cols) {
        const float v = c[static_cast<std::size_t>(r * cols + col)];
        if (v < kInfeasibleCost) {
          ++pairs;
          cost += static_cast<double>(v);
        }
      }
    }
    if (pairs > bestPairs || (pairs == bestPairs && cost < bestCost - 1e-9)) {
      bestPairs = pairs;
      bestCost = cost;
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  return {bestPairs, bestCost};
}

TEST(Hungarian, MatchesBruteForceOnRandomMatrices) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  HungarianSolver solver;
  ASSERT_TRUE(solver.init(7, 7));
  for (int trial = 0; trial < 400; ++trial) {
    const int rows = 1 + static_cast<int>(rng() % 6);
    const int cols = 1 + static_cast<int>(rng() % 6);
    std::vector<float> c(static_cast<std::size_t>(rows * cols));
    for (float& v : c) {
      v = u(rng) < 0.3f ? kInfeasibleCost : 2.0f * u(rng);
    }
    std::vector<int> assign(static_cast<std::size_t>(rows), -2);
    ASSERT_TRUE(solver.solve(c, rows, cols, assign));
    int pairs = 0;
    double cost = 0.0;
    std::vector<int> used(static_cast<std::size_t>(cols), 0);
    for (int r = 0; r < rows; ++r) {
      const int col = assign[static_cast<std::size_t>(r)];
      if (col >= 0) {
        ASSERT_LT(col, cols);
        ASSERT_EQ(used[static_cast<std::size_t>(col)]++, 0) << "column used twice";
        ASSERT_LT(c[static_cast<std::size_t>(r * cols + col)], kInfeasibleCost);
        ++pairs;
        cost += static_cast<double>(c[static_cast<std::size_t>(r * cols + col)]);
      }
    }
    const auto [bestPairs, bestCost] = bruteForce(c, rows, cols);
    EXPECT_EQ(pairs, bestPairs) << "trial " << trial;
    EXPECT_NEAR(cost, bestCost, 1e-4) << "trial " << trial;
  }
}

TEST(Hungarian, RejectsOversizeAndNonFinite) {
  HungarianSolver solver;
  ASSERT_TRUE(solver.init(2, 2));
  std::vector<float> c(9, 1.0f);
  std::vector<int> a(3);
  EXPECT_FALSE(solver.solve(c, 3, 3, a));
  c[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(solver.solve(c, 2, 2, a));
}

WorldDetection detectionAt(double x, double y, double heading, float score = 0.9f) {
  WorldDetection d;
  d.centreEnu = {x, y};
  d.headingEnu_rad = heading;
  d.length_m = 4.5;
  d.width_m = 1.8;
  d.score = score;
  return d;
}

TrackView trackAt(double x, double y, double heading, double sigma = 0.5) {
  TrackView t;
  t.centre = {x, y};
  t.heading_rad = heading;
  t.centreInnovationCov = Eigen::Matrix2d::Identity() * sigma * sigma;
  return t;
}

TEST(Association, GatesRejectFarTurnedAndImprobablePairs) {
  Associator a;
  ASSERT_TRUE(a.init(4, 4, test::seedOneAssociation()));
  const TrackView t = trackAt(0.0, 0.0, 0.0, 0.5);
  EXPECT_LT(a.pairCost(t, detectionAt(0.2, 0.1, 0.05)), 0.5f);
  EXPECT_EQ(a.pairCost(t, detectionAt(7.0, 0.0, 0.0)), kInfeasibleCost);  // distance
  EXPECT_EQ(a.pairCost(t, detectionAt(0.2, 0.0, 0.5 * geometry::kPi)), kInfeasibleCost);  // heading
  EXPECT_EQ(a.pairCost(t, detectionAt(2.5, 0.0, 0.0)), kInfeasibleCost);  // Mahalanobis (5 sigma)
  // A flipped detection passes the heading gate (it is an axis gate); the manager corrects it.
  EXPECT_LT(a.pairCost(t, detectionAt(0.1, 0.0, geometry::kPi)), 0.5f);
  // Heading unknown: only position counts.
  WorldDetection unknown = detectionAt(0.1, 0.0, 1.0);
  unknown.headingKnown = false;
  EXPECT_LT(a.pairCost(t, unknown), 0.5f);
  // A wide covariance (long occlusion) lets the same offset through.
  EXPECT_LT(a.pairCost(trackAt(0.0, 0.0, 0.0, 2.0), detectionAt(2.5, 0.0, 0.0)), kInfeasibleCost);
}

TEST(Association, OptimalNotGreedyAndSecondPassForLowScores) {
  Associator a;
  ASSERT_TRUE(a.init(4, 4, test::seedOneAssociation()));
  // Two tracks 1 m apart in a queue, two detections: each goes to the track it fits.
  const std::vector<TrackView> tracks = {trackAt(0.0, 0.0, 0.0, 0.4), trackAt(1.0, 0.0, 0.0, 0.4)};
  std::vector<WorldDetection> dets = {detectionAt(0.6, 0.0, 0.0), detectionAt(-0.5, 0.0, 0.0)};
  std::vector<int> t2d(2), d2t(2);
  ASSERT_TRUE(a.associate(tracks, dets, t2d, d2t));
  EXPECT_EQ(t2d[0], 1);
  EXPECT_EQ(t2d[1], 0);
  // Low-score detection: matched only in the second pass, and only by a track allowing it.
  dets = {detectionAt(0.1, 0.0, 0.0, 0.3f)};
  AssociationStats stats;
  ASSERT_TRUE(a.associate(std::span(tracks).first(1), dets, t2d, d2t, &stats));
  EXPECT_EQ(t2d[0], 0);
  EXPECT_EQ(stats.secondPassMatches, 1);
  std::vector<TrackView> tentative = {trackAt(0.0, 0.0, 0.0)};
  tentative[0].secondPass = false;
  ASSERT_TRUE(a.associate(tentative, dets, t2d, d2t));
  EXPECT_EQ(t2d[0], -1);
  // Below lowScore: never.
  dets = {detectionAt(0.1, 0.0, 0.0, 0.05f)};
  ASSERT_TRUE(a.associate(std::span(tracks).first(1), dets, t2d, d2t));
  EXPECT_EQ(t2d[0], -1);
}

}  // namespace
}  // namespace vp::tracking
