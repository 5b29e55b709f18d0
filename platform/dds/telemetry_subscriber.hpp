// platform/dds/telemetry_subscriber: the drone's pose from the flight stack's ROS 2 bridge over
// DDS (ArduPilot DDS geopose, or PX4 uXRCE-DDS attitude + global position), as PoseSamples.
//
// Contract: open() creates the topics and best-effort, volatile KEEP_LAST readers on a
// participant in the bridge's domain (Participant::open(domainId): ROS 2 uses the default
// partition and no DDS Security), which match reliable and best-effort ROS 2 writers alike.
// It may allocate and may fail. After that, poll() takes every sample that has arrived, without
// blocking, converts it (platform/dds/telemetry_conversion.hpp) and hands each valid one to a
// PoseSink; rejected samples are only counted, per reason. poll() and wait() return failures as
// values, never throw, and our code does not allocate in them (samples are Cyclone's loans;
// tests/platform/dds measures it). A PoseRing is a caller-owned fixed-capacity sink that keeps the
// newest samples. Not thread-safe: poll and consume on one thread (or guard the sink).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "config/dds_config.hpp"
#include "platform/dds/dds_handles.hpp"
#include "platform/dds/telemetry_conversion.hpp"

namespace vp::platform::dds {

// Receives converted samples; called from poll(), on the polling thread.
class PoseSink {
 public:
  virtual void onPose(const PoseSample& sample) = 0;

 protected:
  ~PoseSink() = default;
};

// Keeps the newest Capacity samples, oldest first; a full ring overwrites its oldest sample
// (the newest pose is the one worth having) and counts it as overwritten.
template <std::size_t Capacity>
class PoseRing final : public PoseSink {
  static_assert(Capacity > 0);

 public:
  void onPose(const PoseSample& sample) override {
    if (size_ == Capacity) {
      head_ = (head_ + 1) % Capacity;
      --size_;
      ++overwritten_;
    }
    samples_[(head_ + size_) % Capacity] = sample;
    ++size_;
  }
  // Removes the oldest sample into *out; false when empty.
  bool pop(PoseSample* out) {
    if (size_ == 0) {
      return false;
    }
    *out = samples_[head_];
    head_ = (head_ + 1) % Capacity;
    --size_;
    return true;
  }
  std::size_t size() const { return size_; }
  std::uint64_t overwritten() const { return overwritten_; }

 private:
  std::array<PoseSample, Capacity> samples_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::uint64_t overwritten_ = 0;
};

struct TelemetryCounters {
  std::uint64_t delivered = 0;
  std::uint64_t nonFinite = 0;
  std::uint64_t notUnitQuaternion = 0;
  std::uint64_t positionOutOfRange = 0;
  std::uint64_t rejected() const { return nonFinite + notUnitQuaternion + positionOutOfRange; }
};

class TelemetrySubscriber {
 public:
  static constexpr std::size_t kMaxReaders = 2;  // PX4: attitude and global position
  static constexpr std::uint32_t kTakeBatch = 16;

  // Fails with DDS_RETCODE_BAD_PARAMETER for config.source == None.
  DdsResult open(const Participant& participant, const config::TelemetryConfig& config);
  // Converts and delivers whatever has arrived; *delivered (optional) counts this call's.
  DdsResult poll(PoseSink& sink, std::size_t* delivered = nullptr);
  // Blocks until a reader has data or the timeout (ns) passes; *triggered says which.
  DdsResult wait(dds_duration_t timeout, bool* triggered = nullptr);

  const TelemetryCounters& counters() const { return counters_; }
  std::size_t readerCount() const { return readerCount_; }
  dds_entity_t reader(std::size_t index) const { return readers_[index].reader.get(); }

 private:
  enum class Kind : std::uint8_t { GeoPose, Px4Attitude, Px4GlobalPosition };
  struct Channel {
    Kind kind = Kind::GeoPose;
    Topic topic;
    Reader reader;
  };
  DdsResult openChannel(const Participant& participant, Kind kind,
                        const dds_topic_descriptor_t& descriptor, const std::string& name,
                        const config::QosProfile& qos);
  DdsResult pollChannel(Channel& channel, PoseSink& sink, std::size_t* delivered);

  std::array<Channel, kMaxReaders> readers_{};
  std::size_t readerCount_ = 0;
  Entity waitset_;
  double altitudeOffset_m_ = 0.0;
  TelemetryCounters counters_{};
};

}  // namespace vp::platform::dds
