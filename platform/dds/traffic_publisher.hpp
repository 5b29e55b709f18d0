// platform/dds/traffic_publisher: the traffic analysis' outputs on DDS: each period's
// statistics and each event, as native topics (<prefix>/traffic_statistics and
// <prefix>/traffic_events: vp_perception.idl's TrafficStatistics and TrafficEvent, keyed by
// drone, in the configured partition) and as ROS 2 topics (rt/<ns>/traffic_statistics and
// rt/<ns>/traffic_events: vp_msgs/msg/TrafficStatistics and TrafficEvent, default partition),
// with the dds.qos.traffic_statistics / traffic_events profiles.
//
// Contract: the report types name features by index (the site's order of each kind); open()
// takes the site's feature ids (at most kMaxFeatureIdChars bytes each, else refused naming the
// id) and the world frame (the events' WGS84 positions), creates the enabled writers and
// allocates every sample buffer (start-up; may fail). toSample()/toRosSample() overwrite every
// field of a preallocated sample (sequences borrow the publisher's arrays, strings are copied
// into the samples' fixed arrays); writeStatistics()/writeEvent() neither allocate in our code
// nor throw: a report naming a feature beyond the ids is refused (BAD_PARAMETER), DDS errors
// are values. Times in the samples are the report's (the frame clock, as the CSV files); the
// DDS source timestamp is the UTC time the caller gives.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "config/dds_config.hpp"
#include "geodesy/geodesy.hpp"
#include "platform/dds/dds_handles.hpp"
#include "traffic/traffic_report.hpp"
#include "vp_msgs/msg/TrafficEvent_.h"
#include "vp_msgs/msg/TrafficStatistics_.h"
#include "vp_perception.h"

namespace vp::platform::dds {

constexpr std::size_t kMaxFeatureIdChars = 64;
constexpr std::size_t kMaxTrafficMovements = traffic::kMaxReportGates * traffic::kMaxReportGates;

// <prefix>/traffic_statistics, <prefix>/traffic_events.
std::string trafficStatisticsTopicName(const config::DdsConfig& config);
std::string trafficEventsTopicName(const config::DdsConfig& config);

// The site's feature ids of each kind, in the site's order (index i of a report names ids[i]).
struct TrafficFeatureIdViews {
  std::span<const std::string> gates;
  std::span<const std::string> zones;
  std::span<const std::string> lanes;
};

using FeatureIdText = std::array<char, kMaxFeatureIdChars + 1>;  // NUL-terminated

// The conversions, on the ids copied to fixed text (what the publisher holds).
struct TrafficSampleIds {
  std::vector<FeatureIdText> gates;
  std::vector<FeatureIdText> zones;
  std::vector<FeatureIdText> lanes;
};
// Copies the ids; false + *why naming an id that is too long.
bool makeSampleIds(const TrafficFeatureIdViews& ids, TrafficSampleIds* out, std::string* why);

// Storage the statistics samples' sequences borrow (both wire types' element types).
struct NativeStatisticsStorage {
  std::array<vp_msg_TrafficGateCount, traffic::kMaxReportGates> gates{};
  std::array<vp_msg_TrafficMovement, kMaxTrafficMovements> movements{};
  std::array<vp_msg_TrafficZone, traffic::kMaxReportZones> zones{};
  std::array<vp_msg_TrafficLane, traffic::kMaxReportLanes> lanes{};
};
struct RosStatisticsStorage {
  std::array<vp_msgs_msg_dds__TrafficGateCount_, traffic::kMaxReportGates> gates{};
  std::array<vp_msgs_msg_dds__TrafficMovement_, kMaxTrafficMovements> movements{};
  std::array<vp_msgs_msg_dds__TrafficZone_, traffic::kMaxReportZones> zones{};
  std::array<vp_msgs_msg_dds__TrafficLane_, traffic::kMaxReportLanes> lanes{};
};

// False (the sample partly written) when the report names a feature beyond ids.
bool toSample(const traffic::TrafficStatistics& statistics, const TrafficSampleIds& ids,
              std::uint32_t droneId, NativeStatisticsStorage& storage,
              vp_msg_TrafficStatistics& sample);
bool toSample(const traffic::TrafficEvent& event, const TrafficSampleIds& ids,
              std::uint32_t droneId, const geodesy::GeodeticPoint& position,
              vp_msg_TrafficEvent& sample);
// header.frame_id is left as it is (the publisher points it at its own text).
bool toRosSample(const traffic::TrafficStatistics& statistics, const TrafficSampleIds& ids,
                 std::uint32_t droneId, std::int64_t stampUtc_ns, RosStatisticsStorage& storage,
                 vp_msgs_msg_dds__TrafficStatistics_& sample);
bool toRosSample(const traffic::TrafficEvent& event, const TrafficSampleIds& ids,
                 std::uint32_t droneId, std::int64_t stampUtc_ns,
                 const geodesy::GeodeticPoint& position, vp_msgs_msg_dds__TrafficEvent_& sample);

class TrafficPublisher {
 public:
  TrafficPublisher() = default;
  TrafficPublisher(const TrafficPublisher&) = delete;  // the samples point into it
  TrafficPublisher& operator=(const TrafficPublisher&) = delete;

  // Opens the native writers when config.native.enabled, the ROS 2 ones when
  // config.ros2.enabled (at least one of them must be open for writes to go anywhere).
  DdsResult open(const Participant& participant, const config::DdsConfig& config,
                 const TrafficFeatureIdViews& ids, const geodesy::LocalFrame& world,
                 std::string* why);
  bool isOpen() const { return open_; }

  // One completed period (timeUtc_ns: the DDS source timestamp and ROS header stamp).
  DdsResult writeStatistics(const traffic::TrafficStatistics& statistics, std::int64_t timeUtc_ns);
  DdsResult writeEvent(const traffic::TrafficEvent& event, std::int64_t timeUtc_ns);

  dds_entity_t statisticsWriter() const { return statisticsWriter_.get(); }
  dds_entity_t eventsWriter() const { return eventsWriter_.get(); }
  dds_entity_t rosStatisticsWriter() const { return rosStatisticsWriter_.get(); }
  dds_entity_t rosEventsWriter() const { return rosEventsWriter_.get(); }

 private:
  bool open_ = false;
  std::uint32_t droneId_ = 0;
  geodesy::LocalFrame world_;
  TrafficSampleIds ids_;
  std::string frameId_;  // the ROS headers' frame_id (the samples point at it)
  Topic statisticsTopic_;
  Writer statisticsWriter_;
  Topic eventsTopic_;
  Writer eventsWriter_;
  Topic rosStatisticsTopic_;
  Writer rosStatisticsWriter_;
  Topic rosEventsTopic_;
  Writer rosEventsWriter_;
  // Large (the movement matrix): on the heap, allocated at open().
  std::unique_ptr<NativeStatisticsStorage> native_;
  std::unique_ptr<RosStatisticsStorage> ros_;
  vp_msg_TrafficStatistics statistics_{};
  vp_msg_TrafficEvent event_{};
  vp_msgs_msg_dds__TrafficStatistics_ rosStatistics_{};
  vp_msgs_msg_dds__TrafficEvent_ rosEvent_{};
};

}  // namespace vp::platform::dds
