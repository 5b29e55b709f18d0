// tools/rsu_subscriber/qos_events: the QoS events of the vehicle-state reader that a roadside
// unit acts on: a track whose states stopped arriving within the topic's deadline (DDS
// "requested deadline missed") and a drone whose writer stopped asserting its liveliness or
// left (DDS "liveliness changed").
//
// Contract: QosEventMonitor::open() (start-up) creates a listener and a guard condition
// attached to the main loop's waitset; the listener is passed to dds_create_reader. Cyclone
// calls the listener on its own threads (one call per instance for deadline misses, one per
// change of a writer's liveliness); the callback only stamps the time (dds_time, UTC ns),
// queues the status under a mutex and triggers the guard condition, so the main loop wakes at
// once. The main loop reports every received vehicle-state sample to noteSample() (which
// instance handle and which writer belong to which drone and track, and their newest
// measurement time) and takes the queued events with drain(), resolved to the product's key.
// A deadline miss is reported once per instance until its next state arrives (Cyclone repeats
// it every deadline period); disposed instances are never reported (Cyclone stops their
// deadline). Return codes of every DDS call are checked; a failure inside a callback is queued
// as a message and printed by the main loop.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "platform/dds/dds_handles.hpp"

namespace vp::rsu {

enum class QosEventKind : std::uint8_t {
  DeadlineMissed,  // no state of the instance within the deadline
  WriterAlive,     // a vehicle-state writer matched or asserted its liveliness again
  WriterLost,      // a writer's liveliness lease expired, or the writer left while alive
};
const char* toString(QosEventKind kind);  // deadline_missed, writer_alive, writer_lost

// One event as printed: the key it concerns and the time since that key's newest state.
struct QosEventRow {
  QosEventKind kind = QosEventKind::DeadlineMissed;
  bool droneKnown = false;  // false: no state of that writer was received yet
  std::uint32_t droneId = 0;
  std::uint32_t trackId = 0;                // DeadlineMissed only
  std::int64_t lastMeasurementTime_ns = 0;  // newest state of the instance / writer; 0 if none
  std::int64_t eventTime_ns = 0;            // when Cyclone reported it (UTC ns)
  std::uint32_t deadlineMissedTotal = 0;    // reader's total count of misses (all instances)
  std::int32_t aliveWriters = 0;            // reader's writer counts after the change
  std::int32_t notAliveWriters = 0;
  // Event time - newest state's measurement time (ms); 0 when there was no state.
  double sinceLastState_ms() const;
};

// CSV row with the state rows' first five columns (event, drone_id, track_id,
// measurement_time_ns = newest state's time, latency_ms = time since it), padded with empty
// columns to `columns`; a JSON line with those keys and the counts.
std::string formatCsv(const QosEventRow& row, std::size_t columns);
std::string formatJson(const QosEventRow& row);
std::string describe(const QosEventRow& row);  // the stderr status line, without prefix

class QosEventMonitor {
 public:
  QosEventMonitor() = default;
  ~QosEventMonitor();
  QosEventMonitor(const QosEventMonitor&) = delete;
  QosEventMonitor& operator=(const QosEventMonitor&) = delete;

  // Start-up: the listener and a guard condition attached to `waitset`.
  platform::dds::DdsResult open(dds_entity_t participant, dds_entity_t waitset);
  const dds_listener_t* listener() const { return listener_; }

  // Every received sample of the vehicle-state reader: valid ones carry drone, track and
  // measurement time; a sample whose instance is no longer alive forgets the instance.
  void noteSample(const dds_sample_info_t& info, std::uint32_t droneId, std::uint32_t trackId,
                  std::int64_t measurementTime_ns);

  // The events queued since the last call (clears the guard condition). `reader` resolves an
  // instance whose state never reached noteSample (dds_instance_get_key). DDS failures, in
  // the callbacks or here, are appended to `errors`.
  std::vector<QosEventRow> drain(dds_entity_t reader, std::vector<std::string>* errors);

 private:
  struct Raw {
    QosEventKind kind;
    std::int64_t time_ns;
    dds_instance_handle_t handle;  // instance (deadline) or publication (liveliness)
    std::uint32_t total;
    std::int32_t alive;
    std::int32_t notAlive;
  };
  struct Instance {
    std::uint32_t droneId = 0;
    std::uint32_t trackId = 0;
    std::int64_t lastMeasurementTime_ns = 0;
    bool deadlineReported = false;
  };
  struct WriterInfo {
    std::uint32_t droneId = 0;
    std::int64_t lastMeasurementTime_ns = 0;
  };
  static void onDeadlineMissed(dds_entity_t reader, dds_requested_deadline_missed_status_t status,
                               void* self);
  static void onLivelinessChanged(dds_entity_t reader, dds_liveliness_changed_status_t status,
                                  void* self);
  void push(const Raw& raw);

  dds_listener_t* listener_ = nullptr;
  platform::dds::Entity guard_;
  std::mutex mutex_;  // guards queue_ and callbackErrors_ (written on Cyclone's threads)
  std::vector<Raw> queue_;
  std::vector<std::string> callbackErrors_;
  // Main thread only.
  std::map<dds_instance_handle_t, Instance> instances_;
  std::map<dds_instance_handle_t, WriterInfo> writers_;
};

}  // namespace vp::rsu
