// tracking/hungarian: optimal assignment (minimum total cost) behind a small solver interface.
//
// Contract: AssignmentSolver::solve() takes a rows x cols cost matrix (row-major view,
// rows <= cols or not) in which entries >= kInfeasibleCost mean "may not be paired", and
// writes, for each row, the column it is assigned to or -1. It minimises the sum of the
// feasible costs over all assignments that pair as many rows as the feasible entries
// allow (a pair that is infeasible is reported as -1, never forced). HungarianSolver
// (shortest augmenting paths with potentials, O(n^3)) allocates its work arrays once in
// init() for the largest matrix it will see; solve() then never allocates and fails
// (returns false) only when the matrix exceeds that capacity or holds a non-finite cost.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace vp::tracking {

constexpr float kInfeasibleCost = 1.0e6f;

class AssignmentSolver {
 public:
  virtual ~AssignmentSolver() = default;
  // costs: rows * cols entries, row-major. rowToCol: at least rows entries.
  virtual bool solve(std::span<const float> costs, int rows, int cols, std::span<int> rowToCol) = 0;
};

class HungarianSolver final : public AssignmentSolver {
 public:
  HungarianSolver() = default;
  // Reserves work space for matrices up to maxRows x maxCols (start-up only).
  bool init(int maxRows, int maxCols);
  bool solve(std::span<const float> costs, int rows, int cols, std::span<int> rowToCol) override;

 private:
  int capacity_ = 0;  // square side n = max(rows, cols) the work arrays hold
  std::vector<double> u_, v_, minv_;
  std::vector<int> p_, way_;
  std::vector<char> used_;
};

}  // namespace vp::tracking
