#include "dds_link.hpp"

#include "loop_log.hpp"

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
  native_ = config.native.enabled;
  ros2_ = config.ros2.enabled;
  rosStatesOpen_ = config.ros2.enabled || config.autoware.enabled;
  if (!check(participant_.open(config), "participant")) {
    return false;
  }
  if (native_ && !(check(states_.open(participant_, config), "vehicle states") &&
                   check(status_.open(participant_, config), "drone status") &&
                   check(occupancy_.open(participant_, config), "occupancy"))) {
    return false;
  }
  if (rosStatesOpen_ && !check(rosStates_.open(participant_, config), "ROS 2 vehicle states")) {
    return false;
  }
  return !ros2_ || (check(rosStatus_.open(participant_, config), "ROS 2 drone status") &&
                    check(rosOccupancy_.open(participant_, config), "ROS 2 occupancy"));
}

bool DdsWriters::openTraffic(const config::DdsConfig& config,
                             const platform::dds::TrafficFeatureIdViews& ids,
                             const geodesy::LocalFrame& world, std::string* why) {
  std::string problem;
  const platform::dds::DdsResult result = traffic_.open(participant_, config, ids, world, &problem);
  if (!result.ok() && why) {
    *why = "dds traffic topics: " + (problem.empty() ? platform::dds::describe(result) : problem);
  }
  return result.ok();
}

platform::dds::PublishResult DdsWriters::publish(const messages::VehicleState& state) {
  platform::dds::PublishResult result;
  if (native_) {
    result = states_.publish(state);
  }
  if (rosStatesOpen_) {
    const platform::dds::PublishResult ros = rosStates_.add(state);
    if (result.ok()) {
      result = ros;
    }
  }
  return result;
}

platform::dds::FrameSummary DdsWriters::endFrame(std::int64_t time_ns) {
  platform::dds::FrameSummary summary;
  if (native_) {
    summary = states_.endFrame(time_ns);
  }
  if (rosStatesOpen_) {
    const platform::dds::Ros2FrameSummary ros = rosStates_.endFrame(time_ns);
    summary.errors += ros.errors;
    if (ros.errors > 0 && !rosErrorLogged_) {
      rosErrorLogged_ = true;
      logLine("writing the ROS 2 vehicle states failed: %s (further failures are only counted)",
              platform::dds::describe(ros.firstError).c_str());
    }
  }
  return summary;
}

platform::dds::DdsResult DdsWriters::writeStatus(const messages::DroneStatus& status) {
  platform::dds::DdsResult result;
  if (native_) {
    result = status_.write(status);
  }
  if (ros2_) {
    const platform::dds::DdsResult ros = rosStatus_.write(status);
    if (result.ok()) {
      result = ros;
    }
  }
  return result;
}

platform::dds::DdsResult DdsWriters::writeOccupancy(const messages::OccupancyGrid& grid) {
  platform::dds::DdsResult result;
  if (native_) {
    result = occupancy_.write(grid);
  }
  if (ros2_) {
    const platform::dds::DdsResult ros = rosOccupancy_.write(grid);
    if (result.ok()) {
      result = ros;
    }
  }
  return result;
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
