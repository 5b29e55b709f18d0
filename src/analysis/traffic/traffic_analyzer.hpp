// traffic/traffic_analyzer: the online traffic analysis of a site from the tracks the loop
// publishes — gate counts and turning movements (GateCounter), zone occupancy, queues and dwell
// of stopped vehicles, lane speeds (mean, 85th percentile, max), and the events wrong-way
// driving, a stop inside a box junction, a gate crossing and a completed turning movement —
// reported per period as TrafficStatistics and per step as TrafficEvent (traffic_report.hpp).
//
// Contract: init() takes the loaded site (its gates, zones and lanes, in file order; the analyzer
// keeps its own copy) and the options, checks both (limits kMaxReport*, ranges of the options; a
// message names the option or the feature by its id) and allocates everything; after that step()
// and finish() perform no heap allocation and never throw (TrafficAnalyzer.AStepAllocatesNothing).
// step() takes one frame's published tracks (tentative ones and non-finite positions are ignored)
// with the frame's time, which must not go backwards (the step is refused, counted, nothing
// changes). A track missing from a step has ended. Definitions (docs/traffic.md):
// - in a zone: the footprint centre is inside the zone's polygon; stopped: speed below
//   stopSpeed_mps; the queue of a zone is its stopped vehicles, its length in metres runs from the
//   end of the zone's lane (the stop line) back to the upstream end of the farthest queued vehicle
//   (its centre projected onto the lane, plus half its length); a zone without a lane measures
//   the queued vehicles' lengths end to end. Occupancy "now" is that of the period's last step,
//   the mean is time-weighted (each step's count holds until the next step).
// - dwell: a vehicle that stops in a zone starts a dwell; it ends when the vehicle moves again,
//   leaves the zone (at that step's time) or its track ends (at its last time); it is reported in
//   the period in which it ends.
// - on a lane: the centre lies within half the lane's width of its polyline; the lane's local
//   direction is that of the nearest segment. Along the lane: heading within
//   laneHeadingTolerance_deg of it (speed samples); against it: moving (speed >=
//   wrongWaySpeed_mps) with a heading more than wrongWayAngle_deg off, for at least wrongWay_s
//   without interruption (one event per track and lane).
// - lane speeds: one sample per vehicle and lane per period, its mean speed over its steps along
//   the lane; p85 is the nearest-rank 85th percentile (the ceil(0.85 n)-th smallest sample), found
//   with std::nth_element in a buffer allocated at init (maxLaneSamples per lane, more dropped and
//   counted).
// - box junction: a vehicle stopped inside a box_junction zone for boxJunctionStop_s (one event
//   per track and zone).
// - periods: the first starts at the first step, each lasts period_s; the step whose time reaches
//   a period's end closes it (completedPeriod() non-null in that step; a step after a gap longer
//   than a period closes one period and starts the next aligned one, the empty ones between are
//   not reported). finish() ends every track and closes the running period at its time
//   (lastPeriod()).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "site/site.hpp"
#include "tracking/track_manager.hpp"
#include "traffic/gate_counter.hpp"
#include "traffic/traffic_report.hpp"

namespace vp::traffic {

// The `traffic:` configuration section.
struct TrafficAnalyzerOptions {
  bool enabled = true;                     // runs when the site has gates, zones or lanes
  double period_s = 60.0;                  // statistics period, [1, 86400]
  double stopSpeed_mps = 1.0;              // below: stopped (queues, dwell, box junction), [0, 10]
  double laneHeadingTolerance_deg = 45.0;  // along a lane within this, (0, 90]
  double wrongWayAngle_deg = 135.0;        // against a lane beyond this, [90, 179]
  double wrongWaySpeed_mps = 2.0;          // wrong-way only when moving at least this, [0, 50]
  double wrongWay_s = 1.0;                 // ... for at least this long, [0, 60]
  double boxJunctionStop_s = 5.0;          // stopped in a box junction this long, [0, 600]
  std::size_t maxTracks = 1024;            // tracks followed at once, [1, 65536]
  std::size_t maxEventsPerStep = 256;      // events one step reports, [1, 65536]
  std::size_t maxLaneSamples = 1024;       // speed samples per lane and period, [1, 65536]
};

struct TrafficAnalyzerStats {
  std::uint64_t steps = 0;
  std::uint64_t stepsRefused = 0;    // time went backwards
  std::uint64_t tracksDropped = 0;   // a new track found the table full
  std::uint64_t eventsDropped = 0;   // beyond maxEventsPerStep in one step
  std::uint64_t samplesDropped = 0;  // lane speed samples beyond maxLaneSamples
  std::uint64_t periods = 0;         // periods closed
};

class TrafficAnalyzer {
 public:
  TrafficAnalyzer() = default;
  // The feature pointers refer to the analyzer's own copy of the site: no copies, moves keep it.
  TrafficAnalyzer(const TrafficAnalyzer&) = delete;
  TrafficAnalyzer& operator=(const TrafficAnalyzer&) = delete;
  TrafficAnalyzer(TrafficAnalyzer&&) = default;
  TrafficAnalyzer& operator=(TrafficAnalyzer&&) = default;

  bool init(const site::Site& site, const TrafficAnalyzerOptions& options, std::string* why);
  // False when disabled or when the site has no gate, zone or lane: step() then does nothing.
  bool active() const { return active_; }

  // One frame's published tracks; false (nothing changes) when time went backwards.
  bool step(std::int64_t time_ns, std::span<const tracking::TrackState> tracks);
  std::span<const TrafficEvent> events() const { return {events_.data(), eventCount_}; }
  // Non-null in the step a period ended (valid until the next step).
  const TrafficStatistics* completedPeriod() const { return completed_ ? &closed_ : nullptr; }
  // End of run: ends every track (dwell, lane samples, turning movements: their events are in
  // events()) and closes the running period at time_ns.
  void finish(std::int64_t time_ns);
  // The period closed by finish() (or the last one closed), null before any.
  const TrafficStatistics* lastPeriod() const { return periods_ > 0 ? &closed_ : nullptr; }

  const TrafficAnalyzerStats& stats() const { return stats_; }
  const GateCounter& gateCounter() const { return counter_; }
  // The site's features the report's indices refer to.
  std::span<const site::Feature* const> gates() const { return {gates_.data(), gateCount_}; }
  std::span<const site::Feature* const> zones() const { return {zones_.data(), zoneCount_}; }
  std::span<const site::Feature* const> lanes() const { return {lanes_.data(), laneCount_}; }

  // Lane geometry helper (also for tools): where a point lies relative to lane index l.
  using LanePlace = site::LanePlace;
  LanePlace placeOnLane(std::size_t lane, const Eigen::Vector2d& point_m) const;
  double laneLength_m(std::size_t lane) const;

 private:
  struct LaneAccumulator {
    double speedSum_mps = 0.0;
    std::uint32_t samples = 0;
    std::int64_t wrongSince_ns = -1;  // against the lane since, -1: not
  };
  struct Slot {
    bool used = false;
    bool seen = false;
    std::uint32_t trackId = 0;
    std::int64_t lastTime_ns = 0;
    Eigen::Vector2d last_m{0.0, 0.0};
    shape::VehicleType type = shape::VehicleType::Sedan;
    double speed_mps = 0.0;
    std::int16_t firstGate = -1;
    std::int16_t lastGate = -1;
    std::uint32_t crossings = 0;
    std::uint32_t boxReported = 0;    // zones (bit per index) with a box-junction event
    std::uint64_t wrongReported = 0;  // lanes (bit per index) with a wrong-way event
    std::array<std::int64_t, kMaxReportZones> stopSince_ns{};  // -1: not stopped in the zone
  };
  struct ZoneAccumulator {
    double vehicleTime_s = 0.0;  // integral of the count over the period
    std::uint32_t now = 0;
    std::uint32_t max = 0;
    std::uint32_t queueNow = 0;
    std::uint32_t queueMax = 0;
    double queueNow_m = 0.0;
    double queueMax_m = 0.0;
    std::uint32_t dwellCount = 0;
    double dwellSum_s = 0.0;
    double dwellMax_s = 0.0;
  };
  struct LaneGeometry {
    double halfWidth_m = 1.75;
    double length_m = 0.0;
    std::int16_t queueZone = -1;
  };

  Slot* find(std::uint32_t trackId);
  Slot* claim(std::uint32_t trackId);
  void emit(const TrafficEvent& event);
  void endDwell(Slot& slot, std::size_t zone, std::int64_t time_ns);
  void flushLaneSamples(std::size_t slotIndex);
  void endTrack(std::size_t slotIndex, std::int64_t time_ns, bool emitMovement);
  void integrateZones(std::int64_t until_ns);
  void closePeriod(std::int64_t end_ns);
  void startPeriod(std::int64_t start_ns);

  TrafficAnalyzerOptions options_{};
  bool active_ = false;
  site::Site site_;
  std::array<const site::Feature*, kMaxReportGates> gates_{};
  std::size_t gateCount_ = 0;
  std::array<const site::Feature*, kMaxReportZones> zones_{};
  std::array<std::int16_t, kMaxReportZones> zoneLane_{};  // lane index of a zone, -1: none
  std::array<bool, kMaxReportZones> zoneBox_{};
  std::size_t zoneCount_ = 0;
  std::array<const site::Feature*, kMaxReportLanes> lanes_{};
  std::array<LaneGeometry, kMaxReportLanes> laneGeometry_{};
  std::size_t laneCount_ = 0;

  GateCounter counter_;
  std::vector<Slot> slots_;
  std::vector<LaneAccumulator> laneAcc_;  // slot * laneCount + lane
  std::vector<double> laneSamples_;       // lane * maxLaneSamples + k
  std::array<std::uint32_t, kMaxReportLanes> laneSampleCount_{};
  std::array<ZoneAccumulator, kMaxReportZones> zoneAcc_{};
  std::vector<TrafficEvent> events_;
  std::size_t eventCount_ = 0;

  bool started_ = false;  // a period is running
  bool haveTime_ = false;
  std::int64_t lastTime_ns_ = 0;
  std::int64_t periodStart_ns_ = 0;
  std::int64_t periodEnd_ns_ = 0;
  std::int64_t period_ns_ = 0;
  std::int64_t integratedUntil_ns_ = 0;
  // Cumulative counts of the GateCounter at the period's start (the period's are the difference).
  std::array<std::array<std::array<std::uint64_t, kReportTypeCount>, 2>, kMaxReportGates>
      countsAtStart_{};
  std::array<std::array<std::uint32_t, kMaxReportGates>, kMaxReportGates> movements_{};
  std::uint32_t wrongWay_ = 0;
  std::uint32_t boxStops_ = 0;
  TrafficStatistics closed_{};
  bool completed_ = false;
  std::uint64_t periods_ = 0;
  TrafficAnalyzerStats stats_{};
};

}  // namespace vp::traffic
