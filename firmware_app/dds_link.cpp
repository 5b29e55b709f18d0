#include "dds_link.hpp"

namespace vp::app {

namespace {

constexpr std::int64_t kNsPerMs = 1'000'000;

}  // namespace

bool DdsWriters::open(const config::DdsConfig& config, std::string* why) {
  namespace dds = platform::dds;
  const auto check = [&](const dds::DdsResult& result, const char* what) {
    if (!result.ok() && why) {
      *why = std::string("dds ") + what + ": " + dds::describe(result);
    }
    return result.ok();
  };
  return check(participant_.open(config), "participant") &&
         check(states_.open(participant_, config), "vehicle states") &&
         check(status_.open(participant_, config), "drone status") &&
         check(occupancy_.open(participant_, config), "occupancy");
}

bool DdsPoseInput::open(const config::TelemetryConfig& config, std::string* why) {
  namespace dds = platform::dds;
  dds::DdsResult result = participant_.open(config.domainId);
  if (result.ok()) {
    result = subscriber_.open(participant_, config);
  }
  if (!result.ok() && why) {
    *why = std::string("dds telemetry (") + config::toString(config.source) +
           "): " + dds::describe(result);
  }
  return result.ok();
}

void DdsPoseInput::poll(std::int64_t /*frameTimeNs*/, telemetry::PoseBuffer& buffer) {
  const std::int64_t receiveNs = clock_.nowNs();
  const std::uint64_t rejectedBefore = subscriber_.counters().rejected();
  if (!subscriber_.poll(ring_).ok()) {
    ++counters_.readErrors;
  }
  counters_.linkRejected += subscriber_.counters().rejected() - rejectedBefore;
  platform::dds::PoseSample in;
  while (ring_.pop(&in)) {
    std::int64_t localNs = 0;
    if (in.timeBase == platform::dds::TelemetryTimeBase::Utc) {
      localNs = in.time_ns - monotonicToUtcNs_;
    } else {
      const auto bootMs = static_cast<std::uint32_t>(in.time_ns / kNsPerMs);
      bootClock_.observe(bootMs, receiveNs);
      localNs = bootClock_.toLocalNs(bootMs) + in.time_ns % kNsPerMs;
    }
    if (in.hasPosition) {
      position_ = in.position;
      havePosition_ = true;
    }
    if (!in.hasAttitude || !havePosition_) {
      continue;  // PX4 position alone: kept for the next attitude
    }
    telemetry::PoseSample sample;
    sample.timestampNs = localNs;
    sample.position = position_;
    sample.bodyToNed = in.bodyToNed;
    sample.gimbal = defaultGimbal_;
    push(sample, buffer);
  }
}

}  // namespace vp::app
