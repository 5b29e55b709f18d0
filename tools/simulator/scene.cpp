#include "scene.hpp"

#include <algorithm>
#include <cmath>

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector2d unitFromAngle(double a) {
  return {std::cos(a), std::sin(a)};
}

double stripDistance(const Road& road, const Eigen::Vector2d& p) {
  const double l = road.lateral(p);
  return std::max(l - road.leftHalf_m(), -l - road.rightHalf_m());
}

double boxDistance(const Eigen::Vector2d& centre, const Eigen::Vector2d& dir, double halfLength,
                   double halfWidth, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = p - centre;
  const double qx = std::fabs(d.dot(dir)) - halfLength;
  const double qy = std::fabs(d.x() * -dir.y() + d.y() * dir.x()) - halfWidth;
  // sqrt rather than hypot: metres cannot overflow, and this runs per ground texel.
  const double ox = std::max(qx, 0.0);
  const double oy = std::max(qy, 0.0);
  const double outside = std::sqrt(ox * ox + oy * oy);
  return outside + std::min(std::max(qx, qy), 0.0);
}

// Union of two regions given by signed distances, with the inner corners rounded to radius r
// (the kerb radius at a junction).
double roundUnion(double a, double b, double r) {
  const double ux = std::max(r - a, 0.0);
  const double uy = std::max(r - b, 0.0);
  return std::max(r, std::min(a, b)) - std::sqrt(ux * ux + uy * uy);
}

Eigen::Vector3f grey(double v) {
  const auto f = static_cast<float>(v);
  return {f, f, f};
}

// Brightness varies by `amount`, hue by a quarter of it (independent channel jitter of the
// full amount would turn browns purple).
Eigen::Vector3f jitterColour(Rng& rng, Eigen::Vector3f c, double amount) {
  c *= static_cast<float>(std::max(0.2, 1.0 + rng.normal(0.0, amount)));
  amount *= 0.25;
  for (int i = 0; i < 3; ++i) {
    c[i] = static_cast<float>(
        std::clamp(static_cast<double>(c[i]) * (1.0 + rng.normal(0.0, amount)), 0.005, 0.95));
  }
  return c;
}

Road makeRoad(Rng& rng, const Eigen::Vector2d& centre, double angle, bool allowParking,
              double parkingChance) {
  Road r;
  r.centre = centre;
  r.dir = unitFromAngle(angle);
  const int lanes = rng.weighted(std::array<double, 3>{0.55, 0.35, 0.10}) + 1;
  r.lanesForward = lanes;
  r.lanesBackward = rng.chance(0.85) ? lanes : std::max(1, lanes + (rng.chance(0.5) ? 1 : -1));
  r.laneWidth_m = rng.uniform(2.9, 3.7);
  const int centreKind = rng.weighted(std::array<double, 4>{0.5, 0.1, 0.25, 0.15});
  r.centreLine = static_cast<CentreLine>(centreKind);
  if (r.centreLine == CentreLine::None && (r.lanesForward > 1 || r.lanesBackward > 1)) {
    r.centreLine = CentreLine::DoubleYellow;
  }
  r.medianHalf_m = r.centreLine == CentreLine::DoubleYellow ? rng.uniform(0.12, 0.25) : 0.06;
  if (allowParking) {
    r.parkingRight_m = rng.chance(parkingChance) ? rng.uniform(2.1, 2.6) : 0.0;
    r.parkingLeft_m = rng.chance(parkingChance) ? rng.uniform(2.1, 2.6) : 0.0;
  }
  r.edgeLines = rng.chance(0.6);
  if (rng.chance(0.5)) {  // US style
    r.dashLength_m = 3.0;
    r.dashGap_m = 9.0;
  } else {
    r.dashLength_m = rng.chance(0.5) ? 3.0 : 6.0;
    r.dashGap_m = 2.0 * r.dashLength_m;
  }
  r.crosswalkWidth_m = rng.uniform(2.5, 4.0);
  r.zebra = rng.chance(0.6);
  return r;
}

bool buildingClear(const SceneSpec& scene, const Building& b, double clearance) {
  const Eigen::Vector2d f = unitFromAngle(b.heading_rad);
  const Eigen::Vector2d n(-f.y(), f.x());
  for (int i = -2; i <= 2; ++i) {
    for (int j = -2; j <= 2; ++j) {
      const Eigen::Vector2d p =
          b.centre + f * (0.5 * b.length_m * i / 2.0) + n * (0.5 * b.width_m * j / 2.0);
      if (scene.roadDistance(p) < clearance) {
        return false;
      }
    }
  }
  for (const Building& o : scene.buildings) {
    const double r1 = 0.5 * std::hypot(b.length_m, b.width_m);
    const double r2 = 0.5 * std::hypot(o.length_m, o.width_m);
    if ((o.centre - b.centre).norm() < 0.8 * (r1 + r2) + 2.0) {
      return false;
    }
  }
  return true;
}

double distanceToBuilding(const Building& b, const Eigen::Vector2d& p) {
  return boxDistance(b.centre, unitFromAngle(b.heading_rad), 0.5 * b.length_m, 0.5 * b.width_m, p);
}

void addBuildings(SceneSpec& scene, Rng& rng, int count) {
  const double clearance = scene.kerbWidth_m + scene.sidewalkWidth_m + 1.0;
  for (int attempt = 0; attempt < count * 30 && static_cast<int>(scene.buildings.size()) < count;
       ++attempt) {
    Building b;
    const double r = rng.uniform(15.0, scene.extent_m * 0.8);
    const double a = rng.uniform(0.0, 2.0 * kPi);
    b.centre = scene.viewCentre + r * unitFromAngle(a);
    // Buildings line up with the nearest road.
    const Road* nearest = &scene.roads[0];
    for (const Road& road : scene.roads) {
      if (std::fabs(road.lateral(b.centre)) < std::fabs(nearest->lateral(b.centre))) {
        nearest = &road;
      }
    }
    b.heading_rad = std::atan2(nearest->dir.y(), nearest->dir.x()) + rng.normal(0.0, 0.03);
    b.length_m = rng.uniform(10.0, 40.0);
    b.width_m = rng.uniform(8.0, std::min(b.length_m, 28.0));
    const bool tall = rng.chance(0.25);
    b.height_m = tall ? rng.uniform(12.0, 30.0) : rng.uniform(3.5, 12.0);
    b.roof = (!tall && rng.chance(0.45)) ? RoofKind::Gabled : RoofKind::Flat;
    b.ridgeHeight_m = b.roof == RoofKind::Gabled ? rng.uniform(0.25, 0.5) * b.width_m : 0.0;
    static const std::array<Eigen::Vector3f, 6> kWalls = {
        Eigen::Vector3f(0.55F, 0.5F, 0.45F), Eigen::Vector3f(0.45F, 0.25F, 0.18F),
        Eigen::Vector3f(0.6F, 0.6F, 0.58F),  Eigen::Vector3f(0.35F, 0.33F, 0.3F),
        Eigen::Vector3f(0.65F, 0.6F, 0.5F),  Eigen::Vector3f(0.3F, 0.35F, 0.4F)};
    b.wallAlbedo = jitterColour(rng, kWalls[static_cast<std::size_t>(rng.uniformInt(0, 5))], 0.08);
    if (b.roof == RoofKind::Gabled) {
      static const std::array<Eigen::Vector3f, 4> kTiles = {
          Eigen::Vector3f(0.35F, 0.12F, 0.08F), Eigen::Vector3f(0.15F, 0.15F, 0.16F),
          Eigen::Vector3f(0.3F, 0.22F, 0.16F), Eigen::Vector3f(0.25F, 0.27F, 0.3F)};
      b.roofAlbedo = jitterColour(rng, kTiles[static_cast<std::size_t>(rng.uniformInt(0, 3))], 0.1);
    } else {
      b.roofAlbedo = jitterColour(rng, grey(rng.uniform(0.12, 0.6)), 0.04);
      b.rooftopUnits = rng.uniformInt(0, 5);
    }
    b.seed = rng.nextU32();
    if (buildingClear(scene, b, clearance)) {
      addRoofFixtures(b);  // own Rng from b.seed: takes no draw from rng
      scene.buildings.push_back(b);
    }
  }
}

bool treeClear(const SceneSpec& scene, const Eigen::Vector2d& p, double canopy) {
  for (const Building& b : scene.buildings) {
    if (distanceToBuilding(b, p) < 0.6 * canopy + 0.5) {
      return false;
    }
  }
  for (const Tree& t : scene.trees) {
    if ((t.position - p).norm() < 0.9 * (t.canopyRadius_m + canopy) * 0.8) {
      return false;
    }
  }
  return true;
}

Tree makeTree(SceneSpec& scene, Rng& rng, const Eigen::Vector2d& position, double radius) {
  Tree t;
  t.position = position;
  t.canopyRadius_m = radius;
  t.canopyVerticalRadius_m = radius * rng.uniform(0.6, 0.95);
  t.canopyCentreHeight_m = t.canopyVerticalRadius_m + rng.uniform(2.5, 6.0);
  t.trunkRadius_m = rng.uniform(0.12, 0.3);
  if (scene.season == "winter") {
    t.leafAlbedo = jitterColour(rng, Eigen::Vector3f(0.13F, 0.11F, 0.09F), 0.15);
    t.gapFraction = static_cast<float>(rng.uniform(0.55, 0.75));
  } else if (scene.season == "autumn") {
    static const std::array<Eigen::Vector3f, 4> kLeaves = {
        Eigen::Vector3f(0.35F, 0.18F, 0.03F), Eigen::Vector3f(0.4F, 0.3F, 0.04F),
        Eigen::Vector3f(0.1F, 0.15F, 0.04F), Eigen::Vector3f(0.3F, 0.07F, 0.03F)};
    t.leafAlbedo = jitterColour(rng, kLeaves[static_cast<std::size_t>(rng.uniformInt(0, 3))], 0.15);
    t.gapFraction = static_cast<float>(rng.uniform(0.1, 0.35));
  } else {
    t.leafAlbedo = jitterColour(rng, Eigen::Vector3f(0.06F, 0.13F, 0.04F), 0.25);
    t.gapFraction = static_cast<float>(rng.uniform(0.0, 0.12));
  }
  t.seed = rng.nextU32();
  return t;
}

void addTrees(SceneSpec& scene, Rng& rng) {
  const double sideOffset = scene.kerbWidth_m + 0.5 * scene.sidewalkWidth_m;
  // Street trees along the pavements: their canopies overhang kerb parking and lanes.
  for (const Road& road : scene.roads) {
    for (int side = -1; side <= 1; side += 2) {
      if (!rng.chance(0.45)) {
        continue;
      }
      const double spacing = rng.uniform(7.0, 15.0);
      const double radius = rng.uniform(2.2, 4.8);
      const double lateral =
          side > 0 ? road.leftHalf_m() + sideOffset : -(road.rightHalf_m() + sideOffset);
      const double start =
          road.along(scene.viewCentre) - scene.extent_m * 0.7 + rng.uniform(0.0, spacing);
      for (double a = start; a < start + scene.extent_m * 1.4;
           a += spacing * rng.uniform(0.85, 1.15)) {
        const Eigen::Vector2d p = road.centre + a * road.dir + lateral * road.leftNormal();
        if (std::fabs(scene.roadDistance(p) - sideOffset) > 0.3 || rng.chance(0.15)) {
          continue;  // near a junction or a driveway, or a gap in the row
        }
        const double r = radius * rng.uniform(0.8, 1.2);
        if (treeClear(scene, p, r)) {
          scene.trees.push_back(makeTree(scene, rng, p, r));
        }
      }
    }
  }
  const int parkTrees = rng.uniformInt(0, 18);
  for (int i = 0, placed = 0; i < parkTrees * 20 && placed < parkTrees; ++i) {
    const double r = rng.uniform(2.0, 6.0);
    const Eigen::Vector2d p = scene.viewCentre + rng.uniform(10.0, scene.extent_m * 0.8) *
                                                     unitFromAngle(rng.uniform(0.0, 2.0 * kPi));
    if (scene.roadDistance(p) < scene.kerbWidth_m + scene.sidewalkWidth_m + 0.3 * r ||
        !treeClear(scene, p, r)) {
      continue;
    }
    scene.trees.push_back(makeTree(scene, rng, p, r));
    ++placed;
  }
}

void addParkingLot(SceneSpec& scene, Rng& rng) {
  const Road& road = scene.roads[0];
  ParkingLot lot;
  lot.dir = road.dir;
  lot.bayWidth_m = rng.uniform(2.4, 2.8);
  lot.bayDepth_m = rng.uniform(4.8, 5.5);
  lot.aisleWidth_m = rng.uniform(6.0, 7.5);
  lot.rows = rng.chance(0.5) ? 2 : 4;
  lot.width_m = lot.rows == 2 ? 2 * lot.bayDepth_m + lot.aisleWidth_m
                              : 4 * lot.bayDepth_m + 2 * lot.aisleWidth_m;
  lot.width_m += 1.0;
  lot.length_m = rng.uniform(30.0, 65.0);
  lot.yellowLines = rng.chance(0.3);
  const double side = rng.chance(0.5) ? -1.0 : 1.0;
  const double roadHalf = side < 0 ? road.rightHalf_m() : road.leftHalf_m();
  const double gap = scene.kerbWidth_m + scene.sidewalkWidth_m + rng.uniform(2.0, 8.0);
  lot.centre = scene.junction + side * (roadHalf + gap + 0.5 * lot.width_m) * road.leftNormal() +
               rng.uniform(-10.0, 10.0) * road.dir;
  // Bays: rows across the lot width, each row facing its aisle.
  const Eigen::Vector2d n = lot.leftNormal();
  const double w0 = -0.5 * lot.width_m + 0.5;
  std::vector<std::pair<double, double>> rowCentres;  // lateral offset, facing (+1: faces +n)
  if (lot.rows == 2) {
    rowCentres = {{w0 + 0.5 * lot.bayDepth_m, 1.0},
                  {w0 + 1.5 * lot.bayDepth_m + lot.aisleWidth_m, -1.0}};
  } else {
    const double d = lot.bayDepth_m;
    const double a = lot.aisleWidth_m;
    rowCentres = {{w0 + 0.5 * d, 1.0},
                  {w0 + 1.5 * d + a, -1.0},
                  {w0 + 2.5 * d + a, 1.0},
                  {w0 + 3.5 * d + 2 * a, -1.0}};
  }
  const int perRow = static_cast<int>((lot.length_m - 2.0) / lot.bayWidth_m);
  const double heading = std::atan2(n.y(), n.x());
  lot.baysPerRow = perRow;
  for (const auto& [offset, facing] : rowCentres) {
    lot.rowOffsets_m.push_back(offset);
    lot.rowFacing.push_back(facing);
    for (int k = 0; k < perRow; ++k) {
      const double along = (k - 0.5 * (perRow - 1)) * lot.bayWidth_m;
      const Eigen::Vector2d c = lot.centre + along * lot.dir + offset * n;
      lot.bays.emplace_back(c.x(), c.y(), facing > 0 ? heading : heading + kPi);
    }
  }
  scene.lots.push_back(lot);
  Patch lotArea;
  lotArea.centre = lot.centre;
  lotArea.dir = lot.dir;
  lotArea.halfLength_m = 0.5 * lot.length_m;
  lotArea.halfWidth_m = 0.5 * lot.width_m;
  scene.paved.push_back(lotArea);
  // Driveway from the road to the lot, crossing the pavement.
  Patch drive;
  drive.dir = n;
  drive.halfWidth_m = 3.2;
  const double from = side * roadHalf;
  const double to = side * (roadHalf + gap + 1.0);
  drive.halfLength_m = 0.5 * std::fabs(to - from) + 0.5;
  const double alongDrive = road.along(lot.centre) + rng.uniform(-0.3, 0.3) * lot.length_m;
  drive.centre = road.centre + alongDrive * road.dir + 0.5 * (from + to) * road.leftNormal();
  scene.paved.push_back(drive);
}

}  // namespace

const char* toString(SceneKind kind) {
  switch (kind) {
    case SceneKind::Intersection:
      return "intersection";
    case SceneKind::Straight:
      return "straight";
    case SceneKind::Parking:
      return "parking";
  }
  return "unknown";
}

std::optional<SceneKind> sceneKindFromString(const std::string& name) {
  for (const SceneKind k : {SceneKind::Intersection, SceneKind::Straight, SceneKind::Parking}) {
    if (name == toString(k)) {
      return k;
    }
  }
  return std::nullopt;
}

double SceneSpec::roadDistance(const Eigen::Vector2d& p) const {
  double d = 1e9;
  for (std::size_t i = 0; i < roads.size(); ++i) {
    const double s = stripDistance(roads[i], p);
    d = i == 0 ? s : roundUnion(d, s, cornerRadius_m);
  }
  for (const Patch& area : paved) {
    d = roundUnion(d, boxDistance(area.centre, area.dir, area.halfLength_m, area.halfWidth_m, p),
                   1.5);
  }
  return d;
}

SceneSpec generateScene(SceneKind kind, Rng& rng, bool islands) {
  SceneSpec scene;
  scene.kind = kind;
  // The islands' own Rng, seeded from a copy of the sequence's: it takes no draw from rng.
  std::optional<Rng> islandRng;
  if (islands) {
    Rng copy = rng;
    islandRng.emplace(copy.next() ^ 0x1514'7d5eULL);
  }
  scene.junction = Eigen::Vector2d(rng.uniform(-20.0, 20.0), rng.uniform(-20.0, 20.0));
  const double seasonDraw = rng.uniform();
  scene.season = seasonDraw < 0.55 ? "summer" : (seasonDraw < 0.75 ? "autumn" : "winter");
  scene.cornerRadius_m = rng.uniform(3.0, 10.0);
  scene.kerbWidth_m = rng.uniform(0.15, 0.3);
  scene.sidewalkWidth_m = rng.uniform(1.5, 4.5);
  const double angleA = rng.uniform(0.0, 2.0 * kPi);

  if (kind == SceneKind::Intersection) {
    scene.roads.push_back(makeRoad(rng, scene.junction, angleA, true, 0.35));
    const double cross = rng.chance(0.6) ? kPi / 2 + rng.normal(0.0, 0.03) : rng.uniform(1.1, 2.0);
    scene.roads.push_back(makeRoad(rng, scene.junction, angleA + cross, true, 0.35));
    if (islandRng) {
      widenMedians(scene, *islandRng);  // before the stop lines, which depend on the widths
    }
    const bool crosswalks = rng.chance(0.8);
    for (int i = 0; i < 2; ++i) {
      Road& r = scene.roads[static_cast<std::size_t>(i)];
      const Road& o = scene.roads[static_cast<std::size_t>(1 - i)];
      const double sinAngle = std::fabs(r.dir.x() * o.dir.y() - r.dir.y() * o.dir.x());
      const double otherHalf = std::max(o.leftHalf_m(), o.rightHalf_m()) / std::max(sinAngle, 0.3);
      const double box = otherHalf + 0.35 * scene.cornerRadius_m + scene.kerbWidth_m;
      if (crosswalks) {
        r.crosswalkCentre_m = box + 0.8 + 0.5 * r.crosswalkWidth_m;
        r.stopDistance_m = r.crosswalkCentre_m + 0.5 * r.crosswalkWidth_m + rng.uniform(0.8, 2.0);
      } else {
        r.stopDistance_m = box + rng.uniform(1.0, 3.0);
      }
    }
    scene.viewCentre =
        scene.junction + Eigen::Vector2d(rng.uniform(-8.0, 8.0), rng.uniform(-8.0, 8.0));
  } else {
    scene.roads.push_back(
        makeRoad(rng, scene.junction, angleA, true, kind == SceneKind::Straight ? 0.6 : 0.35));
    if (islandRng) {
      widenMedians(scene, *islandRng);  // before the parking lot beside the road
    }
    Road& r = scene.roads[0];
    if (kind == SceneKind::Straight && rng.chance(0.3)) {
      r.crosswalkCentre_m = rng.uniform(-20.0, 20.0);  // mid-block crossing (signed along)
    }
    if (kind == SceneKind::Parking) {
      addParkingLot(scene, rng);
      scene.viewCentre = 0.5 * (scene.lots[0].centre + scene.junction) +
                         Eigen::Vector2d(rng.uniform(-5.0, 5.0), rng.uniform(-5.0, 5.0));
    } else {
      scene.viewCentre = scene.junction + rng.uniform(-4.0, 4.0) * r.leftNormal();
    }
  }

  // Ground style.
  GroundStyle& s = scene.style;
  s.concreteRoad = rng.chance(0.3);
  s.slabLength_m = rng.uniform(3.5, 6.0);
  const double roadTone = s.concreteRoad ? rng.uniform(0.28, 0.5) : rng.uniform(0.07, 0.3);
  s.roadAlbedo = jitterColour(rng, grey(roadTone), 0.03);
  s.roadAlbedo[2] *= static_cast<float>(rng.uniform(0.97, 1.06));  // slightly blue or brown
  s.lotAlbedo = jitterColour(rng, grey(rng.uniform(0.07, 0.25)), 0.03);
  s.roadMacroVariation = static_cast<float>(rng.uniform(0.04, 0.18));
  s.roadFineVariation = static_cast<float>(rng.uniform(0.05, 0.2));
  s.wheelTrackDarkening = static_cast<float>(rng.uniform(-0.08, 0.12));
  s.oilStripe = static_cast<float>(rng.uniform(0.0, 0.12));
  s.crackDensity = static_cast<float>(rng.uniform(0.0, 1.0));
  s.crackWidth = static_cast<float>(rng.uniform(0.01, 0.035));
  s.sidewalkAlbedo = jitterColour(rng, grey(rng.uniform(0.3, 0.6)), 0.03);
  s.pavers = rng.chance(0.2);
  if (s.pavers && rng.chance(0.5)) {
    s.sidewalkAlbedo = jitterColour(rng, Eigen::Vector3f(0.35F, 0.2F, 0.15F), 0.1);
  }
  s.sidewalkSlab_m = rng.uniform(1.2, 2.0);
  s.kerbAlbedo = jitterColour(rng, grey(rng.uniform(0.4, 0.65)), 0.02);
  if (scene.season == "winter") {
    s.grassA = jitterColour(rng, Eigen::Vector3f(0.13F, 0.12F, 0.07F), 0.1);
    s.grassB = jitterColour(rng, Eigen::Vector3f(0.09F, 0.1F, 0.05F), 0.1);
  } else if (scene.season == "autumn" || rng.chance(0.2)) {
    s.grassA = jitterColour(rng, Eigen::Vector3f(0.14F, 0.15F, 0.06F), 0.1);
    s.grassB = jitterColour(rng, Eigen::Vector3f(0.08F, 0.12F, 0.04F), 0.1);
  } else {
    s.grassA = jitterColour(rng, Eigen::Vector3f(0.05F, 0.12F, 0.03F), 0.15);
    s.grassB = jitterColour(rng, Eigen::Vector3f(0.1F, 0.15F, 0.05F), 0.15);
  }
  s.soilAlbedo = jitterColour(rng, Eigen::Vector3f(0.17F, 0.13F, 0.09F), 0.15);
  s.soilShare = static_cast<float>(rng.uniform(0.0, 0.3));
  s.whiteMarking = jitterColour(rng, grey(rng.uniform(0.55, 0.8)), 0.02);
  s.yellowMarking = jitterColour(rng, Eigen::Vector3f(0.6F, 0.42F, 0.07F), 0.08);
  s.markingWear = static_cast<float>(rng.uniform(0.0, 0.7));
  s.seed = rng.nextU32();

  // Road surface details.
  for (const Road& road : scene.roads) {
    const int patches = rng.uniformInt(0, 8);
    for (int i = 0; i < patches; ++i) {
      Patch p;
      const double along = road.along(scene.viewCentre) + rng.uniform(-70.0, 70.0);
      const double lateral = rng.uniform(-road.rightHalf_m(), road.leftHalf_m());
      p.centre = road.centre + along * road.dir + lateral * road.leftNormal();
      p.dir = rng.chance(0.8) ? road.dir : road.leftNormal();
      p.halfLength_m = rng.uniform(0.5, 6.0);
      p.halfWidth_m = rng.uniform(0.4, 2.0);
      p.tone = static_cast<float>(rng.uniform(0.75, 1.3));
      scene.patches.push_back(p);
    }
    const int holes = rng.uniformInt(0, 4);
    for (int i = 0; i < holes; ++i) {
      Manhole m;
      const double along = road.along(scene.viewCentre) + rng.uniform(-50.0, 50.0);
      const int lane = rng.uniformInt(0, road.lanesForward - 1);
      const bool forward = rng.chance(0.5);
      m.position =
          road.centre + along * road.dir +
          (road.laneOffset_m(forward, forward ? lane : std::min(lane, road.lanesBackward - 1)) +
           rng.uniform(-1.0, 1.0)) *
              road.leftNormal();
      m.radius_m = rng.uniform(0.28, 0.4);
      scene.manholes.push_back(m);
    }
  }

  const int buildingCount = rng.weighted(std::array<double, 4>{0.15, 0.35, 0.35, 0.15}) * 3;
  addBuildings(scene, rng, buildingCount);
  addTrees(scene, rng);
  addStreetFurniture(scene);  // own Rng: takes no draw from rng
  if (islandRng) {
    addIslands(scene, *islandRng);
  }

  // Light: sun direction and colours (overcast days have weak, soft shadows).
  Lighting& l = scene.light;
  l.overcast = rng.chance(0.3);
  l.sunElevation_deg = rng.uniform(18.0, 75.0);
  l.sunAzimuth_deg = rng.uniform(0.0, 360.0);
  const double el = l.sunElevation_deg * kPi / 180.0;
  const double az = l.sunAzimuth_deg * kPi / 180.0;
  l.sunDirectionEnu =
      Eigen::Vector3d(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  const double warm = std::clamp((35.0 - l.sunElevation_deg) / 20.0, 0.0, 1.0);
  Eigen::Vector3f sun(1.0F, static_cast<float>(0.97 - 0.08 * warm),
                      static_cast<float>(0.92 - 0.2 * warm));
  Eigen::Vector3f sky(0.75F, 0.85F, 1.05F);
  if (l.overcast) {
    l.sunIrradiance = sun * static_cast<float>(rng.uniform(0.05, 0.35));
    l.skyIrradiance =
        Eigen::Vector3f(0.95F, 0.97F, 1.0F) * static_cast<float>(rng.uniform(0.8, 1.1));
    l.shadowSoftnessTexels = static_cast<float>(rng.uniform(2.0, 3.0));
  } else {
    l.sunIrradiance = sun * static_cast<float>(rng.uniform(0.9, 1.1));
    l.skyIrradiance = sky * static_cast<float>(rng.uniform(0.25, 0.45));
    l.shadowSoftnessTexels = static_cast<float>(rng.uniform(0.8, 1.6));
  }

  TrafficParams& t = scene.traffic;
  t.arrivalRatePerLane_hz = rng.uniform(0.04, 0.3);
  t.kerbParkingOccupancy = rng.uniform(0.2, 0.95);
  t.lotOccupancy = rng.uniform(0.3, 0.95);
  t.largeVehicleShare = rng.uniform(0.0, 0.1);
  t.speedLimit_mps = rng.uniform(8.0, 15.0);
  t.signalCycleS = rng.uniform(40.0, 80.0);
  t.signalOffsetS = rng.uniform(0.0, t.signalCycleS);
  return scene;
}

}  // namespace vp::sim
