// tools/rsu_subscriber/qos_events: deadline and liveliness events of the vehicle-state reader.
#include "qos_events.hpp"

#include <cstdio>
#include <utility>

#include "vp_perception.h"

namespace vp::rsu {
namespace {

std::string number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

}  // namespace

const char* toString(QosEventKind kind) {
  switch (kind) {
    case QosEventKind::DeadlineMissed:
      return "deadline_missed";
    case QosEventKind::WriterAlive:
      return "writer_alive";
    case QosEventKind::WriterLost:
      return "writer_lost";
  }
  return "unknown";
}

double QosEventRow::sinceLastState_ms() const {
  if (lastMeasurementTime_ns == 0) {
    return 0.0;
  }
  return static_cast<double>(eventTime_ns - lastMeasurementTime_ns) * 1e-6;
}

std::string formatCsv(const QosEventRow& row, std::size_t columns) {
  std::string line = toString(row.kind);
  line += ',';
  line += row.droneKnown ? std::to_string(row.droneId) : "";
  line += ',';
  line += row.kind == QosEventKind::DeadlineMissed ? std::to_string(row.trackId) : "";
  line += ',';
  line += row.lastMeasurementTime_ns != 0 ? std::to_string(row.lastMeasurementTime_ns) : "";
  line += ',';
  line += row.lastMeasurementTime_ns != 0 ? number(row.sinceLastState_ms()) : "";
  for (std::size_t k = 5; k < columns; ++k) {
    line += ',';
  }
  return line;
}

std::string formatJson(const QosEventRow& row) {
  std::string line = "{\"event\":\"";
  line += toString(row.kind);
  line += "\",\"drone_id\":";
  line += row.droneKnown ? std::to_string(row.droneId) : "null";
  if (row.kind == QosEventKind::DeadlineMissed) {
    line += ",\"track_id\":" + std::to_string(row.trackId);
  }
  line += ",\"measurement_time_ns\":";
  line += row.lastMeasurementTime_ns != 0 ? std::to_string(row.lastMeasurementTime_ns) : "null";
  line += ",\"latency_ms\":";
  line += row.lastMeasurementTime_ns != 0 ? number(row.sinceLastState_ms()) : "null";
  line += ",\"event_time_ns\":" + std::to_string(row.eventTime_ns);
  if (row.kind == QosEventKind::DeadlineMissed) {
    line += ",\"deadline_missed_total\":" + std::to_string(row.deadlineMissedTotal);
  } else {
    line += ",\"alive_writers\":" + std::to_string(row.aliveWriters);
    line += ",\"not_alive_writers\":" + std::to_string(row.notAliveWriters);
  }
  return line + "}";
}

std::string describe(const QosEventRow& row) {
  char since[64] = "no state received";
  if (row.lastMeasurementTime_ns != 0) {
    std::snprintf(since, sizeof(since), "%.1f ms after its newest state", row.sinceLastState_ms());
  }
  const std::string drone = row.droneKnown ? std::to_string(row.droneId) : "(unknown)";
  switch (row.kind) {
    case QosEventKind::DeadlineMissed:
      return "deadline missed: drone " + drone + " track " + std::to_string(row.trackId) + ", " +
             since + " (" + std::to_string(row.deadlineMissedTotal) + " misses in total)";
    case QosEventKind::WriterAlive:
      return "writer alive: drone " + drone + " (" + std::to_string(row.aliveWriters) + " alive, " +
             std::to_string(row.notAliveWriters) + " not alive)";
    case QosEventKind::WriterLost:
      return "writer lost: drone " + drone + ", " + since + " (" +
             std::to_string(row.aliveWriters) + " alive, " + std::to_string(row.notAliveWriters) +
             " not alive)";
  }
  return "unknown event";
}

QosEventMonitor::~QosEventMonitor() {
  if (listener_ != nullptr) {
    dds_delete_listener(listener_);
  }
}

platform::dds::DdsResult QosEventMonitor::open(dds_entity_t participant, dds_entity_t waitset) {
  using platform::dds::DdsResult;
  listener_ = dds_create_listener(this);
  if (listener_ == nullptr) {
    return DdsResult::failure("dds_create_listener", DDS_RETCODE_OUT_OF_RESOURCES);
  }
  // reset_on_invoke: each call carries one change, the status' *_change fields restart at 0.
  if (const dds_return_t rc =
          dds_lset_requested_deadline_missed_arg(listener_, onDeadlineMissed, this, true);
      rc < 0) {
    return DdsResult::failure("dds_lset_requested_deadline_missed_arg", rc);
  }
  if (const dds_return_t rc =
          dds_lset_liveliness_changed_arg(listener_, onLivelinessChanged, this, true);
      rc < 0) {
    return DdsResult::failure("dds_lset_liveliness_changed_arg", rc);
  }
  if (DdsResult r =
          guard_.adopt(dds_create_guardcondition(participant), "dds_create_guardcondition");
      !r.ok()) {
    return r;
  }
  if (const dds_return_t rc = dds_waitset_attach(waitset, guard_.get(), 0); rc < 0) {
    return DdsResult::failure("dds_waitset_attach (guard condition)", rc);
  }
  return DdsResult{};
}

void QosEventMonitor::push(const Raw& raw) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.push_back(raw);
  if (const dds_return_t rc = dds_set_guardcondition(guard_.get(), true); rc < 0) {
    callbackErrors_.push_back(std::string("dds_set_guardcondition: ") + dds_strretcode(rc));
  }
}

void QosEventMonitor::onDeadlineMissed(dds_entity_t, dds_requested_deadline_missed_status_t status,
                                       void* self) {
  static_cast<QosEventMonitor*>(self)->push(Raw{QosEventKind::DeadlineMissed, dds_time(),
                                                status.last_instance_handle, status.total_count, 0,
                                                0});
}

void QosEventMonitor::onLivelinessChanged(dds_entity_t, dds_liveliness_changed_status_t status,
                                          void* self) {
  // alive +1: a writer matched alive or regained its liveliness; alive -1: its lease expired
  // (not_alive +1) or it left while alive. A not-alive writer that leaves changes only
  // not_alive_count: nothing more to report, it was reported lost already.
  QosEventKind kind;
  if (status.alive_count_change > 0) {
    kind = QosEventKind::WriterAlive;
  } else if (status.alive_count_change < 0) {
    kind = QosEventKind::WriterLost;
  } else {
    return;
  }
  static_cast<QosEventMonitor*>(self)->push(Raw{kind, dds_time(), status.last_publication_handle, 0,
                                                static_cast<std::int32_t>(status.alive_count),
                                                static_cast<std::int32_t>(status.not_alive_count)});
}

void QosEventMonitor::noteSample(const dds_sample_info_t& info, std::uint32_t droneId,
                                 std::uint32_t trackId, std::int64_t measurementTime_ns) {
  if (info.valid_data) {
    Instance& instance = instances_[info.instance_handle];
    instance = Instance{droneId, trackId, measurementTime_ns, false};
    writers_[info.publication_handle] = WriterInfo{droneId, measurementTime_ns};
  }
  if (info.instance_state != DDS_IST_ALIVE) {
    instances_.erase(info.instance_handle);  // disposed or without writers: no deadline any more
  }
}

std::vector<QosEventRow> QosEventMonitor::drain(dds_entity_t reader,
                                                std::vector<std::string>* errors) {
  std::vector<Raw> raw;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    raw.swap(queue_);
    for (std::string& e : callbackErrors_) {
      errors->push_back(std::move(e));
    }
    callbackErrors_.clear();
    if (const dds_return_t rc = dds_set_guardcondition(guard_.get(), false); rc < 0) {
      errors->push_back(std::string("dds_set_guardcondition: ") + dds_strretcode(rc));
    }
  }
  std::vector<QosEventRow> rows;
  for (const Raw& r : raw) {
    QosEventRow row;
    row.kind = r.kind;
    row.eventTime_ns = r.time_ns;
    row.deadlineMissedTotal = r.total;
    row.aliveWriters = r.alive;
    row.notAliveWriters = r.notAlive;
    if (r.kind == QosEventKind::DeadlineMissed) {
      auto it = instances_.find(r.handle);
      if (it == instances_.end()) {
        // Its state was not taken yet (or it was forgotten): ask the reader for the key.
        vp_msg_VehicleState key{};
        const dds_return_t rc = dds_instance_get_key(reader, r.handle, &key);
        if (rc < 0) {
          errors->push_back("deadline missed for instance " + std::to_string(r.handle) +
                            ": dds_instance_get_key: " + dds_strretcode(rc));
          continue;
        }
        it = instances_.emplace(r.handle, Instance{key.drone_id, key.track_id, 0, false}).first;
        dds_sample_free(&key, &vp_msg_VehicleState_desc, DDS_FREE_CONTENTS);
      }
      if (it->second.deadlineReported) {
        continue;  // Cyclone repeats the miss every period; once per silence is enough
      }
      it->second.deadlineReported = true;
      row.droneKnown = true;
      row.droneId = it->second.droneId;
      row.trackId = it->second.trackId;
      row.lastMeasurementTime_ns = it->second.lastMeasurementTime_ns;
    } else if (const auto it = writers_.find(r.handle); it != writers_.end()) {
      row.droneKnown = true;
      row.droneId = it->second.droneId;
      row.lastMeasurementTime_ns = it->second.lastMeasurementTime_ns;
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace vp::rsu
