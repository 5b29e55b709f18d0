// tools/rsu_subscriber/traffic_board: totals, last events and their text.
#include "traffic_board.hpp"

#include <sstream>

#include "shape/vehicle_model.hpp"

namespace vp::rsu {
namespace {

constexpr const char* kTypeNames[] = {"estate", "compact", "sports", "sedan",
                                      "suv",    "van",     "large"};

std::uint64_t sum(const std::uint32_t (&byType)[7]) {
  std::uint64_t total = 0;
  for (const std::uint32_t n : byType) {
    total += n;
  }
  return total;
}

}  // namespace

const char* kindName(vp_msg_TrafficEventKind kind) {
  switch (kind) {
    case vp_msg_EVENT_GATE_CROSSING:
      return "gate_crossing";
    case vp_msg_EVENT_WRONG_WAY:
      return "wrong_way";
    case vp_msg_EVENT_BOX_JUNCTION_STOP:
      return "box_junction_stop";
    case vp_msg_EVENT_TURNING_MOVEMENT:
      return "turning_movement";
  }
  return "unknown";
}

bool TrafficBoard::addStatistics(const vp_msg_TrafficStatistics& s) {
  if (!seen_.emplace(s.drone_id, s.period).second) {
    return false;
  }
  for (std::uint32_t g = 0; g < s.gates._length; ++g) {
    const vp_msg_TrafficGateCount& gate = s.gates._buffer[g];
    auto& total = totals_[gate.gate_id];
    total.first += sum(gate.forward);
    total.second += sum(gate.backward);
  }
  return true;
}

void TrafficBoard::addEvent(const vp_msg_TrafficEvent& event) {
  ++events_;
  last_.push_back(event);
  while (last_.size() > kLastEvents) {
    last_.pop_front();
  }
}

std::string TrafficBoard::periodLine(const vp_msg_TrafficStatistics& s) const {
  std::ostringstream line;
  line << "traffic: drone " << s.drone_id << " period " << s.period << " [" << s.start_ns << ", "
       << s.end_ns << ") ns:";
  for (std::uint32_t g = 0; g < s.gates._length; ++g) {
    const vp_msg_TrafficGateCount& gate = s.gates._buffer[g];
    const auto total = totals_.find(gate.gate_id);
    std::uint64_t transporters = 0;  // seed 002's category (shape::categoryOf)
    for (std::size_t t = 0; t < 7; ++t) {
      if (shape::categoryOf(static_cast<shape::VehicleType>(t)) ==
          shape::VehicleCategory::Transporter) {
        transporters += std::uint64_t{gate.forward[t]} + gate.backward[t];
      }
    }
    line << (g == 0 ? " " : "; ") << "gate " << gate.gate_id << " forward " << sum(gate.forward)
         << " backward " << sum(gate.backward) << " [cars "
         << sum(gate.forward) + sum(gate.backward) - transporters << ", transporters "
         << transporters << "]";
    if (total != totals_.end()) {
      line << " (total " << total->second.first << "/" << total->second.second << ")";
    }
  }
  for (std::uint32_t m = 0; m < s.movements._length; ++m) {
    const vp_msg_TrafficMovement& movement = s.movements._buffer[m];
    line << (m == 0 ? "; movements " : ", ") << movement.from_gate_id << "->" << movement.to_gate_id
         << " " << movement.count;
  }
  for (std::uint32_t z = 0; z < s.zones._length; ++z) {
    const vp_msg_TrafficZone& zone = s.zones._buffer[z];
    line << "; zone " << zone.zone_id << " now " << zone.vehicles_now << " queue "
         << zone.queue_now_vehicles << " (" << zone.queue_now_m << " m)";
  }
  for (std::uint32_t l = 0; l < s.lanes._length; ++l) {
    const vp_msg_TrafficLane& lane = s.lanes._buffer[l];
    line << "; lane " << lane.lane_id << " " << lane.vehicles << " vehicles p85 "
         << lane.p85_speed_mps << " m/s";
  }
  line << "; wrong_way " << s.wrong_way_events << ", box_junction_stops " << s.box_junction_stops;
  return line.str();
}

std::string TrafficBoard::eventLine(const vp_msg_TrafficEvent& e) {
  std::ostringstream line;
  line << "traffic event: drone " << e.drone_id << " " << kindName(e.kind) << " track "
       << e.track_id << " " << e.feature_id;
  if (e.kind == vp_msg_EVENT_TURNING_MOVEMENT) {
    line << "->" << e.to_feature_id;
  }
  if (e.kind == vp_msg_EVENT_GATE_CROSSING) {
    line << (e.direction == 0 ? " forward" : " backward");
  }
  const auto type = static_cast<std::size_t>(e.type);
  line << " " << (type < 7 ? kTypeNames[type] : "?") << " " << e.speed_mps << " m/s at "
       << e.time_ns << " ns";
  return line.str();
}

void TrafficBoard::fillOverlay(BevOverlay& overlay) const {
  overlay.gateLabel.clear();
  overlay.eventMarks_m.clear();
  overlay.lines.clear();
  std::ostringstream head;
  head << "traffic: " << seen_.size() << " periods, " << events_ << " events";
  overlay.lines.push_back(head.str());
  for (const auto& [gate, total] : totals_) {
    // Appended piece by piece: GCC 12's -Wrestrict misreads "literal" + std::string&& at -O3.
    std::string label = "F";
    label += std::to_string(total.first);
    label += " B";
    label += std::to_string(total.second);
    overlay.gateLabel[gate] = label;
    overlay.lines.push_back("gate " + gate + ": forward " + std::to_string(total.first) +
                            ", backward " + std::to_string(total.second));
  }
  for (auto it = last_.rbegin(); it != last_.rend(); ++it) {
    overlay.eventMarks_m.emplace_back(it->enu_m[0], it->enu_m[1]);
    std::string text = eventLine(*it);
    text = text.substr(text.find(':') + 2);  // without "traffic event: "
    overlay.lines.push_back(text);
  }
}

geodesy::GeodeticPoint originFrom(const geodesy::GeodeticPoint& position, const double enu_m[3]) {
  const geodesy::LocalFrame at(position);
  return at.toGeodetic(Eigen::Vector3d(-enu_m[0], -enu_m[1], -enu_m[2]));
}

}  // namespace vp::rsu
