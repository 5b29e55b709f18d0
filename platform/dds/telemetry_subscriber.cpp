// platform/dds/telemetry_subscriber: readers of the ROS 2 telemetry topics.
#include "platform/dds/telemetry_subscriber.hpp"

namespace vp::platform::dds {

DdsResult TelemetrySubscriber::open(const Participant& participant,
                                    const config::TelemetryConfig& config) {
  readerCount_ = 0;
  counters_ = {};
  altitudeOffset_m_ = config.ardupilotAltitudeOffset_m;
  // Best effort + volatile is the weakest request, so it matches every ROS 2 writer (the PX4
  // agent writes best effort, ROS nodes often reliable); for a pose only the newest matters.
  config::QosProfile qos;
  qos.reliability = config::Reliability::BestEffort;
  qos.durability = config::Durability::Volatile;
  qos.historyDepth = config.historyDepth;
  DdsResult result;
  switch (config.source) {
    case config::TelemetrySource::None:
      return DdsResult::failure("TelemetrySubscriber::open (telemetry source is none)",
                                DDS_RETCODE_BAD_PARAMETER);
    case config::TelemetrySource::ArduPilot:
      result =
          openChannel(participant, Kind::GeoPose, geographic_msgs_msg_dds__GeoPoseStamped__desc,
                      config.ardupilotGeoPoseTopic, qos);
      break;
    case config::TelemetrySource::Px4:
      result = openChannel(participant, Kind::Px4Attitude, px4_msgs_msg_dds__VehicleAttitude__desc,
                           config.px4AttitudeTopic, qos);
      if (result.ok()) {
        result = openChannel(participant, Kind::Px4GlobalPosition,
                             px4_msgs_msg_dds__VehicleGlobalPosition__desc,
                             config.px4GlobalPositionTopic, qos);
      }
      break;
  }
  if (!result.ok()) {
    return result;
  }
  result = waitset_.adopt(dds_create_waitset(participant.get()), "dds_create_waitset");
  if (!result.ok()) {
    return result;
  }
  for (std::size_t i = 0; i < readerCount_; ++i) {
    // The condition belongs to the reader and is deleted with it.
    const dds_entity_t condition =
        dds_create_readcondition(readers_[i].reader.get(), DDS_ANY_STATE);
    if (condition < 0) {
      return DdsResult::failure("dds_create_readcondition", condition);
    }
    if (const dds_return_t rc = dds_waitset_attach(waitset_.get(), condition, condition); rc < 0) {
      return DdsResult::failure("dds_waitset_attach", rc);
    }
  }
  return DdsResult{};
}

DdsResult TelemetrySubscriber::openChannel(const Participant& participant, Kind kind,
                                           const dds_topic_descriptor_t& descriptor,
                                           const std::string& name, const config::QosProfile& qos) {
  Channel& channel = readers_[readerCount_];
  channel.kind = kind;
  DdsResult result = channel.topic.open(participant, descriptor, name, qos);
  if (!result.ok()) {
    return result;
  }
  result = channel.reader.open(participant, channel.topic, qos, "");  // default partition
  if (result.ok()) {
    ++readerCount_;
  }
  return result;
}

DdsResult TelemetrySubscriber::pollChannel(Channel& channel, PoseSink& sink,
                                           std::size_t* delivered) {
  void* samples[kTakeBatch];
  dds_sample_info_t infos[kTakeBatch];
  for (;;) {
    samples[0] = nullptr;  // loan: Cyclone lends its own buffers, nothing is allocated here
    const dds_return_t n = dds_take(channel.reader.get(), samples, infos, kTakeBatch, kTakeBatch);
    if (n < 0) {
      return DdsResult::failure("dds_take", n);
    }
    if (n == 0) {
      return DdsResult{};
    }
    for (dds_return_t k = 0; k < n; ++k) {
      if (!infos[k].valid_data) {
        continue;  // a writer left (no data)
      }
      PoseSample pose;
      TelemetryRejection rejection = TelemetryRejection::None;
      switch (channel.kind) {
        case Kind::GeoPose:
          rejection =
              fromGeoPose(*static_cast<const geographic_msgs_msg_dds__GeoPoseStamped_*>(samples[k]),
                          altitudeOffset_m_, pose);
          break;
        case Kind::Px4Attitude:
          rejection = fromPx4Attitude(
              *static_cast<const px4_msgs_msg_dds__VehicleAttitude_*>(samples[k]), pose);
          break;
        case Kind::Px4GlobalPosition:
          rejection = fromPx4GlobalPosition(
              *static_cast<const px4_msgs_msg_dds__VehicleGlobalPosition_*>(samples[k]), pose);
          break;
      }
      switch (rejection) {
        case TelemetryRejection::None:
          pose.sourceTimestamp_ns = infos[k].source_timestamp;
          ++counters_.delivered;
          if (delivered != nullptr) {
            ++*delivered;
          }
          sink.onPose(pose);
          break;
        case TelemetryRejection::NonFinite:
          ++counters_.nonFinite;
          break;
        case TelemetryRejection::NotUnitQuaternion:
          ++counters_.notUnitQuaternion;
          break;
        case TelemetryRejection::PositionOutOfRange:
          ++counters_.positionOutOfRange;
          break;
      }
    }
    if (const dds_return_t rc = dds_return_loan(channel.reader.get(), samples, n); rc < 0) {
      return DdsResult::failure("dds_return_loan", rc);
    }
  }
}

DdsResult TelemetrySubscriber::poll(PoseSink& sink, std::size_t* delivered) {
  if (delivered != nullptr) {
    *delivered = 0;
  }
  if (readerCount_ == 0) {
    return DdsResult::failure("TelemetrySubscriber::poll (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  for (std::size_t i = 0; i < readerCount_; ++i) {
    if (const DdsResult result = pollChannel(readers_[i], sink, delivered); !result.ok()) {
      return result;
    }
  }
  return DdsResult{};
}

DdsResult TelemetrySubscriber::wait(dds_duration_t timeout, bool* triggered) {
  if (!waitset_.isOpen()) {
    return DdsResult::failure("TelemetrySubscriber::wait (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  const dds_return_t rc = dds_waitset_wait(waitset_.get(), nullptr, 0, timeout);
  if (rc < 0) {
    return DdsResult::failure("dds_waitset_wait", rc);
  }
  if (triggered != nullptr) {
    *triggered = rc > 0;
  }
  return DdsResult{};
}

}  // namespace vp::platform::dds
