// traffic_eval: the two analyzer runs of a sequence and their comparison (see the header).
#include "traffic_eval.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "config/config.hpp"
#include "geodesy/geodesy.hpp"
#include "output_files/trajectory_file.hpp"
#include "sequence/recorded_sequence.hpp"
#include "site/site.hpp"

namespace vp::traffic_eval {
namespace {

namespace fs = std::filesystem;

// What one analyzer run leaves for the comparison.
struct Run {
  std::vector<traffic::TrafficStatistics> periods;
  std::unordered_map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> movements;
  std::map<CountKey, std::uint64_t> counts;
  std::uint64_t total = 0;
};

// Runs the analyzer over the frames: tracksOf(frame index) gives that frame's tracks.
template <typename TracksOf>
bool runAnalyzer(const site::Site& site, const EvalOptions& options,
                 const std::vector<sequence::FrameRecord>& frames, TracksOf tracksOf, Run* run,
                 std::string* why) {
  traffic::TrafficAnalyzer analyzer;
  if (!analyzer.init(site, options.analyzer, why)) {
    return false;
  }
  const auto collect = [&]() {
    for (const traffic::TrafficEvent& e : analyzer.events()) {
      if (e.kind == traffic::TrafficEventKind::TurningMovement) {
        run->movements[e.trackId] = {e.featureIndex, e.toFeatureIndex};
      }
    }
  };
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::vector<tracking::TrackState>& tracks = tracksOf(i);
    if (!analyzer.step(frames[i].timestamp_ns, tracks)) {
      *why = "frame " + std::to_string(frames[i].frameId) + ": time goes backwards";
      return false;
    }
    collect();
    if (const traffic::TrafficStatistics* s = analyzer.completedPeriod()) {
      run->periods.push_back(*s);
    }
  }
  if (!frames.empty()) {
    analyzer.finish(frames.back().timestamp_ns);
    collect();
    if (const traffic::TrafficStatistics* s = analyzer.lastPeriod()) {
      run->periods.push_back(*s);
    }
  }
  const traffic::GateCounter& counter = analyzer.gateCounter();
  for (std::size_t g = 0; g < counter.gates().size(); ++g) {
    for (int d = 0; d < 2; ++d) {
      for (std::size_t t = 0; t < traffic::kTypeCount; ++t) {
        const std::uint64_t n = counter.count(g, static_cast<traffic::CrossingDirection>(d),
                                              static_cast<shape::VehicleType>(t));
        if (n > 0) {
          run->counts[{g, d, t}] = n;
          run->total += n;
        }
      }
    }
  }
  return true;
}

std::string percent(double share) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << 100.0 * share << " %";
  return s.str();
}

}  // namespace

bool evaluateSequence(const SequenceInput& input, const EvalOptions& options,
                      SequenceResult* result, std::string* why) {
  *result = SequenceResult{};
  result->name = fs::path(input.sequenceDir).filename().string();
  if (result->name.empty()) {
    result->name = fs::path(input.sequenceDir).parent_path().filename().string();
  }
  sequence::SequenceReader reader;
  if (!reader.open(input.sequenceDir, why)) {
    return false;
  }
  if (!reader.hasGroundTruth()) {
    *why = input.sequenceDir + ": no ground_truth/objects.csv: nothing to compare with";
    return false;
  }
  const std::string sitePath = options.siteFile.empty() ? reader.rig().sitePath : options.siteFile;
  if (sitePath.empty()) {
    *why = input.sequenceDir + ": rig.yaml names no site file (site.file); give --site FILE";
    return false;
  }
  site::Site site;
  if (!site::loadSite(sitePath, geodesy::LocalFrame(reader.rig().origin), &site, why)) {
    return false;
  }
  output_files::TrajectoryFile file;
  if (!output_files::readTrajectoryFile(input.tracksFile, &file, why)) {
    return false;
  }
  const std::vector<sequence::FrameRecord>& frames = reader.frames();
  result->frames = frames.size();
  std::map<std::int64_t, std::size_t> indexOfFrame;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    indexOfFrame[frames[i].frameId] = i;
  }

  // Truth as perfect tracks: every true vehicle of a frame, confirmed, at its footprint centre.
  std::vector<std::vector<tracking::TrackState>> truth(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    for (const sequence::ObjectTruth& object : reader.objects(frames[i].frameId)) {
      tracking::TrackState t;
      t.id = static_cast<std::uint32_t>(object.trackId);
      t.status = tracking::TrackStatus::Confirmed;
      t.timestamp_ns = frames[i].timestamp_ns;
      t.centreEnu = object.positionEnu.head<2>();
      t.headingEnu_rad = object.headingEnu_rad;
      t.speed_mps = object.speed_mps;
      t.length_m = object.dimensions_m.x();
      t.width_m = object.dimensions_m.y();
      t.type = object.type;
      truth[i].push_back(t);
    }
  }
  // The app's tracks at the sequence's frame times (rows keyed by frame_id).
  std::vector<std::vector<tracking::TrackState>> measured(frames.size());
  for (std::size_t r = 0; r < file.rows.size(); ++r) {
    const output_files::TrajectoryRecord& row = file.rows[r];
    const auto it = indexOfFrame.find(row.frameId);
    if (it == indexOfFrame.end()) {
      *why = input.tracksFile + ":" + std::to_string(file.lines[r]) + ": frame_id: no frame " +
             std::to_string(row.frameId) + " in " + input.sequenceDir +
             " (a file of another sequence?)";
      return false;
    }
    tracking::TrackState t = output_files::toTrackState(row);
    t.timestamp_ns = frames[it->second].timestamp_ns;
    measured[it->second].push_back(t);
  }

  Run truthRun;
  Run measuredRun;
  if (!runAnalyzer(
          site, options, frames, [&](std::size_t i) -> const auto& { return truth[i]; }, &truthRun,
          why) ||
      !runAnalyzer(
          site, options, frames, [&](std::size_t i) -> const auto& { return measured[i]; },
          &measuredRun, why)) {
    *why = sitePath + ": " + *why;
    return false;
  }
  for (const site::Feature& f : site.features()) {
    if (f.kind == site::FeatureKind::Gate) {
      result->gateIds.push_back(f.id);
    } else if (f.kind == site::FeatureKind::Zone) {
      result->zoneIds.push_back(f.id);
    }
  }
  result->truthCounts = truthRun.counts;
  result->measuredCounts = measuredRun.counts;
  result->truthTotal = truthRun.total;
  result->measuredTotal = measuredRun.total;
  {
    std::map<CountKey, std::int64_t> byType;
    std::map<CountKey, std::int64_t> byCategory;  // the key's last member: the category
    std::map<std::pair<std::size_t, int>, std::int64_t> byDirection;
    const auto add = [&](const CountKey& key, std::int64_t n) {
      byType[key] += n;
      const auto type = static_cast<shape::VehicleType>(std::get<2>(key));
      byCategory[{std::get<0>(key), std::get<1>(key),
                  static_cast<std::size_t>(shape::categoryOf(type))}] += n;
      byDirection[{std::get<0>(key), std::get<1>(key)}] += n;
    };
    for (const auto& [key, n] : truthRun.counts) {
      add(key, -static_cast<std::int64_t>(n));
    }
    for (const auto& [key, n] : measuredRun.counts) {
      add(key, static_cast<std::int64_t>(n));
    }
    const auto cellError = [](const auto& cells) {
      std::uint64_t error = 0;
      for (const auto& [key, d] : cells) {
        error += static_cast<std::uint64_t>(std::llabs(d));
      }
      return error;
    };
    result->typeCellError = cellError(byType);
    result->categoryCellError = cellError(byCategory);
    result->directionCellError = cellError(byDirection);
  }

  // Turning movements: each true vehicle's nearest track over its frames.
  const double match2 = options.matchDistance_m * options.matchDistance_m;
  std::map<std::uint32_t, std::map<std::uint32_t, int>> votes;  // vehicle -> track -> frames
  for (std::size_t i = 0; i < frames.size(); ++i) {
    for (const tracking::TrackState& v : truth[i]) {
      if (truthRun.movements.count(v.id) == 0) {
        continue;
      }
      const tracking::TrackState* best = nullptr;
      double best2 = match2;
      for (const tracking::TrackState& t : measured[i]) {
        const double d2 = (t.centreEnu - v.centreEnu).squaredNorm();
        if (t.status != tracking::TrackStatus::Tentative && d2 <= best2) {
          best = &t;
          best2 = d2;
        }
      }
      if (best != nullptr) {
        ++votes[v.id][best->id];
      }
    }
  }
  for (const auto& [vehicle, movement] : truthRun.movements) {
    ++result->movementVehicles;
    const auto found = votes.find(vehicle);
    if (found == votes.end()) {
      ++result->movementUnmatched;
      continue;
    }
    const auto track =
        std::max_element(found->second.begin(), found->second.end(),
                         [](const auto& a, const auto& b) { return a.second < b.second; });
    const auto m = measuredRun.movements.find(track->first);
    if (m != measuredRun.movements.end() && m->second == movement) {
      ++result->movementAgreeing;
    }
  }

  // Queues: the queue zones (every zone when none has the role), period by period.
  std::vector<std::size_t> queueZones;
  std::size_t z = 0;
  for (const site::Feature& f : site.features()) {
    if (f.kind == site::FeatureKind::Zone) {
      if (f.role == site::ZoneRole::Queue) {
        queueZones.push_back(z);
      }
      ++z;
    }
  }
  if (queueZones.empty()) {
    for (std::size_t k = 0; k < z; ++k) {
      queueZones.push_back(k);
    }
  }
  const std::size_t periods = std::min(truthRun.periods.size(), measuredRun.periods.size());
  for (std::size_t p = 0; p < periods; ++p) {
    for (const std::size_t zone : queueZones) {
      const traffic::ZoneRecord& t = truthRun.periods[p].zones[zone];
      const traffic::ZoneRecord& m = measuredRun.periods[p].zones[zone];
      const double error = std::abs(static_cast<double>(m.maxQueue_vehicles) -
                                    static_cast<double>(t.maxQueue_vehicles));
      ++result->queuePeriods;
      result->queueAgreeing += error <= 1.0 ? 1 : 0;
      result->queueAbsError_vehicles += error;
      result->queueAbsError_m += std::abs(m.maxQueue_m - t.maxQueue_m);
      result->truthQueuedPeriods += t.maxQueue_vehicles > 0 ? 1 : 0;
    }
  }
  return true;
}

SequenceResult sumResults(const std::vector<SequenceResult>& results) {
  SequenceResult total;
  total.name = "total";
  for (const SequenceResult& r : results) {
    total.frames += r.frames;
    total.truthTotal += r.truthTotal;
    total.measuredTotal += r.measuredTotal;
    total.directionCellError += r.directionCellError;
    total.typeCellError += r.typeCellError;
    total.categoryCellError += r.categoryCellError;
    total.movementVehicles += r.movementVehicles;
    total.movementAgreeing += r.movementAgreeing;
    total.movementUnmatched += r.movementUnmatched;
    total.queuePeriods += r.queuePeriods;
    total.queueAgreeing += r.queueAgreeing;
    total.queueAbsError_vehicles += r.queueAbsError_vehicles;
    total.queueAbsError_m += r.queueAbsError_m;
    total.truthQueuedPeriods += r.truthQueuedPeriods;
  }
  return total;
}

Acceptance accept(const SequenceResult& r) {
  Acceptance a;
  if (r.truthTotal > 0) {
    a.countError =
        std::abs(static_cast<double>(r.measuredTotal) - static_cast<double>(r.truthTotal)) /
        static_cast<double>(r.truthTotal);
    a.directionError =
        static_cast<double>(r.directionCellError) / static_cast<double>(r.truthTotal);
    a.typeError = static_cast<double>(r.typeCellError) / static_cast<double>(r.truthTotal);
    a.categoryError = static_cast<double>(r.categoryCellError) / static_cast<double>(r.truthTotal);
  } else {
    a.countError = a.directionError = a.typeError = a.categoryError =
        r.measuredTotal > 0 ? 1.0 : 0.0;
  }
  if (r.movementVehicles > 0) {
    a.movementShare =
        static_cast<double>(r.movementAgreeing) / static_cast<double>(r.movementVehicles);
  }
  if (r.queuePeriods > 0) {
    a.queueShare = static_cast<double>(r.queueAgreeing) / static_cast<double>(r.queuePeriods);
  }
  a.countsPass = a.countError <= 0.02 && a.directionError <= 0.02 && a.typeError <= 0.02;
  a.movementsPass = a.movementShare >= 0.95;
  a.queuesPass = a.queueShare >= 0.90;
  return a;
}

void printResult(const SequenceResult& r, bool details, std::ostream& out) {
  const Acceptance a = accept(r);
  out << r.name << ": " << r.frames << " frames\n";
  if (details) {
    out << "  gate counts (gate direction type: truth measured)\n";
    std::map<CountKey, std::pair<std::uint64_t, std::uint64_t>> rows;
    for (const auto& [key, n] : r.truthCounts) {
      rows[key].first = n;
    }
    for (const auto& [key, n] : r.measuredCounts) {
      rows[key].second = n;
    }
    for (const auto& [key, n] : rows) {
      const auto& [gate, direction, type] = key;
      out << "    " << (gate < r.gateIds.size() ? r.gateIds[gate] : std::to_string(gate)) << " "
          << (direction == 0 ? "forward" : "backward") << " "
          << shape::toString(static_cast<shape::VehicleType>(type)) << ": " << n.first << " "
          << n.second << "\n";
    }
  }
  out << "  gate counts: truth " << r.truthTotal << ", measured " << r.measuredTotal
      << ", relative error of the totals " << percent(a.countError) << ", by gate and direction "
      << percent(a.directionError) << ", by gate, direction and type " << percent(a.typeError)
      << " (sum of |measured - truth| over the cells / truth; acceptance <= 2 % each): "
      << (a.countsPass ? "pass" : "FAIL") << "\n";
  out << "  gate counts by gate, direction and seed 002's category (car; transporter: large): "
      << percent(a.categoryError)
      << " (acceptance <= 2 %): " << (a.categoryError <= 0.02 ? "pass" : "FAIL") << "\n";
  out << "  turning movements: " << r.movementVehicles << " true vehicles crossed two gates, "
      << r.movementAgreeing << " matched tracks with the same origin -> destination ("
      << r.movementUnmatched << " without a track): " << percent(a.movementShare)
      << " (acceptance >= 95 %): " << (a.movementsPass ? "pass" : "FAIL") << "\n";
  const double n = std::max<double>(1.0, static_cast<double>(r.queuePeriods));
  out << "  queue length: " << r.queuePeriods << " zone-periods (" << r.truthQueuedPeriods
      << " with a true queue), " << r.queueAgreeing
      << " within 1 vehicle: " << percent(a.queueShare)
      << " (acceptance >= 90 %): " << (a.queuesPass ? "pass" : "FAIL") << "; mean |error| "
      << std::fixed << std::setprecision(2) << r.queueAbsError_vehicles / n << " vehicles, "
      << r.queueAbsError_m / n << " m\n";
  out << std::defaultfloat;
}

namespace {

constexpr const char* kUsage = R"(usage:
  vp_traffic_eval --sequence DIR --tracks FILE [--sequence DIR --tracks FILE ...] [options]

Runs the traffic analysis on the ground truth of each recorded sequence (perfect tracks) and on
the app's trajectory file of it, with the sequence's site file, and prints gate counts, turning
movements and queue lengths measured against truth (docs/traffic.md, "Evaluation").

  --sequence DIR        a recorded sequence with ground_truth/ and a site file (rig.yaml site.file)
  --tracks FILE         the app's trajectory file of the sequence (--trajectory-csv)
  --site FILE           a site file for every sequence instead of their own
  --config FILE         take the traffic: section of this app configuration
  --period S            statistics period for the queue comparison, s (default 10)
  --match-distance M    a track matches a true vehicle within M m (default 3)
  --details             the gate count tables per sequence
  --require-acceptance  exit status 3 when a total misses its acceptance threshold
)";

bool number(const std::string& text, double* value) {
  try {
    std::size_t used = 0;
    *value = std::stod(text, &used);
    return used == text.size() && std::isfinite(*value);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

int runTrafficEval(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  EvalOptions options;
  std::vector<SequenceInput> inputs;
  bool details = false;
  bool require = false;
  std::string configFile;
  std::optional<double> period_s;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    const auto value = [&]() -> const std::string* {
      if (i + 1 >= args.size()) {
        err << "vp_traffic_eval: " << arg << " needs a value\n" << kUsage;
        return nullptr;
      }
      return &args[++i];
    };
    if (arg == "-h" || arg == "--help") {
      out << kUsage;
      return 0;
    } else if (arg == "--details") {
      details = true;
    } else if (arg == "--require-acceptance") {
      require = true;
    } else if (arg == "--sequence" || arg == "--tracks" || arg == "--site" || arg == "--config" ||
               arg == "--period" || arg == "--match-distance") {
      const std::string* v = value();
      if (v == nullptr) {
        return 2;
      }
      if (arg == "--sequence") {
        inputs.push_back({*v, ""});
      } else if (arg == "--tracks") {
        if (inputs.empty() || !inputs.back().tracksFile.empty()) {
          err << "vp_traffic_eval: --tracks " << *v << " must follow its --sequence\n";
          return 2;
        }
        inputs.back().tracksFile = *v;
      } else if (arg == "--site") {
        options.siteFile = *v;
      } else if (arg == "--config") {
        configFile = *v;
      } else {
        double x = 0.0;
        if (!number(*v, &x) || x <= 0.0) {
          err << "vp_traffic_eval: " << arg << " must be a positive number, got '" << *v << "'\n";
          return 2;
        }
        if (arg == "--period") {
          period_s = x;
        } else {
          options.matchDistance_m = x;
        }
      }
    } else {
      err << "vp_traffic_eval: unknown argument '" << arg << "'\n" << kUsage;
      return 2;
    }
  }
  if (inputs.empty()) {
    err << "vp_traffic_eval: give at least one --sequence DIR --tracks FILE\n" << kUsage;
    return 2;
  }
  for (const SequenceInput& input : inputs) {
    if (input.tracksFile.empty()) {
      err << "vp_traffic_eval: --sequence " << input.sequenceDir << " has no --tracks FILE\n";
      return 2;
    }
  }
  if (!configFile.empty()) {
    try {
      options.analyzer = config::loadConfig(configFile).traffic;
      options.analyzer.period_s = 10.0;
    } catch (const std::exception& e) {
      err << "vp_traffic_eval: " << e.what() << "\n";
      return 1;
    }
  }
  if (period_s) {
    options.analyzer.period_s = *period_s;
  }
  options.analyzer.enabled = true;
  std::vector<SequenceResult> results;
  for (const SequenceInput& input : inputs) {
    SequenceResult result;
    std::string why;
    if (!evaluateSequence(input, options, &result, &why)) {
      err << "vp_traffic_eval: " << why << "\n";
      return 1;
    }
    printResult(result, details, out);
    results.push_back(std::move(result));
  }
  const SequenceResult total = sumResults(results);
  if (results.size() > 1) {
    printResult(total, false, out);
  }
  return require && !accept(total).pass() ? 3 : 0;
}

}  // namespace vp::traffic_eval
