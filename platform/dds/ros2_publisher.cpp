// platform/dds/ros2_publisher: ROS 2 topics with preallocated samples.
#include "platform/dds/ros2_publisher.hpp"

namespace vp::platform::dds {
namespace {

// The default partition: what every ROS 2 node uses.
const std::string kRosPartition;

DdsResult openRosWriter(const Participant& participant, const dds_topic_descriptor_t& descriptor,
                        const std::string& name, const config::QosProfile& profile, Topic& topic,
                        Writer& writer) {
  const DdsResult result = topic.open(participant, descriptor, name, profile);
  if (!result.ok()) {
    return result;
  }
  return writer.open(participant, topic, profile, kRosPartition);
}

DdsResult write(const Writer& writer, const void* sample, std::int64_t time_ns) {
  const dds_return_t rc = dds_write_ts(writer.get(), sample, time_ns);
  return rc < 0 ? DdsResult::failure("dds_write_ts", rc) : DdsResult{};
}

}  // namespace

std::string ros2TopicName(const config::Ros2Config& ros2, const char* name) {
  if (ros2.topicNamespace.empty()) {
    return std::string("rt/") + name;
  }
  return "rt/" + ros2.topicNamespace + "/" + name;
}

std::string autowareTopicName(const config::AutowareConfig& autoware) {
  return "rt" + autoware.topic;
}

DdsResult Ros2StatePublisher::open(const Participant& participant,
                                   const config::DdsConfig& config) {
  droneId_ = config.droneId;
  currentCount_ = 0;
  previousCount_ = 0;
  if (config.ros2.enabled) {
    array_.reserve(kMaxTracks, kMaxTracks, config.ros2.frameId);
    array_.begin(droneId_, 0);
    const DdsResult result = openRosWriter(participant, vp_msgs_msg_dds__VehicleStateArray__desc,
                                           ros2TopicName(config.ros2, "vehicle_states"),
                                           config.vehicleState, arrayTopic_, arrayWriter_);
    if (!result.ok()) {
      return result;
    }
  }
  if (config.autoware.enabled) {
    objects_.reserve(kMaxTracks, config.autoware.frameId,
                     ros2::AutowareOptions{config.autoware.stationarySpeed_mps});
    objects_.begin(0);
    const DdsResult result = openRosWriter(
        participant, autoware_perception_msgs_msg_dds__TrackedObjects__desc,
        autowareTopicName(config.autoware), config.vehicleState, autowareTopic_, autowareWriter_);
    if (!result.ok()) {
      return result;
    }
  }
  return DdsResult{};
}

bool Ros2StatePublisher::wasPublished(std::uint32_t trackId) const {
  for (std::size_t i = 0; i < previousCount_; ++i) {
    if (previous_[i] == trackId) {
      return true;
    }
  }
  return false;
}

bool Ros2StatePublisher::inFrame(std::uint32_t trackId) const {
  for (std::size_t i = 0; i < currentCount_; ++i) {
    if (current_[i] == trackId) {
      return true;
    }
  }
  return false;
}

PublishResult Ros2StatePublisher::add(const messages::VehicleState& state) {
  if (!isOpen()) {
    return PublishResult{PublishOutcome::NotOpen};
  }
  if (state.status == messages::TrackStatus::Tentative && !wasPublished(state.trackId)) {
    return PublishResult{PublishOutcome::Skipped};
  }
  if (const messages::ValidationError error = messages::validate(state);
      error != messages::ValidationError::None) {
    return PublishResult{PublishOutcome::InvalidState, {}, error};
  }
  if (currentCount_ == kMaxTracks || inFrame(state.trackId)) {
    // A second state of one track in a frame would be a caller's bug; it is refused as full.
    return PublishResult{PublishOutcome::TableFull};
  }
  if (arrayWriter_.isOpen() && !array_.add(state)) {
    return PublishResult{PublishOutcome::TableFull};
  }
  if (autowareWriter_.isOpen() && !objects_.add(state)) {
    return PublishResult{PublishOutcome::TableFull};
  }
  current_[currentCount_++] = state.trackId;
  return PublishResult{};
}

Ros2FrameSummary Ros2StatePublisher::endFrame(std::int64_t time_ns) {
  Ros2FrameSummary summary;
  const auto fail = [&summary](const DdsResult& result) {
    if (!result.ok() && summary.errors++ == 0) {
      summary.firstError = result;
    }
  };
  if (!isOpen()) {
    fail(DdsResult::failure("Ros2StatePublisher::endFrame (not open)",
                            DDS_RETCODE_PRECONDITION_NOT_MET));
    return summary;
  }
  // Tracks of the previous frame that are not in this one were deleted by the tracker.
  for (std::size_t i = 0; i < previousCount_; ++i) {
    if (!inFrame(previous_[i])) {
      if (arrayWriter_.isOpen() && !array_.addRemoved(previous_[i])) {
        fail(DdsResult::failure("VehicleStateArray.removed_track_ids (full)",
                                DDS_RETCODE_OUT_OF_RESOURCES));
        break;
      }
      ++summary.removed;
    }
  }
  summary.vehicles = static_cast<std::uint32_t>(currentCount_);
  if (arrayWriter_.isOpen()) {
    array_.setTime(time_ns);
    fail(write(arrayWriter_, &array_.sample(), time_ns));
    array_.begin(droneId_, time_ns);
  }
  if (autowareWriter_.isOpen()) {
    objects_.setTime(time_ns);
    fail(write(autowareWriter_, &objects_.sample(), time_ns));
    objects_.begin(time_ns);
  }
  previous_ = current_;
  previousCount_ = currentCount_;
  currentCount_ = 0;
  return summary;
}

DdsResult Ros2DroneStatusWriter::open(const Participant& participant,
                                      const config::DdsConfig& config) {
  sample_.reserve(config.ros2.frameId);
  return openRosWriter(participant, vp_msgs_msg_dds__DroneStatus__desc,
                       ros2TopicName(config.ros2, "drone_status"), config.droneStatus, topic_,
                       writer_);
}

DdsResult Ros2DroneStatusWriter::write(const messages::DroneStatus& status) {
  if (!writer_.isOpen()) {
    return DdsResult::failure("Ros2DroneStatusWriter::write (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  sample_.fill(status);
  return dds::write(writer_, &sample_.sample(), status.time_ns);
}

DdsResult Ros2OccupancyWriter::open(const Participant& participant,
                                    const config::DdsConfig& config) {
  sample_.reserve(static_cast<std::size_t>(config.grid.rows) * config.grid.cols,
                  config.ros2.frameId);
  return openRosWriter(participant, nav_msgs_msg_dds__OccupancyGrid__desc,
                       ros2TopicName(config.ros2, "occupancy"), config.occupancy, topic_, writer_);
}

DdsResult Ros2OccupancyWriter::write(const messages::OccupancyGrid& grid) {
  if (!writer_.isOpen()) {
    return DdsResult::failure("Ros2OccupancyWriter::write (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  if (messages::validate(grid) != messages::ValidationError::None || !sample_.fill(grid)) {
    return DdsResult::failure("Ros2OccupancyWriter::write (invalid grid or larger than configured)",
                              DDS_RETCODE_BAD_PARAMETER);
  }
  return dds::write(writer_, &sample_.sample(), grid.time_ns);
}

}  // namespace vp::platform::dds
