// config/traffic_section: `traffic:` into the traffic analysis' own options
// (traffic::TrafficAnalyzerOptions, docs/traffic.md). The ranges are the analyzer's, which
// checks them again at init().
#include <cstddef>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kPeriodRange_s = Range::closed(1.0, 86400.0);
const Range kStopSpeedRange_mps = Range::closed(0.0, 10.0);
const Range kToleranceRange_deg = Range{0.0, 90.0, true};  // (0, 90]
const Range kAgainstRange_deg = Range::closed(90.0, 179.0);
const Range kWrongWaySpeedRange_mps = Range::closed(0.0, 50.0);
const Range kWrongWayRange_s = Range::closed(0.0, 60.0);
const Range kBoxStopRange_s = Range::closed(0.0, 600.0);
const Range kCapacityRange = Range::closed(1.0, 65536.0);

std::size_t capacity(MapReader& section, const char* key, std::size_t fallback) {
  return static_cast<std::size_t>(section.integer(key, kCapacityRange, static_cast<int>(fallback)));
}

}  // namespace

traffic::TrafficAnalyzerOptions readTraffic(MapReader section) {
  const traffic::TrafficAnalyzerOptions d;
  traffic::TrafficAnalyzerOptions t;
  t.enabled = section.boolean("enabled", d.enabled);
  t.period_s = section.number("period_s", kPeriodRange_s, d.period_s);
  t.stopSpeed_mps = section.number("stop_speed_mps", kStopSpeedRange_mps, d.stopSpeed_mps);
  t.laneHeadingTolerance_deg =
      section.number("lane_heading_tolerance_deg", kToleranceRange_deg, d.laneHeadingTolerance_deg);
  t.wrongWayAngle_deg =
      section.number("wrong_way_angle_deg", kAgainstRange_deg, d.wrongWayAngle_deg);
  t.wrongWaySpeed_mps =
      section.number("wrong_way_speed_mps", kWrongWaySpeedRange_mps, d.wrongWaySpeed_mps);
  t.wrongWay_s = section.number("wrong_way_s", kWrongWayRange_s, d.wrongWay_s);
  t.boxJunctionStop_s = section.number("box_junction_stop_s", kBoxStopRange_s, d.boxJunctionStop_s);
  t.maxTracks = capacity(section, "max_tracks", d.maxTracks);
  t.maxEventsPerStep = capacity(section, "max_events_per_step", d.maxEventsPerStep);
  t.maxLaneSamples = capacity(section, "max_lane_samples", d.maxLaneSamples);
  section.warnUnknownKeys();
  return t;
}

}  // namespace vp::config::detail
