// vp_rsu_subscriber: the roadside-unit side of the DDS interface. Subscribes to the vehicle
// states, drone status and occupancy grid of the perception drones, prints every state (and
// every disposed track) as a CSV row or a JSON line, measures the latency from the frame
// capture time (DDS source timestamp) to reception, and periodically draws a bird's-eye PNG.
// It also reports the vehicle-state reader's QoS events: a track whose deadline passed without
// a state, and a drone whose writer lost its liveliness or left (qos_events.hpp). It receives
// the traffic analysis' outputs too (traffic_board.hpp): each period's gate counts and each
// event are printed on stderr, and the bird's-eye view draws the site map (--site) with the
// gates' totals and the last events.
#include <dds/dds.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bev_view.hpp"
#include "config/config.hpp"
#include "platform/dds/conversion.hpp"
#include "platform/dds/dds_handles.hpp"
#include "platform/dds/traffic_publisher.hpp"
#include "qos_events.hpp"
#include "site/site.hpp"
#include "state_format.hpp"
#include "traffic_board.hpp"

namespace {

namespace dds = vp::platform::dds;
namespace msg = vp::messages;

std::atomic<bool> gStop{false};
void onSignal(int) {
  gStop = true;
}

struct Options {
  std::string configPath;
  std::optional<std::uint32_t> domainId;
  std::optional<std::string> partition;
  std::optional<std::string> topicPrefix;
  bool json = false;
  std::string outPath;  // empty = stdout
  std::string bevPath;
  double bevPeriod_s = 1.0;
  vp::rsu::BevSettings bev{};
  double duration_s = 0.0;     // 0 = until interrupted
  long long maxEvents = 0;     // 0 = unlimited
  double statsPeriod_s = 0.0;  // 0 = only at exit
  bool untilWritersGone = false;
  std::string sitePath;                              // --site: drawn in the bird's-eye view
  std::optional<vp::geodesy::GeodeticPoint> origin;  // --origin: the drones' world origin
};

void printHelp() {
  std::cout <<
      R"(vp_rsu_subscriber: receive vehicle states from perception drones over DDS.

Usage: vp_rsu_subscriber [options]

  --config FILE         YAML file with a `dds:` section (domain, partition, QoS, security;
                        other sections are ignored); see docs/configuration.md and docs/dds.md.
                        Without it the defaults are used.
  --domain N            DDS domain id (overrides the file), 0..232
  --partition NAME      DDS partition (overrides the file)
  --topic-prefix P      topic prefix (default vp: vp/vehicle_state, vp/drone_status, vp/occupancy)
  --format csv|json     output format of the state events (default csv, with a header row)
  --out FILE            write the events to FILE instead of stdout
  --bev-png FILE        draw a bird's-eye view of the current tracks into FILE periodically
  --bev-period-s S      period of the bird's-eye view (default 1)
  --bev-range-m M       half-width of the view in metres (default 60)
  --bev-centre E,N      centre of the view in world ENU metres (default 0,0)
  --duration-s S        stop after S seconds (default: run until Ctrl-C)
  --max-events N        stop after N events (states + disposals)
  --stats-period-s S    print latency statistics to stderr every S seconds (always at exit)
  --until-writers-gone  stop once every vehicle-state writer seen has left (end of a replay)
  --site FILE           the site map (site.geojson, docs/site_map.md) the drones analyse:
                        drawn in the bird's-eye view (areas, lanes, gates with their ids and
                        counts, zones)
  --origin LAT,LON,H    the drones' world ENU origin (WGS84 degrees, ellipsoidal metres), to
                        place the site; default: taken from the first vehicle state or
                        traffic event received (each gives a point in both frames)
  --help                this text

Each event is one row: event (state|disposed), drone_id, track_id, measurement_time_ns,
latency_ms (reception - capture time; needs synchronised clocks), then every field of the
state with its unit in the column name. QoS events are rows too, with only the first five
columns: deadline_missed (a track got no state within dds.qos.vehicle_state.deadline_s; once
per silence of the track), writer_alive and writer_lost (a drone's writer matched or regained
its liveliness / its liveliness lease expired or it left); measurement_time_ns is then the
newest state of that track or drone and latency_ms the time since it. They are also reported
as a line on stderr.

Traffic (docs/traffic.md): the statistics of each period (<prefix>/traffic_statistics) are
printed on stderr as one line, "traffic: drone D period P [start, end) ns: gate G forward F
backward B (total F/B); ...; movements A->B N; ...", each event (<prefix>/traffic_events) as
"traffic event: drone D KIND track T FEATURE ...", and the totals of every gate at exit. The network is configured as usual for Cyclone DDS
(CYCLONEDDS_URI). Exit status: 0 on success, 2 on a usage error, 1 on a DDS error.
)";
}

[[noreturn]] void usageError(const std::string& message) {
  std::cerr << "vp_rsu_subscriber: " << message << " (see --help)\n";
  std::exit(2);
}

double parseNumber(const std::string& option, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(value) || value < 0) {
    usageError(option + ": expected a non-negative number, got '" + text + "'");
  }
  return value;
}

Options parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      printHelp();
      std::exit(0);
    }
    if (arg == "--until-writers-gone") {
      o.untilWritersGone = true;
      continue;
    }
    if (i + 1 >= argc) {
      usageError(arg.rfind("--", 0) == 0 ? arg + ": missing value"
                                         : "unknown argument '" + arg + "'");
    }
    const char* value = argv[++i];
    if (arg == "--config") {
      o.configPath = value;
    } else if (arg == "--domain") {
      const double d = parseNumber(arg, value);
      if (d > 232 || d != std::floor(d)) {
        usageError("--domain: expected an integer in [0, 232], got '" + std::string(value) + "'");
      }
      o.domainId = static_cast<std::uint32_t>(d);
    } else if (arg == "--partition") {
      o.partition = value;
    } else if (arg == "--topic-prefix") {
      o.topicPrefix = value;
    } else if (arg == "--format") {
      const std::string f = value;
      if (f != "csv" && f != "json") {
        usageError("--format: expected csv or json, got '" + f + "'");
      }
      o.json = f == "json";
    } else if (arg == "--out") {
      o.outPath = value;
    } else if (arg == "--bev-png") {
      o.bevPath = value;
    } else if (arg == "--bev-period-s") {
      o.bevPeriod_s = parseNumber(arg, value);
    } else if (arg == "--bev-range-m") {
      o.bev.range_m = parseNumber(arg, value);
      if (o.bev.range_m <= 0) {
        usageError("--bev-range-m: must be > 0");
      }
    } else if (arg == "--bev-centre") {
      if (std::sscanf(value, "%lf,%lf", &o.bev.centreEast_m, &o.bev.centreNorth_m) != 2) {
        usageError("--bev-centre: expected E,N in metres, got '" + std::string(value) + "'");
      }
    } else if (arg == "--duration-s") {
      o.duration_s = parseNumber(arg, value);
    } else if (arg == "--max-events") {
      o.maxEvents = static_cast<long long>(parseNumber(arg, value));
    } else if (arg == "--site") {
      o.sitePath = value;
    } else if (arg == "--origin") {
      vp::geodesy::GeodeticPoint p;
      if (std::sscanf(value, "%lf,%lf,%lf", &p.latitude_deg, &p.longitude_deg, &p.height_m) != 3 ||
          !(std::abs(p.latitude_deg) <= 90.0) || !(std::abs(p.longitude_deg) <= 180.0)) {
        usageError("--origin: expected LAT,LON,H (degrees, degrees, metres), got '" +
                   std::string(value) + "'");
      }
      o.origin = p;
    } else if (arg == "--stats-period-s") {
      o.statsPeriod_s = parseNumber(arg, value);
    } else {
      usageError("unknown option '" + arg + "'");
    }
  }
  return o;
}

int fail(const dds::DdsResult& result, const char* what) {
  std::cerr << "vp_rsu_subscriber: " << what << ": " << dds::describe(result) << "\n";
  return 1;
}

double latency_ms(const dds_sample_info_t& info) {
  return static_cast<double>(dds_time() - info.source_timestamp) * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parseOptions(argc, argv);
  vp::config::DdsConfig config;
  if (!options.configPath.empty()) {
    try {
      // Only the dds: section is read: an RSU has no camera or terrain of its own.
      vp::config::DdsSection loaded = vp::config::loadDdsSection(options.configPath);
      for (const std::string& warning : loaded.warnings) {
        std::cerr << "vp_rsu_subscriber: warning: " << warning << "\n";
      }
      config = loaded.dds;
    } catch (const vp::config::ConfigError& e) {
      std::cerr << "vp_rsu_subscriber: " << e.what() << "\n";
      return 2;
    }
  }
  config.domainId = options.domainId.value_or(config.domainId);
  config.partition = options.partition.value_or(config.partition);
  config.topicPrefix = options.topicPrefix.value_or(config.topicPrefix);

  std::ofstream file;
  if (!options.outPath.empty()) {
    file.open(options.outPath);
    if (!file) {
      std::cerr << "vp_rsu_subscriber: " << options.outPath << ": cannot open for writing\n";
      return 2;
    }
  }
  std::ostream& out = options.outPath.empty() ? std::cout : file;

  // The site map: checked now (a bad file is a usage error), placed once the origin is known.
  vp::site::Site site;
  bool sitePlaced = false;
  const auto placeSite = [&](const vp::geodesy::GeodeticPoint& origin, const char* from) {
    std::string why;
    if (!vp::site::loadSite(options.sitePath, vp::geodesy::LocalFrame(origin), &site, &why)) {
      std::cerr << "vp_rsu_subscriber: --site: " << why << "\n";
      return false;
    }
    sitePlaced = true;
    std::cerr << "vp_rsu_subscriber: site " << options.sitePath << " (" << site.features().size()
              << " features) placed at the origin " << origin.latitude_deg << ", "
              << origin.longitude_deg << " (" << from << ")\n";
    return true;
  };
  if (!options.sitePath.empty()) {
    if (options.origin) {
      if (!placeSite(*options.origin, "--origin")) {
        return 2;
      }
    } else {
      vp::site::Site check;
      std::string why;
      if (!vp::site::loadSite(options.sitePath, vp::geodesy::LocalFrame(), &check, &why)) {
        std::cerr << "vp_rsu_subscriber: --site: " << why << "\n";
        return 2;
      }
    }
  }

  // Declared before the participant: the reader's listener calls into it until the reader is
  // deleted with the participant.
  vp::rsu::QosEventMonitor qosEvents;
  dds::Participant participant;
  dds::Topic stateTopic;
  dds::Topic statusTopic;
  dds::Topic gridTopic;
  dds::Reader stateReader;
  dds::Reader statusReader;
  dds::Reader gridReader;
  dds::Topic trafficStatisticsTopic;
  dds::Topic trafficEventsTopic;
  dds::Reader trafficStatisticsReader;
  dds::Reader trafficEventsReader;
  if (auto r = participant.open(config); !r.ok()) {
    return fail(r, "cannot create the DDS participant (domain, CYCLONEDDS_URI, security files?)");
  }
  if (auto r = stateTopic.open(participant, vp_msg_VehicleState_desc,
                               dds::vehicleStateTopicName(config), config.vehicleState);
      !r.ok()) {
    return fail(r, "vehicle state topic");
  }
  if (auto r = statusTopic.open(participant, vp_msg_DroneStatus_desc,
                                dds::droneStatusTopicName(config), config.droneStatus);
      !r.ok()) {
    return fail(r, "drone status topic");
  }
  if (auto r = gridTopic.open(participant, vp_msg_OccupancyGrid_desc,
                              dds::occupancyTopicName(config), config.occupancy);
      !r.ok()) {
    return fail(r, "occupancy topic");
  }
  if (auto r = trafficStatisticsTopic.open(participant, vp_msg_TrafficStatistics_desc,
                                           dds::trafficStatisticsTopicName(config),
                                           config.trafficStatistics);
      !r.ok()) {
    return fail(r, "traffic statistics topic");
  }
  if (auto r = trafficEventsTopic.open(participant, vp_msg_TrafficEvent_desc,
                                       dds::trafficEventsTopicName(config), config.trafficEvents);
      !r.ok()) {
    return fail(r, "traffic events topic");
  }
  const dds_entity_t waitset = dds_create_waitset(participant.get());
  if (waitset < 0) {
    return fail(dds::DdsResult::failure("dds_create_waitset", waitset), "waitset");
  }
  if (auto r = qosEvents.open(participant.get(), waitset); !r.ok()) {
    return fail(r, "QoS event listener");
  }
  if (auto r = stateReader.open(participant, stateTopic, config.vehicleState, config.partition,
                                qosEvents.listener());
      !r.ok()) {
    return fail(r, "vehicle state reader");
  }
  if (auto r = statusReader.open(participant, statusTopic, config.droneStatus, config.partition);
      !r.ok()) {
    return fail(r, "drone status reader");
  }
  if (auto r = gridReader.open(participant, gridTopic, config.occupancy, config.partition);
      !r.ok()) {
    return fail(r, "occupancy reader");
  }

  if (auto r = trafficStatisticsReader.open(participant, trafficStatisticsTopic,
                                            config.trafficStatistics, config.partition);
      !r.ok()) {
    return fail(r, "traffic statistics reader");
  }
  if (auto r = trafficEventsReader.open(participant, trafficEventsTopic, config.trafficEvents,
                                        config.partition);
      !r.ok()) {
    return fail(r, "traffic events reader");
  }

  for (const dds_entity_t reader : {stateReader.get(), statusReader.get(), gridReader.get(),
                                    trafficStatisticsReader.get(), trafficEventsReader.get()}) {
    const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
    if (condition < 0) {
      return fail(dds::DdsResult::failure("dds_create_readcondition", condition), "read condition");
    }
    if (const dds_return_t rc = dds_waitset_attach(waitset, condition, reader); rc < 0) {
      return fail(dds::DdsResult::failure("dds_waitset_attach", rc), "waitset");
    }
  }

  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::cerr << "vp_rsu_subscriber: domain " << config.domainId << ", partition '"
            << config.partition << "', topics " << dds::vehicleStateTopicName(config) << ", "
            << dds::droneStatusTopicName(config) << ", " << dds::occupancyTopicName(config) << ", "
            << dds::trafficStatisticsTopicName(config) << ", "
            << dds::trafficEventsTopicName(config) << "\n";
  if (!options.json) {
    out << vp::rsu::csvHeader() << "\n" << std::flush;
  }

  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  Clock::time_point nextBev = start;
  Clock::time_point nextStats = start + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(options.statsPeriod_s));
  vp::rsu::LatencyStats latency;
  std::map<std::pair<std::uint32_t, std::uint32_t>, msg::VehicleState> tracks;
  msg::OccupancyGrid lastGrid;
  std::set<std::pair<std::uint32_t, std::uint32_t>> disposed;
  vp::rsu::TrafficBoard traffic;
  long long events = 0;
  const std::size_t csvColumns =
      static_cast<std::size_t>(
          std::count(vp::rsu::csvHeader().begin(), vp::rsu::csvHeader().end(), ',')) +
      1;
  std::vector<std::string> qosErrors;
  const auto drawBev = [&](std::string* why) {
    std::vector<msg::VehicleState> current;
    for (const auto& entry : tracks) {
      current.push_back(entry.second);
    }
    vp::rsu::BevOverlay overlay;
    overlay.site = sitePlaced ? &site : nullptr;
    traffic.fillOverlay(overlay);
    return vp::rsu::writeBev(options.bev, current, lastGrid.cells.empty() ? nullptr : &lastGrid,
                             options.bevPath, why, &overlay);
  };
  constexpr int kBatch = 64;
  void* samples[kBatch];
  dds_sample_info_t infos[kBatch];

  while (!gStop) {
    const Clock::time_point now = Clock::now();
    if (options.duration_s > 0 &&
        now - start >= std::chrono::duration<double>(options.duration_s)) {
      break;
    }
    if (options.maxEvents > 0 && events >= options.maxEvents) {
      break;
    }
    if (options.untilWritersGone) {
      dds_subscription_matched_status_t matched{};
      if (dds_get_subscription_matched_status(stateReader.get(), &matched) >= 0 &&
          matched.total_count > 0 && matched.current_count == 0) {
        // The last writer left: drain what it sent before leaving, then stop.
        gStop = true;
      }
    }
    if (const dds_return_t rc = dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(100)); rc < 0) {
      return fail(dds::DdsResult::failure("dds_waitset_wait", rc), "waiting for data");
    }
    // Vehicle states (loaned samples: Cyclone owns the memory until dds_return_loan).
    samples[0] = nullptr;
    dds_return_t n = dds_take(stateReader.get(), samples, infos, kBatch, kBatch);
    if (n < 0) {
      return fail(dds::DdsResult::failure("dds_take", n), "vehicle states");
    }
    for (int k = 0; k < n; ++k) {
      const auto& sample = *static_cast<const vp_msg_VehicleState*>(samples[k]);
      const double ms = latency_ms(infos[k]);
      msg::VehicleState state = dds::fromSample(sample);  // key fields are valid for disposals
      if (!options.sitePath.empty() && !sitePlaced && infos[k].valid_data &&
          !placeSite(vp::rsu::originFrom(state.position, state.enu_m.data()),
                     "from a vehicle state")) {
        return 2;
      }
      const auto key = std::make_pair(state.droneId, state.trackId);
      qosEvents.noteSample(infos[k], state.droneId, state.trackId, state.measurementTime_ns);
      if (infos[k].valid_data) {
        latency.add(ms);
        tracks[key] = state;
        disposed.erase(key);
        out << (options.json ? vp::rsu::formatJson(vp::rsu::EventKind::State, state, ms)
                             : vp::rsu::formatCsv(vp::rsu::EventKind::State, state, ms))
            << "\n";
        ++events;
      }
      // A disposal comes as its own invalid sample, or as the instance state of the track's
      // last (still unread) state: reported once either way.
      if (infos[k].instance_state == DDS_IST_NOT_ALIVE_DISPOSED && disposed.insert(key).second) {
        tracks.erase(key);
        out << (options.json ? vp::rsu::formatJson(vp::rsu::EventKind::Disposed, state, ms)
                             : vp::rsu::formatCsv(vp::rsu::EventKind::Disposed, state, ms))
            << "\n";
        ++events;
      } else if (infos[k].instance_state == DDS_IST_NOT_ALIVE_NO_WRITERS) {
        tracks.erase(key);  // unregistered without dispose: the writer is gone
      }
    }
    if (n > 0) {
      out.flush();
      dds_return_loan(stateReader.get(), samples, n);
    }
    // QoS events queued by the listener (after the states: an instance's newest state is known).
    const std::vector<vp::rsu::QosEventRow> qosRows =
        qosEvents.drain(stateReader.get(), &qosErrors);
    for (const vp::rsu::QosEventRow& row : qosRows) {
      std::cerr << "vp_rsu_subscriber: " << vp::rsu::describe(row) << "\n";
      out << (options.json ? vp::rsu::formatJson(row) : vp::rsu::formatCsv(row, csvColumns))
          << "\n";
      ++events;
    }
    if (!qosRows.empty()) {
      out.flush();
    }
    for (const std::string& error : qosErrors) {
      std::cerr << "vp_rsu_subscriber: QoS events: " << error << "\n";
    }
    qosErrors.clear();
    // Drone status: reported on stderr, it is not part of the event stream.
    samples[0] = nullptr;
    n = dds_take(statusReader.get(), samples, infos, kBatch, kBatch);
    for (int k = 0; k < n; ++k) {
      if (infos[k].valid_data) {
        const msg::DroneStatus s =
            dds::fromSample(*static_cast<const vp_msg_DroneStatus*>(samples[k]));
        std::cerr << "vp_rsu_subscriber: drone " << s.droneId << " model '" << s.modelId.data()
                  << "' " << s.frameRate_hz << " Hz, latency median " << s.latencyMedian_ms
                  << " ms, frames " << s.framesProcessed << ", dropped " << s.framesDropped
                  << ", tracks " << s.activeTracks << "\n";
      }
    }
    if (n > 0) {
      dds_return_loan(statusReader.get(), samples, n);
    }
    samples[0] = nullptr;
    n = dds_take(gridReader.get(), samples, infos, kBatch, kBatch);
    for (int k = 0; k < n; ++k) {
      if (infos[k].valid_data) {
        dds::fromSample(*static_cast<const vp_msg_OccupancyGrid*>(samples[k]), lastGrid);
      }
    }
    if (n > 0) {
      dds_return_loan(gridReader.get(), samples, n);
    }

    // Traffic: each period's counts and each event as a line on stderr.
    samples[0] = nullptr;
    n = dds_take(trafficStatisticsReader.get(), samples, infos, kBatch, kBatch);
    for (int k = 0; k < n; ++k) {
      if (infos[k].valid_data) {
        const auto& statistics = *static_cast<const vp_msg_TrafficStatistics*>(samples[k]);
        if (traffic.addStatistics(statistics)) {
          std::cerr << "vp_rsu_subscriber: " << traffic.periodLine(statistics) << "\n";
        }
      }
    }
    if (n > 0) {
      dds_return_loan(trafficStatisticsReader.get(), samples, n);
    }
    samples[0] = nullptr;
    n = dds_take(trafficEventsReader.get(), samples, infos, kBatch, kBatch);
    for (int k = 0; k < n; ++k) {
      if (infos[k].valid_data) {
        const auto& event = *static_cast<const vp_msg_TrafficEvent*>(samples[k]);
        if (!options.sitePath.empty() && !sitePlaced) {
          const vp::geodesy::GeodeticPoint position{event.position.latitude_deg,
                                                    event.position.longitude_deg, 0.0};
          const double enu[3] = {event.enu_m[0], event.enu_m[1], 0.0};
          if (!placeSite(vp::rsu::originFrom(position, enu), "from a traffic event")) {
            return 2;
          }
        }
        traffic.addEvent(event);
        std::cerr << "vp_rsu_subscriber: " << vp::rsu::TrafficBoard::eventLine(event) << "\n";
      }
    }
    if (n > 0) {
      dds_return_loan(trafficEventsReader.get(), samples, n);
    }

    if (!options.bevPath.empty() && (Clock::now() >= nextBev || gStop)) {
      std::string why;
      if (!drawBev(&why)) {
        std::cerr << "vp_rsu_subscriber: bird's-eye view: " << why << "\n";
      }
      nextBev = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(options.bevPeriod_s));
    }
    if (options.statsPeriod_s > 0 && Clock::now() >= nextStats) {
      std::cerr << "vp_rsu_subscriber: latency " << latency.summary() << ", " << tracks.size()
                << " live tracks\n";
      nextStats = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(options.statsPeriod_s));
    }
  }
  if (traffic.periods() > 0 || traffic.events() > 0) {
    std::cerr << "vp_rsu_subscriber: traffic totals: " << traffic.periods() << " periods, "
              << traffic.events() << " events";
    for (const auto& [gate, total] : traffic.totals()) {
      std::cerr << "; gate " << gate << " forward " << total.first << " backward " << total.second;
    }
    std::cerr << "\n";
  }
  std::cerr << "vp_rsu_subscriber: " << events << " events, latency " << latency.summary() << "\n";
  return 0;
}
