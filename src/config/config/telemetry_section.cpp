// config/telemetry_section: `telemetry:` (where the drone pose comes from) into the firmware
// app's TelemetryLinkConfig (config/loop_config.hpp).
#include <string>
#include <string_view>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kPortRange = Range::closed(0.0, 65535.0);
const Range kSystemIdRange = Range::closed(0.0, 255.0);
const Range kLinkLatencyRangeS = Range::closed(0.0, 1.0);
const Range kLookaheadRangeS = Range::closed(0.0, 10.0);

constexpr std::string_view kTelemetryKindNames =
    "recording, mavlink_udp, mavlink_serial, dds, none";
constexpr std::string_view kBaudNames =
    "9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600, 1000000, 1500000, "
    "2000000, 3000000";

std::optional<TelemetrySourceKind> telemetryKindFromString(const std::string& text) {
  return enumFromString(text,
                        std::array{TelemetrySourceKind::Recording, TelemetrySourceKind::MavlinkUdp,
                                   TelemetrySourceKind::MavlinkSerial, TelemetrySourceKind::Dds,
                                   TelemetrySourceKind::None},
                        [](TelemetrySourceKind kind) { return toString(kind); });
}
std::optional<int> baudFromString(const std::string& text) {
  for (const int baud : {9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600, 1000000,
                         1500000, 2000000, 3000000}) {
    if (text == std::to_string(baud)) {
      return baud;
    }
  }
  return std::nullopt;
}

}  // namespace

TelemetryLinkConfig readTelemetryLink(MapReader section) {
  const TelemetryLinkConfig d;
  TelemetryLinkConfig t;
  t.source = section.choice<TelemetrySourceKind>("source", telemetryKindFromString,
                                                 kTelemetryKindNames, d.source);
  t.udpBindAddress = section.text("udp_bind_address", d.udpBindAddress);
  t.udpPort = section.integer("udp_port", kPortRange, d.udpPort);
  t.serialDevice = section.text("serial_device", d.serialDevice);
  t.serialBaud = section.choice<int>("serial_baud", baudFromString, kBaudNames, d.serialBaud);
  t.systemId = section.integer("system_id", kSystemIdRange, d.systemId);
  t.geoidSeparation_m =
      section.number("geoid_separation_m", kAltitudeOffsetRange_m, d.geoidSeparation_m);
  t.linkLatency_s = section.number("link_latency_s", kLinkLatencyRangeS, d.linkLatency_s);
  t.replayLookahead_s = section.number("replay_lookahead_s", kLookaheadRangeS, d.replayLookahead_s);
  section.warnUnknownKeys();
  return t;
}

}  // namespace vp::config::detail
