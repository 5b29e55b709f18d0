// platform/dds/traffic_publisher: traffic statistics and events with preallocated samples.
#include "platform/dds/traffic_publisher.hpp"

#include <algorithm>
#include <cstring>
#include <memory>

#include "platform/dds/ros2_conversion.hpp"
#include "platform/dds/ros2_publisher.hpp"

namespace vp::platform::dds {
namespace {

const std::string kRosPartition;  // the default partition (ROS 2)

template <typename Sequence, typename T, std::size_t N>
void borrow(Sequence& sequence, std::array<T, N>& storage) {
  sequence._buffer = storage.data();
  sequence._maximum = static_cast<std::uint32_t>(N);
  sequence._length = 0;
  sequence._release = false;
}

template <std::size_t N>
void copyId(const FeatureIdText& id, char (&out)[N]) {
  static_assert(N == kMaxFeatureIdChars + 1);
  std::memcpy(out, id.data(), N);
}

// The report's statistics into either wire type (same member names in both).
template <typename Storage, typename Sample>
bool fillStatistics(const traffic::TrafficStatistics& s, const TrafficSampleIds& ids,
                    Storage& storage, Sample& sample) {
  borrow(sample.gates, storage.gates);
  borrow(sample.movements, storage.movements);
  borrow(sample.zones, storage.zones);
  borrow(sample.lanes, storage.lanes);
  sample.period = s.sequence;
  sample.start_ns = s.start_ns;
  sample.end_ns = s.end_ns;
  sample.wrong_way_events = s.wrongWayEvents;
  sample.box_junction_stops = s.boxJunctionStops;
  if (s.gateCount > std::min(traffic::kMaxReportGates, ids.gates.size()) ||
      s.zoneCount > std::min(traffic::kMaxReportZones, ids.zones.size()) ||
      s.laneCount > std::min(traffic::kMaxReportLanes, ids.lanes.size())) {
    return false;
  }
  for (std::size_t g = 0; g < s.gateCount; ++g) {
    const traffic::GateCountRecord& record = s.gates[g];
    if (record.gateIndex >= ids.gates.size()) {
      return false;
    }
    auto& out = storage.gates[g];
    copyId(ids.gates[record.gateIndex], out.gate_id);
    for (std::size_t t = 0; t < traffic::kReportTypeCount; ++t) {
      out.forward[t] = record.byDirectionAndType[0][t];
      out.backward[t] = record.byDirectionAndType[1][t];
    }
  }
  sample.gates._length = static_cast<std::uint32_t>(s.gateCount);
  std::uint32_t movements = 0;
  for (std::size_t from = 0; from < s.gateCount; ++from) {
    for (std::size_t to = 0; to < s.gateCount; ++to) {
      if (s.movements[from][to] == 0) {
        continue;
      }
      auto& out = storage.movements[movements++];
      copyId(ids.gates[from], out.from_gate_id);
      copyId(ids.gates[to], out.to_gate_id);
      out.count = s.movements[from][to];
    }
  }
  sample.movements._length = movements;
  for (std::size_t z = 0; z < s.zoneCount; ++z) {
    const traffic::ZoneRecord& r = s.zones[z];
    if (r.zoneIndex >= ids.zones.size()) {
      return false;
    }
    auto& out = storage.zones[z];
    copyId(ids.zones[r.zoneIndex], out.zone_id);
    out.vehicles_now = r.vehiclesNow;
    out.mean_vehicles = r.meanVehicles;
    out.max_vehicles = r.maxVehicles;
    out.queue_now_vehicles = r.queueNow_vehicles;
    out.max_queue_vehicles = r.maxQueue_vehicles;
    out.queue_now_m = r.queueNow_m;
    out.max_queue_m = r.maxQueue_m;
    out.dwell_count = r.dwellCount;
    out.mean_dwell_s = r.meanDwell_s;
    out.max_dwell_s = r.maxDwell_s;
  }
  sample.zones._length = static_cast<std::uint32_t>(s.zoneCount);
  for (std::size_t l = 0; l < s.laneCount; ++l) {
    const traffic::LaneRecord& r = s.lanes[l];
    if (r.laneIndex >= ids.lanes.size()) {
      return false;
    }
    auto& out = storage.lanes[l];
    copyId(ids.lanes[r.laneIndex], out.lane_id);
    out.vehicles = r.vehicles;
    out.mean_speed_mps = r.meanSpeed_mps;
    out.p85_speed_mps = r.p85Speed_mps;
    out.max_speed_mps = r.maxSpeed_mps;
  }
  sample.lanes._length = static_cast<std::uint32_t>(s.laneCount);
  return true;
}

// The ids an event names: feature (gate, lane or zone by kind) and destination gate.
bool eventIds(const traffic::TrafficEvent& e, const TrafficSampleIds& ids,
              const FeatureIdText** feature, const FeatureIdText** to) {
  const std::vector<FeatureIdText>* features = &ids.gates;
  if (e.kind == traffic::TrafficEventKind::WrongWay) {
    features = &ids.lanes;
  } else if (e.kind == traffic::TrafficEventKind::BoxJunctionStop) {
    features = &ids.zones;
  }
  static const FeatureIdText kEmpty{};
  if (e.featureIndex >= features->size()) {
    return false;
  }
  *feature = &(*features)[e.featureIndex];
  *to = &kEmpty;
  if (e.kind == traffic::TrafficEventKind::TurningMovement) {
    if (e.toFeatureIndex >= ids.gates.size()) {
      return false;
    }
    *to = &ids.gates[e.toFeatureIndex];
  }
  return static_cast<int>(e.type) < shape::kVehicleTypeCount &&
         static_cast<int>(e.kind) <= static_cast<int>(traffic::TrafficEventKind::TurningMovement);
}

DdsResult write(const Writer& writer, const void* sample, std::int64_t time_ns) {
  const dds_return_t rc = dds_write_ts(writer.get(), sample, time_ns);
  return rc < 0 ? DdsResult::failure("dds_write_ts", rc) : DdsResult{};
}

DdsResult openWriter(const Participant& participant, const dds_topic_descriptor_t& descriptor,
                     const std::string& name, const config::QosProfile& profile,
                     const std::string& partition, Topic& topic, Writer& writer) {
  const DdsResult result = topic.open(participant, descriptor, name, profile);
  if (!result.ok()) {
    return result;
  }
  return writer.open(participant, topic, profile, partition);
}

}  // namespace

std::string trafficStatisticsTopicName(const config::DdsConfig& config) {
  return config.topicPrefix + "/traffic_statistics";
}

std::string trafficEventsTopicName(const config::DdsConfig& config) {
  return config.topicPrefix + "/traffic_events";
}

bool makeSampleIds(const TrafficFeatureIdViews& ids, TrafficSampleIds* out, std::string* why) {
  const auto copy = [&](std::span<const std::string> from, std::vector<FeatureIdText>& to,
                        const char* kind) {
    to.assign(from.size(), FeatureIdText{});
    for (std::size_t i = 0; i < from.size(); ++i) {
      if (from[i].size() > kMaxFeatureIdChars) {
        if (why != nullptr) {
          *why = std::string("traffic topics: ") + kind + " id '" + from[i].substr(0, 80) +
                 "...' is longer than " + std::to_string(kMaxFeatureIdChars) + " bytes";
        }
        return false;
      }
      std::copy(from[i].begin(), from[i].end(), to[i].begin());
    }
    return true;
  };
  return copy(ids.gates, out->gates, "gate") && copy(ids.zones, out->zones, "zone") &&
         copy(ids.lanes, out->lanes, "lane");
}

bool toSample(const traffic::TrafficStatistics& statistics, const TrafficSampleIds& ids,
              std::uint32_t droneId, NativeStatisticsStorage& storage,
              vp_msg_TrafficStatistics& sample) {
  sample.drone_id = droneId;
  return fillStatistics(statistics, ids, storage, sample);
}

bool toRosSample(const traffic::TrafficStatistics& statistics, const TrafficSampleIds& ids,
                 std::uint32_t droneId, std::int64_t stampUtc_ns, RosStatisticsStorage& storage,
                 vp_msgs_msg_dds__TrafficStatistics_& sample) {
  sample.header.stamp = ros2::toRosTime(stampUtc_ns);
  sample.drone_id = droneId;
  return fillStatistics(statistics, ids, storage, sample);
}

bool toSample(const traffic::TrafficEvent& e, const TrafficSampleIds& ids, std::uint32_t droneId,
              const geodesy::GeodeticPoint& position, vp_msg_TrafficEvent& sample) {
  const FeatureIdText* feature = nullptr;
  const FeatureIdText* to = nullptr;
  if (!eventIds(e, ids, &feature, &to)) {
    return false;
  }
  sample.drone_id = droneId;
  sample.time_ns = e.time_ns;
  sample.kind = static_cast<vp_msg_TrafficEventKind>(e.kind);
  sample.track_id = e.trackId;
  copyId(*feature, sample.feature_id);
  copyId(*to, sample.to_feature_id);
  sample.direction = e.direction;
  sample.type = static_cast<vp_msg_VehicleType>(e.type);
  sample.speed_mps = static_cast<float>(e.speed_mps);
  sample.enu_m[0] = e.positionEnu_m.x();
  sample.enu_m[1] = e.positionEnu_m.y();
  sample.position = vp_msg_Wgs84Position{position.latitude_deg, position.longitude_deg, 0.0};
  return true;
}

bool toRosSample(const traffic::TrafficEvent& e, const TrafficSampleIds& ids, std::uint32_t droneId,
                 std::int64_t stampUtc_ns, const geodesy::GeodeticPoint& position,
                 vp_msgs_msg_dds__TrafficEvent_& sample) {
  const FeatureIdText* feature = nullptr;
  const FeatureIdText* to = nullptr;
  if (!eventIds(e, ids, &feature, &to)) {
    return false;
  }
  sample.header.stamp = ros2::toRosTime(stampUtc_ns);
  sample.drone_id = droneId;
  sample.time_ns = e.time_ns;
  sample.kind = static_cast<std::uint8_t>(e.kind);
  sample.track_id = e.trackId;
  copyId(*feature, sample.feature_id);
  copyId(*to, sample.to_feature_id);
  sample.direction = e.direction;
  sample.type = static_cast<std::uint8_t>(e.type);
  sample.speed_mps = static_cast<float>(e.speed_mps);
  sample.east_m = e.positionEnu_m.x();
  sample.north_m = e.positionEnu_m.y();
  sample.position =
      vp_msgs_msg_dds__GeodeticPoint_{position.latitude_deg, position.longitude_deg, 0.0};
  return true;
}

DdsResult TrafficPublisher::open(const Participant& participant, const config::DdsConfig& config,
                                 const TrafficFeatureIdViews& ids, const geodesy::LocalFrame& world,
                                 std::string* why) {
  if (!makeSampleIds(ids, &ids_, why)) {
    return DdsResult::failure("TrafficPublisher::open (feature id too long)",
                              DDS_RETCODE_BAD_PARAMETER);
  }
  droneId_ = config.droneId;
  world_ = world;
  frameId_ = config.ros2.frameId;
  if (config.native.enabled) {
    native_ = std::make_unique<NativeStatisticsStorage>();
    DdsResult result =
        openWriter(participant, vp_msg_TrafficStatistics_desc, trafficStatisticsTopicName(config),
                   config.trafficStatistics, config.partition, statisticsTopic_, statisticsWriter_);
    if (result.ok()) {
      result = openWriter(participant, vp_msg_TrafficEvent_desc, trafficEventsTopicName(config),
                          config.trafficEvents, config.partition, eventsTopic_, eventsWriter_);
    }
    if (!result.ok()) {
      return result;
    }
  }
  if (config.ros2.enabled) {
    ros_ = std::make_unique<RosStatisticsStorage>();
    rosStatistics_.header.frame_id = frameId_.data();
    rosEvent_.header.frame_id = frameId_.data();
    DdsResult result =
        openWriter(participant, vp_msgs_msg_dds__TrafficStatistics__desc,
                   ros2TopicName(config.ros2, "traffic_statistics"), config.trafficStatistics,
                   kRosPartition, rosStatisticsTopic_, rosStatisticsWriter_);
    if (result.ok()) {
      result = openWriter(participant, vp_msgs_msg_dds__TrafficEvent__desc,
                          ros2TopicName(config.ros2, "traffic_events"), config.trafficEvents,
                          kRosPartition, rosEventsTopic_, rosEventsWriter_);
    }
    if (!result.ok()) {
      return result;
    }
  }
  open_ = true;
  return DdsResult{};
}

DdsResult TrafficPublisher::writeStatistics(const traffic::TrafficStatistics& statistics,
                                            std::int64_t timeUtc_ns) {
  if (!open_) {
    return DdsResult::failure("TrafficPublisher::writeStatistics (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  DdsResult first{};
  if (statisticsWriter_.isOpen()) {
    if (!toSample(statistics, ids_, droneId_, *native_, statistics_)) {
      return DdsResult::failure("TrafficPublisher::writeStatistics (unknown feature)",
                                DDS_RETCODE_BAD_PARAMETER);
    }
    first = write(statisticsWriter_, &statistics_, timeUtc_ns);
  }
  if (rosStatisticsWriter_.isOpen()) {
    if (!toRosSample(statistics, ids_, droneId_, timeUtc_ns, *ros_, rosStatistics_)) {
      return DdsResult::failure("TrafficPublisher::writeStatistics (unknown feature)",
                                DDS_RETCODE_BAD_PARAMETER);
    }
    const DdsResult result = write(rosStatisticsWriter_, &rosStatistics_, timeUtc_ns);
    if (first.ok()) {
      first = result;
    }
  }
  return first;
}

DdsResult TrafficPublisher::writeEvent(const traffic::TrafficEvent& event,
                                       std::int64_t timeUtc_ns) {
  if (!open_) {
    return DdsResult::failure("TrafficPublisher::writeEvent (not open)",
                              DDS_RETCODE_PRECONDITION_NOT_MET);
  }
  const geodesy::GeodeticPoint position =
      world_.toGeodetic(Eigen::Vector3d(event.positionEnu_m.x(), event.positionEnu_m.y(), 0.0));
  DdsResult first{};
  if (eventsWriter_.isOpen()) {
    if (!toSample(event, ids_, droneId_, position, event_)) {
      return DdsResult::failure("TrafficPublisher::writeEvent (unknown feature)",
                                DDS_RETCODE_BAD_PARAMETER);
    }
    first = write(eventsWriter_, &event_, timeUtc_ns);
  }
  if (rosEventsWriter_.isOpen()) {
    if (!toRosSample(event, ids_, droneId_, timeUtc_ns, position, rosEvent_)) {
      return DdsResult::failure("TrafficPublisher::writeEvent (unknown feature)",
                                DDS_RETCODE_BAD_PARAMETER);
    }
    const DdsResult result = write(rosEventsWriter_, &rosEvent_, timeUtc_ns);
    if (first.ok()) {
      first = result;
    }
  }
  return first;
}

}  // namespace vp::platform::dds
