// traffic/gate_counter: counts vehicles crossing counting lines (gates) from the tracker's
// published tracks, by gate, direction and vehicle type, and the turning movements between
// gates (seed 002's counts by category and direction; an intersection's origin -> destination
// matrix).
//
// Contract: init() checks the gates (at most kMaxGates, unique ids, each at least
// kMinGateLength_m long; a message names the gate by its id) and allocates everything for
// maxTracks tracks and maxCrossingsPerStep crossings; after that step() performs no heap
// allocation and never throws. step() takes one frame's published tracks (confirmed and lost,
// as the loop publishes them; tentative ones are ignored) with the frame's time; time must not
// go backwards (the step is refused and counted). A track crosses a gate when the segment
// between its footprint centres of two consecutive steps crosses the gate's segment.
// Direction: standing at the gate's first point looking at its second, a Forward crossing goes
// from the right to the left (along the left normal), a Backward one the other way. A point
// exactly on the line counts as the right side, so a track that stops on the line and goes on
// is counted once. A track missing from a step has ended (the loop publishes a track every
// frame until the tracker deletes it): its turning movement — from the gate it crossed first
// to the gate it crossed last, when those are two crossings — is counted then, under the
// track's type at its end. Tracks beyond maxTracks and crossings beyond maxCrossingsPerStep
// are dropped and counted.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"
#include "tracking/track_manager.hpp"

namespace vp::traffic {

constexpr std::size_t kMaxGates = 32;
constexpr double kMinGateLength_m = 0.5;
constexpr std::size_t kTypeCount = static_cast<std::size_t>(shape::kVehicleTypeCount);

// A counting line in the world ENU frame (m), from `first` to `second`.
struct Gate {
  std::uint32_t id = 0;
  Eigen::Vector2d first_m{0.0, 0.0};
  Eigen::Vector2d second_m{0.0, 0.0};
};

enum class CrossingDirection : std::uint8_t { Forward = 0, Backward = 1 };
const char* toString(CrossingDirection direction);  // "forward", "backward"

struct GateCrossing {
  std::uint32_t gateId = 0;
  std::uint32_t trackId = 0;
  std::int64_t time_ns = 0;  // the step in which the crossing was seen
  CrossingDirection direction = CrossingDirection::Forward;
  shape::VehicleType type = shape::VehicleType::Sedan;  // the track's fused type then
  double speed_mps = 0.0;
};

struct GateCounterOptions {
  std::size_t maxTracks = 1024;           // tracks followed at once, [1, 65536]
  std::size_t maxCrossingsPerStep = 256;  // events one step can report, [1, 65536]
};

struct GateCounterStats {
  std::uint64_t steps = 0;
  std::uint64_t crossings = 0;
  std::uint64_t turningMovements = 0;
  std::uint64_t tracksDropped = 0;     // a new track found the table full
  std::uint64_t crossingsDropped = 0;  // beyond maxCrossingsPerStep in one step (still counted)
  std::uint64_t stepsRefused = 0;      // time went backwards
};

class GateCounter {
 public:
  bool init(std::span<const Gate> gates, const GateCounterOptions& options, std::string* why);

  // One frame's published tracks; returns false (nothing changes) when time went backwards.
  bool step(std::int64_t time_ns, std::span<const tracking::TrackState> tracks);
  // Ends every followed track (their turning movements are counted), e.g. at the end of a run.
  void finish();

  // The crossings seen by the last step (at most maxCrossingsPerStep of them).
  std::span<const GateCrossing> crossings() const { return {events_.data(), eventCount_}; }
  // Crossings since init() of gate index g (the order given to init()).
  std::uint64_t count(std::size_t gate, CrossingDirection direction, shape::VehicleType type) const;
  std::uint64_t count(std::size_t gate, CrossingDirection direction) const;
  // Tracks that crossed gate index `from` first and gate index `to` last (two crossings or more).
  std::uint64_t turningMovements(std::size_t from, std::size_t to) const;
  std::uint64_t turningMovements(std::size_t from, std::size_t to, shape::VehicleType type) const;
  std::span<const Gate> gates() const { return {gates_.data(), gateCount_}; }
  const GateCounterStats& stats() const { return stats_; }

 private:
  struct Slot {
    bool used = false;
    bool seen = false;  // present in the current step
    std::uint32_t trackId = 0;
    Eigen::Vector2d last_m{0.0, 0.0};
    shape::VehicleType type = shape::VehicleType::Sedan;
    std::int16_t firstGate = -1;
    std::int16_t lastGate = -1;
    std::uint32_t crossings = 0;
  };
  Slot* find(std::uint32_t trackId);
  Slot* claim(std::uint32_t trackId);
  void cross(Slot& slot, const tracking::TrackState& track, const Eigen::Vector2d& from,
             std::int64_t time_ns);
  void end(Slot& slot);

  std::array<Gate, kMaxGates> gates_{};
  std::size_t gateCount_ = 0;
  GateCounterOptions options_{};
  std::vector<Slot> slots_;
  std::vector<GateCrossing> events_;
  std::size_t eventCount_ = 0;
  bool haveTime_ = false;
  std::int64_t lastTime_ns_ = 0;
  std::array<std::array<std::array<std::uint64_t, kTypeCount>, 2>, kMaxGates> counts_{};
  std::array<std::array<std::array<std::uint64_t, kTypeCount>, kMaxGates>, kMaxGates> movements_{};
  GateCounterStats stats_{};
};

}  // namespace vp::traffic
