#include "traffic/traffic_report.hpp"

namespace vp::traffic {

const char* toString(TrafficEventKind kind) {
  switch (kind) {
    case TrafficEventKind::GateCrossing:
      return "gate_crossing";
    case TrafficEventKind::WrongWay:
      return "wrong_way";
    case TrafficEventKind::BoxJunctionStop:
      return "box_junction_stop";
    case TrafficEventKind::TurningMovement:
      return "turning_movement";
  }
  return "unknown";
}

}  // namespace vp::traffic
