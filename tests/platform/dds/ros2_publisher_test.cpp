// The ROS 2 outputs over loopback: our publisher writes known states, a drone status and a grid;
// vp_test_ros2_reader (a separate process built only from the generated C types and ddsc, as
// a ROS 2 node on rmw_cyclonedds reads: default partition, plain CDR only) prints every field
// it receives, and each is compared with what was sent, converted here by hand from the
// documented mapping (docs/dds.md, "ROS 2 and Autoware"). Plus: our conversion path allocates
// nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "dds_test_support.hpp"
#include "platform/dds/ros2_conversion.hpp"
#include "platform/dds/ros2_publisher.hpp"

namespace vp::platform::dds {
namespace {

using namespace std::chrono_literals;
using Fields = std::map<std::string, std::string>;

bool waitForMatch(dds_entity_t writer, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(writer, &status) >= 0 && status.current_count >= 1) {
      return true;
    }
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

// The reader's printing rules: doubles %.17g, floats %.9g, integers in decimal.
std::string text(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}
std::string textF(float value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.9g", static_cast<double>(value));
  return buffer;
}
std::string textI(long long value) {
  return std::to_string(value);
}

// Every field of a state, non-zero, including UTM, rear axle, variances and keypoints.
messages::VehicleState fullState(std::uint32_t trackId, std::int64_t time_ns, bool large) {
  messages::VehicleState s = test::makeState(trackId, time_ns);
  s.headingEnu_rad = 0.7 + 0.01 * trackId;
  s.poseCovariance = {0.04F, 0.001F, 0.002F, 0.05F, -0.003F, 0.006F};
  s.utmZone = 16;
  s.utmNorthernHemisphere = true;
  s.utmEasting_m = 305'123.625 + trackId;
  s.utmNorthing_m = 4'771'234.5 - trackId;
  s.rearAxleEnu_m = {1.25 * trackId - 1.4, -2.5 * trackId - 0.2, 0.1};
  s.rearAxlePosition = {43.07309 + 1e-6 * trackId, -89.40121, 250.0625};
  s.lengthVariance_m2 = 0.0625F;
  s.widthVariance_m2 = 0.015625F;
  if (large) {
    s.type = shape::VehicleType::Large;
    s.typeProbability = {0.01F, 0.02F, 0.01F, 0.05F, 0.03F, 0.08F, 0.8F};
    s.shape.count = 0;
    s.keypointCount = 0;
    s.status = messages::TrackStatus::Lost;
    s.speed_mps = 0.25F;  // below the stationary threshold
    s.length_m = 12.0F;
    s.width_m = 2.55F;
    s.height_m = 3.2F;
  } else {
    s.type = shape::VehicleType::Suv;
    s.keypointCount = shape::kKeypointCount;
    for (int k = 0; k < shape::kKeypointCount; ++k) {
      const auto kf = static_cast<float>(k);
      s.keypointsEnu_m[static_cast<std::size_t>(k)] = {0.5F * kf, -0.25F * kf, 0.03125F * kf};
    }
  }
  return s;
}

void putTime(Fields& f, const std::string& key, std::int64_t time_ns) {
  f[key + ".sec"] = textI(time_ns / 1'000'000'000);
  f[key + ".nanosec"] = textI(time_ns % 1'000'000'000);
}

void putHeader(Fields& f, const std::string& topic, std::int64_t time_ns,
               const std::string& frame) {
  putTime(f, topic + ".header.stamp", time_ns);
  f[topic + ".header.frame_id"] = frame;
}

void putGeodetic(Fields& f, const std::string& key, const geodesy::GeodeticPoint& p) {
  f[key + ".latitude_deg"] = text(p.latitude_deg);
  f[key + ".longitude_deg"] = text(p.longitude_deg);
  f[key + ".height_m"] = text(p.height_m);
}

void putPoint(Fields& f, const std::string& key, double x, double y, double z) {
  f[key + ".x"] = text(x);
  f[key + ".y"] = text(y);
  f[key + ".z"] = text(z);
}

void putState(Fields& f, const std::string& key, const messages::VehicleState& s) {
  f[key + ".drone_id"] = textI(s.droneId);
  f[key + ".track_id"] = textI(s.trackId);
  putTime(f, key + ".measurement_time", s.measurementTime_ns);
  f[key + ".track_age_s"] = textF(s.trackAge_s);
  putGeodetic(f, key + ".position", s.position);
  putPoint(f, key + ".enu_m", s.enu_m[0], s.enu_m[1], s.enu_m[2]);
  f[key + ".heading_enu_rad"] = text(s.headingEnu_rad);
  f[key + ".heading_true_north_deg"] = text(s.headingTrueNorth_deg);
  f[key + ".speed_mps"] = textF(s.speed_mps);
  f[key + ".velocity_enu_mps.0"] = textF(s.velocityEnu_mps[0]);
  f[key + ".velocity_enu_mps.1"] = textF(s.velocityEnu_mps[1]);
  f[key + ".yaw_rate_radps"] = textF(s.yawRate_radps);
  f[key + ".acceleration_mps2"] = textF(s.acceleration_mps2);
  f[key + ".length_m"] = textF(s.length_m);
  f[key + ".width_m"] = textF(s.width_m);
  f[key + ".height_m"] = textF(s.height_m);
  f[key + ".type"] = textI(static_cast<int>(s.type));
  for (std::size_t k = 0; k < s.typeProbability.size(); ++k) {
    f[key + ".type_probability." + std::to_string(k)] = textF(s.typeProbability[k]);
  }
  f[key + ".asm_gamma.length"] = textI(s.shape.count);
  for (int k = 0; k < s.shape.count; ++k) {
    f[key + ".asm_gamma." + std::to_string(k)] = textF(s.shape.gamma[static_cast<std::size_t>(k)]);
  }
  for (std::size_t k = 0; k < 6; ++k) {
    f[key + ".pose_covariance." + std::to_string(k)] = textF(s.poseCovariance[k]);
  }
  f[key + ".height_variance_m2"] = textF(s.heightVariance_m2);
  f[key + ".speed_variance_m2ps2"] = textF(s.speedVariance_m2ps2);
  f[key + ".yaw_rate_variance_rad2ps2"] = textF(s.yawRateVariance_rad2ps2);
  f[key + ".detection_confidence"] = textF(s.detectionConfidence);
  f[key + ".status"] = textI(static_cast<int>(s.status));
  f[key + ".utm_zone"] = textI(s.utmZone);
  f[key + ".utm_northern_hemisphere"] = textI(s.utmNorthernHemisphere ? 1 : 0);
  f[key + ".utm_easting_m"] = text(s.utmEasting_m);
  f[key + ".utm_northing_m"] = text(s.utmNorthing_m);
  putPoint(f, key + ".rear_axle_enu_m", s.rearAxleEnu_m[0], s.rearAxleEnu_m[1], s.rearAxleEnu_m[2]);
  putGeodetic(f, key + ".rear_axle_position", s.rearAxlePosition);
  f[key + ".length_variance_m2"] = textF(s.lengthVariance_m2);
  f[key + ".width_variance_m2"] = textF(s.widthVariance_m2);
  f[key + ".keypoints_enu_m.length"] = textI(s.keypointCount);
  for (int k = 0; k < s.keypointCount; ++k) {
    const auto& p = s.keypointsEnu_m[static_cast<std::size_t>(k)];
    putPoint(f, key + ".keypoints_enu_m." + std::to_string(k), static_cast<double>(p[0]),
             static_cast<double>(p[1]), static_cast<double>(p[2]));
  }
}

// Autoware's view of a state, from the mapping table of docs/dds.md.
void putObject(Fields& f, const std::string& key, const messages::VehicleState& s) {
  const std::uint8_t uuid[16] = {0,
                                 0,
                                 0,
                                 static_cast<std::uint8_t>(s.droneId),
                                 'v',
                                 'p',
                                 0x80,
                                 0,
                                 0x80,
                                 0,
                                 0,
                                 0,
                                 0,
                                 0,
                                 static_cast<std::uint8_t>(s.trackId >> 8),
                                 static_cast<std::uint8_t>(s.trackId)};
  for (int k = 0; k < 16; ++k) {
    f[key + ".object_id.uuid." + std::to_string(k)] = textI(uuid[k]);
  }
  f[key + ".existence_probability"] = textF(s.detectionConfidence);
  float car = 0.0F;
  for (int k = 0; k < shape::kCarTypeCount; ++k) {
    car += s.typeProbability[static_cast<std::size_t>(k)];
  }
  const float large = s.typeProbability[6];
  const bool truckFirst = large > car;
  f[key + ".classification.length"] = "2";
  f[key + ".classification.0.label"] = truckFirst ? "2" : "1";  // TRUCK : CAR
  f[key + ".classification.0.probability"] = textF(truckFirst ? large : car);
  f[key + ".classification.1.label"] = truckFirst ? "1" : "2";
  f[key + ".classification.1.probability"] = textF(truckFirst ? car : large);
  const std::string kin = key + ".kinematics";
  putPoint(f, kin + ".pose_with_covariance.pose.position", s.enu_m[0], s.enu_m[1],
           s.enu_m[2] + 0.5 * static_cast<double>(s.height_m));
  putPoint(f, kin + ".pose_with_covariance.pose.orientation", 0.0, 0.0,
           std::sin(0.5 * s.headingEnu_rad));
  f[kin + ".pose_with_covariance.pose.orientation.w"] = text(std::cos(0.5 * s.headingEnu_rad));
  std::vector<double> pose(36, 0.0);
  const auto& c = s.poseCovariance;
  pose[0] = c[0];
  pose[1] = pose[6] = c[1];
  pose[5] = pose[30] = c[2];
  pose[7] = c[3];
  pose[11] = pose[31] = c[4];
  pose[35] = c[5];
  pose[14] = static_cast<double>(s.heightVariance_m2) / 4.0;
  std::vector<double> twist(36, 0.0);
  twist[0] = s.speedVariance_m2ps2;
  twist[35] = s.yawRateVariance_rad2ps2;
  for (int k = 0; k < 36; ++k) {
    const std::string i = "." + std::to_string(k);
    f[kin + ".pose_with_covariance.covariance" + i] = text(pose[static_cast<std::size_t>(k)]);
    f[kin + ".twist_with_covariance.covariance" + i] = text(twist[static_cast<std::size_t>(k)]);
    f[kin + ".acceleration_with_covariance.covariance" + i] = "0";
  }
  putPoint(f, kin + ".twist_with_covariance.twist.linear", static_cast<double>(s.speed_mps), 0, 0);
  putPoint(f, kin + ".twist_with_covariance.twist.angular", 0, 0,
           static_cast<double>(s.yawRate_radps));
  putPoint(f, kin + ".acceleration_with_covariance.accel.linear",
           static_cast<double>(s.acceleration_mps2), 0, 0);
  putPoint(f, kin + ".acceleration_with_covariance.accel.angular", 0, 0, 0);
  f[kin + ".orientation_availability"] = "2";  // AVAILABLE
  f[kin + ".is_stationary"] = std::fabs(s.speed_mps) < 0.5F ? "1" : "0";
  f[key + ".shape.type"] = "0";  // BOUNDING_BOX
  f[key + ".shape.footprint.points.length"] = "4";
  const double l = static_cast<double>(0.5F * s.length_m);
  const double w = static_cast<double>(0.5F * s.width_m);
  putPoint(f, key + ".shape.footprint.points.0", l, w, 0);
  putPoint(f, key + ".shape.footprint.points.1", -l, w, 0);
  putPoint(f, key + ".shape.footprint.points.2", -l, -w, 0);
  putPoint(f, key + ".shape.footprint.points.3", l, -w, 0);
  putPoint(f, key + ".shape.dimensions", static_cast<double>(s.length_m),
           static_cast<double>(s.width_m), static_cast<double>(s.height_m));
}

// The reader's output as one field map per message, in arrival order per topic.
std::map<std::string, std::vector<Fields>> parseReader(FILE* pipe) {
  std::map<std::string, std::vector<Fields>> messages;
  char line[4096];
  Fields* current = nullptr;
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    std::string text(line);
    if (!text.empty() && text.back() == '\n') {
      text.pop_back();
    }
    if (text.rfind("BEGIN ", 0) == 0) {
      current = &messages[text.substr(6)].emplace_back();
    } else if (text.rfind("END ", 0) == 0) {
      current = nullptr;
    } else if (current != nullptr) {
      const std::size_t eq = text.find('=');
      (*current)[text.substr(0, eq)] = text.substr(eq + 1);
    }
  }
  return messages;
}

void expectSame(const Fields& received, const Fields& expected) {
  for (const auto& [key, value] : expected) {
    const auto it = received.find(key);
    if (it == received.end()) {
      ADD_FAILURE() << "missing field " << key;
      continue;
    }
    EXPECT_EQ(it->second, value) << key;
  }
  for (const auto& [key, value] : received) {
    EXPECT_TRUE(expected.count(key) == 1) << "unexpected field " << key << "=" << value;
  }
}

TEST(Ros2ReaderProcess, ReceivesEveryFieldOfStatesObjectsStatusAndGrid) {
  test::useLoopbackDds();
  config::DdsConfig config = test::uniqueDdsConfig();
  config.droneId = 7;
  config.ros2.topicNamespace = "vp_" + std::to_string(getpid());
  config.ros2.frameId = "site_enu";
  config.autoware.enabled = true;
  config.autoware.topic = "/perception/test_" + std::to_string(getpid()) + "/objects";
  config.grid.rows = 3;
  config.grid.cols = 4;
  const std::string command =
      std::string(VP_ROS2_READER) + " --domain " + std::to_string(config.domainId) +
      " --namespace " + config.ros2.topicNamespace + " --autoware-topic " + config.autoware.topic +
      " --states 2 --status 1 --occupancy 1 --objects 2 --timeout-s 60";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);

  const std::int64_t t1 = 1'700'000'000'123'456'789;
  const std::int64_t t2 = t1 + 100'000'000;
  const messages::VehicleState car1 = fullState(5, t1, false);
  const messages::VehicleState truck1 = fullState(300, t1, true);
  const messages::VehicleState car2 = fullState(5, t2, false);
  messages::DroneStatus status;
  status.droneId = 7;
  status.time_ns = t2 + 5;
  status.position = {43.07, -89.4, 310.5};
  status.attitudeQuaternion = {0.9, 0.1, -0.2, 0.3};
  status.gimbalEuler_deg = {1.5F, -85.0F, 12.25F};
  status.frameRate_hz = 9.5F;
  status.latencyMedian_ms = 41.5F;
  status.latencyP99_ms = 77.25F;
  status.inferenceMedian_ms = 20.125F;
  status.framesProcessed = 1234;
  status.framesDropped = 5;
  status.corruptFrames = 1;
  status.stalePoses = 2;
  status.outsideDtm = 3;
  status.publishErrors = 4;
  status.activeTracks = 2;
  status.setModelId("det-v3-int8");
  messages::OccupancyGrid grid;
  grid.resize(3, 4);
  grid.droneId = 7;
  grid.time_ns = t2 + 7;
  grid.originEast_m = -12.5;
  grid.originNorth_m = 20.25;
  grid.resolution_m = 0.5F;
  for (std::size_t k = 0; k < grid.cells.size(); ++k) {
    grid.cells[k] = static_cast<std::uint8_t>(k % 3);  // unobserved, free, occupied
  }

  {
    Participant participant;
    ASSERT_TRUE(participant.open(config).ok());
    Ros2StatePublisher states;
    Ros2DroneStatusWriter statusWriter;
    Ros2OccupancyWriter gridWriter;
    ASSERT_TRUE(states.open(participant, config).ok());
    ASSERT_TRUE(statusWriter.open(participant, config).ok());
    ASSERT_TRUE(gridWriter.open(participant, config).ok());
    for (const dds_entity_t writer : {states.arrayWriter(), states.autowareWriter(),
                                      statusWriter.writer(), gridWriter.writer()}) {
      ASSERT_TRUE(waitForMatch(writer, 30000ms)) << "the reader process did not match";
    }
    // Frame 1: a car and a (lost) truck; frame 2: the truck was deleted.
    EXPECT_TRUE(states.add(car1).ok());
    EXPECT_TRUE(states.add(truck1).ok());
    const Ros2FrameSummary first = states.endFrame(t1);
    EXPECT_EQ(first.errors, 0U) << describe(first.firstError);
    EXPECT_EQ(first.vehicles, 2U);
    EXPECT_EQ(first.removed, 0U);
    EXPECT_EQ(dds_wait_for_acks(states.arrayWriter(), DDS_SECS(10)), DDS_RETCODE_OK);
    EXPECT_EQ(dds_wait_for_acks(states.autowareWriter(), DDS_SECS(10)), DDS_RETCODE_OK);
    EXPECT_TRUE(states.add(car2).ok());
    const Ros2FrameSummary second = states.endFrame(t2);
    EXPECT_EQ(second.errors, 0U) << describe(second.firstError);
    EXPECT_EQ(second.vehicles, 1U);
    EXPECT_EQ(second.removed, 1U);
    EXPECT_TRUE(statusWriter.write(status).ok());
    EXPECT_TRUE(gridWriter.write(grid).ok());
    for (const dds_entity_t writer : {states.arrayWriter(), states.autowareWriter(),
                                      statusWriter.writer(), gridWriter.writer()}) {
      EXPECT_EQ(dds_wait_for_acks(writer, DDS_SECS(10)), DDS_RETCODE_OK);
    }
    // The participant stays until the reader has everything (it exits on its own).
    const std::map<std::string, std::vector<Fields>> received = parseReader(pipe);
    EXPECT_EQ(pclose(pipe), 0) << "the reader timed out or failed";

    ASSERT_EQ(received.count("vehicle_states"), 1U);
    ASSERT_EQ(received.at("vehicle_states").size(), 2U);
    Fields frame1;
    putHeader(frame1, "vehicle_states", t1, "site_enu");
    frame1["vehicle_states.drone_id"] = "7";
    frame1["vehicle_states.vehicles.length"] = "2";
    putState(frame1, "vehicle_states.vehicles.0", car1);
    putState(frame1, "vehicle_states.vehicles.1", truck1);
    frame1["vehicle_states.removed_track_ids.length"] = "0";
    expectSame(received.at("vehicle_states")[0], frame1);
    Fields frame2;
    putHeader(frame2, "vehicle_states", t2, "site_enu");
    frame2["vehicle_states.drone_id"] = "7";
    frame2["vehicle_states.vehicles.length"] = "1";
    putState(frame2, "vehicle_states.vehicles.0", car2);
    frame2["vehicle_states.removed_track_ids.length"] = "1";
    frame2["vehicle_states.removed_track_ids.0"] = "300";
    expectSame(received.at("vehicle_states")[1], frame2);

    ASSERT_EQ(received.count("tracked_objects"), 1U);
    ASSERT_EQ(received.at("tracked_objects").size(), 2U);
    Fields objects1;
    putHeader(objects1, "tracked_objects", t1, "map");
    objects1["tracked_objects.objects.length"] = "2";
    putObject(objects1, "tracked_objects.objects.0", car1);
    putObject(objects1, "tracked_objects.objects.1", truck1);
    expectSame(received.at("tracked_objects")[0], objects1);
    Fields objects2;
    putHeader(objects2, "tracked_objects", t2, "map");
    objects2["tracked_objects.objects.length"] = "1";
    putObject(objects2, "tracked_objects.objects.0", car2);
    expectSame(received.at("tracked_objects")[1], objects2);
    // The truck: classified TRUCK first, stationary; the car: CAR first, moving.
    EXPECT_EQ(
        received.at("tracked_objects")[0].at("tracked_objects.objects.1.classification.0.label"),
        "2");
    EXPECT_EQ(
        received.at("tracked_objects")[0].at("tracked_objects.objects.1.kinematics.is_stationary"),
        "1");
    EXPECT_EQ(
        received.at("tracked_objects")[0].at("tracked_objects.objects.0.classification.0.label"),
        "1");

    ASSERT_EQ(received.count("drone_status"), 1U);
    Fields st;
    putHeader(st, "drone_status", status.time_ns, "site_enu");
    st["drone_status.drone_id"] = "7";
    putGeodetic(st, "drone_status.position", status.position);
    st["drone_status.attitude_frd_to_ned.x"] = text(0.1);
    st["drone_status.attitude_frd_to_ned.y"] = text(-0.2);
    st["drone_status.attitude_frd_to_ned.z"] = text(0.3);
    st["drone_status.attitude_frd_to_ned.w"] = text(0.9);
    st["drone_status.gimbal_euler_deg.0"] = textF(1.5F);
    st["drone_status.gimbal_euler_deg.1"] = textF(-85.0F);
    st["drone_status.gimbal_euler_deg.2"] = textF(12.25F);
    st["drone_status.frame_rate_hz"] = textF(9.5F);
    st["drone_status.latency_median_ms"] = textF(41.5F);
    st["drone_status.latency_p99_ms"] = textF(77.25F);
    st["drone_status.inference_median_ms"] = textF(20.125F);
    st["drone_status.frames_processed"] = "1234";
    st["drone_status.frames_dropped"] = "5";
    st["drone_status.corrupt_frames"] = "1";
    st["drone_status.stale_poses"] = "2";
    st["drone_status.outside_dtm"] = "3";
    st["drone_status.publish_errors"] = "4";
    st["drone_status.active_tracks"] = "2";
    st["drone_status.model_id"] = "det-v3-int8";
    expectSame(received.at("drone_status")[0], st);

    ASSERT_EQ(received.count("occupancy"), 1U);
    Fields og;
    putHeader(og, "occupancy", grid.time_ns, "site_enu");
    putTime(og, "occupancy.info.map_load_time", grid.time_ns);
    og["occupancy.info.resolution"] = textF(0.5F);
    og["occupancy.info.width"] = "4";
    og["occupancy.info.height"] = "3";
    putPoint(og, "occupancy.info.origin.position", -12.5, 20.25, 0.0);
    og["occupancy.info.origin.orientation.x"] = "0";
    og["occupancy.info.origin.orientation.y"] = "0";
    og["occupancy.info.origin.orientation.z"] = "0";
    og["occupancy.info.origin.orientation.w"] = "1";
    og["occupancy.data.length"] = "12";
    const char* const values[] = {"-1", "0", "100"};
    for (std::size_t k = 0; k < 12; ++k) {
      og["occupancy.data." + std::to_string(k)] = values[k % 3];
    }
    expectSame(received.at("occupancy")[0], og);
  }
}

// Our side of every ROS 2 write: filling the array, the Autoware objects, the status and the
// grid into the preallocated samples allocates nothing (Cyclone's serialisation is measured in
// docs/dds.md, not asserted).
TEST(Ros2Conversion, OurPublishPathDoesNotAllocate) {
  std::vector<messages::VehicleState> states;
  for (std::uint32_t id = 1; id <= 200; ++id) {
    states.push_back(fullState(id, 1'700'000'000'000'000'000, id % 7 == 0));
  }
  messages::DroneStatus status;
  status.setModelId("det-v3-int8");
  messages::OccupancyGrid grid;
  grid.resize(200, 200);
  ros2::VehicleStateArrayBuffer array;
  ros2::TrackedObjectsBuffer objects;
  ros2::DroneStatusBuffer statusSample;
  ros2::OccupancyGridBuffer gridSample;
  array.reserve(1024, 1024, "map");
  objects.reserve(1024, "map", ros2::AutowareOptions{});
  statusSample.reserve("map");
  gridSample.reserve(200 * 200, "map");
  test::AllocationCounter counter;
  for (int frame = 0; frame < 20; ++frame) {
    array.begin(7, frame);
    objects.begin(frame);
    for (const auto& s : states) {
      EXPECT_TRUE(array.add(s));
      EXPECT_TRUE(objects.add(s));
    }
    EXPECT_TRUE(array.addRemoved(99));
    statusSample.fill(status);
    EXPECT_TRUE(gridSample.fill(grid));
  }
  counter.stop();
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(array.sample().vehicles._length, 200U);
  EXPECT_EQ(objects.sample().objects._length, 200U);
  // A full buffer refuses instead of growing.
  ros2::VehicleStateArrayBuffer small;
  small.reserve(1, 1, "map");
  small.begin(7, 0);
  EXPECT_TRUE(small.add(states[0]));
  EXPECT_FALSE(small.add(states[1]));
  EXPECT_TRUE(small.addRemoved(1));
  EXPECT_FALSE(small.addRemoved(2));
}

TEST(Ros2Conversion, TimeAndTopicNames) {
  const builtin_interfaces_msg_dds__Time_ t = ros2::toRosTime(1'700'000'000'250'000'000);
  EXPECT_EQ(t.sec, 1'700'000'000);
  EXPECT_EQ(t.nanosec, 250'000'000U);
  const builtin_interfaces_msg_dds__Time_ before = ros2::toRosTime(-1);  // floor
  EXPECT_EQ(before.sec, -1);
  EXPECT_EQ(before.nanosec, 999'999'999U);
  config::Ros2Config ros2;
  EXPECT_EQ(ros2TopicName(ros2, "vehicle_states"), "rt/vp/vehicle_states");
  ros2.topicNamespace = "";
  EXPECT_EQ(ros2TopicName(ros2, "occupancy"), "rt/occupancy");
  EXPECT_EQ(autowareTopicName(config::AutowareConfig{}),
            "rt/perception/object_recognition/tracking/objects");
  EXPECT_EQ(std::string(vp_msgs_msg_dds__VehicleStateArray__desc.m_typename),
            "vp_msgs::msg::dds_::VehicleStateArray_");
  EXPECT_EQ(std::string(autoware_perception_msgs_msg_dds__TrackedObjects__desc.m_typename),
            "autoware_perception_msgs::msg::dds_::TrackedObjects_");
  EXPECT_EQ(std::string(nav_msgs_msg_dds__OccupancyGrid__desc.m_typename),
            "nav_msgs::msg::dds_::OccupancyGrid_");
}

}  // namespace
}  // namespace vp::platform::dds
