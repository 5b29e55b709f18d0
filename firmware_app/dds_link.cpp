#include "dds_link.hpp"

namespace vp::app {

namespace {

constexpr std::int64_t kNsPer_ms = 1'000'000;

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

void DdsPoseInput::poll(std::int64_t /*frameTime_ns*/, telemetry::PoseBuffer& buffer) {
  const std::int64_t receive_ns = clock_.now_ns();
  const std::uint64_t rejectedBefore = subscriber_.counters().rejected();
  if (!subscriber_.poll(ring_).ok()) {
    ++counters_.readErrors;
  }
  counters_.linkRejected += subscriber_.counters().rejected() - rejectedBefore;
  platform::dds::PoseSample in;
  while (ring_.pop(&in)) {
    std::int64_t local_ns = 0;
    if (in.timeBase == platform::dds::TelemetryTimeBase::Utc) {
      local_ns = in.time_ns - monotonicToUtcNs_;
    } else {
      const auto boot_ms = static_cast<std::uint32_t>(in.time_ns / kNsPer_ms);
      bootClock_.observe(boot_ms, receive_ns);
      local_ns = bootClock_.toLocal_ns(boot_ms) + in.time_ns % kNsPer_ms;
    }
    if (in.hasPosition) {
      position_ = in.position;
      havePosition_ = true;
    }
    if (!in.hasAttitude || !havePosition_) {
      continue;  // PX4 position alone: kept for the next attitude
    }
    telemetry::PoseSample sample;
    sample.timestamp_ns = local_ns;
    sample.position = position_;
    sample.bodyToNed = in.bodyToNed;
    sample.gimbal = defaultGimbal_;
    push(sample, buffer);
  }
}

}  // namespace vp::app
