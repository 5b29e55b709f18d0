// diagnostics/latency_histogram: fixed-memory latency statistics for the real-time loop.
//
// Contract: record() files a duration (ns) into one of kBinCount logarithmic bins spanning
// kMin_ns..kMax_ns (8 bins per octave: a quantile read back is within 9 % of the true value;
// durations outside the span land in the first/last bin and are still counted, and the exact
// minimum, maximum and mean are kept beside the bins). quantile(q) returns the upper edge of
// the bin holding the q-th sample (a conservative estimate). No allocation, no locks: one
// writer thread; a reader on another thread takes snapshot() copies (plain struct copy under a
// seqlock-free "copy and check count" scheme is not attempted: the loop hands snapshots to
// the reporter itself). reset() starts a new reporting period.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace vp::diagnostics {

class LatencyHistogram {
 public:
  static constexpr std::int64_t kMin_ns = 1'000;           // 1 us
  static constexpr std::int64_t kMax_ns = 16'000'000'000;  // 16 s
  static constexpr int kBinsPerOctave = 8;
  // log2(16 s / 1 us) = 23.9 octaves
  static constexpr int kBinCount = 24 * kBinsPerOctave;

  void record(std::int64_t ns) {
    if (ns < 0)
      ns = 0;
    ++bins_[static_cast<std::size_t>(binOf(ns))];
    ++count_;
    sumNs_ += static_cast<double>(ns);
    if (ns < minNs_)
      minNs_ = ns;
    if (ns > maxNs_)
      maxNs_ = ns;
  }

  void reset() { *this = LatencyHistogram(); }

  std::uint64_t count() const { return count_; }
  std::int64_t min_ns() const { return count_ ? minNs_ : 0; }
  std::int64_t max_ns() const { return count_ ? maxNs_ : 0; }
  double mean_ns() const { return count_ ? sumNs_ / static_cast<double>(count_) : 0.0; }

  // Upper edge of the bin holding the ceil(q * count)-th smallest sample, clamped to the
  // exact maximum (the exact minimum / maximum for the first / last rank); 0 when empty.
  std::int64_t quantile_ns(double q) const {
    if (count_ == 0)
      return 0;
    const double clamped = q < 0.0 ? 0.0 : (q > 1.0 ? 1.0 : q);
    const auto rank = static_cast<std::uint64_t>(std::ceil(clamped * static_cast<double>(count_)));
    if (rank <= 1)
      return minNs_;  // the extremes are known exactly
    if (rank >= count_)
      return maxNs_;
    std::uint64_t seen = 0;
    for (int b = 0; b < kBinCount - 1; ++b) {
      seen += bins_[static_cast<std::size_t>(b)];
      if (seen >= rank) {
        const std::int64_t edge = upperEdge_ns(b);
        return edge < maxNs_ ? edge : maxNs_;
      }
    }
    return maxNs_;  // the overflow bin
  }
  std::int64_t median_ns() const { return quantile_ns(0.5); }
  std::int64_t p99_ns() const { return quantile_ns(0.99); }

  static int binOf(std::int64_t ns) {
    if (ns <= kMin_ns)
      return 0;
    const double octaves = std::log2(static_cast<double>(ns) / static_cast<double>(kMin_ns));
    const int bin = static_cast<int>(octaves * kBinsPerOctave);
    return bin >= kBinCount ? kBinCount - 1 : bin;
  }
  static std::int64_t upperEdge_ns(int bin) {
    return static_cast<std::int64_t>(static_cast<double>(kMin_ns) *
                                     std::exp2(static_cast<double>(bin + 1) / kBinsPerOctave));
  }

 private:
  std::array<std::uint32_t, kBinCount> bins_{};
  std::uint64_t count_ = 0;
  double sumNs_ = 0.0;
  std::int64_t minNs_ = std::numeric_limits<std::int64_t>::max();
  std::int64_t maxNs_ = 0;
};

}  // namespace vp::diagnostics
