// traffic_eval: the offline acceptance measurement of the traffic analysis (docs/traffic.md,
// "Evaluation"). For a recorded sequence with ground truth and a site file, the analyzer
// (traffic::TrafficAnalyzer) runs twice with the same options and the same frame times: on the
// ground-truth vehicles as perfect tracks, and on the app's trajectory file of that sequence.
// The figures compare the two:
// - gate counts by gate, direction and type, and the relative error of the totals; the same by
//   seed 002's categories (car, transporter) is reported beside them;
// - turning movements: each true vehicle that crossed two gates is matched to the track nearest
//   to it over its frames (within matchDistance_m, the track with the most such frames); the
//   vehicle agrees when that track's movement has the same origin and destination gates;
// - queue length: per queue zone (role queue; every zone when the site has none) and period, the
//   largest queue of the period in vehicles, truth vs measured; agreement within 1 vehicle.
// Contract: evaluateSequence() reads the inputs (sequence, site, trajectory file) and returns
// false with a message naming the file and line on bad input; the report functions only format.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include "traffic/traffic_analyzer.hpp"

namespace vp::traffic_eval {

struct EvalOptions {
  traffic::TrafficAnalyzerOptions analyzer{};  // period_s 10 unless the caller sets it
  double matchDistance_m = 3.0;  // a track is near a true vehicle within this of its centre
  std::string siteFile;          // empty: the sequence's (rig.yaml site.file)
  EvalOptions() { analyzer.period_s = 10.0; }
};

struct SequenceInput {
  std::string sequenceDir;
  std::string tracksFile;  // the app's trajectory file of the sequence
};

// Gate counts keyed by (gate index, direction 0 forward / 1 backward, type index).
using CountKey = std::tuple<std::size_t, int, std::size_t>;

struct SequenceResult {
  std::string name;
  std::size_t frames = 0;
  std::vector<std::string> gateIds;
  std::vector<std::string> zoneIds;
  std::map<CountKey, std::uint64_t> truthCounts;
  std::map<CountKey, std::uint64_t> measuredCounts;
  std::uint64_t truthTotal = 0;
  std::uint64_t measuredTotal = 0;
  // Sums over the count cells of |measured - truth|: per gate and direction (types pooled), and
  // per gate, direction and type (a vehicle counted under a wrong type adds 2). Summed per
  // sequence in a total (cells of different sequences never offset each other).
  std::uint64_t directionCellError = 0;
  std::uint64_t typeCellError = 0;
  // The same per gate, direction and seed 002's category (car / transporter, shape::categoryOf).
  std::uint64_t categoryCellError = 0;
  // Turning movements.
  std::size_t movementVehicles = 0;   // true vehicles that crossed two gates
  std::size_t movementAgreeing = 0;   // their matched track has the same origin -> destination
  std::size_t movementUnmatched = 0;  // no track near them
  // Queue length per zone and period.
  std::size_t queuePeriods = 0;         // zone-periods compared
  std::size_t queueAgreeing = 0;        // |measured - truth| <= 1 vehicle
  double queueAbsError_vehicles = 0.0;  // sum of |measured - truth| (max queue of the period)
  double queueAbsError_m = 0.0;         // sum of |measured - truth| (max queue length, m)
  std::size_t truthQueuedPeriods = 0;   // zone-periods with a true queue of at least one vehicle
};

bool evaluateSequence(const SequenceInput& input, const EvalOptions& options,
                      SequenceResult* result, std::string* why);

// The totals over several sequences (name "total").
SequenceResult sumResults(const std::vector<SequenceResult>& results);

struct Acceptance {
  double countError = 0.0;      // |measured - truth| / truth of the gate totals (0 without truth)
  double directionError = 0.0;  // directionCellError / truth
  double typeError = 0.0;       // typeCellError / truth: the counts by type and direction
  double categoryError = 0.0;   // categoryCellError / truth: by seed 002's category (reported)
  double movementShare = 1.0;   // agreeing / vehicles (1 without vehicles)
  double queueShare = 1.0;      // agreeing / zone-periods (1 without any)
  bool countsPass = true;       // totals, by direction and by type and direction all <= 2 %
  bool movementsPass = true;    // >= 95 %
  bool queuesPass = true;       // >= 90 %
  bool pass() const { return countsPass && movementsPass && queuesPass; }
};
Acceptance accept(const SequenceResult& result);

// Human-readable figures of one result (the tables with details when `details`).
void printResult(const SequenceResult& result, bool details, std::ostream& out);

// vp_traffic_eval's command line: arguments after the program name; output to out, messages to
// err; returns the exit status (0, 1 bad input, 2 bad usage, 3 acceptance failed with
// --require-acceptance).
int runTrafficEval(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace vp::traffic_eval
