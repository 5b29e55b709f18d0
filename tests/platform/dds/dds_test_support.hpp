// tests/platform/dds/dds_test_support: loopback-only Cyclone DDS configuration and per-test domain
// and partition, so that tests (and ctest -j) never hear each other or the network.
#pragma once

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>
#include <thread>

#include <dds/dds.h>

#include "config/dds_config.hpp"
#include "messages/messages.hpp"

namespace vp::test {

// Unicast discovery on 127.0.0.1 only (the loopback interface has no multicast).
inline void useLoopbackDds() {
  static const char* const kUri =
      "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
      "address=\"127.0.0.1\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
      "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30"
      "</MaxAutoParticipantIndex><Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery>"
      "</Domain></CycloneDDS>";
  setenv("CYCLONEDDS_URI", kUri, 1);
}

// Waits until the writer has `count` matched readers (discovery), up to `timeout`.
inline bool waitForMatch(dds_entity_t writer, std::uint32_t count,
                         std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(writer, &status) >= 0 && status.current_count >= count) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// A domain id and partition unique to this process and call.
inline config::DdsConfig uniqueDdsConfig() {
  static std::atomic<int> counter{0};
  const int k = counter++;
  config::DdsConfig config;
  config.domainId = static_cast<std::uint32_t>(1 + (getpid() * 7 + k) % 200);
  config.partition = "test_" + std::to_string(getpid()) + "_" + std::to_string(k);
  return config;
}

// A plausible confirmed track with every field set to a distinct value.
inline messages::VehicleState makeState(std::uint32_t trackId, std::int64_t time_ns) {
  messages::VehicleState s;
  const float t = static_cast<float>(trackId);
  s.droneId = 7;
  s.trackId = trackId;
  s.measurementTime_ns = time_ns;
  s.trackAge_s = 1.5F + t;
  s.position = {43.0731 + 1e-6 * trackId, -89.4012 - 1e-6 * trackId, 250.125 + trackId};
  s.enu_m = {1.25 * trackId, -2.5 * trackId, 0.1};
  s.headingEnu_rad = std::fmod(0.01 * trackId, 6.28);
  s.headingTrueNorth_deg = std::fmod(90.0 + 0.573 * trackId, 360.0);
  s.speed_mps = 13.9F + 0.1F * t;
  s.velocityEnu_mps = {13.8F, 0.3F * t};
  s.yawRate_radps = 0.02F;
  s.acceleration_mps2 = -0.5F;
  s.length_m = 4.6F;
  s.width_m = 1.8F;
  s.height_m = 1.45F;
  s.type = static_cast<shape::VehicleType>(trackId % shape::kVehicleTypeCount);
  s.typeProbability = {0.05F, 0.1F, 0.05F, 0.6F, 0.1F, 0.05F, 0.05F};
  s.shape.count = 3;
  s.shape.gamma = {0.5F, -1.25F, 0.125F * t, 0, 0, 0, 0, 0};
  s.poseCovariance = {0.04F, 0.001F, 0.0F, 0.05F, 0.0F, 0.003F};
  s.heightVariance_m2 = 0.09F;
  s.speedVariance_m2ps2 = 0.25F;
  s.yawRateVariance_rad2ps2 = 0.0004F;
  s.detectionConfidence = 0.93F;
  s.status = messages::TrackStatus::Confirmed;
  s.utmZone = 16;
  s.utmNorthernHemisphere = trackId % 2 == 0;
  s.utmEasting_m = 304510.3816 + 0.125 * trackId;
  s.utmNorthing_m = 4771730.8701 - 0.25 * trackId;
  s.rearAxleEnu_m = {1.25 * trackId - 1.3, -2.5 * trackId, 0.05};
  s.rearAxlePosition = {43.0731 + 1.1e-6 * trackId, -89.4012 - 0.9e-6 * trackId, 250.0 + trackId};
  s.lengthVariance_m2 = 0.0625F;
  s.widthVariance_m2 = 0.0049F + 1e-4F * t;
  s.keypointCount = static_cast<std::uint8_t>(shape::kKeypointCount);
  for (std::size_t k = 0; k < s.keypointsEnu_m.size(); ++k) {
    const float f = static_cast<float>(k);
    s.keypointsEnu_m[k] = {1.25F * t + 0.1F * f, -2.5F * t - 0.05F * f, 0.03F * f};
  }
  return s;
}

}  // namespace vp::test
