// platform/dds/perception_publisher: writers with preallocated samples.
#include "platform/dds/perception_publisher.hpp"

#include "platform/dds/conversion.hpp"

namespace vp::platform::dds {

const char* toString(PublishOutcome outcome) {
  switch (outcome) {
    case PublishOutcome::Written:
      return "written";
    case PublishOutcome::Skipped:
      return "skipped";
    case PublishOutcome::InvalidState:
      return "invalid state";
    case PublishOutcome::TableFull:
      return "too many published tracks";
    case PublishOutcome::DdsError:
      return "DDS error";
    case PublishOutcome::NotOpen:
      return "writer not open";
  }
  return "unknown";
}

DdsResult VehicleStatePublisher::open(const Participant& participant,
                                      const config::DdsConfig& config) {
  publishedCount_ = 0;
  DdsResult result = topic_.open(participant, vp_msg_VehicleState_desc,
                                 vehicleStateTopicName(config), config.vehicleState);
  if (!result.ok()) {
    return result;
  }
  return writer_.open(participant, topic_, config.vehicleState, config.partition);
}

std::size_t VehicleStatePublisher::find(std::uint32_t droneId, std::uint32_t trackId) const {
  for (std::size_t i = 0; i < publishedCount_; ++i) {
    if (published_[i].trackId == trackId && published_[i].droneId == droneId) {
      return i;
    }
  }
  return publishedCount_;
}

PublishResult VehicleStatePublisher::publish(const messages::VehicleState& state) {
  if (!writer_.isOpen()) {
    return PublishResult{PublishOutcome::NotOpen};
  }
  std::size_t index = find(state.droneId, state.trackId);
  const bool known = index < publishedCount_;
  if (!known && state.status == messages::TrackStatus::Tentative) {
    return PublishResult{PublishOutcome::Skipped};
  }
  if (const messages::ValidationError error = messages::validate(state);
      error != messages::ValidationError::None) {
    return PublishResult{PublishOutcome::InvalidState, {}, error};
  }
  if (!known) {
    if (publishedCount_ == kMaxTracks) {
      return PublishResult{PublishOutcome::TableFull};
    }
    index = publishedCount_++;
    published_[index] = Published{state.droneId, state.trackId, false};
  }
  published_[index].seenThisFrame = true;
  toSample(state, sample_);
  const dds_return_t rc = dds_write_ts(writer_.get(), &sample_, state.measurementTime_ns);
  if (rc < 0) {
    return PublishResult{PublishOutcome::DdsError, DdsResult::failure("dds_write_ts", rc)};
  }
  return PublishResult{};
}

DdsResult VehicleStatePublisher::disposeAt(std::size_t index, std::int64_t time_ns) {
  // Only the key fields of the sample matter for dispose and unregister.
  sample_.drone_id = published_[index].droneId;
  sample_.track_id = published_[index].trackId;
  published_[index] = published_[--publishedCount_];  // order does not matter
  dds_return_t rc = dds_dispose_ts(writer_.get(), &sample_, time_ns);
  if (rc < 0) {
    return DdsResult::failure("dds_dispose_ts", rc);
  }
  rc = dds_unregister_instance_ts(writer_.get(), &sample_, time_ns);
  if (rc < 0) {
    return DdsResult::failure("dds_unregister_instance_ts", rc);
  }
  return DdsResult{};
}

PublishResult VehicleStatePublisher::remove(std::uint32_t droneId, std::uint32_t trackId,
                                            std::int64_t time_ns) {
  if (!writer_.isOpen()) {
    return PublishResult{PublishOutcome::NotOpen};
  }
  const std::size_t index = find(droneId, trackId);
  if (index == publishedCount_) {
    return PublishResult{PublishOutcome::Skipped};
  }
  const DdsResult result = disposeAt(index, time_ns);
  if (!result.ok()) {
    return PublishResult{PublishOutcome::DdsError, result};
  }
  return PublishResult{};
}

FrameSummary VehicleStatePublisher::endFrame(std::int64_t time_ns) {
  FrameSummary summary;
  std::size_t i = 0;
  while (i < publishedCount_) {
    if (published_[i].seenThisFrame) {
      published_[i].seenThisFrame = false;
      ++i;
      continue;
    }
    // disposeAt moves the last entry into slot i, which is examined next.
    if (!disposeAt(i, time_ns).ok()) {
      ++summary.errors;
    }
    ++summary.disposed;
  }
  return summary;
}

DdsResult DroneStatusWriter::open(const Participant& participant, const config::DdsConfig& config) {
  DdsResult result = topic_.open(participant, vp_msg_DroneStatus_desc, droneStatusTopicName(config),
                                 config.droneStatus);
  if (!result.ok()) {
    return result;
  }
  return writer_.open(participant, topic_, config.droneStatus, config.partition);
}

DdsResult DroneStatusWriter::write(const messages::DroneStatus& status) {
  if (!writer_.isOpen()) {
    return DdsResult::failure("DroneStatusWriter::write (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  toSample(status, sample_);
  const dds_return_t rc = dds_write_ts(writer_.get(), &sample_, status.time_ns);
  return rc < 0 ? DdsResult::failure("dds_write_ts", rc) : DdsResult{};
}

DdsResult OccupancyWriter::open(const Participant& participant, const config::DdsConfig& config) {
  DdsResult result = topic_.open(participant, vp_msg_OccupancyGrid_desc, occupancyTopicName(config),
                                 config.occupancy);
  if (!result.ok()) {
    return result;
  }
  return writer_.open(participant, topic_, config.occupancy, config.partition);
}

DdsResult OccupancyWriter::write(const messages::OccupancyGrid& grid) {
  if (!writer_.isOpen()) {
    return DdsResult::failure("OccupancyWriter::write (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  if (messages::validate(grid) != messages::ValidationError::None) {
    return DdsResult::failure("OccupancyWriter::write (invalid grid)", DDS_RETCODE_BAD_PARAMETER);
  }
  toSample(grid, sample_);
  const dds_return_t rc = dds_write_ts(writer_.get(), &sample_, grid.time_ns);
  // The sample borrowed the grid's buffer; forget it so nothing can free or reuse it.
  sample_.cells._buffer = nullptr;
  sample_.cells._length = 0;
  sample_.cells._maximum = 0;
  return rc < 0 ? DdsResult::failure("dds_write_ts", rc) : DdsResult{};
}

}  // namespace vp::platform::dds
