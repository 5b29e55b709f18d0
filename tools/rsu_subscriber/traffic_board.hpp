// tools/rsu_subscriber/traffic_board: what the roadside unit keeps of the drones' traffic
// outputs (TrafficStatistics per period, TrafficEvent as they happen): the gate counts totalled
// over the periods received (by gate id and direction), the last events, and their text lines.
//
// Contract: a period is counted once per (drone, period number), so that the transient-local
// history a late or restarted reader receives again does not count twice. periodLine() is the
// line the subscriber prints for each period ("traffic: drone 1 period 3 [t0, t1) ns: gate
// north-in forward 3 backward 1 [cars 4, transporters 0] (total 12/4); ..."; cars and
// transporters are seed 002's categories: trucks and buses are transporters); eventLine() the one
// for each event. fillOverlay() gives the bird's-eye view its gate labels ("F12 B4"), event marks
// and text panel. The site's world frame: originFrom() estimates the drones' ENU origin from a
// sample that gives a point both in ENU and in WGS84 (exact at that point; the flat-frame
// approximation of the drones' own frame elsewhere, a few mm per 100 m).
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "bev_view.hpp"
#include "geodesy/geodesy.hpp"
#include "vp_perception.h"

namespace vp::rsu {

class TrafficBoard {
 public:
  static constexpr std::size_t kLastEvents = 8;

  // False when this (drone, period) was already counted (the line is then not printed).
  bool addStatistics(const vp_msg_TrafficStatistics& statistics);
  void addEvent(const vp_msg_TrafficEvent& event);
  std::string periodLine(const vp_msg_TrafficStatistics& statistics) const;
  static std::string eventLine(const vp_msg_TrafficEvent& event);
  void fillOverlay(BevOverlay& overlay) const;

  std::uint64_t periods() const { return seen_.size(); }
  std::uint64_t events() const { return events_; }
  // Totals over the periods received: gate id -> {forward, backward}.
  const std::map<std::string, std::pair<std::uint64_t, std::uint64_t>>& totals() const {
    return totals_;
  }

 private:
  std::set<std::pair<std::uint32_t, std::uint64_t>> seen_;
  std::map<std::string, std::pair<std::uint64_t, std::uint64_t>> totals_;
  std::deque<vp_msg_TrafficEvent> last_;
  std::uint64_t events_ = 0;
};

const char* kindName(vp_msg_TrafficEventKind kind);  // "gate_crossing", ...

// The world origin for which `position` has the ENU coordinates `enu_m`.
geodesy::GeodeticPoint originFrom(const geodesy::GeodeticPoint& position, const double enu_m[3]);

}  // namespace vp::rsu
