// Road users that are not vehicles (vp_simulate --road-users): rows of parked motorbikes and
// scooters and bicycle racks at the kerb edge of the pavements, and groups of pedestrians on the
// pavements and the grass. On real footage a row of motorbikes, a full bicycle rack or a few
// people together make a car-sized blob of colour at 5-15 cm per pixel; the simulator draws them
// as background (listed in ground_truth/furniture.csv, never as vehicles). Sizes follow real
// machines and people: motorbikes 1.8-2.3 m long, scooters 1.6-1.9 m, bicycles 1.65-1.85 m,
// people 1.5-1.95 m tall.
#include <array>
#include <cmath>
#include <cstdint>

#include "scene.hpp"

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kKerbClearance_m = 0.6;  // as the other pavement furniture

// Paint of motorbikes and bicycle frames: black, white, silver, red, blue, and a rare bright
// colour.
Eigen::Vector3f machineColour(Rng& rng) {
  static const std::array<Eigen::Vector3f, 7> kColours = {
      Eigen::Vector3f(0.04F, 0.04F, 0.045F), Eigen::Vector3f(0.75F, 0.75F, 0.73F),
      Eigen::Vector3f(0.45F, 0.46F, 0.47F),  Eigen::Vector3f(0.5F, 0.05F, 0.04F),
      Eigen::Vector3f(0.05F, 0.12F, 0.4F),   Eigen::Vector3f(0.7F, 0.5F, 0.05F),
      Eigen::Vector3f(0.12F, 0.35F, 0.1F)};
  const auto pick = static_cast<std::size_t>(
      rng.weighted(std::array<double, 7>{0.34, 0.16, 0.16, 0.14, 0.1, 0.05, 0.05}));
  return toneColour(rng, kColours[pick], 0.12);
}

// A row of `count` motorbikes or bicycles side by side at `pitch_m`, each `machineLength_m` long:
// the item's length axis runs along the row, the machines point across it (+left normal).
StreetFurniture makeRow(FurnitureKind kind, int count, double pitch_m, double machineLength_m,
                        double height_m, Rng& rng) {
  StreetFurniture item;
  item.kind = kind;
  item.count = count;
  item.length_m = (count - 1) * pitch_m + 0.8;  // handlebars stick out beside the end machines
  item.width_m = machineLength_m;
  item.height_m = height_m;
  item.albedo = machineColour(rng);  // the first machine's; the mesh varies the others
  item.roofAlbedo = toneColour(rng, Eigen::Vector3f(0.42F, 0.43F, 0.44F), 0.15);  // rack rail
  item.seed = rng.nextU32();
  return item;
}

StreetFurniture makeMotorbikes(Rng& rng) {
  const bool scooters = rng.chance(0.35);
  const int count = rng.weighted(std::array<double, 5>{0.3, 0.25, 0.2, 0.15, 0.1}) + 1;
  const double length = scooters ? rng.uniform(1.6, 1.9) : rng.uniform(1.8, 2.3);
  return makeRow(FurnitureKind::Motorbikes, count, rng.uniform(0.9, 1.2), length,
                 scooters ? rng.uniform(1.05, 1.2) : rng.uniform(1.1, 1.35), rng);
}

StreetFurniture makeBicycles(Rng& rng) {
  const int count = rng.uniformInt(2, 8);
  return makeRow(FurnitureKind::Bicycles, count, rng.uniform(0.6, 0.85), rng.uniform(1.65, 1.85),
                 rng.uniform(0.95, 1.1), rng);
}

// One to five people within a footprint of about a metre per person.
StreetFurniture makePedestrians(Rng& rng) {
  StreetFurniture item;
  item.kind = FurnitureKind::Pedestrians;
  item.count = rng.weighted(std::array<double, 5>{0.35, 0.3, 0.15, 0.12, 0.08}) + 1;
  item.length_m = 0.6 + 0.7 * (item.count - 1) * rng.uniform(0.8, 1.2);
  item.width_m = item.count == 1 ? 0.45 : rng.uniform(0.6, 1.4);
  item.height_m = rng.uniform(1.5, 1.95);                                  // the tallest member
  item.albedo = toneColour(rng, Eigen::Vector3f(0.3F, 0.3F, 0.32F), 0.5);  // first one's top
  item.roofAlbedo = Eigen::Vector3f(0.08F, 0.06F, 0.05F);                  // hair
  item.seed = rng.nextU32();
  return item;
}

// Rows at the kerb edge of each pavement, pedestrians anywhere on it.
void addAlongPavements(SceneSpec& scene, Rng& rng) {
  const double kerb = scene.kerbWidth_m;
  for (const Road& road : scene.roads) {
    for (int side = -1; side <= 1; side += 2) {
      const double roadHalf = side > 0 ? road.leftHalf_m() : road.rightHalf_m();
      const Eigen::Vector2d towardsRoad = -side * road.leftNormal();
      const double first = road.along(scene.viewCentre) - scene.extent_m * 0.7;
      const double last = first + scene.extent_m * 1.4;
      for (double a = first + rng.uniform(0.0, 15.0); a < last; a += rng.uniform(8.0, 25.0)) {
        // Pedestrians 35 %, motorbikes 35 %, bicycles 30 % (groups of people also on the grass).
        const int pick = rng.weighted(std::array<double, 3>{0.35, 0.35, 0.3});
        StreetFurniture item = pick == 0   ? makePedestrians(rng)
                               : pick == 1 ? makeMotorbikes(rng)
                                           : makeBicycles(rng);
        double lateral = 0.0;
        if (item.kind == FurnitureKind::Pedestrians) {
          // Walking along the pavement or standing anywhere on it.
          const double room = scene.sidewalkWidth_m - kKerbClearance_m - item.width_m;
          lateral =
              kerb + kKerbClearance_m + 0.5 * item.width_m + rng.uniform(0.0, std::max(room, 0.0));
          item.heading_rad = std::atan2(road.dir.y(), road.dir.x()) +
                             (rng.chance(0.5) ? 0.0 : kPi) + rng.normal(0.0, 0.3);
        } else {
          // The row along the kerb, the machines' front wheels towards the road (or the
          // pavement: parked either way).
          lateral = kerb + kKerbClearance_m + 0.5 * item.width_m;
          const Eigen::Vector2d front =
              rng.chance(0.7) ? towardsRoad : Eigen::Vector2d(-towardsRoad);
          item.heading_rad = std::atan2(-front.x(), front.y()) + rng.normal(0.0, 0.08);
        }
        item.centre = road.centre + a * road.dir + side * (roadHalf + lateral) * road.leftNormal();
        // A row that does not fit (a tree, a bench) is shortened, as riders park in the gap.
        const int fewest = item.kind == FurnitureKind::Bicycles ? 2 : 1;
        const double pitch = item.count > 1 ? (item.length_m - 0.8) / (item.count - 1) : 0.0;
        const double minRoad = kerb + kKerbClearance_m - 0.01;
        bool clear = furnitureSiteClear(scene, item, minRoad);
        while (!clear && item.kind != FurnitureKind::Pedestrians && item.count > fewest) {
          --item.count;
          item.length_m = (item.count - 1) * pitch + 0.8;
          clear = furnitureSiteClear(scene, item, minRoad);
        }
        if (clear) {
          scene.furniture.push_back(item);
        }
      }
    }
  }
}

// A few groups of people on the grass and plazas away from the roads.
void addOnGrass(SceneSpec& scene, Rng& rng) {
  const int groups = rng.uniformInt(0, 4);
  const double minRoad = scene.kerbWidth_m + scene.sidewalkWidth_m + 0.5;
  for (int attempt = 0, placed = 0; attempt < groups * 25 && placed < groups; ++attempt) {
    placed += placeOffTheRoads(scene, rng, makePedestrians(rng), minRoad) ? 1 : 0;
  }
}

}  // namespace

void addRoadUsers(SceneSpec& scene) {
  Rng rng((static_cast<std::uint64_t>(scene.style.seed) << 32U) ^ 0x0b1c'7c1eULL);
  addAlongPavements(scene, rng);
  addOnGrass(scene, rng);
}

}  // namespace vp::sim
