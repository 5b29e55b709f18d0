// Street furniture of a scene: benches, bus shelters, kiosks and stair/underpass entrances on
// the pavements and the grass; with addPoles, sign posts and street lamps along the kerbs. Real
// drone footage shows the detector boxing these (a white bench looks like a small white car from 90
// m); the simulator draws them so that training sees them as background. Sizes follow real objects;
// every site is checked against the drivable area, the buildings, the tree trunks and the other
// furniture.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>

#include "scene.hpp"

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Clear space kept between furniture and the kerb line (a vehicle's mirror or a turning
// vehicle's overhang must not reach it) and between furniture and other objects.
constexpr double kKerbClearance_m = 0.6;
constexpr double kObjectClearance_m = 0.8;

StreetFurniture makeItem(FurnitureKind kind, Rng& rng) {
  StreetFurniture item;
  item.kind = kind;
  switch (kind) {
    case FurnitureKind::Bench: {
      item.length_m = rng.uniform(1.5, 2.2);
      item.width_m = rng.uniform(0.5, 0.7);
      item.backrest = rng.chance(0.7);
      item.height_m = item.backrest ? rng.uniform(0.75, 0.9) : rng.uniform(0.42, 0.48);
      // White (painted or concrete) 35 %, grey metal 25 %, wood 40 %.
      const int colour = rng.weighted(std::array<double, 3>{0.35, 0.25, 0.4});
      if (colour == 0) {
        item.albedo = toneColour(rng, Eigen::Vector3f(0.8F, 0.8F, 0.78F), 0.05);
      } else if (colour == 1) {
        item.albedo = toneColour(rng, Eigen::Vector3f(0.38F, 0.39F, 0.4F), 0.2);
      } else {
        item.albedo = toneColour(rng, Eigen::Vector3f(0.36F, 0.23F, 0.13F), 0.2);
      }
      break;
    }
    case FurnitureKind::Shelter: {
      item.length_m = rng.uniform(3.0, 6.0);
      item.width_m = rng.uniform(1.5, 2.0);
      item.height_m = rng.uniform(2.4, 2.8);
      static const std::array<Eigen::Vector3f, 3> kFrames = {Eigen::Vector3f(0.55F, 0.56F, 0.57F),
                                                             Eigen::Vector3f(0.06F, 0.07F, 0.07F),
                                                             Eigen::Vector3f(0.08F, 0.18F, 0.12F)};
      item.albedo = toneColour(rng, kFrames[static_cast<std::size_t>(rng.uniformInt(0, 2))], 0.1);
      item.roofAlbedo = toneColour(rng, Eigen::Vector3f(0.12F, 0.14F, 0.15F), 0.3);  // glass tint
      break;
    }
    case FurnitureKind::Kiosk: {
      item.length_m = rng.uniform(2.0, 3.5);
      item.width_m = rng.uniform(1.5, 2.5);
      item.height_m = rng.uniform(2.4, 3.0);
      static const std::array<Eigen::Vector3f, 4> kWalls = {
          Eigen::Vector3f(0.7F, 0.68F, 0.62F), Eigen::Vector3f(0.15F, 0.3F, 0.18F),
          Eigen::Vector3f(0.5F, 0.12F, 0.08F), Eigen::Vector3f(0.35F, 0.36F, 0.38F)};
      item.albedo = toneColour(rng, kWalls[static_cast<std::size_t>(rng.uniformInt(0, 3))], 0.1);
      item.roofAlbedo = toneColour(rng, Eigen::Vector3f(0.3F, 0.3F, 0.31F), 0.4);
      break;
    }
    case FurnitureKind::StairEntrance: {
      item.length_m = rng.uniform(4.0, 8.0);  // along the stairs
      item.width_m = rng.uniform(1.8, 3.5);
      item.height_m = rng.uniform(0.95, 1.1);                                    // railing top
      item.albedo = toneColour(rng, Eigen::Vector3f(0.5F, 0.49F, 0.46F), 0.15);  // concrete parapet
      item.roofAlbedo = toneColour(rng, Eigen::Vector3f(0.2F, 0.2F, 0.21F), 0.3);  // railing
      break;
    }
    case FurnitureKind::SignPost: {
      // The plate (0.6-0.9 m, round, square or triangular signs alike as a square) on a pole
      // whose top is 2.6-3.6 m up; length is the plate's width along the item's axis.
      item.length_m = rng.uniform(0.6, 0.9);
      item.width_m = 0.12;
      item.height_m = rng.uniform(2.0, 2.7) + item.length_m;
      item.albedo = toneColour(rng, Eigen::Vector3f(0.5F, 0.5F, 0.5F), 0.15);  // galvanised pole
      // White, blue, red, yellow plates (their faces; the back is the pole's grey).
      static const std::array<Eigen::Vector3f, 4> kPlates = {
          Eigen::Vector3f(0.78F, 0.78F, 0.76F), Eigen::Vector3f(0.04F, 0.12F, 0.42F),
          Eigen::Vector3f(0.55F, 0.05F, 0.05F), Eigen::Vector3f(0.75F, 0.58F, 0.05F)};
      item.roofAlbedo = toneColour(rng,
                                   kPlates[static_cast<std::size_t>(
                                       rng.weighted(std::array<double, 4>{0.35, 0.35, 0.2, 0.1}))],
                                   0.08);
      break;
    }
    case FurnitureKind::StreetLamp: {
      item.length_m = 0.3;  // the pole's base
      item.width_m = 0.3;
      item.height_m = rng.uniform(6.0, 10.0);
      item.reach_m = rng.uniform(0.8, 2.5);
      // Galvanised grey 60 %, painted dark grey or green 40 %.
      item.albedo = rng.chance(0.6) ? toneColour(rng, Eigen::Vector3f(0.5F, 0.5F, 0.5F), 0.15)
                                    : toneColour(rng, Eigen::Vector3f(0.07F, 0.09F, 0.08F), 0.3);
      item.roofAlbedo = toneColour(rng, Eigen::Vector3f(0.25F, 0.25F, 0.26F), 0.3);  // lamp head
      break;
    }
    case FurnitureKind::Motorbikes:
    case FurnitureKind::Bicycles:
    case FurnitureKind::Pedestrians:
      break;  // road users are drawn by road_users.cpp
  }
  item.seed = rng.nextU32();
  return item;
}

// Points sampled over the footprint grown by `grow` (corners, edge midpoints, centre).
std::array<Eigen::Vector2d, 9> samplePoints(const Footprint& f, double grow) {
  const Eigen::Vector2d n(-f.axis.y(), f.axis.x());
  std::array<Eigen::Vector2d, 9> out{};
  std::size_t k = 0;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      out[k++] = f.centre + i * (f.halfLength_m + grow) * f.axis + j * (f.halfWidth_m + grow) * n;
    }
  }
  return out;
}

}  // namespace

bool furnitureSiteClear(const SceneSpec& scene, const StreetFurniture& item, double minRoad_m) {
  const Footprint f = footprintOf(item);
  for (const Eigen::Vector2d& p : samplePoints(f, 0.0)) {
    if (scene.roadDistance(p) < minRoad_m) {
      return false;
    }
  }
  for (const Building& b : scene.buildings) {
    const Footprint fb{b.centre,
                       {std::cos(b.heading_rad), std::sin(b.heading_rad)},
                       0.5 * b.length_m,
                       0.5 * b.width_m};
    if (footprintsOverlap(f, fb, kObjectClearance_m)) {
      return false;
    }
  }
  for (const Tree& t : scene.trees) {
    const Footprint trunk{t.position, {1.0, 0.0}, t.trunkRadius_m, t.trunkRadius_m};
    if (footprintsOverlap(f, trunk, 0.4)) {
      return false;
    }
  }
  for (const StreetFurniture& o : scene.furniture) {
    if (footprintsOverlap(f, footprintOf(o), kObjectClearance_m)) {
      return false;
    }
  }
  return true;
}

namespace {

void addPavementFurniture(SceneSpec& scene, Rng& rng) {
  const double kerb = scene.kerbWidth_m;
  for (const Road& road : scene.roads) {
    for (int side = -1; side <= 1; side += 2) {
      const double spacing = rng.uniform(25.0, 50.0);
      const double roadHalf = side > 0 ? road.leftHalf_m() : road.rightHalf_m();
      const double start =
          road.along(scene.viewCentre) - scene.extent_m * 0.7 + rng.uniform(0.0, spacing);
      for (double a = start; a < start + scene.extent_m * 1.4;
           a += spacing * rng.uniform(0.8, 1.2)) {
        // Bench 50 %, bus shelter 15 %, kiosk 8 %, nothing 27 %.
        const int pick = rng.weighted(std::array<double, 4>{0.5, 0.15, 0.08, 0.27});
        if (pick == 3) {
          continue;
        }
        StreetFurniture item = makeItem(static_cast<FurnitureKind>(pick), rng);
        // Near edge kerbClearance behind the kerb (kiosks at the back of the pavement); the
        // front (+left normal of the item) faces the road.
        double nearEdge = kerb + kKerbClearance_m;
        if (item.kind == FurnitureKind::Kiosk) {
          nearEdge = std::max(nearEdge, kerb + scene.sidewalkWidth_m - 0.5 * item.width_m);
        }
        const double lateral = side * (roadHalf + nearEdge + 0.5 * item.width_m);
        item.centre = road.centre + a * road.dir + lateral * road.leftNormal();
        const Eigen::Vector2d front = -side * road.leftNormal();  // towards the road
        // Length along the road, +left normal of the item towards the road.
        item.heading_rad = std::atan2(-front.x(), front.y());
        if (furnitureSiteClear(scene, item, kerb + kKerbClearance_m - 0.01)) {
          scene.furniture.push_back(item);
        }
      }
    }
  }
}

void addGrassFurniture(SceneSpec& scene, Rng& rng) {
  // Park benches 0-6, a kiosk (30 %), stair/underpass entrances 0-2 (40 %): off the pavement.
  const int benches = rng.uniformInt(0, 6);
  const int kiosks = rng.chance(0.3) ? 1 : 0;
  const int entrances = rng.chance(0.4) ? rng.uniformInt(1, 2) : 0;
  const double minRoad = scene.kerbWidth_m + scene.sidewalkWidth_m + 0.5;
  const std::array<std::pair<FurnitureKind, int>, 3> wanted = {
      std::make_pair(FurnitureKind::Bench, benches), std::make_pair(FurnitureKind::Kiosk, kiosks),
      std::make_pair(FurnitureKind::StairEntrance, entrances)};
  for (const auto& [kind, count] : wanted) {
    for (int attempt = 0, placed = 0; attempt < count * 25 && placed < count; ++attempt) {
      placed += placeOffTheRoads(scene, rng, makeItem(kind, rng), minRoad) ? 1 : 0;
    }
  }
}

// Along each side of each road: street lamps every U(25, 40) m on a lit side (70 %), sign
// posts at sites every U(15, 45) m (60 % of the sites), and at an intersection a sign post on
// the right of each approach at its stop line. Each stands kKerbClearance_m behind the kerb
// (the lamp's arm and a plate overhang the pavement above a vehicle's height, not the lanes)
// and outside every tree's crown.
void addPoleRow(SceneSpec& scene, const Road& road, int side, Rng& rng) {
  const double kerb = scene.kerbWidth_m;
  const double roadHalf = side > 0 ? road.leftHalf_m() : road.rightHalf_m();
  const Eigen::Vector2d front = -side * road.leftNormal();  // towards the road
  const double roadHeading = std::atan2(road.dir.y(), road.dir.x());
  const double first = road.along(scene.viewCentre) - scene.extent_m * 0.7;
  const double last = first + scene.extent_m * 1.4;
  const auto place = [&](StreetFurniture item, double along) {
    // The footprint's half extent across the road (a plate facing the traffic lies across it).
    const Eigen::Vector2d axis = item.axis();
    const double halfAcross =
        0.5 * item.length_m * std::fabs(axis.dot(road.leftNormal())) +
        0.5 * item.width_m * std::fabs(Eigen::Vector2d(-axis.y(), axis.x()).dot(road.leftNormal()));
    const double lateral = side * (roadHalf + kerb + kKerbClearance_m + halfAcross);
    item.centre = road.centre + along * road.dir + lateral * road.leftNormal();
    // Poles stand clear of the street trees' crowns (a lamp inside a crown would not be seen,
    // and lighting plans keep them apart).
    const bool underCrown = std::any_of(scene.trees.begin(), scene.trees.end(), [&](const Tree& t) {
      return (t.position - item.centre).norm() < t.canopyRadius_m + 0.5;
    });
    if (!underCrown && furnitureSiteClear(scene, item, kerb + kKerbClearance_m - 0.01)) {
      scene.furniture.push_back(item);
    }
  };
  if (rng.chance(0.7)) {
    const double spacing = rng.uniform(25.0, 40.0);
    for (double a = first + rng.uniform(0.0, spacing); a < last; a += spacing) {
      StreetFurniture lamp = makeItem(FurnitureKind::StreetLamp, rng);
      lamp.heading_rad = std::atan2(-front.x(), front.y());  // the arm (front) over the road
      place(lamp, a);
    }
  }
  for (double a = first + rng.uniform(0.0, 30.0); a < last; a += rng.uniform(15.0, 45.0)) {
    if (rng.chance(0.6)) {
      StreetFurniture sign = makeItem(FurnitureKind::SignPost, rng);
      sign.heading_rad = roadHeading + (rng.chance(0.6) ? 0.5 * kPi : 0.0);  // facing traffic
      place(sign, a);
    }
  }
  if (scene.kind == SceneKind::Intersection && road.stopDistance_m < 1e8) {
    // Traffic on the right of the centreline (forward lanes, side -1) approaches the junction
    // at along = -stopDistance; on the left (side +1) at +stopDistance.
    StreetFurniture sign = makeItem(FurnitureKind::SignPost, rng);
    sign.heading_rad = roadHeading + 0.5 * kPi;
    place(sign, side < 0 ? -road.stopDistance_m - 1.0 : road.stopDistance_m + 1.0);
  }
}

}  // namespace

void addPoles(SceneSpec& scene) {
  Rng rng((static_cast<std::uint64_t>(scene.style.seed) << 32U) ^ 0x9015'b0a7ULL);
  for (const Road& road : scene.roads) {
    for (int side = -1; side <= 1; side += 2) {
      addPoleRow(scene, road, side, rng);
    }
  }
}

const char* toString(FurnitureKind kind) {
  switch (kind) {
    case FurnitureKind::Bench:
      return "bench";
    case FurnitureKind::Shelter:
      return "shelter";
    case FurnitureKind::Kiosk:
      return "kiosk";
    case FurnitureKind::StairEntrance:
      return "stair_entrance";
    case FurnitureKind::SignPost:
      return "sign_post";
    case FurnitureKind::StreetLamp:
      return "street_lamp";
    case FurnitureKind::Motorbikes:
      return "motorbikes";
    case FurnitureKind::Bicycles:
      return "bicycles";
    case FurnitureKind::Pedestrians:
      return "pedestrians";
  }
  return "unknown";
}

bool placeOffTheRoads(SceneSpec& scene, Rng& rng, StreetFurniture item, double minRoad_m) {
  const double r = rng.uniform(6.0, scene.extent_m * 0.6);
  const double a = rng.uniform(0.0, 2.0 * kPi);
  item.centre = scene.viewCentre + r * Eigen::Vector2d(std::cos(a), std::sin(a));
  item.heading_rad = rng.uniform(0.0, 2.0 * kPi);
  if (!furnitureSiteClear(scene, item, minRoad_m)) {
    return false;
  }
  scene.furniture.push_back(item);
  return true;
}

bool footprintsOverlap(const Footprint& a, const Footprint& b, double margin_m) {
  const std::array<Eigen::Vector2d, 4> axes = {a.axis, Eigen::Vector2d(-a.axis.y(), a.axis.x()),
                                               b.axis, Eigen::Vector2d(-b.axis.y(), b.axis.x())};
  const auto radius = [](const Footprint& f, const Eigen::Vector2d& u) {
    const Eigen::Vector2d n(-f.axis.y(), f.axis.x());
    return f.halfLength_m * std::fabs(f.axis.dot(u)) + f.halfWidth_m * std::fabs(n.dot(u));
  };
  const Eigen::Vector2d d = b.centre - a.centre;
  for (const Eigen::Vector2d& u : axes) {
    if (std::fabs(d.dot(u)) > radius(a, u) + radius(b, u) + 2.0 * margin_m) {
      return false;  // a separating axis
    }
  }
  return true;
}

Footprint footprintOf(const StreetFurniture& item) {
  return {item.centre, item.axis(), 0.5 * item.length_m, 0.5 * item.width_m};
}

Eigen::Vector3f toneColour(Rng& rng, Eigen::Vector3f c, double amount) {
  c *= static_cast<float>(std::max(0.3, 1.0 + rng.normal(0.0, amount)));
  return c.cwiseMin(0.92F).cwiseMax(0.01F);
}

void addStreetFurniture(SceneSpec& scene) {
  Rng rng((static_cast<std::uint64_t>(scene.style.seed) << 32U) ^ 0x5eed'f00dULL);
  addPavementFurniture(scene, rng);
  addGrassFurniture(scene, rng);
}

}  // namespace vp::sim
