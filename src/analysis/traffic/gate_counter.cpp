#include "gate_counter.hpp"

#include <cmath>
#include <set>

#include "traffic/track_slots.hpp"

namespace vp::traffic {

namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Left of the directed line first -> second (strictly); on the line counts as right.
bool leftOf(const Gate& gate, const Eigen::Vector2d& p) {
  return cross2(gate.second_m - gate.first_m, p - gate.first_m) > 0.0;
}

// Whether the step from -> to crosses the gate's segment (its sides change and the crossing
// point of the two lines lies within the gate's ends).
bool crosses(const Gate& gate, const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  if (leftOf(gate, from) == leftOf(gate, to)) {
    return false;
  }
  const Eigen::Vector2d g = gate.second_m - gate.first_m;
  const Eigen::Vector2d m = to - from;
  const double denominator = cross2(g, m);
  if (denominator == 0.0) {
    return false;  // parallel: cannot change sides (guarded above), numerically degenerate
  }
  // from + t m = first + s g  =>  s = cross(from - first, m) / cross(g, m)
  const double s = cross2(from - gate.first_m, m) / denominator;
  return s >= 0.0 && s <= 1.0;
}

bool published(const tracking::TrackState& track) {
  return track.status != tracking::TrackStatus::Tentative;
}

}  // namespace

const char* toString(CrossingDirection direction) {
  return direction == CrossingDirection::Forward ? "forward" : "backward";
}

bool GateCounter::init(std::span<const Gate> gates, const GateCounterOptions& options,
                       std::string* why) {
  const auto fail = [why](const std::string& problem) {
    if (why != nullptr) {
      *why = problem;
    }
    return false;
  };
  if (gates.size() > kMaxGates) {
    return fail(std::to_string(gates.size()) + " gates: at most " + std::to_string(kMaxGates));
  }
  if (options.maxTracks < 1 || options.maxTracks > 65536) {
    return fail("maxTracks must be in [1, 65536], got " + std::to_string(options.maxTracks));
  }
  if (options.maxCrossingsPerStep < 1 || options.maxCrossingsPerStep > 65536) {
    return fail("maxCrossingsPerStep must be in [1, 65536], got " +
                std::to_string(options.maxCrossingsPerStep));
  }
  std::set<std::uint32_t> ids;
  for (const Gate& gate : gates) {
    const std::string name = "gate " + std::to_string(gate.id);
    if (!ids.insert(gate.id).second) {
      return fail(name + ": the id is used twice");
    }
    if (!gate.first_m.allFinite() || !gate.second_m.allFinite()) {
      return fail(name + ": an end point is not finite");
    }
    const double length_m = (gate.second_m - gate.first_m).norm();
    if (!(length_m >= kMinGateLength_m)) {
      return fail(name + ": " + std::to_string(length_m) + " m long, at least " +
                  std::to_string(kMinGateLength_m) + " m");
    }
  }
  gateCount_ = gates.size();
  for (std::size_t g = 0; g < gateCount_; ++g) {
    gates_[g] = gates[g];
  }
  options_ = options;
  slots_.assign(options.maxTracks, Slot{});
  events_.assign(options.maxCrossingsPerStep, GateCrossing{});
  eventCount_ = 0;
  haveTime_ = false;
  counts_ = {};
  movements_ = {};
  stats_ = {};
  return true;
}

GateCounter::Slot* GateCounter::find(std::uint32_t trackId) {
  return findTrackSlot(std::span<Slot>(slots_), trackId);
}

GateCounter::Slot* GateCounter::claim(std::uint32_t trackId) {
  return claimTrackSlot(std::span<Slot>(slots_), trackId);  // released slots are empty
}

void GateCounter::cross(Slot& slot, const tracking::TrackState& track, const Eigen::Vector2d& from,
                        std::int64_t time_ns) {
  const Eigen::Vector2d& to = track.centreEnu;
  for (std::size_t g = 0; g < gateCount_; ++g) {
    const Gate& gate = gates_[g];
    if (!crosses(gate, from, to)) {
      continue;
    }
    const CrossingDirection direction =
        leftOf(gate, to) ? CrossingDirection::Forward : CrossingDirection::Backward;
    const auto type = static_cast<std::size_t>(track.type);
    ++counts_[g][static_cast<std::size_t>(direction)][type];
    ++stats_.crossings;
    if (slot.firstGate < 0) {
      slot.firstGate = static_cast<std::int16_t>(g);
    }
    slot.lastGate = static_cast<std::int16_t>(g);
    ++slot.crossings;
    if (eventCount_ < events_.size()) {
      events_[eventCount_++] = {gate.id, track.id, time_ns, direction, track.type, track.speed_mps};
    } else {
      ++stats_.crossingsDropped;
    }
  }
}

void GateCounter::end(Slot& slot) {
  if (slot.crossings >= 2 && slot.firstGate >= 0 && slot.lastGate >= 0) {
    ++movements_[static_cast<std::size_t>(slot.firstGate)][static_cast<std::size_t>(slot.lastGate)]
                [static_cast<std::size_t>(slot.type)];
    ++stats_.turningMovements;
  }
  slot = Slot{};
}

bool GateCounter::step(std::int64_t time_ns, std::span<const tracking::TrackState> tracks) {
  if (haveTime_ && time_ns < lastTime_ns_) {
    ++stats_.stepsRefused;
    return false;
  }
  haveTime_ = true;
  lastTime_ns_ = time_ns;
  ++stats_.steps;
  eventCount_ = 0;
  for (Slot& slot : slots_) {
    slot.seen = false;
  }
  for (const tracking::TrackState& track : tracks) {
    if (!published(track) || !track.centreEnu.allFinite()) {
      continue;
    }
    Slot* slot = find(track.id);
    if (slot == nullptr) {
      slot = claim(track.id);
      if (slot == nullptr) {
        ++stats_.tracksDropped;
        continue;
      }
    } else if (!slot->seen) {
      cross(*slot, track, slot->last_m, time_ns);
    }
    slot->seen = true;
    slot->last_m = track.centreEnu;
    slot->type = track.type;
  }
  for (Slot& slot : slots_) {
    if (slot.used && !slot.seen) {
      end(slot);
    }
  }
  return true;
}

void GateCounter::finish() {
  for (Slot& slot : slots_) {
    if (slot.used) {
      end(slot);
    }
  }
}

std::uint64_t GateCounter::count(std::size_t gate, CrossingDirection direction,
                                 shape::VehicleType type) const {
  if (gate >= gateCount_) {
    return 0;
  }
  return counts_[gate][static_cast<std::size_t>(direction)][static_cast<std::size_t>(type)];
}

std::uint64_t GateCounter::count(std::size_t gate, CrossingDirection direction) const {
  std::uint64_t total = 0;
  for (std::size_t t = 0; t < kTypeCount; ++t) {
    total += count(gate, direction, static_cast<shape::VehicleType>(t));
  }
  return total;
}

std::uint64_t GateCounter::turningMovements(std::size_t from, std::size_t to,
                                            shape::VehicleType type) const {
  if (from >= gateCount_ || to >= gateCount_) {
    return 0;
  }
  return movements_[from][to][static_cast<std::size_t>(type)];
}

std::uint64_t GateCounter::turningMovements(std::size_t from, std::size_t to) const {
  std::uint64_t total = 0;
  for (std::size_t t = 0; t < kTypeCount; ++t) {
    total += turningMovements(from, to, static_cast<shape::VehicleType>(t));
  }
  return total;
}

}  // namespace vp::traffic
