// platform/dds/perception_publisher: the drone's three writers: vehicle states (one DDS
// instance per track), drone status and the occupancy grid.
//
// Contract: open() creates the topic and writer (start-up; may allocate, may fail). After
// that, publish()/write()/remove()/endFrame() neither allocate in our code (samples and the
// table of published tracks are preallocated; tests/platform/dds measures it) nor throw: errors are
// returned as values. DDS source timestamps are the states' measurement times (frame capture
// time, UTC ns), so receivers measure latency from capture.
// Instance life cycle of VehicleStatePublisher: a track is written once it is Confirmed, and
// keeps being written (also as Lost, while the tracker coasts it) until it is deleted; then its
// instance is disposed and unregistered, which readers see as NOT_ALIVE_DISPOSED. Tentative
// tracks are never published. Deletion is either explicit (remove()) or implied by the frame
// protocol: publish() every current track, then endFrame() disposes every published track
// that was not in the frame. At most kMaxTracks tracks are published at once.
#pragma once

#include <array>
#include <cstdint>

#include "config/dds_config.hpp"
#include "messages/messages.hpp"
#include "platform/dds/dds_handles.hpp"
#include "vp_perception.h"

namespace vp::platform::dds {

enum class PublishOutcome : std::uint8_t {
  Written,
  Skipped,       // tentative track (never published yet)
  InvalidState,  // failed messages::validate(); nothing was written
  TableFull,     // more than kMaxTracks published tracks
  DdsError,      // see PublishResult::dds
  NotOpen,
};
const char* toString(PublishOutcome outcome);

struct PublishResult {
  PublishOutcome outcome = PublishOutcome::Written;
  DdsResult dds{};
  messages::ValidationError validation = messages::ValidationError::None;
  bool ok() const {
    return outcome == PublishOutcome::Written || outcome == PublishOutcome::Skipped;
  }
};

struct FrameSummary {
  std::uint32_t disposed = 0;
  std::uint32_t errors = 0;
};

class VehicleStatePublisher {
 public:
  static constexpr std::size_t kMaxTracks = 1024;

  DdsResult open(const Participant& participant, const config::DdsConfig& config);

  PublishResult publish(const messages::VehicleState& state);
  // Disposes and unregisters one published track (no-op returning Skipped if not published).
  PublishResult remove(std::uint32_t droneId, std::uint32_t trackId, std::int64_t time_ns);
  // Disposes every published track not passed to publish() since the previous endFrame().
  FrameSummary endFrame(std::int64_t time_ns);

  std::size_t publishedCount() const { return publishedCount_; }
  dds_entity_t writer() const { return writer_.get(); }

 private:
  struct Published {
    std::uint32_t droneId = 0;
    std::uint32_t trackId = 0;
    bool seenThisFrame = false;
  };
  std::size_t find(std::uint32_t droneId, std::uint32_t trackId) const;  // publishedCount_ if none
  DdsResult disposeAt(std::size_t index, std::int64_t time_ns);          // also removes the entry

  Topic topic_;
  Writer writer_;
  vp_msg_VehicleState sample_{};
  std::array<Published, kMaxTracks> published_{};
  std::size_t publishedCount_ = 0;
};

class DroneStatusWriter {
 public:
  DdsResult open(const Participant& participant, const config::DdsConfig& config);
  DdsResult write(const messages::DroneStatus& status);
  dds_entity_t writer() const { return writer_.get(); }

 private:
  Topic topic_;
  Writer writer_;
  vp_msg_DroneStatus sample_{};
};

class OccupancyWriter {
 public:
  DdsResult open(const Participant& participant, const config::DdsConfig& config);
  DdsResult write(const messages::OccupancyGrid& grid);
  dds_entity_t writer() const { return writer_.get(); }

 private:
  Topic topic_;
  Writer writer_;
  vp_msg_OccupancyGrid sample_{};
};

}  // namespace vp::platform::dds
