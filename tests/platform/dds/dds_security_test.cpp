// DDS Security end to end, on loopback with Cyclone's real plugins (Debian's libddsc0debian
// folder): the drone publishes with authentication, access control and encryption on; four
// vp_rsu_subscriber processes listen at once. Only the roadside unit with a certificate of the
// same CA and a grant for the topics receives anything, and it receives every sample; one
// without security, one whose CA is another, and one authenticated without a grant for the
// perception topics receive nothing. Certificates are made at test time by
// scripts/make_dds_certs.sh (openssl) into a temporary folder.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "dds_test_support.hpp"
#include "platform/dds/perception_publisher.hpp"

namespace vp::platform::dds {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr std::uint32_t kTracks = 20;
constexpr int kFrames = 10;
// Long enough for the unauthorised subscribers to try discovery while the drone publishes.
constexpr int kSubscriberDuration_s = 10;

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The `dds:` section of a roadside unit's file: the test's domain and partition, a history
// deep enough to keep every sample of a frame burst, and the given identity.
void writeRsuConfig(const fs::path& file, const config::DdsConfig& site, const fs::path& certs,
                    const std::string& identity) {
  std::ofstream out(file);
  out << "dds:\n  domain_id: " << site.domainId << "\n  partition: " << site.partition
      << "\n  qos:\n    vehicle_state:\n      history_depth: 1000\n      lifespan_s: 0\n"
      << "      deadline_s: 0\n";
  if (!identity.empty()) {
    out << "  security:\n    enabled: true\n    identity_ca: " << (certs / "ca.pem").string()
        << "\n    identity_certificate: " << (certs / (identity + ".pem")).string()
        << "\n    private_key: " << (certs / (identity + "_key.pem")).string()
        << "\n    permissions_ca: " << (certs / "ca.pem").string()
        << "\n    governance: " << (certs / "governance.p7s").string()
        << "\n    permissions: " << (certs / "permissions.p7s").string() << "\n";
  }
}

struct Subscriber {
  std::string name;
  FILE* pipe = nullptr;
  fs::path stdoutFile;
  fs::path stderrFile;
  std::string output;
  int status = -1;
};

int stateRows(const std::string& csv, std::set<std::pair<std::uint32_t, std::string>>* keys) {
  std::istringstream lines(csv);
  std::string line;
  int rows = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("state,", 0) != 0) {
      continue;
    }
    ++rows;
    // state,drone_id,track_id,measurement_time_ns,...
    std::stringstream split(line);
    std::string event, drone, track, time;
    std::getline(split, event, ',');
    std::getline(split, drone, ',');
    std::getline(split, track, ',');
    std::getline(split, time, ',');
    if (keys != nullptr) {
      keys->insert({static_cast<std::uint32_t>(std::stoul(track)), time});
    }
  }
  return rows;
}

TEST(DdsSecurity, OnlyAuthenticatedAndPermittedParticipantsReceive) {
  test::useLoopbackDds();
  config::DdsConfig site = test::uniqueDdsConfig();
  site.vehicleState.historyDepth = 1000;
  site.vehicleState.lifespan_s = 0.0;
  site.vehicleState.deadline_s = 0.0;
  const fs::path dir = fs::temp_directory_path() / ("vp_dds_security_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string script = std::string(VP_SOURCE_DIR) + "/scripts/make_dds_certs.sh";
  for (const char* ca : {"site", "other"}) {
    const std::string command = script + " " + (dir / ca).string() + " " +
                                std::to_string(site.domainId) + " vp > /dev/null";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
  }
  site.security.enabled = true;
  site.security.identityCa = (dir / "site/ca.pem").string();
  site.security.identityCertificate = (dir / "site/drone.pem").string();
  site.security.privateKey = (dir / "site/drone_key.pem").string();
  site.security.permissionsCa = (dir / "site/ca.pem").string();
  site.security.governance = (dir / "site/governance.p7s").string();
  site.security.permissions = (dir / "site/permissions.p7s").string();

  // name, folder of its certificates, identity ("" = no security)
  const std::tuple<const char*, const char*, const char*> kinds[] = {
      {"authorised", "site", "rsu"},
      {"unauthenticated", "site", ""},
      {"other_ca", "other", "rsu"},
      {"no_permission", "site", "guest"}};
  std::vector<Subscriber> subscribers;
  for (const auto& [name, ca, identity] : kinds) {
    Subscriber s;
    s.name = name;
    const fs::path file = dir / (std::string(name) + ".yaml");
    writeRsuConfig(file, site, dir / ca, identity);
    // Files, not the pipe: a full pipe would stall the subscriber's take loop.
    s.stdoutFile = dir / (std::string(name) + ".csv");
    s.stderrFile = dir / (std::string(name) + ".err");
    const std::string command = std::string(VP_RSU_SUBSCRIBER) + " --config " + file.string() +
                                " --duration-s " + std::to_string(kSubscriberDuration_s) +
                                (s.name == "authorised" ? " --until-writers-gone" : "") + " >" +
                                s.stdoutFile.string() + " 2>" + s.stderrFile.string();
    s.pipe = popen(command.c_str(), "r");
    ASSERT_NE(s.pipe, nullptr);
    subscribers.push_back(s);
  }

  const auto start = std::chrono::steady_clock::now();
  std::set<std::pair<std::uint32_t, std::string>> sent;
  dds_publication_matched_status_t matched{};
  {
    Participant participant;
    const DdsResult opened = participant.open(site);
    ASSERT_TRUE(opened.ok()) << describe(opened) << " (security plugins in "
                             << site.security.pluginDir << ")";
    VehicleStatePublisher publisher;
    ASSERT_TRUE(publisher.open(participant, site).ok());
    // Authentication (RSA handshake) and encrypted discovery take a moment.
    bool found = false;
    for (int i = 0; i < 2000 && !found; ++i) {
      found = dds_get_publication_matched_status(publisher.writer(), &matched) >= 0 &&
              matched.current_count > 0;
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_TRUE(found) << "the authorised subscriber never matched";
    std::this_thread::sleep_for(300ms);  // its reader matches the writer too
    const std::int64_t t0 = dds_time();
    for (int frame = 0; frame < kFrames; ++frame) {
      const std::int64_t t = t0 + frame * 100'000'000LL;
      for (std::uint32_t id = 1; id <= kTracks; ++id) {
        ASSERT_TRUE(publisher.publish(test::makeState(id, t)).ok());
        sent.insert({id, std::to_string(t)});
      }
      EXPECT_EQ(publisher.endFrame(t).disposed, 0U);
      EXPECT_EQ(dds_wait_for_acks(publisher.writer(), DDS_SECS(5)), DDS_RETCODE_OK);
      std::this_thread::sleep_for(100ms);
    }
    // Keep publishing until the others have had several seconds to find the drone.
    while (std::chrono::steady_clock::now() - start < std::chrono::seconds(6)) {
      std::this_thread::sleep_for(100ms);
    }
    ASSERT_GE(dds_get_publication_matched_status(publisher.writer(), &matched), 0);
  }  // the writer leaves: the authorised subscriber stops

  for (Subscriber& s : subscribers) {
    s.status = pclose(s.pipe);
    s.output = readFile(s.stdoutFile);
  }
  // Exactly one reader ever matched the drone's writer: the authorised one.
  EXPECT_EQ(matched.total_count, 1U);

  std::set<std::pair<std::uint32_t, std::string>> received;
  for (const Subscriber& s : subscribers) {
    SCOPED_TRACE(s.name + ": " + readFile(s.stderrFile));
    if (s.name == "authorised") {
      EXPECT_EQ(s.status, 0);
      EXPECT_EQ(stateRows(s.output, &received), kFrames * static_cast<int>(kTracks));
      EXPECT_EQ(received, sent);  // every sample, each once
    } else if (s.name == "no_permission") {
      // Authenticated, but access control refuses the perception topic locally.
      EXPECT_NE(s.status, 0);
      EXPECT_EQ(stateRows(s.output, nullptr), 0);
      EXPECT_NE(readFile(s.stderrFile).find("vehicle state"), std::string::npos);
    } else {
      EXPECT_EQ(s.status, 0);  // ran its full duration, heard nothing
      EXPECT_EQ(stateRows(s.output, nullptr), 0);
    }
  }
  std::printf("security: authorised received %zu of %zu samples; the other three 0\n",
              received.size(), sent.size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vp::platform::dds
