// platform/dds/dds_handles: RAII owners of Cyclone DDS entities and QoS objects, and the QoS
// built from the typed configuration (config/dds_config.hpp, the `dds:` section).
//
// Contract: every class here owns exactly one handle and releases it in its destructor
// (dds_delete for entities, which also deletes their children; dds_delete_qos for QoS);
// they are move-only. Constructors never fail; open() does, returning a DdsResult that carries
// the failing call and Cyclone's return code (describe() spells it with dds_strretcode).
// No product logic lives here. The participant reads the network configuration from
// CYCLONEDDS_URI as Cyclone always does; DDS Security, when enabled in the configuration, is
// set through the participant's QoS properties, loading the plugins from
// SecurityConfig::pluginDir (Debian: /usr/lib/<triplet>/libddsc0debian).
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <string>

#include "config/dds_config.hpp"

namespace vp::platform::dds {

// Outcome of a DDS call: rc >= 0 is success; `call` names what failed (a string literal).
struct DdsResult {
  dds_return_t rc = DDS_RETCODE_OK;
  const char* call = "";
  bool ok() const { return rc >= 0; }
  static DdsResult failure(const char* what, dds_return_t code) { return DdsResult{code, what}; }
};
std::string describe(const DdsResult& result);  // "dds_create_participant: Bad Parameter"

class Qos {
 public:
  Qos() : qos_(dds_create_qos()) {}
  ~Qos() { dds_delete_qos(qos_); }
  Qos(const Qos&) = delete;
  Qos& operator=(const Qos&) = delete;
  dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

// Reliability, durability, history, deadline, lifespan, liveliness of one topic.
void applyProfile(const config::QosProfile& profile, Qos& qos);
// Participant QoS: the DDS Security properties when security is enabled.
void applySecurity(const config::SecurityConfig& security, Qos& qos);

class Entity {
 public:
  Entity() = default;
  ~Entity() { reset(); }
  Entity(Entity&& other) noexcept : handle_(other.handle_) { other.handle_ = 0; }
  Entity& operator=(Entity&& other) noexcept;
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;

  dds_entity_t get() const { return handle_; }
  bool isOpen() const { return handle_ > 0; }
  void reset();
  // Takes ownership of a freshly created handle, or returns the failure it encodes.
  DdsResult adopt(dds_entity_t handle, const char* call);

 private:
  dds_entity_t handle_ = 0;
};

class Participant : public Entity {
 public:
  // The perception participant: config.domainId, with DDS Security when config.security says so.
  DdsResult open(const config::DdsConfig& config);
  // A plain participant in another domain (the flight stack's ROS 2 bridge: no security).
  DdsResult open(std::uint32_t domainId);
};

class Topic : public Entity {
 public:
  DdsResult open(const Participant& participant, const dds_topic_descriptor_t& descriptor,
                 const std::string& name, const config::QosProfile& profile);
};

// A writer under its own publisher, so that the partition applies to it alone. An empty
// partition means the default partition (what ROS 2 uses).
class Writer {
 public:
  DdsResult open(const Participant& participant, const Topic& topic,
                 const config::QosProfile& profile, const std::string& partition);
  dds_entity_t get() const { return writer_.get(); }
  bool isOpen() const { return writer_.isOpen(); }

 private:
  Entity publisher_;  // deleting it deletes the writer too; declared first, destroyed last
  Entity writer_;
};

class Reader {
 public:
  // `listener` (optional, copied by Cyclone) is installed when the reader is created, so that
  // no status change between creation and a later dds_set_listener is missed.
  DdsResult open(const Participant& participant, const Topic& topic,
                 const config::QosProfile& profile, const std::string& partition,
                 const dds_listener_t* listener = nullptr);
  dds_entity_t get() const { return reader_.get(); }
  bool isOpen() const { return reader_.isOpen(); }

 private:
  Entity subscriber_;
  Entity reader_;
};

// Topic names: <prefix>/vehicle_state, <prefix>/drone_status, <prefix>/occupancy.
std::string vehicleStateTopicName(const config::DdsConfig& config);
std::string droneStatusTopicName(const config::DdsConfig& config);
std::string occupancyTopicName(const config::DdsConfig& config);

}  // namespace vp::platform::dds
