#include "traffic/traffic_analyzer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "traffic/track_slots.hpp"

namespace vp::traffic {

namespace {

constexpr double kNsPerS = 1e9;

std::int64_t toNs(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * kNsPerS));
}

bool published(const tracking::TrackState& track) {
  return track.status != tracking::TrackStatus::Tentative;
}

// |a - b| folded into [0, pi].
double angleBetween(double a_rad, double b_rad) {
  return std::abs(std::remainder(a_rad - b_rad, 2.0 * std::numbers::pi));
}

bool inRange(double value, double low, double high) {
  return std::isfinite(value) && value >= low && value <= high;
}

}  // namespace

bool TrafficAnalyzer::init(const site::Site& site, const TrafficAnalyzerOptions& options,
                           std::string* why) {
  const auto fail = [why](const std::string& problem) {
    if (why != nullptr) {
      *why = problem;
    }
    return false;
  };
  active_ = false;  // until the site and the options are accepted
  const auto range = [&fail](const char* key, double value, const char* interval) {
    return fail(std::string("traffic.") + key + " must be in " + interval + ", got " +
                std::to_string(value));
  };
  if (!inRange(options.period_s, 1.0, 86400.0)) {
    return range("period_s", options.period_s, "[1, 86400]");
  }
  if (!inRange(options.stopSpeed_mps, 0.0, 10.0)) {
    return range("stop_speed_mps", options.stopSpeed_mps, "[0, 10]");
  }
  if (!inRange(options.laneHeadingTolerance_deg, 0.0, 90.0) ||
      options.laneHeadingTolerance_deg == 0.0) {
    return range("lane_heading_tolerance_deg", options.laneHeadingTolerance_deg, "(0, 90]");
  }
  if (!inRange(options.wrongWayAngle_deg, 90.0, 179.0)) {
    return range("wrong_way_angle_deg", options.wrongWayAngle_deg, "[90, 179]");
  }
  if (!inRange(options.wrongWaySpeed_mps, 0.0, 50.0)) {
    return range("wrong_way_speed_mps", options.wrongWaySpeed_mps, "[0, 50]");
  }
  if (!inRange(options.wrongWay_s, 0.0, 60.0)) {
    return range("wrong_way_s", options.wrongWay_s, "[0, 60]");
  }
  if (!inRange(options.boxJunctionStop_s, 0.0, 600.0)) {
    return range("box_junction_stop_s", options.boxJunctionStop_s, "[0, 600]");
  }
  const auto count = [&fail](const char* key, std::size_t value) {
    if (value < 1 || value > 65536) {
      return fail(std::string("traffic.") + key + " must be in [1, 65536], got " +
                  std::to_string(value));
    }
    return true;
  };
  if (!count("max_tracks", options.maxTracks) ||
      !count("max_events_per_step", options.maxEventsPerStep) ||
      !count("max_lane_samples", options.maxLaneSamples)) {
    return false;
  }

  const std::string source = site.sourceName().empty() ? "site" : site.sourceName();
  const std::size_t gates = site.count(site::FeatureKind::Gate);
  const std::size_t zones = site.count(site::FeatureKind::Zone);
  const std::size_t lanes = site.count(site::FeatureKind::Lane);
  if (gates > kMaxReportGates || zones > kMaxReportZones || lanes > kMaxReportLanes) {
    return fail(source + ": " + std::to_string(gates) + " gates, " + std::to_string(zones) +
                " zones, " + std::to_string(lanes) + " lanes: the traffic analysis takes at most " +
                std::to_string(kMaxReportGates) + ", " + std::to_string(kMaxReportZones) + " and " +
                std::to_string(kMaxReportLanes));
  }

  options_ = options;
  site_ = site;
  gateCount_ = zoneCount_ = laneCount_ = 0;
  std::vector<Gate> counterGates;
  for (const site::Feature& feature : site_.features()) {
    const std::span<const Eigen::Vector2d> v = site_.vertices(feature);
    const std::string name = source + ": " + toString(feature.kind) + " \"" + feature.id + "\"";
    if (feature.kind == site::FeatureKind::Gate) {
      // A gate drawn with more positions counts along the chord of its ends.
      const Gate gate{static_cast<std::uint32_t>(gateCount_), v.front(), v.back()};
      if (!((gate.second_m - gate.first_m).norm() >= kMinGateLength_m)) {
        return fail(name + ": its ends are less than " + std::to_string(kMinGateLength_m) +
                    " m apart");
      }
      counterGates.push_back(gate);
      gates_[gateCount_++] = &feature;
    } else if (feature.kind == site::FeatureKind::Lane) {
      LaneGeometry& g = laneGeometry_[laneCount_];
      g = LaneGeometry{};
      g.halfWidth_m = 0.5 * feature.width_m;
      if (!(feature.width_m > 0.0)) {
        return fail(name + ": width_m must be > 0");
      }
      g.length_m = site_.laneLength_m(feature);
      if (g.length_m == 0.0) {
        return fail(name + ": the lane has no length");
      }
      lanes_[laneCount_++] = &feature;
    }
  }
  for (const site::Feature& feature : site_.features()) {
    if (feature.kind != site::FeatureKind::Zone) {
      continue;
    }
    const std::size_t z = zoneCount_++;
    zones_[z] = &feature;
    zoneBox_[z] = feature.role == site::ZoneRole::BoxJunction;
    zoneLane_[z] = -1;
    if (!feature.lane.empty()) {
      for (std::size_t l = 0; l < laneCount_; ++l) {
        if (lanes_[l]->id == feature.lane) {
          zoneLane_[z] = static_cast<std::int16_t>(l);
        }
      }
      if (zoneLane_[z] < 0) {
        return fail(source + ": zone \"" + feature.id + "\": lane \"" + feature.lane +
                    "\" is not a lane of the site");
      }
    }
  }
  std::string counterWhy;
  if (!counter_.init(
          counterGates,
          {.maxTracks = options.maxTracks, .maxCrossingsPerStep = options.maxEventsPerStep},
          &counterWhy)) {
    return fail(source + ": " + counterWhy);
  }

  Slot empty;
  empty.stopSince_ns.fill(-1);
  slots_.assign(options.maxTracks, empty);
  laneAcc_.assign(options.maxTracks * laneCount_, LaneAccumulator{});
  laneSamples_.assign(options.maxLaneSamples * laneCount_, 0.0);
  laneSampleCount_ = {};
  zoneAcc_ = {};
  events_.assign(options.maxEventsPerStep, TrafficEvent{});
  eventCount_ = 0;
  active_ = options.enabled && (gateCount_ + zoneCount_ + laneCount_) > 0;
  started_ = false;
  haveTime_ = false;
  completed_ = false;
  periods_ = 0;
  period_ns_ = toNs(options.period_s);
  closed_ = {};
  stats_ = {};
  movements_ = {};
  countsAtStart_ = {};
  wrongWay_ = boxStops_ = 0;
  return true;
}

TrafficAnalyzer::LanePlace TrafficAnalyzer::placeOnLane(std::size_t lane,
                                                        const Eigen::Vector2d& point_m) const {
  if (lane >= laneCount_) {
    LanePlace none;
    none.distance_m = std::numeric_limits<double>::infinity();
    return none;
  }
  return site_.placeOnLane(*lanes_[lane], point_m);
}

double TrafficAnalyzer::laneLength_m(std::size_t lane) const {
  return lane < laneCount_ ? laneGeometry_[lane].length_m : 0.0;
}

TrafficAnalyzer::Slot* TrafficAnalyzer::find(std::uint32_t trackId) {
  return findTrackSlot(std::span<Slot>(slots_), trackId);
}

TrafficAnalyzer::Slot* TrafficAnalyzer::claim(std::uint32_t trackId) {
  return claimTrackSlot(std::span<Slot>(slots_), trackId);  // released slots are empty
}

void TrafficAnalyzer::emit(const TrafficEvent& event) {
  if (eventCount_ < events_.size()) {
    events_[eventCount_++] = event;
  } else {
    ++stats_.eventsDropped;
  }
}

void TrafficAnalyzer::endDwell(Slot& slot, std::size_t zone, std::int64_t time_ns) {
  const double dwell_s =
      static_cast<double>(std::max<std::int64_t>(0, time_ns - slot.stopSince_ns[zone])) / kNsPerS;
  ZoneAccumulator& z = zoneAcc_[zone];
  ++z.dwellCount;
  z.dwellSum_s += dwell_s;
  z.dwellMax_s = std::max(z.dwellMax_s, dwell_s);
  slot.stopSince_ns[zone] = -1;
}

void TrafficAnalyzer::flushLaneSamples(std::size_t slotIndex) {
  for (std::size_t l = 0; l < laneCount_; ++l) {
    LaneAccumulator& acc = laneAcc_[slotIndex * laneCount_ + l];
    if (acc.samples == 0) {
      continue;
    }
    if (laneSampleCount_[l] < options_.maxLaneSamples) {
      laneSamples_[l * options_.maxLaneSamples + laneSampleCount_[l]++] =
          acc.speedSum_mps / acc.samples;
    } else {
      ++stats_.samplesDropped;
    }
    acc.speedSum_mps = 0.0;
    acc.samples = 0;
  }
}

void TrafficAnalyzer::endTrack(std::size_t slotIndex, std::int64_t time_ns, bool emitMovement) {
  Slot& slot = slots_[slotIndex];
  for (std::size_t z = 0; z < zoneCount_; ++z) {
    if (slot.stopSince_ns[z] >= 0) {
      endDwell(slot, z, slot.lastTime_ns);
    }
  }
  flushLaneSamples(slotIndex);
  if (slot.crossings >= 2 && slot.firstGate >= 0 && slot.lastGate >= 0) {
    ++movements_[static_cast<std::size_t>(slot.firstGate)][static_cast<std::size_t>(slot.lastGate)];
    if (emitMovement) {
      TrafficEvent event;
      event.kind = TrafficEventKind::TurningMovement;
      event.time_ns = time_ns;
      event.trackId = slot.trackId;
      event.featureIndex = static_cast<std::uint32_t>(slot.firstGate);
      event.toFeatureIndex = static_cast<std::uint32_t>(slot.lastGate);
      event.type = slot.type;
      event.speed_mps = slot.speed_mps;
      event.positionEnu_m = slot.last_m;
      emit(event);
    }
  }
  for (std::size_t l = 0; l < laneCount_; ++l) {
    laneAcc_[slotIndex * laneCount_ + l] = LaneAccumulator{};
  }
  Slot empty;
  empty.stopSince_ns.fill(-1);
  slot = empty;
}

void TrafficAnalyzer::integrateZones(std::int64_t until_ns) {
  if (until_ns <= integratedUntil_ns_) {
    return;
  }
  const double dt_s = static_cast<double>(until_ns - integratedUntil_ns_) / kNsPerS;
  for (std::size_t z = 0; z < zoneCount_; ++z) {
    zoneAcc_[z].vehicleTime_s += zoneAcc_[z].now * dt_s;
  }
  integratedUntil_ns_ = until_ns;
}

void TrafficAnalyzer::startPeriod(std::int64_t start_ns) {
  periodStart_ns_ = start_ns;
  periodEnd_ns_ = start_ns + period_ns_;
  integratedUntil_ns_ = start_ns;
  for (std::size_t g = 0; g < gateCount_; ++g) {
    for (std::size_t d = 0; d < 2; ++d) {
      for (std::size_t t = 0; t < kReportTypeCount; ++t) {
        countsAtStart_[g][d][t] = counter_.count(g, static_cast<CrossingDirection>(d),
                                                 static_cast<shape::VehicleType>(t));
      }
    }
  }
  movements_ = {};
  for (std::size_t z = 0; z < zoneCount_; ++z) {
    ZoneAccumulator& acc = zoneAcc_[z];
    // The vehicles present carry over: they are the period's first state.
    acc.vehicleTime_s = 0.0;
    acc.max = acc.now;
    acc.queueMax = acc.queueNow;
    acc.queueMax_m = acc.queueNow_m;
    acc.dwellCount = 0;
    acc.dwellSum_s = 0.0;
    acc.dwellMax_s = 0.0;
  }
  laneSampleCount_ = {};
  wrongWay_ = 0;
  boxStops_ = 0;
}

void TrafficAnalyzer::closePeriod(std::int64_t end_ns) {
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].used) {
      flushLaneSamples(i);
    }
  }
  TrafficStatistics& s = closed_;
  s.sequence = periods_;
  s.start_ns = periodStart_ns_;
  s.end_ns = end_ns;
  s.gateCount = gateCount_;
  for (std::size_t g = 0; g < gateCount_; ++g) {
    s.gates[g].gateIndex = static_cast<std::uint32_t>(g);
    for (std::size_t d = 0; d < 2; ++d) {
      for (std::size_t t = 0; t < kReportTypeCount; ++t) {
        s.gates[g].byDirectionAndType[d][t] =
            static_cast<std::uint32_t>(counter_.count(g, static_cast<CrossingDirection>(d),
                                                      static_cast<shape::VehicleType>(t)) -
                                       countsAtStart_[g][d][t]);
      }
    }
  }
  s.movements = movements_;
  const double duration_s = static_cast<double>(end_ns - periodStart_ns_) / kNsPerS;
  s.zoneCount = zoneCount_;
  for (std::size_t z = 0; z < zoneCount_; ++z) {
    const ZoneAccumulator& acc = zoneAcc_[z];
    ZoneRecord& r = s.zones[z];
    r.zoneIndex = static_cast<std::uint32_t>(z);
    r.vehiclesNow = acc.now;
    r.meanVehicles = duration_s > 0.0 ? acc.vehicleTime_s / duration_s : acc.now;
    r.maxVehicles = acc.max;
    r.queueNow_vehicles = acc.queueNow;
    r.maxQueue_vehicles = acc.queueMax;
    r.queueNow_m = acc.queueNow_m;
    r.maxQueue_m = acc.queueMax_m;
    r.dwellCount = acc.dwellCount;
    r.meanDwell_s = acc.dwellCount > 0 ? acc.dwellSum_s / acc.dwellCount : 0.0;
    r.maxDwell_s = acc.dwellMax_s;
  }
  s.laneCount = laneCount_;
  for (std::size_t l = 0; l < laneCount_; ++l) {
    LaneRecord& r = s.lanes[l];
    r = LaneRecord{};
    r.laneIndex = static_cast<std::uint32_t>(l);
    const std::size_t n = laneSampleCount_[l];
    r.vehicles = static_cast<std::uint32_t>(n);
    if (n == 0) {
      continue;
    }
    double* first = laneSamples_.data() + l * options_.maxLaneSamples;
    double sum = 0.0;
    double max = first[0];
    for (std::size_t k = 0; k < n; ++k) {
      sum += first[k];
      max = std::max(max, first[k]);
    }
    r.meanSpeed_mps = sum / static_cast<double>(n);
    r.maxSpeed_mps = max;
    // Nearest rank: the ceil(0.85 n)-th smallest, in place (the samples are spent).
    const auto rank = static_cast<std::size_t>(std::ceil(0.85 * static_cast<double>(n)));
    const std::size_t k = std::clamp<std::size_t>(rank, 1, n) - 1;
    std::nth_element(first, first + k, first + n);
    r.p85Speed_mps = first[k];
  }
  s.wrongWayEvents = wrongWay_;
  s.boxJunctionStops = boxStops_;
  ++periods_;
  ++stats_.periods;
  completed_ = true;
}

bool TrafficAnalyzer::step(std::int64_t time_ns, std::span<const tracking::TrackState> tracks) {
  if (haveTime_ && time_ns < lastTime_ns_) {
    ++stats_.stepsRefused;
    return false;
  }
  eventCount_ = 0;
  completed_ = false;
  haveTime_ = true;
  lastTime_ns_ = time_ns;
  if (!active_) {
    return true;
  }
  ++stats_.steps;
  if (!started_) {
    started_ = true;
    startPeriod(time_ns);
  } else if (time_ns >= periodEnd_ns_) {
    integrateZones(periodEnd_ns_);
    closePeriod(periodEnd_ns_);
    startPeriod(periodEnd_ns_ + (time_ns - periodEnd_ns_) / period_ns_ * period_ns_);
  }
  integrateZones(time_ns);

  const std::int64_t wrongWay_ns = toNs(options_.wrongWay_s);
  const std::int64_t boxStop_ns = toNs(options_.boxJunctionStop_s);
  const double tolerance_rad = options_.laneHeadingTolerance_deg * std::numbers::pi / 180.0;
  const double against_rad = options_.wrongWayAngle_deg * std::numbers::pi / 180.0;
  std::array<std::uint32_t, kMaxReportZones> now{};
  std::array<std::uint32_t, kMaxReportZones> queue{};
  std::array<double, kMaxReportZones> queue_m{};

  for (Slot& slot : slots_) {
    slot.seen = false;
  }
  for (const tracking::TrackState& track : tracks) {
    if (!published(track) || !track.centreEnu.allFinite() || !std::isfinite(track.speed_mps) ||
        !std::isfinite(track.headingEnu_rad)) {
      continue;
    }
    Slot* slot = find(track.id);
    if (slot == nullptr) {
      slot = claim(track.id);
      if (slot == nullptr) {
        ++stats_.tracksDropped;
        continue;
      }
    }
    const auto slotIndex = static_cast<std::size_t>(slot - slots_.data());
    const Eigen::Vector2d& c = track.centreEnu;
    const double speed_mps = std::abs(track.speed_mps);
    const bool stopped = speed_mps < options_.stopSpeed_mps;
    slot->seen = true;
    slot->lastTime_ns = time_ns;
    slot->last_m = c;
    slot->type = track.type;
    slot->speed_mps = speed_mps;

    TrafficEvent event;
    event.time_ns = time_ns;
    event.trackId = track.id;
    event.type = track.type;
    event.speed_mps = speed_mps;
    event.positionEnu_m = c;

    for (std::size_t z = 0; z < zoneCount_; ++z) {
      const bool inside = site_.contains(*zones_[z], c);
      if (!inside || !stopped) {
        if (slot->stopSince_ns[z] >= 0) {
          endDwell(*slot, z, time_ns);
        }
        if (inside) {
          ++now[z];
        }
        continue;
      }
      ++now[z];
      ++queue[z];
      if (zoneLane_[z] >= 0) {
        const auto l = static_cast<std::size_t>(zoneLane_[z]);
        const double fromEnd_m =
            laneGeometry_[l].length_m - placeOnLane(l, c).along_m + 0.5 * track.length_m;
        queue_m[z] = std::max(queue_m[z], std::max(0.0, fromEnd_m));
      } else {
        queue_m[z] += std::max(0.0, track.length_m);
      }
      if (slot->stopSince_ns[z] < 0) {
        slot->stopSince_ns[z] = time_ns;
      }
      const std::uint32_t bit = 1U << z;
      if (zoneBox_[z] && (slot->boxReported & bit) == 0 &&
          time_ns - slot->stopSince_ns[z] >= boxStop_ns) {
        slot->boxReported |= bit;
        ++boxStops_;
        event.kind = TrafficEventKind::BoxJunctionStop;
        event.featureIndex = static_cast<std::uint32_t>(z);
        emit(event);
      }
    }

    for (std::size_t l = 0; l < laneCount_; ++l) {
      LaneAccumulator& acc = laneAcc_[slotIndex * laneCount_ + l];
      const LanePlace place = placeOnLane(l, c);
      if (!(place.distance_m <= laneGeometry_[l].halfWidth_m)) {
        acc.wrongSince_ns = -1;
        continue;
      }
      const double off_rad = angleBetween(track.headingEnu_rad, place.direction_rad);
      if (off_rad <= tolerance_rad) {
        acc.speedSum_mps += speed_mps;
        ++acc.samples;
      }
      if (off_rad > against_rad && speed_mps >= options_.wrongWaySpeed_mps) {
        if (acc.wrongSince_ns < 0) {
          acc.wrongSince_ns = time_ns;
        }
        const std::uint64_t bit = std::uint64_t{1} << l;
        if ((slot->wrongReported & bit) == 0 && time_ns - acc.wrongSince_ns >= wrongWay_ns) {
          slot->wrongReported |= bit;
          ++wrongWay_;
          event.kind = TrafficEventKind::WrongWay;
          event.featureIndex = static_cast<std::uint32_t>(l);
          emit(event);
        }
      } else {
        acc.wrongSince_ns = -1;
      }
    }
  }

  // Gate crossings: the counter follows the same tracks with the same table size.
  counter_.step(time_ns, tracks);
  for (const GateCrossing& crossing : counter_.crossings()) {
    TrafficEvent event;
    event.kind = TrafficEventKind::GateCrossing;
    event.time_ns = time_ns;
    event.trackId = crossing.trackId;
    event.featureIndex = crossing.gateId;
    event.direction = static_cast<std::uint8_t>(crossing.direction);
    event.type = crossing.type;
    event.speed_mps = std::abs(crossing.speed_mps);
    if (Slot* slot = find(crossing.trackId)) {
      event.positionEnu_m = slot->last_m;
      if (slot->firstGate < 0) {
        slot->firstGate = static_cast<std::int16_t>(crossing.gateId);
      }
      slot->lastGate = static_cast<std::int16_t>(crossing.gateId);
      ++slot->crossings;
    }
    emit(event);
  }

  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].used && !slots_[i].seen) {
      endTrack(i, time_ns, true);
    }
  }
  for (std::size_t z = 0; z < zoneCount_; ++z) {
    ZoneAccumulator& acc = zoneAcc_[z];
    acc.now = now[z];
    acc.max = std::max(acc.max, now[z]);
    acc.queueNow = queue[z];
    acc.queueMax = std::max(acc.queueMax, queue[z]);
    acc.queueNow_m = queue_m[z];
    acc.queueMax_m = std::max(acc.queueMax_m, queue_m[z]);
  }
  return true;
}

void TrafficAnalyzer::finish(std::int64_t time_ns) {
  eventCount_ = 0;
  completed_ = false;
  if (!active_ || !started_) {
    return;
  }
  const std::int64_t end_ns = std::min(std::max(time_ns, lastTime_ns_), periodEnd_ns_);
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].used) {
      endTrack(i, end_ns, true);
    }
  }
  counter_.finish();
  integrateZones(end_ns);
  closePeriod(end_ns);
  started_ = false;
}

}  // namespace vp::traffic
