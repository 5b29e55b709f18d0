// tools/rsu_subscriber/state_format: one received vehicle-state event as a CSV row or a JSON
// line, and the latency statistics the subscriber prints.
//
// Contract: doubles are printed with 17 significant digits and floats with 9, so that parsing
// a row gives back exactly the published values (the integration test compares them with ==).
// csvHeader() names the columns in the order formatCsv() writes them: every field of the
// state, the 36 keypoints last as kp<k>_{e,n,u}_m (0 beyond keypoint_count). An event is either a
// state ("state") or the disposal of a track's instance ("disposed", only the key columns
// and the latency are meaningful). Latency = reception time - DDS source timestamp (frame
// capture time), in ms; it assumes drone and roadside clocks are synchronised (GNSS/PTP).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "messages/messages.hpp"

namespace vp::rsu {

enum class EventKind : std::uint8_t { State, Disposed };

const std::string& csvHeader();
std::string formatCsv(EventKind kind, const messages::VehicleState& state, double latency_ms);
std::string formatJson(EventKind kind, const messages::VehicleState& state, double latency_ms);

class LatencyStats {
 public:
  void add(double latency_ms) { samples_.push_back(latency_ms); }
  std::size_t count() const { return samples_.size(); }
  // "n=120 median=0.41 ms p99=1.20 ms max=2.03 ms" (or "n=0").
  std::string summary() const;

 private:
  std::vector<double> samples_;
};

}  // namespace vp::rsu
