// messages/dds_config: YAML -> DdsConfig. Each key is one line stating its type, range and
// default, mirroring docs/dds.md; keys left unread become "unknown key" warnings.
#include "messages/dds_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace vp::messages {
namespace {

namespace fs = std::filesystem;

class Section {
 public:
  Section(YAML::Node node, std::string path, const std::string* source,
          std::vector<std::string>* warnings)
      : node_(std::move(node)), path_(std::move(path)), source_(source), warnings_(warnings) {
    if (node_ && !node_.IsNull() && !node_.IsMap()) {
      fail(path_, "expected a map");
    }
  }
  ~Section() {
    if (!node_ || !node_.IsMap()) {
      return;
    }
    for (const auto& entry : node_) {
      const std::string key = entry.first.as<std::string>();
      if (read_.count(key) == 0) {
        warnings_->push_back(*source_ + ": unknown key '" + path_ + "." + key + "'");
      }
    }
  }
  Section(const Section&) = delete;
  Section& operator=(const Section&) = delete;

  Section child(const std::string& key) {
    read_.insert(key);
    return Section(node_ && node_.IsMap() ? node_[key] : YAML::Node(), path_ + "." + key, source_,
                   warnings_);
  }

  double number(const std::string& key, double fallback, double lo, double hi) {
    const YAML::Node value = get(key);
    if (!value) {
      return fallback;
    }
    double result = 0.0;
    if (!value.IsScalar() || value.Tag() == "!" || !YAML::convert<double>::decode(value, result)) {
      fail(path_ + "." + key, "expected a number");
    }
    if (!std::isfinite(result) || result < lo || result > hi) {
      std::ostringstream message;
      message << "must be in [" << lo << ", " << hi << "], got " << value.Scalar();
      fail(path_ + "." + key, message.str());
    }
    return result;
  }
  std::int64_t integer(const std::string& key, std::int64_t fallback, std::int64_t lo,
                       std::int64_t hi) {
    const double value = number(key, static_cast<double>(fallback), static_cast<double>(lo),
                                static_cast<double>(hi));
    if (value != std::floor(value)) {
      fail(path_ + "." + key, "expected an integer");
    }
    return static_cast<std::int64_t>(value);
  }
  bool boolean(const std::string& key, bool fallback) {
    const YAML::Node value = get(key);
    if (!value) {
      return fallback;
    }
    bool result = false;
    if (!value.IsScalar() || !YAML::convert<bool>::decode(value, result)) {
      fail(path_ + "." + key, "expected true or false");
    }
    return result;
  }
  std::string text(const std::string& key, const std::string& fallback) {
    const YAML::Node value = get(key);
    if (!value) {
      return fallback;
    }
    if (!value.IsScalar()) {
      fail(path_ + "." + key, "expected a string");
    }
    return value.Scalar();
  }
  // A file path, resolved against baseDir when relative.
  std::string file(const std::string& key, const std::string& baseDir) {
    const std::string value = text(key, "");
    if (value.empty() || fs::path(value).is_absolute()) {
      return value;
    }
    return (fs::path(baseDir) / value).lexically_normal().string();
  }
  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw DdsConfigError(*source_ + ": " + path + ": " + problem);
  }
  [[noreturn]] void failKey(const std::string& key, const std::string& problem) const {
    fail(path_ + "." + key, problem);
  }

 private:
  YAML::Node get(const std::string& key) {
    read_.insert(key);
    if (!node_ || !node_.IsMap()) {
      return YAML::Node(YAML::NodeType::Undefined);
    }
    const YAML::Node value = node_[key];
    if (!value || value.IsNull()) {
      return YAML::Node(YAML::NodeType::Undefined);
    }
    return value;
  }

  YAML::Node node_;
  std::string path_;
  const std::string* source_;
  std::vector<std::string>* warnings_;
  std::set<std::string> read_;
};

constexpr double kMaxDuration_s = 3600.0;

QosProfile readQos(Section section, const QosProfile& defaults) {
  QosProfile qos = defaults;
  const std::string reliability = section.text("reliability", toString(defaults.reliability));
  if (reliability == "reliable") {
    qos.reliability = Reliability::Reliable;
  } else if (reliability == "best_effort") {
    qos.reliability = Reliability::BestEffort;
  } else {
    section.failKey("reliability",
                    "unknown value '" + reliability + "' (expected reliable, best_effort)");
  }
  qos.maxBlocking_s = section.number("max_blocking_s", defaults.maxBlocking_s, 0.0, 10.0);
  const std::string durability = section.text("durability", toString(defaults.durability));
  if (durability == "volatile") {
    qos.durability = Durability::Volatile;
  } else if (durability == "transient_local") {
    qos.durability = Durability::TransientLocal;
  } else {
    section.failKey("durability",
                    "unknown value '" + durability + "' (expected volatile, transient_local)");
  }
  qos.historyDepth =
      static_cast<std::int32_t>(section.integer("history_depth", defaults.historyDepth, 1, 1000));
  qos.deadline_s = section.number("deadline_s", defaults.deadline_s, 0.0, kMaxDuration_s);
  qos.lifespan_s = section.number("lifespan_s", defaults.lifespan_s, 0.0, kMaxDuration_s);
  qos.livelinessLease_s =
      section.number("liveliness_lease_s", defaults.livelinessLease_s, 0.0, kMaxDuration_s);
  return qos;
}

}  // namespace

QosProfile DdsConfig::defaultVehicleStateQos() {
  // Reliable KEEP_LAST 1: a lost sample is resent only while it is still the newest state of
  // its track, and disposals (track deleted) are never lost. Lifespan drops states that sat
  // in a queue for more than 5 frames; the deadline flags a track not refreshed for 3 frames.
  QosProfile qos;
  qos.reliability = Reliability::Reliable;
  qos.maxBlocking_s = 0.01;
  qos.historyDepth = 1;
  qos.deadline_s = 0.3;
  qos.lifespan_s = 0.5;
  qos.livelinessLease_s = 2.0;
  return qos;
}

QosProfile DdsConfig::defaultDroneStatusQos() {
  // Transient-local so that a roadside unit joining late gets the current status at once.
  QosProfile qos;
  qos.reliability = Reliability::Reliable;
  qos.durability = Durability::TransientLocal;
  qos.historyDepth = 1;
  qos.deadline_s = 3.0;
  qos.livelinessLease_s = 5.0;
  return qos;
}

QosProfile DdsConfig::defaultOccupancyQos() {
  // Best effort: a grid is large (fragmented) and superseded by the next one; resending an old
  // one over a lossy link only delays the new one.
  QosProfile qos;
  qos.reliability = Reliability::BestEffort;
  qos.historyDepth = 1;
  qos.lifespan_s = 1.0;
  return qos;
}

const char* toString(Reliability reliability) {
  return reliability == Reliability::Reliable ? "reliable" : "best_effort";
}
const char* toString(Durability durability) {
  return durability == Durability::TransientLocal ? "transient_local" : "volatile";
}

DdsConfigResult parseDdsConfig(const std::string& yamlText, const std::string& sourceName,
                               const std::string& baseDir) {
  YAML::Node document;
  try {
    document = YAML::Load(yamlText);
  } catch (const YAML::Exception& e) {
    throw DdsConfigError(sourceName + ": YAML syntax error at line " +
                         std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  DdsConfigResult result;
  if (document && !document.IsNull() && !document.IsMap()) {
    throw DdsConfigError(sourceName + ": expected a map of sections at the top level");
  }
  YAML::Node ddsNode = document && document.IsMap() ? document["dds"] : YAML::Node();
  {
    Section dds(ddsNode, "dds", &sourceName, &result.warnings);
    DdsConfig& c = result.config;
    c.enabled = dds.boolean("enabled", c.enabled);
    c.domainId = static_cast<std::uint32_t>(dds.integer("domain_id", c.domainId, 0, 232));
    c.partition = dds.text("partition", c.partition);
    c.droneId = static_cast<std::uint32_t>(dds.integer("drone_id", c.droneId, 0, 0xFFFFFFFF));
    c.topicPrefix = dds.text("topic_prefix", c.topicPrefix);
    if (c.topicPrefix.empty()) {
      dds.fail("dds.topic_prefix", "must not be empty");
    }
    c.statusRate_hz = dds.number("status_rate_hz", c.statusRate_hz, 0.01, 100.0);
    c.occupancyRate_hz = dds.number("occupancy_rate_hz", c.occupancyRate_hz, 0.0, 100.0);
    {
      Section qos = dds.child("qos");
      c.vehicleState = readQos(qos.child("vehicle_state"), c.vehicleState);
      c.droneStatus = readQos(qos.child("drone_status"), c.droneStatus);
      c.occupancy = readQos(qos.child("occupancy"), c.occupancy);
    }
    {
      Section grid = dds.child("occupancy_grid");
      c.grid.originEast_m = grid.number("origin_east_m", c.grid.originEast_m, -1e5, 1e5);
      c.grid.originNorth_m = grid.number("origin_north_m", c.grid.originNorth_m, -1e5, 1e5);
      c.grid.resolution_m = grid.number("resolution_m", c.grid.resolution_m, 0.05, 10.0);
      c.grid.rows = static_cast<std::uint32_t>(grid.integer("rows", c.grid.rows, 1, 2048));
      c.grid.cols = static_cast<std::uint32_t>(grid.integer("cols", c.grid.cols, 1, 2048));
    }
    {
      Section sec = dds.child("security");
      SecurityConfig& s = c.security;
      s.enabled = sec.boolean("enabled", s.enabled);
      s.pluginDir = sec.text("plugin_dir", s.pluginDir);
      s.identityCa = sec.file("identity_ca", baseDir);
      s.identityCertificate = sec.file("identity_certificate", baseDir);
      s.privateKey = sec.file("private_key", baseDir);
      s.permissionsCa = sec.file("permissions_ca", baseDir);
      s.governance = sec.file("governance", baseDir);
      s.permissions = sec.file("permissions", baseDir);
      if (s.enabled) {
        for (const auto& [key, value] :
             {std::pair<const char*, const std::string*>{"identity_ca", &s.identityCa},
              {"identity_certificate", &s.identityCertificate},
              {"private_key", &s.privateKey},
              {"permissions_ca", &s.permissionsCa},
              {"governance", &s.governance},
              {"permissions", &s.permissions}}) {
          if (value->empty()) {
            sec.fail(std::string("dds.security.") + key, "missing (required when enabled)");
          }
        }
      }
    }
  }
  return result;
}

DdsConfigResult loadDdsConfig(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw DdsConfigError(path + ": cannot open configuration file");
  }
  std::stringstream text;
  text << in.rdbuf();
  return parseDdsConfig(text.str(), path, fs::absolute(path).parent_path().string());
}

}  // namespace vp::messages
