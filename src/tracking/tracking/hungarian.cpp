#include "tracking/hungarian.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vp::tracking {

bool HungarianSolver::init(int maxRows, int maxCols) {
  if (maxRows < 0 || maxCols < 0) {
    return false;
  }
  capacity_ = std::max(maxRows, maxCols);
  const auto n = static_cast<std::size_t>(capacity_) + 1;
  u_.assign(n, 0.0);
  v_.assign(n, 0.0);
  minv_.assign(n, 0.0);
  p_.assign(n, 0);
  way_.assign(n, 0);
  used_.assign(n, 0);
  return true;
}

bool HungarianSolver::solve(std::span<const float> costs, int rows, int cols,
                            std::span<int> rowToCol) {
  if (rows < 0 || cols < 0 || rows > capacity_ || cols > capacity_ ||
      costs.size() < static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) ||
      rowToCol.size() < static_cast<std::size_t>(rows)) {
    return false;
  }
  for (int r = 0; r < rows; ++r) {
    rowToCol[static_cast<std::size_t>(r)] = -1;
  }
  if (rows == 0 || cols == 0) {
    return true;
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
       ++i) {
    if (!std::isfinite(costs[i])) {
      return false;
    }
  }
  // Square the problem with infeasible padding: every padded or infeasible pair costs the
  // same large constant, so the optimum pairs as many feasible entries as possible and
  // among those has the minimum cost (kInfeasibleCost exceeds any sum of feasible costs
  // for the matrix sizes the tracker uses).
  const int n = std::max(rows, cols);
  const double big = kInfeasibleCost;
  auto cost = [&](int i, int j) -> double {  // 1-based
    if (i > rows || j > cols) {
      return big;
    }
    const float c = costs[static_cast<std::size_t>(i - 1) * static_cast<std::size_t>(cols) +
                          static_cast<std::size_t>(j - 1)];
    return c >= kInfeasibleCost ? big : static_cast<double>(c);
  };
  const double inf = std::numeric_limits<double>::infinity();
  std::fill(u_.begin(), u_.begin() + n + 1, 0.0);
  std::fill(v_.begin(), v_.begin() + n + 1, 0.0);
  std::fill(p_.begin(), p_.begin() + n + 1, 0);
  std::fill(way_.begin(), way_.begin() + n + 1, 0);
  // e-maxx formulation: rows are added one at a time, each by a shortest augmenting path in
  // reduced costs (Dijkstra with potentials u, v).
  for (int i = 1; i <= n; ++i) {
    p_[0] = i;
    int j0 = 0;
    std::fill(minv_.begin(), minv_.begin() + n + 1, inf);
    std::fill(used_.begin(), used_.begin() + n + 1, 0);
    do {
      used_[static_cast<std::size_t>(j0)] = 1;
      const int i0 = p_[static_cast<std::size_t>(j0)];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= n; ++j) {
        const auto uj = static_cast<std::size_t>(j);
        if (used_[uj] != 0) {
          continue;
        }
        const double cur = cost(i0, j) - u_[static_cast<std::size_t>(i0)] - v_[uj];
        if (cur < minv_[uj]) {
          minv_[uj] = cur;
          way_[uj] = j0;
        }
        if (minv_[uj] < delta) {
          delta = minv_[uj];
          j1 = j;
        }
      }
      for (int j = 0; j <= n; ++j) {
        const auto uj = static_cast<std::size_t>(j);
        if (used_[uj] != 0) {
          u_[static_cast<std::size_t>(p_[uj])] += delta;
          v_[uj] -= delta;
        } else {
          minv_[uj] -= delta;
        }
      }
      j0 = j1;
    } while (p_[static_cast<std::size_t>(j0)] != 0);
    do {
      const int j1 = way_[static_cast<std::size_t>(j0)];
      p_[static_cast<std::size_t>(j0)] = p_[static_cast<std::size_t>(j1)];
      j0 = j1;
    } while (j0 != 0);
  }
  for (int j = 1; j <= n; ++j) {
    const int i = p_[static_cast<std::size_t>(j)];
    if (i >= 1 && i <= rows && j <= cols && cost(i, j) < big) {
      rowToCol[static_cast<std::size_t>(i - 1)] = j - 1;
    }
  }
  return true;
}

}  // namespace vp::tracking
