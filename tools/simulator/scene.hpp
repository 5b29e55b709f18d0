// simulator/scene: the static world of a simulated sequence, drawn from the seed.
//
// Contract: generateScene() turns a scene kind and the sequence's Rng into a SceneSpec: the
// road layout (an intersection of two roads, a straight section, or a straight road with a
// parking lot), lane and marking style, kerbs and pavements, asphalt patches and manholes,
// buildings with their roof fixtures, trees, street furniture, the lighting (sun
// elevation/azimuth, sun and sky colour) and the traffic parameters. Everything is in the world
// ENU frame (metres, x east, y north); z is taken from the terrain when the scene is built. The
// spec is plain data: the renderer, the ground texture and the traffic read it, nothing
// modifies it after generation.
// Right-hand traffic: a road's forward lanes lie to the right of its direction.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim_random.hpp"

namespace vp::sim {

enum class SceneKind { Intersection, Straight, Parking };
const char* toString(SceneKind kind);
std::optional<SceneKind> sceneKindFromString(const std::string& name);

enum class CentreLine { DoubleYellow, YellowDashed, WhiteDashed, None };

struct Road {
  Eigen::Vector2d centre{0, 0};  // a point on the centreline, ENU m
  Eigen::Vector2d dir{1, 0};     // unit direction of the forward lanes
  int lanesForward = 1;          // right of the centreline
  int lanesBackward = 1;         // left of the centreline, driving against dir
  double laneWidth_m = 3.3;
  double medianHalf_m = 0.15;   // half the gap between opposing lanes
  double parkingRight_m = 0.0;  // kerb parking lane width right of the forward lanes (0: none)
  double parkingLeft_m = 0.0;   // ... left of the backward lanes
  CentreLine centreLine = CentreLine::DoubleYellow;
  bool edgeLines = true;  // solid line between travel and parking lanes / kerb
  double dashLength_m = 3.0;
  double dashGap_m = 6.0;
  double stopDistance_m = 1e9;     // |along| of the stop lines (intersection only)
  double crosswalkCentre_m = 1e9;  // |along| of the crosswalk centres (1e9: none)
  double crosswalkWidth_m = 3.0;
  bool zebra = true;  // zebra stripes, else two transverse lines
  // > 0: the median is widened to hold raised traffic islands of this half width (addIslands);
  // outside the islands it is a painted median, hatched when medianHatch.
  double islandHalfWidth_m = 0.0;
  bool medianHatch = false;

  Eigen::Vector2d leftNormal() const { return {-dir.y(), dir.x()}; }
  double rightHalf_m() const { return medianHalf_m + lanesForward * laneWidth_m + parkingRight_m; }
  double leftHalf_m() const { return medianHalf_m + lanesBackward * laneWidth_m + parkingLeft_m; }
  // Lateral offset (along leftNormal) of a travel lane's centre: forward lanes are negative.
  double laneOffset_m(bool forward, int lane) const {
    const double o = medianHalf_m + (lane + 0.5) * laneWidth_m;
    return forward ? -o : o;
  }
  double along(const Eigen::Vector2d& p) const { return (p - centre).dot(dir); }
  double lateral(const Eigen::Vector2d& p) const { return (p - centre).dot(leftNormal()); }
};

struct ParkingLot {
  Eigen::Vector2d centre{0, 0};
  Eigen::Vector2d dir{1, 0};  // along the rows of bays
  double length_m = 40.0;     // along dir
  double width_m = 30.0;
  double bayWidth_m = 2.5;
  double bayDepth_m = 5.0;
  double aisleWidth_m = 6.5;
  int rows = 2;  // rows of bays (pairs back to back share a line)
  bool yellowLines = false;
  std::vector<double> rowOffsets_m;  // lateral (along leftNormal) centre of each bay row
  std::vector<double> rowFacing;     // +1: cars in the row face +leftNormal, -1: the other way
  int baysPerRow = 0;
  // Bay centres and the heading a car parked in them faces (filled by the generator).
  std::vector<Eigen::Vector3d> bays;  // x, y, heading (rad, ENU)
  Eigen::Vector2d leftNormal() const { return {-dir.y(), dir.x()}; }
};

enum class RoofKind { Flat, Gabled };

// Things on a roof that look like small objects from above (roof_fixtures.cpp places them).
enum class RoofFixtureKind { Hvac, Skylight, Dormer, SolarPanel };

struct RoofFixture {
  RoofFixtureKind kind = RoofFixtureKind::Hvac;
  // Footprint centre in the roof's frame: along the length axis and across it (m from the
  // building centre); gabled roofs: across > 0 on the +normal slope.
  double along_m = 0.0;
  double across_m = 0.0;
  double length_m = 1.0;  // along the building's length axis
  double width_m = 1.0;   // across it (horizontal)
  double height_m = 0.0;  // above the roof (HVAC box, dormer front; flush fixtures: 0)
};

struct Building {
  Eigen::Vector2d centre{0, 0};
  double heading_rad = 0.0;  // direction of the length axis
  double length_m = 20.0;
  double width_m = 12.0;
  double height_m = 8.0;  // eaves height above the lowest ground point of the footprint
  RoofKind roof = RoofKind::Flat;
  double ridgeHeight_m = 0.0;  // gabled: ridge above the eaves
  Eigen::Vector3f wallAlbedo{0.5F, 0.45F, 0.4F};
  Eigen::Vector3f roofAlbedo{0.3F, 0.3F, 0.3F};
  int rooftopUnits = 0;  // flat roofs: boxes of HVAC units
  std::uint32_t seed = 0;
  std::vector<RoofFixture> fixtures;  // HVAC units, skylights, dormers, solar panels
};

struct Tree {
  Eigen::Vector2d position{0, 0};
  double canopyRadius_m = 3.0;
  double canopyVerticalRadius_m = 2.4;
  double canopyCentreHeight_m = 6.0;  // above the ground at the trunk
  double trunkRadius_m = 0.2;
  Eigen::Vector3f leafAlbedo{0.08F, 0.16F, 0.05F};
  float gapFraction = 0.1F;  // share of the canopy that lets light through (bare trees: high)
  std::uint32_t seed = 0;
};

// Street furniture: static non-vehicle objects on pavements and grass (street_furniture.cpp).
// They are not vehicles in the ground truth; the detector must learn to ignore them. Sign posts
// and street lamps (addPoles) are tall and thin: from a tilted camera the pole, the plate or
// the arm and their shadows make car-sized lines and blobs.
// Road users that are not vehicles (addRoadUsers): a row of parked motorbikes or scooters, a
// bicycle rack with its bicycles, a group of pedestrians; one item per row or group, since
// from 100 m such a row is one car-sized blob.
enum class FurnitureKind {
  Bench,
  Shelter,
  Kiosk,
  StairEntrance,
  SignPost,
  StreetLamp,
  Motorbikes,
  Bicycles,
  Pedestrians
};
const char* toString(FurnitureKind kind);

struct StreetFurniture {
  FurnitureKind kind = FurnitureKind::Bench;
  Eigen::Vector2d centre{0, 0};  // footprint centre, ENU m
  double heading_rad = 0.0;      // direction of the length axis; the front faces +left normal
  double length_m = 1.8;
  double width_m = 0.6;   // footprint depth (across the length axis)
  double height_m = 0.8;  // top above the ground (bench backrest, shelter roof, railing, pole)
  double reach_m = 0.0;   // street lamps: the arm's reach from the pole towards the front
  Eigen::Vector3f albedo{0.5F, 0.5F, 0.5F};      // slats, frame, walls, parapet
  Eigen::Vector3f roofAlbedo{0.3F, 0.3F, 0.3F};  // shelter glass tint, kiosk roof, sign plate
  bool backrest = true;                          // benches
  // Road users: members of the row or group (motorbikes and bicycles side by side along the
  // length axis, each facing +left normal; pedestrians anywhere in the footprint).
  int count = 1;
  std::uint32_t seed = 0;
  Eigen::Vector2d axis() const { return {std::cos(heading_rad), std::sin(heading_rad)}; }
};

// A raised traffic island in a road's median: a divider on a junction's approach or a
// pedestrian refuge at a crossing. Kerbed, planted (grass, weeds, bushes) or paved, pointed at
// both ends; a sign post at a nose. Real footage shows the detector boxing planted islands of a
// car's size; the simulator draws them so that training sees them as background.
struct Island {
  Eigen::Vector2d centre{0, 0};
  Eigen::Vector2d dir{1, 0};  // unit, along the road
  double halfLength_m = 5.0;  // centre to tip
  double halfWidth_m = 0.8;
  double noseLength_m = 2.0;      // length of the tapered end towards -dir
  double noseHighLength_m = 2.0;  // ... and towards +dir (0: a blunt end, a wedge-shaped island)
  bool planted = true;            // grass and weeds, else paving
  // Signed distance (m) from the island's kerb line: < 0 inside.
  double distance(const Eigen::Vector2d& p) const;
};

struct Patch {  // repaired rectangle of road surface
  Eigen::Vector2d centre{0, 0};
  Eigen::Vector2d dir{1, 0};
  double halfLength_m = 1.0;
  double halfWidth_m = 1.0;
  float tone = 1.0F;  // albedo multiplier
};

struct Manhole {
  Eigen::Vector2d position{0, 0};
  double radius_m = 0.32;
};

struct GroundStyle {
  bool concreteRoad = false;  // slabs with joints instead of asphalt
  double slabLength_m = 4.5;
  Eigen::Vector3f roadAlbedo{0.12F, 0.12F, 0.12F};
  Eigen::Vector3f lotAlbedo{0.10F, 0.10F, 0.10F};
  float roadMacroVariation = 0.1F;
  float roadFineVariation = 0.1F;
  float wheelTrackDarkening = 0.08F;  // darker (or lighter, < 0) bands where tyres run
  float oilStripe = 0.05F;            // dark stripe along lane centres
  float crackDensity = 0.5F;          // 0..1
  float crackWidth = 0.02F;
  Eigen::Vector3f sidewalkAlbedo{0.4F, 0.39F, 0.37F};
  bool pavers = false;  // small pavers instead of concrete slabs
  double sidewalkSlab_m = 1.5;
  Eigen::Vector3f kerbAlbedo{0.5F, 0.5F, 0.48F};
  Eigen::Vector3f grassA{0.06F, 0.12F, 0.03F};
  Eigen::Vector3f grassB{0.12F, 0.14F, 0.05F};
  Eigen::Vector3f soilAlbedo{0.16F, 0.12F, 0.08F};
  float soilShare = 0.2F;
  Eigen::Vector3f whiteMarking{0.7F, 0.7F, 0.68F};
  Eigen::Vector3f yellowMarking{0.6F, 0.45F, 0.08F};
  float markingWear = 0.3F;  // 0 fresh .. 1 nearly gone
  std::uint32_t seed = 0;
};

struct Lighting {
  double sunElevation_deg = 45.0;
  double sunAzimuth_deg = 180.0;             // clockwise from north
  Eigen::Vector3d sunDirectionEnu{0, 0, 1};  // unit vector towards the sun
  Eigen::Vector3f sunIrradiance{1.0F, 0.97F, 0.9F};
  Eigen::Vector3f skyIrradiance{0.3F, 0.33F, 0.4F};
  float shadowSoftnessTexels = 1.0F;  // PCF radius of the shadow map
  bool overcast = false;
};

struct TrafficParams {
  double arrivalRatePerLane_hz = 0.15;  // Poisson arrivals at each entry lane
  double kerbParkingOccupancy = 0.5;    // share of kerb parking slots taken
  double lotOccupancy = 0.7;
  double largeVehicleShare = 0.05;
  double speedLimit_mps = 12.0;
  double signalCycleS = 40.0;  // intersection: full cycle of the four phases
  double signalOffsetS = 0.0;
};

struct SceneSpec {
  SceneKind kind = SceneKind::Intersection;
  std::vector<Road> roads;         // intersection: 2; straight / parking: 1
  Eigen::Vector2d junction{0, 0};  // intersection centre (or the road's reference point)
  double cornerRadius_m = 6.0;     // kerb radius at the intersection corners
  double kerbWidth_m = 0.2;
  double sidewalkWidth_m = 2.5;
  std::vector<ParkingLot> lots;
  std::vector<Patch> paved;  // extra drivable rectangles (lots, driveways); tone unused
  std::vector<Building> buildings;
  std::vector<Tree> trees;
  std::vector<StreetFurniture> furniture;
  std::vector<Island> islands;  // vp_simulate --islands
  std::vector<Patch> patches;
  std::vector<Manhole> manholes;
  GroundStyle style{};
  Lighting light{};
  TrafficParams traffic{};
  Eigen::Vector2d viewCentre{0, 0};  // where the camera looks
  double extent_m = 150.0;           // objects are generated within this radius of viewCentre
  std::string season = "summer";     // summer | autumn | winter (colours, bare trees)

  // Signed distance (m) from the kerb line of the drivable area (roads and lots): < 0 on
  // the road, > 0 off it. Rounded intersection corners use cornerRadius_m.
  double roadDistance(const Eigen::Vector2d& p) const;
};

// islands: raised traffic islands in the medians (islands.cpp), drawn from an Rng of their own;
// the road they stand in is widened, so the scene differs from the seed's scene without them.
SceneSpec generateScene(SceneKind kind, Rng& rng, bool islands = false);

// Oriented rectangle on the ground plane (overlap tests of furniture, buildings, vehicles).
struct Footprint {
  Eigen::Vector2d centre{0, 0};
  Eigen::Vector2d axis{1, 0};  // unit, along the length
  double halfLength_m = 0.5;
  double halfWidth_m = 0.5;
};
// True when the rectangles, each grown by margin_m, intersect (separating axis test).
bool footprintsOverlap(const Footprint& a, const Footprint& b, double margin_m);
Footprint footprintOf(const StreetFurniture& item);

// Street furniture (street_furniture.cpp), called by generateScene after the buildings and
// trees, and roof fixtures (roof_fixtures.cpp), called for each building placed. Each draws
// from its own Rng seeded from a value the scene already drew (the style's, the building's
// seed): they take nothing from the sequence's Rng, so every other draw of a seed stays as it
// was without them.
void addStreetFurniture(SceneSpec& scene);
// A colour of the street furniture and the islands' planting scaled by a random factor
// N(1, amount) (at least 0.3), kept within reflectances [0.01, 0.92] (street_furniture.cpp).
Eigen::Vector3f toneColour(Rng& rng, Eigen::Vector3f c, double amount);
void addRoofFixtures(Building& building);
// Sign posts and street lamps along the kerbs (street_furniture.cpp), appended to
// scene.furniture: opt-in (vp_simulate --poles), from an Rng of its own, so that a seed's scene
// is otherwise the one it is without them.
void addPoles(SceneSpec& scene);
// Road users that are not vehicles (road_users.cpp), appended to scene.furniture: rows of
// parked motorbikes and scooters and bicycle racks at the kerb edge of the pavements, groups
// of pedestrians on the pavements and the grass. Opt-in (vp_simulate --road-users), from an Rng
// of their own, so that a seed's scene is otherwise the one it is without them.
void addRoadUsers(SceneSpec& scene);
// True when the item's footprint lies at least minRoad_m off the drivable area and clear of
// the buildings, the tree trunks and the furniture already placed (street_furniture.cpp).
bool furnitureSiteClear(const SceneSpec& scene, const StreetFurniture& item, double minRoad_m);
// Places the item at a random site within 0.6 extent_m of the view centre, at any heading
// (the radius, the bearing and the heading drawn from rng in that order), when the site is clear
// (furnitureSiteClear with minRoad_m); returns whether it was placed (street_furniture.cpp).
bool placeOffTheRoads(SceneSpec& scene, Rng& rng, StreetFurniture item, double minRoad_m);
// Traffic islands (islands.cpp), in two steps of generateScene: widenMedians chooses the roads
// that get islands and widens their medians before anything is placed beside the roads;
// addIslands places the islands, their planting and their sign posts once the stop lines,
// crosswalks and trees are known. Both draw only from rng (the islands' own).
void widenMedians(SceneSpec& scene, Rng& rng);
void addIslands(SceneSpec& scene, Rng& rng);

}  // namespace vp::sim
