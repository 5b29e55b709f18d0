// platform/dds/dds_handles: entity and QoS wrappers.
#include "platform/dds/dds_handles.hpp"

#include <cmath>

namespace vp::platform::dds {
namespace {

// 0 in the configuration means "off", which DDS spells as an infinite duration.
dds_duration_t toDuration(double seconds) {
  if (seconds <= 0.0) {
    return DDS_INFINITY;
  }
  return static_cast<dds_duration_t>(std::llround(seconds * 1e9));
}

void setProp(Qos& qos, const char* name, const std::string& value) {
  dds_qset_prop(qos.get(), name, value.c_str());
}

std::string fileUri(const std::string& path) {
  return "file:" + path;
}

}  // namespace

std::string describe(const DdsResult& result) {
  if (result.ok()) {
    return "ok";
  }
  return std::string(result.call) + ": " + dds_strretcode(result.rc);
}

void applyProfile(const config::QosProfile& profile, Qos& qos) {
  dds_qset_reliability(qos.get(),
                       profile.reliability == config::Reliability::Reliable
                           ? DDS_RELIABILITY_RELIABLE
                           : DDS_RELIABILITY_BEST_EFFORT,
                       static_cast<dds_duration_t>(std::llround(profile.maxBlocking_s * 1e9)));
  dds_qset_durability(qos.get(), profile.durability == config::Durability::TransientLocal
                                     ? DDS_DURABILITY_TRANSIENT_LOCAL
                                     : DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, profile.historyDepth);
  if (profile.durability == config::Durability::TransientLocal) {
    // What a late reader gets is the durability service's history (Cyclone's default: the
    // last sample per instance); keep as many as the history depth says.
    dds_qset_durability_service(qos.get(), 0, DDS_HISTORY_KEEP_LAST, profile.historyDepth,
                                DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  }
  dds_qset_deadline(qos.get(), toDuration(profile.deadline_s));
  dds_qset_lifespan(qos.get(), toDuration(profile.lifespan_s));
  dds_qset_liveliness(qos.get(), DDS_LIVELINESS_AUTOMATIC, toDuration(profile.livelinessLease_s));
}

void applySecurity(const config::SecurityConfig& security, Qos& qos) {
  if (!security.enabled) {
    return;
  }
  // The three plugins Debian ships in its private folder: property prefix, library, entry name.
  struct Plugin {
    const char* prefix;
    const char* library;
    const char* entry;
  };
  constexpr Plugin kPlugins[] = {{"dds.sec.auth", "libdds_security_auth.so", "authentication"},
                                 {"dds.sec.access", "libdds_security_ac.so", "access_control"},
                                 {"dds.sec.crypto", "libdds_security_crypto.so", "crypto"}};
  for (const Plugin& p : kPlugins) {
    const std::string prefix = p.prefix;
    setProp(qos, (prefix + ".library.path").c_str(), security.pluginDir + "/" + p.library);
    setProp(qos, (prefix + ".library.init").c_str(), std::string("init_") + p.entry);
    setProp(qos, (prefix + ".library.finalize").c_str(), std::string("finalize_") + p.entry);
  }
  setProp(qos, "dds.sec.auth.identity_ca", fileUri(security.identityCa));
  setProp(qos, "dds.sec.auth.identity_certificate", fileUri(security.identityCertificate));
  setProp(qos, "dds.sec.auth.private_key", fileUri(security.privateKey));
  setProp(qos, "dds.sec.access.permissions_ca", fileUri(security.permissionsCa));
  setProp(qos, "dds.sec.access.governance", fileUri(security.governance));
  setProp(qos, "dds.sec.access.permissions", fileUri(security.permissions));
}

Entity& Entity::operator=(Entity&& other) noexcept {
  if (this != &other) {
    reset();
    handle_ = other.handle_;
    other.handle_ = 0;
  }
  return *this;
}

void Entity::reset() {
  if (handle_ > 0) {
    // Nothing useful can be done about a failed delete in a destructor; the handle is gone.
    (void)dds_delete(handle_);
  }
  handle_ = 0;
}

DdsResult Entity::adopt(dds_entity_t handle, const char* call) {
  reset();
  if (handle < 0) {
    return DdsResult::failure(call, handle);
  }
  handle_ = handle;
  return DdsResult{};
}

DdsResult Participant::open(const config::DdsConfig& config) {
  Qos qos;
  applySecurity(config.security, qos);
  return adopt(
      dds_create_participant(static_cast<dds_domainid_t>(config.domainId), qos.get(), nullptr),
      "dds_create_participant");
}

DdsResult Participant::open(std::uint32_t domainId) {
  return adopt(dds_create_participant(static_cast<dds_domainid_t>(domainId), nullptr, nullptr),
               "dds_create_participant");
}

DdsResult Topic::open(const Participant& participant, const dds_topic_descriptor_t& descriptor,
                      const std::string& name, const config::QosProfile& profile) {
  Qos qos;
  applyProfile(profile, qos);
  return adopt(dds_create_topic(participant.get(), &descriptor, name.c_str(), qos.get(), nullptr),
               "dds_create_topic");
}

DdsResult Writer::open(const Participant& participant, const Topic& topic,
                       const config::QosProfile& profile, const std::string& partition) {
  Qos publisherQos;
  const char* partitions[] = {partition.c_str()};
  if (!partition.empty()) {
    dds_qset_partition(publisherQos.get(), 1, partitions);
  }
  DdsResult result = publisher_.adopt(
      dds_create_publisher(participant.get(), publisherQos.get(), nullptr), "dds_create_publisher");
  if (!result.ok()) {
    return result;
  }
  Qos writerQos;
  applyProfile(profile, writerQos);
  return writer_.adopt(dds_create_writer(publisher_.get(), topic.get(), writerQos.get(), nullptr),
                       "dds_create_writer");
}

DdsResult Reader::open(const Participant& participant, const Topic& topic,
                       const config::QosProfile& profile, const std::string& partition,
                       const dds_listener_t* listener) {
  Qos subscriberQos;
  const char* partitions[] = {partition.c_str()};
  if (!partition.empty()) {
    dds_qset_partition(subscriberQos.get(), 1, partitions);
  }
  DdsResult result =
      subscriber_.adopt(dds_create_subscriber(participant.get(), subscriberQos.get(), nullptr),
                        "dds_create_subscriber");
  if (!result.ok()) {
    return result;
  }
  Qos readerQos;
  applyProfile(profile, readerQos);
  return reader_.adopt(dds_create_reader(subscriber_.get(), topic.get(), readerQos.get(), listener),
                       "dds_create_reader");
}

std::string vehicleStateTopicName(const config::DdsConfig& config) {
  return config.topicPrefix + "/vehicle_state";
}
std::string droneStatusTopicName(const config::DdsConfig& config) {
  return config.topicPrefix + "/drone_status";
}
std::string occupancyTopicName(const config::DdsConfig& config) {
  return config.topicPrefix + "/occupancy";
}

}  // namespace vp::platform::dds
