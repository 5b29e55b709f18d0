// traffic::GateCounter against tracks driven along known paths: crossings by gate, direction
// and type, turning movements between gates, the tie rule on the line, capacity limits, the
// configuration checks, and no allocation per step.
#include "traffic/gate_counter.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "alloc_counter.hpp"

namespace vp::traffic {
namespace {

constexpr std::int64_t kStep_ns = 100'000'000;  // 10 Hz

tracking::TrackState track(std::uint32_t id, double east_m, double north_m,
                           shape::VehicleType type = shape::VehicleType::Sedan) {
  tracking::TrackState t;
  t.id = id;
  t.status = tracking::TrackStatus::Confirmed;
  t.centreEnu = {east_m, north_m};
  t.type = type;
  t.speed_mps = 10.0;
  return t;
}

// A four-arm intersection around the origin: gates across each arm, 20 m out, each drawn so
// that Forward is "into the intersection".
std::vector<Gate> intersectionGates() {
  return {
      {10, {-20.0, 5.0}, {-20.0, -5.0}},  // west arm (index 0): eastbound is Forward
      {20, {20.0, -5.0}, {20.0, 5.0}},    // east arm (1): westbound is Forward
      {30, {-5.0, -20.0}, {5.0, -20.0}},  // south arm (2): northbound is Forward
      {40, {5.0, 20.0}, {-5.0, 20.0}},    // north arm (3): southbound is Forward
  };
}

GateCounter makeCounter(std::span<const Gate> gates, GateCounterOptions options = {}) {
  GateCounter counter;
  std::string why;
  EXPECT_TRUE(counter.init(gates, options, &why)) << why;
  return counter;
}

// Drives one track along the points, one step each, then one empty step (the track ends).
void drive(GateCounter& counter, std::int64_t& t_ns, std::uint32_t id,
           const std::vector<Eigen::Vector2d>& path, shape::VehicleType type) {
  for (const Eigen::Vector2d& p : path) {
    const tracking::TrackState state = track(id, p.x(), p.y(), type);
    ASSERT_TRUE(counter.step(t_ns, std::span<const tracking::TrackState>(&state, 1)));
    t_ns += kStep_ns;
  }
  ASSERT_TRUE(counter.step(t_ns, {}));
  t_ns += kStep_ns;
}

std::vector<Eigen::Vector2d> line(Eigen::Vector2d from, Eigen::Vector2d to, int steps) {
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k <= steps; ++k) {
    points.push_back(from + (to - from) * (static_cast<double>(k) / steps));
  }
  return points;
}

TEST(GateCounter, CountsEachCrossingOnceByDirectionAndType) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates);
  std::int64_t t = 0;
  // Eastbound through the west arm into the intersection: one Forward crossing of gate 10.
  drive(counter, t, 1, line({-40.0, -2.0}, {-10.0, -2.0}, 15), shape::VehicleType::Van);
  EXPECT_EQ(counter.count(0, CrossingDirection::Forward, shape::VehicleType::Van), 1U);
  EXPECT_EQ(counter.count(0, CrossingDirection::Forward), 1U);
  EXPECT_EQ(counter.count(0, CrossingDirection::Backward), 0U);
  // Westbound out of the intersection through the west arm: Backward.
  drive(counter, t, 2, line({-10.0, 2.0}, {-40.0, 2.0}, 15), shape::VehicleType::Large);
  EXPECT_EQ(counter.count(0, CrossingDirection::Backward, shape::VehicleType::Large), 1U);
  // Past the gate's end (north of it): nothing.
  drive(counter, t, 3, line({-40.0, 8.0}, {-10.0, 8.0}, 15), shape::VehicleType::Sedan);
  EXPECT_EQ(counter.count(0, CrossingDirection::Forward), 1U);
  for (std::size_t g = 1; g < gates.size(); ++g) {
    EXPECT_EQ(counter.count(g, CrossingDirection::Forward), 0U) << g;
    EXPECT_EQ(counter.count(g, CrossingDirection::Backward), 0U) << g;
  }
  EXPECT_EQ(counter.stats().crossings, 2U);
}

TEST(GateCounter, ReportsTheCrossingsOfTheStepWithTrackTypeAndSpeed) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates);
  const tracking::TrackState before = track(7, 2.0, -21.0, shape::VehicleType::Suv);
  const tracking::TrackState after = track(7, 2.0, -19.0, shape::VehicleType::Suv);
  ASSERT_TRUE(counter.step(0, std::span<const tracking::TrackState>(&before, 1)));
  EXPECT_TRUE(counter.crossings().empty());
  ASSERT_TRUE(counter.step(kStep_ns, std::span<const tracking::TrackState>(&after, 1)));
  ASSERT_EQ(counter.crossings().size(), 1U);
  const GateCrossing& c = counter.crossings()[0];
  EXPECT_EQ(c.gateId, 30U);
  EXPECT_EQ(c.trackId, 7U);
  EXPECT_EQ(c.time_ns, kStep_ns);
  EXPECT_EQ(c.direction, CrossingDirection::Forward);
  EXPECT_EQ(c.type, shape::VehicleType::Suv);
  EXPECT_DOUBLE_EQ(c.speed_mps, 10.0);
  EXPECT_STREQ(toString(c.direction), "forward");
}

TEST(GateCounter, AStopOnTheLineIsOneCrossing) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates);
  std::int64_t t = 0;
  // Up to the south gate's line (north = -20 exactly), a wait there, then on: one crossing.
  drive(counter, t, 1, {{0.0, -24.0}, {0.0, -20.0}, {0.0, -20.0}, {0.0, -20.0}, {0.0, -16.0}},
        shape::VehicleType::Sedan);
  EXPECT_EQ(counter.count(2, CrossingDirection::Forward), 1U);
  EXPECT_EQ(counter.count(2, CrossingDirection::Backward), 0U);
  // Onto the line and back: no net crossing is counted twice; it is counted as it happened.
  drive(counter, t, 2, {{1.0, -24.0}, {1.0, -20.0}, {1.0, -24.0}}, shape::VehicleType::Sedan);
  EXPECT_EQ(counter.count(2, CrossingDirection::Forward), 1U);
  EXPECT_EQ(counter.count(2, CrossingDirection::Backward), 0U);
}

TEST(GateCounter, TurningMovementsFromTheFirstToTheLastGate) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates);
  std::int64_t t = 0;
  // West arm in, north arm out (a left turn for an eastbound car): 0 -> 3.
  std::vector<Eigen::Vector2d> leftTurn = line({-40.0, -2.0}, {-2.0, -2.0}, 19);
  const std::vector<Eigen::Vector2d> north = line({-2.0, 0.0}, {-2.0, 40.0}, 20);
  leftTurn.insert(leftTurn.end(), north.begin(), north.end());
  drive(counter, t, 1, leftTurn, shape::VehicleType::Compact);
  // South arm in, east arm out (a right turn), twice, one of them a van: 2 -> 1.
  std::vector<Eigen::Vector2d> rightTurn = line({2.0, -40.0}, {2.0, 2.0}, 21);
  const std::vector<Eigen::Vector2d> east = line({4.0, 2.0}, {40.0, 2.0}, 18);
  rightTurn.insert(rightTurn.end(), east.begin(), east.end());
  drive(counter, t, 2, rightTurn, shape::VehicleType::Sedan);
  drive(counter, t, 3, rightTurn, shape::VehicleType::Van);
  // Only one gate crossed (the track ends inside): no movement.
  drive(counter, t, 4, line({-40.0, -2.0}, {-5.0, -2.0}, 10), shape::VehicleType::Sedan);

  EXPECT_EQ(counter.turningMovements(0, 3), 1U);
  EXPECT_EQ(counter.turningMovements(0, 3, shape::VehicleType::Compact), 1U);
  EXPECT_EQ(counter.turningMovements(2, 1), 2U);
  EXPECT_EQ(counter.turningMovements(2, 1, shape::VehicleType::Van), 1U);
  std::uint64_t total = 0;
  for (std::size_t a = 0; a < gates.size(); ++a) {
    for (std::size_t b = 0; b < gates.size(); ++b) {
      total += counter.turningMovements(a, b);
    }
  }
  EXPECT_EQ(total, 3U);
  EXPECT_EQ(counter.stats().turningMovements, 3U);
  EXPECT_EQ(counter.count(0, CrossingDirection::Forward), 2U);   // tracks 1 and 4
  EXPECT_EQ(counter.count(3, CrossingDirection::Backward), 1U);  // track 1 leaves northwards
}

TEST(GateCounter, FinishCountsTheMovementsOfTracksStillAlive) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates);
  std::int64_t t = 0;
  for (const Eigen::Vector2d& p : line({-40.0, -2.0}, {40.0, -2.0}, 20)) {
    const tracking::TrackState state = track(5, p.x(), p.y());
    ASSERT_TRUE(counter.step(t, std::span<const tracking::TrackState>(&state, 1)));
    t += kStep_ns;
  }
  EXPECT_EQ(counter.turningMovements(0, 1), 0U);
  counter.finish();
  EXPECT_EQ(counter.turningMovements(0, 1), 1U);  // straight through, west to east
}

TEST(GateCounter, TentativeTracksAndTimeGoingBackwardsAreIgnored) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates);
  tracking::TrackState a = track(1, -21.0, 0.0);
  tracking::TrackState b = track(1, -19.0, 0.0);
  a.status = b.status = tracking::TrackStatus::Tentative;
  ASSERT_TRUE(counter.step(0, std::span<const tracking::TrackState>(&a, 1)));
  ASSERT_TRUE(counter.step(kStep_ns, std::span<const tracking::TrackState>(&b, 1)));
  EXPECT_EQ(counter.stats().crossings, 0U);
  EXPECT_FALSE(counter.step(0, {}));
  EXPECT_EQ(counter.stats().stepsRefused, 1U);
}

TEST(GateCounter, FullTablesDropAndCount) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates, {.maxTracks = 2, .maxCrossingsPerStep = 1});
  std::vector<tracking::TrackState> before;
  std::vector<tracking::TrackState> after;
  for (std::uint32_t id = 1; id <= 3; ++id) {
    before.push_back(track(id, -21.0, static_cast<double>(id)));
    after.push_back(track(id, -19.0, static_cast<double>(id)));
  }
  ASSERT_TRUE(counter.step(0, before));
  EXPECT_EQ(counter.stats().tracksDropped, 1U);  // the third track
  ASSERT_TRUE(counter.step(kStep_ns, after));
  EXPECT_EQ(counter.crossings().size(), 1U);
  EXPECT_EQ(counter.stats().crossingsDropped, 1U);
  EXPECT_EQ(counter.count(0, CrossingDirection::Forward), 2U);  // counted all the same
}

TEST(GateCounter, BadGatesAreRefusedNamingTheGate) {
  GateCounter counter;
  std::string why;
  const std::vector<Gate> shortGate{{5, {0.0, 0.0}, {0.1, 0.0}}};
  EXPECT_FALSE(counter.init(shortGate, {}, &why));
  EXPECT_NE(why.find("gate 5:"), std::string::npos) << why;
  const std::vector<Gate> twice{{6, {0.0, 0.0}, {5.0, 0.0}}, {6, {0.0, 1.0}, {5.0, 1.0}}};
  EXPECT_FALSE(counter.init(twice, {}, &why));
  EXPECT_NE(why.find("gate 6: the id is used twice"), std::string::npos) << why;
  const std::vector<Gate> notFinite{{7, {0.0, 0.0}, {std::nan(""), 0.0}}};
  EXPECT_FALSE(counter.init(notFinite, {}, &why));
  EXPECT_NE(why.find("gate 7: an end point is not finite"), std::string::npos) << why;
  const std::vector<Gate> many(kMaxGates + 1);
  EXPECT_FALSE(counter.init(many, {}, &why));
  EXPECT_NE(why.find("at most"), std::string::npos) << why;
  EXPECT_FALSE(counter.init(intersectionGates(), {.maxTracks = 0}, &why));
  EXPECT_NE(why.find("maxTracks"), std::string::npos) << why;
}

TEST(GateCounter, AStepAllocatesNothing) {
  const std::vector<Gate> gates = intersectionGates();
  GateCounter counter = makeCounter(gates, {.maxTracks = 256});
  std::vector<tracking::TrackState> states;
  for (std::uint32_t id = 0; id < 200; ++id) {
    states.push_back(track(id, -30.0, -4.0 + 0.04 * id));
  }
  test::AllocationCounter allocations;
  std::int64_t t = 0;
  for (int k = 0; k < 30; ++k) {
    for (tracking::TrackState& s : states) {
      s.centreEnu.x() += 1.0;
    }
    ASSERT_TRUE(counter.step(t, states));
    t += kStep_ns;
  }
  counter.finish();
  allocations.stop();
  EXPECT_EQ(allocations.count(), 0U);
  EXPECT_EQ(counter.count(0, CrossingDirection::Forward), 200U);
}

}  // namespace
}  // namespace vp::traffic
