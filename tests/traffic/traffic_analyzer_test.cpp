// traffic::TrafficAnalyzer on a small site built in code (a west-east road with an eastbound
// lane, a queue zone before its end, a box junction beyond, two gates): zone occupancy, queue in
// vehicles and metres, dwell, lane speeds and p85, wrong-way and box-junction events, turning
// movements, periods, bad options, and no allocation per step.
#include "traffic/traffic_analyzer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "alloc_counter.hpp"

namespace vp::traffic {
namespace {

constexpr std::int64_t kStep_ns = 100'000'000;  // 10 Hz
constexpr std::int64_t kSecond_ns = 1'000'000'000;
constexpr auto kSedan = static_cast<std::size_t>(shape::VehicleType::Sedan);

void add(site::Site& site, site::FeatureKind kind, const std::string& id,
         std::vector<Eigen::Vector2d> points, double width_m = site::kDefaultLaneWidth_m,
         site::ZoneRole role = site::ZoneRole::Count, const std::string& lane = "") {
  site::Feature f;
  f.kind = kind;
  f.id = id;
  f.index = site.features().size();
  f.width_m = width_m;
  f.role = role;
  f.lane = lane;
  site.append(std::move(f), points);
}

std::vector<Eigen::Vector2d> box(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

// Road along north = 0 from east -100 to 100. Lane "eb" (eastbound, north -1.75, 3.5 m wide) ends
// at east 0 (the stop line). Queue zone "q" over east [-60, 0] of the eastbound half; box junction
// "box" over east [0, 20]; gates "w" at east -80 and "e" at east 40 across the road (forward =
// eastbound).
site::Site testSite() {
  site::Site site("test.geojson");
  add(site, site::FeatureKind::Drivable, "road", box(-100.0, -7.0, 100.0, 7.0));
  add(site, site::FeatureKind::Lane, "eb", {{-100.0, -1.75}, {-50.0, -1.75}, {0.0, -1.75}});
  add(site, site::FeatureKind::Zone, "q", box(-60.0, -3.5, 0.0, 0.0), 3.5, site::ZoneRole::Queue,
      "eb");
  add(site, site::FeatureKind::Zone, "box", box(0.0, -7.0, 20.0, 7.0), 3.5,
      site::ZoneRole::BoxJunction);
  add(site, site::FeatureKind::Gate, "w", {{-80.0, 7.0}, {-80.0, -7.0}});
  add(site, site::FeatureKind::Gate, "e", {{40.0, 7.0}, {40.0, -7.0}});
  return site;
}

tracking::TrackState track(std::uint32_t id, double east_m, double north_m, double speed_mps,
                           double heading_rad = 0.0, double length_m = 4.0) {
  tracking::TrackState t;
  t.id = id;
  t.status = tracking::TrackStatus::Confirmed;
  t.centreEnu = {east_m, north_m};
  t.headingEnu_rad = heading_rad;
  t.speed_mps = speed_mps;
  t.length_m = length_m;
  t.type = shape::VehicleType::Sedan;
  return t;
}

TrafficAnalyzerOptions options(double period_s = 10.0) {
  TrafficAnalyzerOptions o;
  o.period_s = period_s;
  o.maxTracks = 64;
  return o;
}

void initOrFail(TrafficAnalyzer& analyzer, const site::Site& site,
                const TrafficAnalyzerOptions& o) {
  std::string why;
  ASSERT_TRUE(analyzer.init(site, o, &why)) << why;
}

std::size_t countEvents(const TrafficAnalyzer& a, TrafficEventKind kind) {
  const auto e = a.events();
  return static_cast<std::size_t>(
      std::count_if(e.begin(), e.end(), [kind](const TrafficEvent& x) { return x.kind == kind; }));
}

TEST(TrafficAnalyzer, QueueInVehiclesAndMetresFromTheStopLine) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(60.0));
  // Three cars standing nose to tail before the stop line (centres 3, 9 and 15 m back, 4 m long),
  // a fourth driving through the zone.
  const std::vector<tracking::TrackState> tracks = {
      track(1, -3.0, -1.75, 0.0), track(2, -9.0, -1.75, 0.2), track(3, -15.0, -1.75, 0.5),
      track(4, -30.0, -1.75, 8.0)};
  std::int64_t t = 0;
  for (int k = 0; k < 20; ++k, t += kStep_ns) {
    ASSERT_TRUE(a.step(t, tracks));
  }
  a.finish(t);
  const TrafficStatistics* s = a.lastPeriod();
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->zoneCount, 2U);
  const ZoneRecord& q = s->zones[0];
  EXPECT_EQ(q.vehiclesNow, 4U);
  EXPECT_EQ(q.maxVehicles, 4U);
  EXPECT_NEAR(q.meanVehicles, 4.0, 1e-9);
  EXPECT_EQ(q.queueNow_vehicles, 3U);
  EXPECT_EQ(q.maxQueue_vehicles, 3U);
  EXPECT_NEAR(q.queueNow_m, 17.0, 1e-9);  // 15 m to the last centre + half of 4 m
  EXPECT_NEAR(q.maxQueue_m, 17.0, 1e-9);
  // The box junction is empty.
  EXPECT_EQ(s->zones[1].maxVehicles, 0U);
}

TEST(TrafficAnalyzer, ZoneWithoutLaneMeasuresTheQueuedLengths) {
  site::Site site("plain.geojson");
  add(site, site::FeatureKind::Drivable, "road", box(-100.0, -7.0, 100.0, 7.0));
  add(site, site::FeatureKind::Zone, "z", box(-10.0, -7.0, 10.0, 7.0));
  TrafficAnalyzer a;
  initOrFail(a, site, options());
  const std::vector<tracking::TrackState> tracks = {track(1, 0.0, 0.0, 0.0, 0.0, 4.5),
                                                    track(2, 5.0, 0.0, 0.0, 0.0, 12.0)};
  ASSERT_TRUE(a.step(0, tracks));
  a.finish(kStep_ns);
  EXPECT_NEAR(a.lastPeriod()->zones[0].queueNow_m, 16.5, 1e-9);
}

TEST(TrafficAnalyzer, MeanOccupancyIsTimeWeighted) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(10.0));
  // One car in the queue zone for the first 4 s of a 10 s period, none after.
  std::int64_t t = 0;
  for (; t < 10 * kSecond_ns; t += kStep_ns) {
    const tracking::TrackState car = track(1, -20.0, -1.75, 0.0);
    ASSERT_TRUE(a.step(t, t < 4 * kSecond_ns ? std::span<const tracking::TrackState>(&car, 1)
                                             : std::span<const tracking::TrackState>()));
  }
  ASSERT_TRUE(a.step(t, {}));
  const TrafficStatistics* s = a.completedPeriod();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->start_ns, 0);
  EXPECT_EQ(s->end_ns, 10 * kSecond_ns);
  EXPECT_NEAR(s->zones[0].meanVehicles, 0.4, 1e-9);
  EXPECT_EQ(s->zones[0].maxVehicles, 1U);
  EXPECT_EQ(s->zones[0].vehiclesNow, 0U);
  // The car stood 4 s (from its first step to the step where it was gone... its last step).
  EXPECT_EQ(s->zones[0].dwellCount, 1U);
  EXPECT_NEAR(s->zones[0].meanDwell_s, 3.9, 1e-9);
}

TEST(TrafficAnalyzer, DwellEndsWhenTheVehicleMovesOrLeaves) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(60.0));
  std::int64_t t = 0;
  // Car 1 stands 3 s, then moves on inside the zone; car 2 stands 5 s and then is outside the zone.
  for (int k = 0; k <= 60; ++k, t += kStep_ns) {
    std::vector<tracking::TrackState> tracks;
    tracks.push_back(track(1, -40.0 + (k > 30 ? 0.5 * (k - 30) : 0.0), -1.75, k > 30 ? 5.0 : 0.0));
    tracks.push_back(k <= 50 ? track(2, -50.0, -1.75, 0.0) : track(2, -50.0, 5.0, 0.0));
    ASSERT_TRUE(a.step(t, tracks));
  }
  a.finish(t);
  const ZoneRecord& q = a.lastPeriod()->zones[0];
  EXPECT_EQ(q.dwellCount, 2U);
  EXPECT_NEAR(q.maxDwell_s, 5.1, 1e-9);               // 0 .. 5.1 s (outside at k = 51)
  EXPECT_NEAR(q.meanDwell_s, (3.1 + 5.1) / 2, 1e-9);  // car 1 moves at k = 31
}

TEST(TrafficAnalyzer, LaneSpeedsOneSamplePerVehicleWithNearestRankP85) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(60.0));
  // Twenty cars along the lane at 1..20 m/s (one per track), each for 10 steps; one car off the
  // lane (north of it, beyond half the width) and one crossing it at right angles do not count.
  std::int64_t t = 0;
  for (int k = 0; k < 10; ++k, t += kStep_ns) {
    std::vector<tracking::TrackState> tracks;
    for (std::uint32_t id = 1; id <= 20; ++id) {
      tracks.push_back(track(id, -95.0 + 4.0 * id, -1.75 + 0.5, static_cast<double>(id)));
    }
    tracks.push_back(track(100, -50.0, 1.0, 30.0));                            // off the lane
    tracks.push_back(track(101, -20.0, -1.75, 30.0, 0.5 * std::numbers::pi));  // across it
    ASSERT_TRUE(a.step(t, tracks));
  }
  a.finish(t);
  const LaneRecord& lane = a.lastPeriod()->lanes[0];
  ASSERT_EQ(a.lastPeriod()->laneCount, 1U);
  EXPECT_EQ(lane.vehicles, 20U);
  EXPECT_NEAR(lane.meanSpeed_mps, 10.5, 1e-9);
  EXPECT_NEAR(lane.p85Speed_mps, 17.0, 1e-9);  // ceil(0.85 * 20) = 17th smallest
  EXPECT_NEAR(lane.maxSpeed_mps, 20.0, 1e-9);
}

TEST(TrafficAnalyzer, WrongWayOncePerTrackAndLaneAfterTheMinimumTime) {
  const site::Site site = testSite();
  TrafficAnalyzerOptions o = options(60.0);
  o.wrongWay_s = 1.0;
  TrafficAnalyzer a;
  initOrFail(a, site, o);
  std::int64_t t = 0;
  std::size_t events = 0;
  std::int64_t firstEvent_ns = -1;
  // Westbound on the eastbound lane at 10 m/s for 3 s; a westbound car that stops is not moving.
  for (int k = 0; k < 30; ++k, t += kStep_ns) {
    const std::vector<tracking::TrackState> tracks = {
        track(7, -10.0 - 1.0 * k, -1.75, 10.0, std::numbers::pi),
        track(8, -70.0, -1.75, 0.5, std::numbers::pi)};
    ASSERT_TRUE(a.step(t, tracks));
    for (const TrafficEvent& e : a.events()) {
      if (e.kind == TrafficEventKind::WrongWay) {
        ++events;
        EXPECT_EQ(e.trackId, 7U);
        EXPECT_EQ(e.featureIndex, 0U);
        if (firstEvent_ns < 0) {
          firstEvent_ns = e.time_ns;
        }
      }
    }
  }
  EXPECT_EQ(events, 1U);
  EXPECT_EQ(firstEvent_ns, 10 * kStep_ns);  // 1 s after the first frame against the lane
  a.finish(t);
  EXPECT_EQ(a.lastPeriod()->wrongWayEvents, 1U);
}

TEST(TrafficAnalyzer, ABriefTurnAgainstTheLaneIsNoWrongWay) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(60.0));
  std::int64_t t = 0;
  for (int k = 0; k < 40; ++k, t += kStep_ns) {
    // Against the lane for 0.5 s out of every 1 s: never 1 s in a row.
    const double heading = (k % 10) < 5 ? std::numbers::pi : 0.0;
    const tracking::TrackState car = track(1, -50.0, -1.75, 10.0, heading);
    ASSERT_TRUE(a.step(t, std::span<const tracking::TrackState>(&car, 1)));
    EXPECT_EQ(countEvents(a, TrafficEventKind::WrongWay), 0U) << k;
  }
}

TEST(TrafficAnalyzer, BoxJunctionStopOncePerTrackAndZone) {
  const site::Site site = testSite();
  TrafficAnalyzerOptions o = options(60.0);
  o.boxJunctionStop_s = 2.0;
  TrafficAnalyzer a;
  initOrFail(a, site, o);
  std::int64_t t = 0;
  std::vector<std::int64_t> eventTimes;
  // Car 3 stops in the box for 4 s; car 4 stops there 1 s only; car 5 stops in the queue zone.
  for (int k = 0; k < 40; ++k, t += kStep_ns) {
    const std::vector<tracking::TrackState> tracks = {track(3, 10.0, -1.75, 0.0),
                                                      track(4, 15.0, 2.0, k < 10 ? 0.0 : 5.0),
                                                      track(5, -10.0, -1.75, 0.0)};
    ASSERT_TRUE(a.step(t, tracks));
    for (const TrafficEvent& e : a.events()) {
      ASSERT_EQ(e.kind, TrafficEventKind::BoxJunctionStop);
      EXPECT_EQ(e.trackId, 3U);
      EXPECT_EQ(e.featureIndex, 1U);  // the second zone
      eventTimes.push_back(e.time_ns);
    }
  }
  ASSERT_EQ(eventTimes.size(), 1U);
  EXPECT_EQ(eventTimes[0], 2 * kSecond_ns);
  a.finish(t);
  EXPECT_EQ(a.lastPeriod()->boxJunctionStops, 1U);
}

TEST(TrafficAnalyzer, GateCrossingsAndTurningMovementEvents) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(60.0));
  std::int64_t t = 0;
  std::size_t crossings = 0;
  std::size_t movements = 0;
  // East along the road from -90 to 50 at 14 m/s, then gone.
  for (int k = 0; k <= 100; ++k, t += kStep_ns) {
    const tracking::TrackState car = track(9, -90.0 + 1.4 * k, -1.75, 14.0);
    const std::span<const tracking::TrackState> tracks =
        k < 100 ? std::span<const tracking::TrackState>(&car, 1)
                : std::span<const tracking::TrackState>();
    ASSERT_TRUE(a.step(t, tracks));
    for (const TrafficEvent& e : a.events()) {
      if (e.kind == TrafficEventKind::GateCrossing) {
        EXPECT_EQ(e.direction, 0U);  // forward
        EXPECT_EQ(e.featureIndex, crossings);
        ++crossings;
      } else if (e.kind == TrafficEventKind::TurningMovement) {
        EXPECT_EQ(e.featureIndex, 0U);
        EXPECT_EQ(e.toFeatureIndex, 1U);
        EXPECT_EQ(e.time_ns, 100 * kStep_ns);
        ++movements;
      }
    }
  }
  EXPECT_EQ(crossings, 2U);
  EXPECT_EQ(movements, 1U);
  a.finish(t);
  const TrafficStatistics* s = a.lastPeriod();
  EXPECT_EQ(s->gateCount, 2U);
  EXPECT_EQ(s->gates[0].byDirectionAndType[0][kSedan], 1U);
  EXPECT_EQ(s->gates[1].byDirectionAndType[0][kSedan], 1U);
  EXPECT_EQ(s->movements[0][1], 1U);
}

TEST(TrafficAnalyzer, PeriodsCloseInTheStepThatReachesTheirEnd) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(10.0));
  std::int64_t t = 5 * kSecond_ns;  // the first period starts at the first step
  std::vector<std::int64_t> closedAt;
  std::vector<std::uint32_t> crossingsPerPeriod;
  // One car crosses gate w every 2 s (each its own track for 1 s).
  for (int k = 0; k < 250; ++k, t += kStep_ns) {
    const std::uint32_t id = static_cast<std::uint32_t>(k / 20);
    const double east = (k % 20) < 10 ? -81.0 : -79.0;
    const tracking::TrackState car = track(id, east, -1.75, 10.0);
    ASSERT_TRUE(a.step(t, std::span<const tracking::TrackState>(&car, 1)));
    if (const TrafficStatistics* s = a.completedPeriod()) {
      closedAt.push_back(t);
      EXPECT_EQ(s->start_ns,
                5 * kSecond_ns + static_cast<std::int64_t>(closedAt.size() - 1) * 10 * kSecond_ns);
      EXPECT_EQ(s->end_ns, s->start_ns + 10 * kSecond_ns);
      EXPECT_EQ(s->sequence, closedAt.size() - 1);
      crossingsPerPeriod.push_back(s->gates[0].byDirectionAndType[0][kSedan]);
    }
  }
  ASSERT_EQ(closedAt.size(), 2U);
  EXPECT_EQ(closedAt[0], 15 * kSecond_ns);
  EXPECT_EQ(closedAt[1], 25 * kSecond_ns);
  EXPECT_EQ(crossingsPerPeriod[0], 5U);
  EXPECT_EQ(crossingsPerPeriod[1], 5U);
  a.finish(t);
  ASSERT_NE(a.lastPeriod(), nullptr);
  EXPECT_EQ(a.lastPeriod()->start_ns, 25 * kSecond_ns);
  EXPECT_EQ(a.lastPeriod()->end_ns, t);
  EXPECT_EQ(a.lastPeriod()->gates[0].byDirectionAndType[0][kSedan],
            2U);                // 25..30 s (the third at 30.4 s)
  EXPECT_FALSE(a.step(0, {}));  // time went backwards
}

TEST(TrafficAnalyzer, AGapLongerThanAPeriodClosesOneAndRestartsOnTheGrid) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  initOrFail(a, site, options(10.0));
  ASSERT_TRUE(a.step(0, {}));
  ASSERT_TRUE(a.step(kSecond_ns, {}));
  EXPECT_EQ(a.completedPeriod(), nullptr);
  ASSERT_TRUE(a.step(35 * kSecond_ns, {}));  // periods [10, 20) and [20, 30) had no frame
  const TrafficStatistics* first = a.completedPeriod();
  ASSERT_NE(first, nullptr);
  const std::int64_t firstStart_ns = first->start_ns;
  const std::int64_t firstEnd_ns = first->end_ns;
  EXPECT_EQ(firstStart_ns, 0);
  EXPECT_EQ(firstEnd_ns, 10 * kSecond_ns);
  a.finish(38 * kSecond_ns);
  const TrafficStatistics* last = a.lastPeriod();
  ASSERT_NE(last, nullptr);
  const std::uint64_t sequence = last->sequence;
  const std::int64_t lastStart_ns = last->start_ns;
  const std::int64_t lastEnd_ns = last->end_ns;
  EXPECT_EQ(sequence, 1U);
  EXPECT_EQ(lastStart_ns, 30 * kSecond_ns);
  EXPECT_EQ(lastEnd_ns, 38 * kSecond_ns);
}

TEST(TrafficAnalyzer, BadOptionsAndSitesAreRefusedNamingTheKeyOrFeature) {
  const site::Site site = testSite();
  TrafficAnalyzer a;
  std::string why;
  TrafficAnalyzerOptions o;
  o.period_s = 0.0;
  EXPECT_FALSE(a.init(site, o, &why));
  EXPECT_NE(why.find("traffic.period_s"), std::string::npos) << why;
  o = {};
  o.wrongWayAngle_deg = 45.0;
  EXPECT_FALSE(a.init(site, o, &why));
  EXPECT_NE(why.find("traffic.wrong_way_angle_deg"), std::string::npos) << why;
  o = {};
  o.maxTracks = 0;
  EXPECT_FALSE(a.init(site, o, &why));
  EXPECT_NE(why.find("traffic.max_tracks"), std::string::npos) << why;

  site::Site bad("bad.geojson");
  add(bad, site::FeatureKind::Drivable, "road", box(-10.0, -7.0, 10.0, 7.0));
  add(bad, site::FeatureKind::Gate, "tiny", {{0.0, 0.0}, {0.1, 0.0}});
  EXPECT_FALSE(a.init(bad, {}, &why));
  EXPECT_NE(why.find("bad.geojson: gate \"tiny\""), std::string::npos) << why;

  site::Site none("none.geojson");
  add(none, site::FeatureKind::Drivable, "road", box(-10.0, -7.0, 10.0, 7.0));
  ASSERT_TRUE(a.init(none, {}, &why)) << why;
  EXPECT_FALSE(a.active());  // nothing to analyse
  TrafficAnalyzerOptions off;
  off.enabled = false;
  ASSERT_TRUE(a.init(site, off, &why)) << why;
  EXPECT_FALSE(a.active());
}

TEST(TrafficAnalyzer, AStepAllocatesNothing) {
  const site::Site site = testSite();
  TrafficAnalyzerOptions o = options(1.0);  // several periods close inside the measured loop
  o.maxTracks = 256;
  o.maxLaneSamples = 64;  // fewer than the vehicles: samples are dropped, not stored
  o.wrongWay_s = 0.0;
  o.boxJunctionStop_s = 0.0;
  TrafficAnalyzer a;
  initOrFail(a, site, o);
  std::vector<tracking::TrackState> states;
  for (std::uint32_t id = 0; id < 200; ++id) {
    // Some eastbound through the gates, some stopped in the queue and the box, some wrong way.
    const double heading = id % 7 == 0 ? std::numbers::pi : 0.0;
    const double speed = id % 3 == 0 ? 0.0 : 10.0;
    states.push_back(track(id, -90.0 + 0.5 * id, -1.75, speed, heading));
  }
  test::AllocationCounter allocations;
  std::int64_t t = 0;
  std::size_t events = 0;
  std::size_t periods = 0;
  for (int k = 0; k < 40; ++k, t += kStep_ns) {
    for (tracking::TrackState& s : states) {
      s.centreEnu.x() += s.speed_mps * 0.1 * std::cos(s.headingEnu_rad);
    }
    // Tracks end and new ones start every step.
    states[static_cast<std::size_t>(k)].id += 1000;
    ASSERT_TRUE(a.step(t, states));
    events += a.events().size();
    periods += a.completedPeriod() != nullptr ? 1 : 0;
  }
  a.finish(t);
  allocations.stop();
  EXPECT_EQ(allocations.count(), 0U);
  EXPECT_GT(events, 0U);
  EXPECT_EQ(periods, 3U);
  EXPECT_GT(a.stats().samplesDropped, 0U);
}

}  // namespace
}  // namespace vp::traffic
