#include "car_generator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "shape/mesh_builder.hpp"

namespace vp::shape {

namespace {

constexpr int kMaxAttempts = 1000;  // redraws of a rejected car; never reached in practice
constexpr double kMinSideArea_m2 = 1e-3;
constexpr double kDegToRad = std::numbers::pi / 180.0;

// Platform-independent variates from the raw 64-bit stream.
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0, 1)
}

double uniform(std::mt19937_64& rng, const DimensionRange& r) {
  return r.min + (r.max - r.min) * uniform01(rng);
}

double standardNormal(std::mt19937_64& rng) {
  const double u1 = 1.0 - uniform01(rng);  // (0, 1]: log() stays finite
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

// Correlation of width, height and wheelbase with the common size factor (length).
constexpr double kWheelbaseLoading = 0.85;
constexpr double kWidthLoading = 0.6;
constexpr double kHeightLoading = 0.3;

double loaded(double loading, double factor, double own) {
  return loading * factor + std::sqrt(1.0 - loading * loading) * own;
}

// Ranges per type: docs/asm.md gives the representative models and the reasoning.
const std::array<CarTypeSpec, kCarTypeCount> kSpecs = [] {
  std::array<CarTypeSpec, kCarTypeCount> s{};
  CarTypeSpec common;
  common.bonnetRise_m = {0.14, 0.22};
  common.trackInset_m = {0.22, 0.30};
  common.roofDrop_m = {0.02, 0.06};
  common.cornerInset_m = {0.08, 0.14};
  common.lightWidth_m = {0.28, 0.42};
  common.rearBumperHeight_m = {0.50, 0.62};
  common.frontBumperHeight_m = {0.45, 0.55};
  common.cowlHeight_m = {0.92, 1.02};

  CarTypeSpec& estate = s[static_cast<int>(VehicleType::Estate)];
  estate = common;
  estate.type = VehicleType::Estate;
  estate.length_m = {4.72, 0.12, {4.45, 5.00}};
  estate.width_m = {1.83, 0.03, {1.78, 1.90}};
  estate.height_m = {1.48, 0.03, {1.42, 1.55}};
  estate.wheelbase_m = {2.78, 0.08, {2.60, 2.99}};
  estate.frontOverhangShare = {0.42, 0.50};
  estate.wheelRadius_m = {0.31, 0.35};
  estate.sillHeight_m = {0.21, 0.29};
  estate.windscreenSetback_m = {0.30, 0.55};
  estate.windscreenRake_deg = {24.0, 30.0};
  estate.roofTaper_m = {0.35, 0.48};
  estate.roofDrop_m = {0.0, 0.04};
  estate.rearStyle = RearStyle::Hatch;
  estate.rearRoofInset_m = {0.18, 0.32};
  estate.rearWindowAngle_deg = {15.0, 30.0};
  estate.deckHeight_m = {0.95, 1.08};
  estate.tailDrop_m = {0.05, 0.15};

  CarTypeSpec& compact = s[static_cast<int>(VehicleType::Compact)];
  compact = common;
  compact.type = VehicleType::Compact;
  compact.length_m = {4.10, 0.22, {3.55, 4.45}};
  compact.width_m = {1.76, 0.05, {1.62, 1.84}};
  compact.height_m = {1.47, 0.035, {1.40, 1.56}};
  compact.wheelbase_m = {2.58, 0.09, {2.30, 2.72}};
  compact.frontOverhangShare = {0.50, 0.58};
  compact.wheelRadius_m = {0.29, 0.33};
  compact.sillHeight_m = {0.22, 0.30};
  compact.frontBumperHeight_m = {0.48, 0.58};
  compact.windscreenSetback_m = {0.20, 0.40};
  compact.windscreenRake_deg = {26.0, 32.0};
  compact.roofTaper_m = {0.35, 0.48};
  compact.rearStyle = RearStyle::Hatch;
  compact.rearRoofInset_m = {0.35, 0.55};
  compact.rearWindowAngle_deg = {25.0, 40.0};
  compact.deckHeight_m = {0.95, 1.05};
  compact.tailDrop_m = {0.05, 0.15};

  CarTypeSpec& sports = s[static_cast<int>(VehicleType::Sports)];
  sports = common;
  sports.type = VehicleType::Sports;
  sports.length_m = {4.35, 0.25, {3.90, 4.80}};
  sports.width_m = {1.84, 0.06, {1.73, 1.95}};
  sports.height_m = {1.30, 0.04, {1.20, 1.38}};
  sports.wheelbase_m = {2.50, 0.12, {2.30, 2.75}};
  sports.frontOverhangShare = {0.42, 0.55};
  sports.wheelRadius_m = {0.32, 0.35};
  sports.sillHeight_m = {0.15, 0.22};
  sports.frontBumperHeight_m = {0.38, 0.46};
  sports.bonnetRise_m = {0.10, 0.16};
  sports.cowlHeight_m = {0.80, 0.90};
  sports.windscreenSetback_m = {0.50, 0.90};
  sports.windscreenRake_deg = {20.0, 26.0};
  sports.roofTaper_m = {0.40, 0.55};
  sports.roofDrop_m = {0.03, 0.08};
  sports.rearStyle = RearStyle::Fastback;
  sports.roofLength_m = {0.25, 0.65};
  sports.deckLength_m = {0.20, 0.55};
  sports.rearWindowAngle_deg = {10.0, 32.0};
  sports.deckHeight_m = {0.82, 0.95};
  sports.tailDrop_m = {0.0, 0.05};
  sports.rearBumperHeight_m = {0.42, 0.55};

  CarTypeSpec& sedan = s[static_cast<int>(VehicleType::Sedan)];
  sedan = common;
  sedan.type = VehicleType::Sedan;
  sedan.length_m = {4.75, 0.14, {4.45, 5.05}};
  sedan.width_m = {1.84, 0.03, {1.76, 1.90}};
  sedan.height_m = {1.45, 0.025, {1.40, 1.51}};
  sedan.wheelbase_m = {2.83, 0.08, {2.65, 3.00}};
  sedan.frontOverhangShare = {0.42, 0.50};
  sedan.wheelRadius_m = {0.31, 0.35};
  sedan.sillHeight_m = {0.20, 0.28};
  sedan.windscreenSetback_m = {0.30, 0.55};
  sedan.windscreenRake_deg = {24.0, 30.0};
  sedan.roofTaper_m = {0.38, 0.50};
  sedan.rearStyle = RearStyle::Notchback;
  sedan.roofLength_m = {0.80, 1.15};
  sedan.deckLength_m = {0.45, 0.80};
  sedan.rearWindowAngle_deg = {15.0, 40.0};
  sedan.deckHeight_m = {0.98, 1.08};
  sedan.tailDrop_m = {0.0, 0.04};

  CarTypeSpec& suv = s[static_cast<int>(VehicleType::Suv)];
  suv = common;
  suv.type = VehicleType::Suv;
  suv.length_m = {4.60, 0.20, {4.20, 4.95}};
  suv.width_m = {1.88, 0.05, {1.80, 2.00}};
  suv.height_m = {1.66, 0.05, {1.56, 1.78}};
  suv.wheelbase_m = {2.77, 0.10, {2.58, 2.98}};
  suv.frontOverhangShare = {0.45, 0.53};
  suv.wheelRadius_m = {0.34, 0.38};
  suv.sillHeight_m = {0.32, 0.42};
  suv.frontBumperHeight_m = {0.62, 0.75};
  suv.bonnetRise_m = {0.15, 0.25};
  suv.cowlHeight_m = {1.05, 1.20};
  suv.windscreenSetback_m = {0.25, 0.45};
  suv.windscreenRake_deg = {27.0, 34.0};
  suv.roofTaper_m = {0.30, 0.42};
  suv.roofDrop_m = {0.0, 0.05};
  suv.rearStyle = RearStyle::Hatch;
  suv.rearRoofInset_m = {0.20, 0.35};
  suv.rearWindowAngle_deg = {15.0, 30.0};
  suv.deckHeight_m = {1.05, 1.20};
  suv.tailDrop_m = {0.05, 0.15};
  suv.rearBumperHeight_m = {0.62, 0.75};

  CarTypeSpec& van = s[static_cast<int>(VehicleType::Van)];
  van = common;
  van.type = VehicleType::Van;
  van.length_m = {4.75, 0.20, {4.40, 5.15}};
  van.width_m = {1.90, 0.05, {1.80, 2.00}};
  van.height_m = {1.82, 0.09, {1.65, 2.00}};
  van.wheelbase_m = {2.90, 0.14, {2.70, 3.25}};
  van.frontOverhangShare = {0.45, 0.55};
  van.wheelRadius_m = {0.32, 0.36};
  van.sillHeight_m = {0.25, 0.34};
  van.frontBumperHeight_m = {0.55, 0.70};
  van.bonnetRise_m = {0.15, 0.25};
  van.cowlHeight_m = {1.00, 1.15};
  van.windscreenSetback_m = {0.15, 0.35};
  van.windscreenRake_deg = {28.0, 38.0};
  van.roofTaper_m = {0.25, 0.38};
  van.roofDrop_m = {0.0, 0.04};
  van.rearStyle = RearStyle::Hatch;
  van.rearRoofInset_m = {0.12, 0.25};
  van.rearWindowAngle_deg = {4.0, 16.0};
  van.deckHeight_m = {1.00, 1.15};
  van.tailDrop_m = {0.05, 0.15};
  van.rearBumperHeight_m = {0.55, 0.70};
  return s;
}();

constexpr DimensionRange kBonnetSetback_m{0.04, 0.12};
constexpr DimensionRange kTailInset_m{0.03, 0.08};
constexpr DimensionRange kArchClearance_m{0.10, 0.16};  // arch half width beyond the tyre
constexpr DimensionRange kArchGap_m{0.03, 0.08};        // arch top above the tyre
constexpr double kBeltMargin_m = 0.05;  // arch tops stay this far below the bonnet/belt line
constexpr double kMinLightGap_m = 0.3;  // between the inner ends of the two lights

// z of the line through (xa, za) and (xb, zb) at x.
double lineZ(double xa, double za, double xb, double zb, double x) {
  return za + (zb - za) * (x - xa) / (xb - xa);
}

// Draws everything but the overall size; returns false for a combination the topology or the
// type's own limits do not allow (the caller redraws).
bool drawShape(const CarTypeSpec& spec, std::mt19937_64& rng, CarDimensions* d) {
  const double overhangs = d->length_m - d->wheelbase_m;
  d->frontOverhang_m = overhangs * uniform(rng, spec.frontOverhangShare);
  d->rearOverhang_m = overhangs - d->frontOverhang_m;
  d->wheelRadius_m = uniform(rng, spec.wheelRadius_m);
  d->track_m = d->width_m - uniform(rng, spec.trackInset_m);
  d->sillHeight_m = uniform(rng, spec.sillHeight_m);
  d->frontBumperHeight_m = uniform(rng, spec.frontBumperHeight_m);
  d->bonnetFrontHeight_m = d->frontBumperHeight_m + uniform(rng, spec.bonnetRise_m);
  d->bonnetSetback_m = uniform(rng, kBonnetSetback_m);
  d->cowlHeight_m = uniform(rng, spec.cowlHeight_m);
  d->windscreenSetback_m = uniform(rng, spec.windscreenSetback_m);
  d->windscreenRake_deg = uniform(rng, spec.windscreenRake_deg);
  d->roofWidth_m = d->width_m - uniform(rng, spec.roofTaper_m);
  d->roofDrop_m = uniform(rng, spec.roofDrop_m);
  d->deckHeight_m = uniform(rng, spec.deckHeight_m);
  d->tailDrop_m = uniform(rng, spec.tailDrop_m);
  d->tailInset_m = uniform(rng, kTailInset_m);
  d->rearBumperHeight_m = uniform(rng, spec.rearBumperHeight_m);
  d->cornerInset_m = uniform(rng, spec.cornerInset_m);
  d->headLightWidth_m = uniform(rng, spec.lightWidth_m);
  d->tailLightWidth_m = uniform(rng, spec.lightWidth_m);
  d->archHalfWidth_m = d->wheelRadius_m + uniform(rng, kArchClearance_m);
  d->archGap_m = uniform(rng, kArchGap_m);

  const double halfLength = 0.5 * d->length_m;
  const double frontAxle = halfLength - d->frontOverhang_m;
  const double windscreenBaseX = frontAxle - d->windscreenSetback_m;
  const double roofFrontX = windscreenBaseX - (d->height_m - d->cowlHeight_m) /
                                                  std::tan(d->windscreenRake_deg * kDegToRad);
  const double roofRearZ = d->height_m - d->roofDrop_m;
  const double tailX = -halfLength + d->tailInset_m;
  if (spec.rearStyle == RearStyle::Hatch) {
    d->rearRoofInset_m = uniform(rng, spec.rearRoofInset_m);
    d->rearWindowAngle_deg = uniform(rng, spec.rearWindowAngle_deg);
    const double roofRearX = -halfLength + d->rearRoofInset_m;
    d->roofLength_m = roofFrontX - roofRearX;
    const double baseX =
        roofRearX - (roofRearZ - d->deckHeight_m) * std::tan(d->rearWindowAngle_deg * kDegToRad);
    if (baseX < -halfLength + 0.04) {
      return false;  // the tailgate glass would stick out behind the bumper
    }
  } else {
    d->roofLength_m = uniform(rng, spec.roofLength_m);
    d->deckLength_m = uniform(rng, spec.deckLength_m);
    const double roofRearX = roofFrontX - d->roofLength_m;
    const double baseX = tailX + d->deckLength_m;
    if (baseX >= roofRearX) {
      return false;
    }
    d->rearWindowAngle_deg = std::atan2(roofRearZ - d->deckHeight_m, roofRearX - baseX) / kDegToRad;
    d->rearRoofInset_m = roofRearX + halfLength;
    if (!spec.rearWindowAngle_deg.contains(d->rearWindowAngle_deg)) {
      return false;
    }
  }
  return d->roofLength_m >= 0.25;
}

}  // namespace

const CarTypeSpec& carTypeSpec(VehicleType type) {
  return kSpecs[static_cast<std::size_t>(std::min(static_cast<int>(type), kCarTypeCount - 1))];
}

KeypointModel buildCarKeypoints(const CarDimensions& d) {
  KeypointModel k = KeypointModel::Zero();
  const auto setPair = [&k](int pair, double x, double y, double z) {
    k.col(2 * pair) = Eigen::Vector3d(x, y, z);
    k.col(2 * pair + 1) = Eigen::Vector3d(x, -y, z);
  };
  const double halfLength = 0.5 * d.length_m;
  const double halfWidth = 0.5 * d.width_m;
  const double frontAxle = halfLength - d.frontOverhang_m;
  const double rearAxle = frontAxle - d.wheelbase_m;
  const double cornerY = halfWidth - d.cornerInset_m;

  // Front face: bumper corner (P0), bonnet front corner (P1).
  const double x0 = halfLength;
  const double z0 = d.frontBumperHeight_m;
  const double x1 = halfLength - d.bonnetSetback_m;
  const double z1 = d.bonnetFrontHeight_m;
  // Greenhouse: windscreen base (P2), roof front (P3), roof rear (P4), rear window base (P5).
  const double x2 = frontAxle - d.windscreenSetback_m;
  const double z2 = d.cowlHeight_m;
  const double z3 = d.height_m;
  const double x3 = x2 - (z3 - z2) / std::tan(d.windscreenRake_deg * kDegToRad);
  const double z4 = d.height_m - d.roofDrop_m;
  const double z5 = d.deckHeight_m;
  const double x4 = -halfLength + d.rearRoofInset_m;
  double x5 = 0.0;
  if (carTypeSpec(d.type).rearStyle != RearStyle::Hatch) {
    x5 = -halfLength + d.tailInset_m + d.deckLength_m;
  } else {
    x5 = x4 - (z4 - z5) * std::tan(d.rearWindowAngle_deg * kDegToRad);
  }
  // Rear face: tail top corner (P6), rear bumper corner (P7).
  const double x6 = -halfLength + d.tailInset_m;
  const double z6 = z5 - d.tailDrop_m;
  const double x7 = -halfLength;
  const double z7 = d.rearBumperHeight_m;

  setPair(0, frontAxle, 0.5 * d.track_m + 0.5 * kWheelWidth_m, d.wheelRadius_m);
  setPair(1, rearAxle, 0.5 * d.track_m + 0.5 * kWheelWidth_m, d.wheelRadius_m);
  setPair(2, x0, cornerY, z0);
  setPair(3, x1, cornerY, z1);
  setPair(4, x2, halfWidth, z2);
  setPair(5, x3, 0.5 * d.roofWidth_m, z3);
  setPair(6, x4, 0.5 * d.roofWidth_m, z4);
  setPair(7, x5, halfWidth, z5);
  setPair(8, x6, cornerY, z6);
  setPair(9, x7, cornerY, z7);
  // Arch tops: above the tyre, but below the bonnet line (front) and the belt line (rear).
  const double tyreTop = 2.0 * d.wheelRadius_m + d.archGap_m;
  const double frontTop = std::min(tyreTop, lineZ(x1, z1, x2, z2, frontAxle) - kBeltMargin_m);
  const double rearTop = std::min(tyreTop, lineZ(x2, z2, x5, z5, rearAxle) - kBeltMargin_m);
  const double ra = d.archHalfWidth_m;
  setPair(10, frontAxle, halfWidth, frontTop);
  setPair(11, rearAxle, halfWidth, rearTop);
  setPair(12, frontAxle + ra, halfWidth, d.sillHeight_m);
  setPair(13, frontAxle - ra, halfWidth, d.sillHeight_m);
  setPair(14, rearAxle + ra, halfWidth, d.sillHeight_m);
  setPair(15, rearAxle - ra, halfWidth, d.sillHeight_m);
  // Light inner corners: 70 % up the front / rear face, a light width in from the corner.
  constexpr double kLightLevel = 0.7;
  const double headY = std::max(cornerY - d.headLightWidth_m, 0.5 * kMinLightGap_m);
  setPair(16, x0 + kLightLevel * (x1 - x0), headY, z0 + kLightLevel * (z1 - z0));
  const double tailY = std::max(cornerY - d.tailLightWidth_m, 0.5 * kMinLightGap_m);
  setPair(17, x7 + kLightLevel * (x6 - x7), tailY, z7 + kLightLevel * (z6 - z7));
  return k;
}

bool carProfileValid(const KeypointModel& keypoints) {
  if (!keypoints.allFinite()) {
    return false;
  }
  for (const Triangle& t : mesh()) {
    const int sideOf0 = t.v[0] % 2;
    if (t.v[1] % 2 != sideOf0 || t.v[2] % 2 != sideOf0) {
      continue;  // strips across the car are valid when the two sides are
    }
    const Eigen::Vector3d a = keypoints.col(t.v[0]);
    const Eigen::Vector3d normal =
        (keypoints.col(t.v[1]) - a).cross(keypoints.col(t.v[2]) - a);  // 2 * area
    double outward = sideOf0 == 0 ? normal.y() : -normal.y();
    // The lights are the only one-sided triangles not on a side: they face forward / back.
    if (t.part == SurfacePart::HeadLight) {
      outward = normal.x();
    } else if (t.part == SurfacePart::TailLight) {
      outward = -normal.x();
    }
    if (!(outward > 2.0 * kMinSideArea_m2)) {
      return false;
    }
  }
  return meshVolume(keypoints) > 0.0;
}

GeneratedCar generateCar(VehicleType type, std::mt19937_64& rng) {
  const CarTypeSpec& spec = carTypeSpec(type);
  GeneratedCar car;
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    CarDimensions d;
    d.type = spec.type;
    // Overall size: correlated normals (common size factor), truncated by redrawing.
    const double size = standardNormal(rng);
    d.length_m = spec.length_m.mean + spec.length_m.sd * size;
    d.wheelbase_m = spec.wheelbase_m.mean +
                    spec.wheelbase_m.sd * loaded(kWheelbaseLoading, size, standardNormal(rng));
    d.width_m =
        spec.width_m.mean + spec.width_m.sd * loaded(kWidthLoading, size, standardNormal(rng));
    d.height_m =
        spec.height_m.mean + spec.height_m.sd * loaded(kHeightLoading, size, standardNormal(rng));
    if (!spec.length_m.range.contains(d.length_m) ||
        !spec.wheelbase_m.range.contains(d.wheelbase_m) ||
        !spec.width_m.range.contains(d.width_m) || !spec.height_m.range.contains(d.height_m)) {
      continue;
    }
    if (!drawShape(spec, rng, &d)) {
      continue;
    }
    car.dimensions = d;
    car.keypoints = buildCarKeypoints(d);
    if (carProfileValid(car.keypoints)) {
      return car;
    }
  }
  return car;  // unreachable for the shipped ranges (the tests draw thousands of cars)
}

// --- Large vehicles ------------------------------------------------------------------------

namespace {

const std::array<LargeVehicleSpec, kLargeVehicleKindCount> kLargeSpecs = {{
    {LargeVehicleKind::CityBus, {10.5, 12.2}, {2.50, 2.55}, {2.90, 3.30}, {0.47, 0.50}},
    {LargeVehicleKind::ArticulatedBus, {17.9, 18.2}, {2.50, 2.55}, {2.90, 3.30}, {0.47, 0.50}},
    {LargeVehicleKind::Coach, {12.0, 14.0}, {2.50, 2.55}, {3.50, 3.90}, {0.50, 0.54}},
    {LargeVehicleKind::RigidTruck, {7.0, 12.0}, {2.45, 2.55}, {3.20, 4.00}, {0.40, 0.54}},
    {LargeVehicleKind::SemiTrailer, {15.5, 16.5}, {2.55, 2.55}, {3.80, 4.00}, {0.50, 0.54}},
}};

// A prism whose side profile is a stack of bands between horizontal levels: the front edge
// of the profile runs through frontX[i] at z[i], the rear edge through rearX[i].
struct BandedBody {
  std::vector<double> z;
  std::vector<double> frontX;
  std::vector<double> rearX;
  double halfWidth = 1.0;
  double centreY = 0.0;  // the body spans centreY +- halfWidth (a bed's side wall: off the axis)
  std::vector<SurfacePart> side;   // per band
  std::vector<SurfacePart> front;  // per band
  std::vector<SurfacePart> rear;   // per band
  SurfacePart roof = SurfacePart::Paint;
  SurfacePart bottom = SurfacePart::Underbody;
  int headLightBand = -1;
  int tailLightBand = -1;
  double lightWidth = 0.35;
};

void addBody(BodyMesh* m, const BandedBody& b) {
  const int levels = static_cast<int>(b.z.size());
  const int first = static_cast<int>(m->vertices.size());
  const auto addPair = [m, &b](double x, double y, double z) {
    const int left = static_cast<int>(m->vertices.size());
    m->vertices.emplace_back(x, b.centreY + y, z);
    m->vertices.emplace_back(x, b.centreY - y, z);
    return detail::Pair{left, left + 1};
  };
  // Profile order (counter-clockwise in x-z): up the front edge, then down the rear edge.
  for (int i = 0; i < levels; ++i) {
    addPair(b.frontX[static_cast<std::size_t>(i)], b.halfWidth, b.z[static_cast<std::size_t>(i)]);
  }
  for (int i = levels - 1; i >= 0; --i) {
    addPair(b.rearX[static_cast<std::size_t>(i)], b.halfWidth, b.z[static_cast<std::size_t>(i)]);
  }
  const auto front = [first](int i) { return detail::Pair{first + 2 * i, first + 2 * i + 1}; };
  const auto rear = [first, levels](int i) {
    const int p = 2 * levels - 1 - i;
    return detail::Pair{first + 2 * p, first + 2 * p + 1};
  };
  const auto inner = [&](double x, double z) {
    return addPair(x, std::max(b.halfWidth - b.lightWidth, 0.3), z);
  };
  detail::MeshBuilder mb(&m->triangles);
  for (int i = 0; i + 1 < levels; ++i) {
    const auto band = static_cast<std::size_t>(i);
    mb.side(front(i), front(i + 1), rear(i + 1), b.side[band]);
    mb.side(front(i), rear(i + 1), rear(i), b.side[band]);
    const double zLight = b.z[band] + 0.6 * (b.z[band + 1] - b.z[band]);
    if (i == b.headLightBand) {
      const double x = b.frontX[band] + 0.6 * (b.frontX[band + 1] - b.frontX[band]);
      mb.lightStrip(front(i), front(i + 1), inner(x, zLight), SurfacePart::HeadLight,
                    b.front[band]);
    } else {
      mb.strip(front(i), front(i + 1), b.front[band]);
    }
    if (i == b.tailLightBand) {
      const double x = b.rearX[band] + 0.6 * (b.rearX[band + 1] - b.rearX[band]);
      mb.lightStrip(rear(i + 1), rear(i), inner(x, zLight), SurfacePart::TailLight, b.rear[band]);
    } else {
      mb.strip(rear(i + 1), rear(i), b.rear[band]);
    }
  }
  mb.strip(front(levels - 1), rear(levels - 1), b.roof);
  mb.strip(rear(0), front(0), b.bottom);
}

// A plain box (two levels), e.g. a cargo box or a chassis frame.
BandedBody box(double xFront, double xRear, double zBottom, double zTop, double halfWidth,
               SurfacePart part) {
  BandedBody b;
  b.z = {zBottom, zTop};
  b.frontX = {xFront, xFront};
  b.rearX = {xRear, xRear};
  b.halfWidth = halfWidth;
  b.side = b.front = b.rear = {part};
  b.roof = part;
  b.bottom = part == SurfacePart::Paint ? SurfacePart::Underbody : part;
  return b;
}

void addAxle(BodyMesh* m, double x) {
  const double y = 0.5 * m->width_m - 0.03;
  m->wheelCentres.emplace_back(x, y, m->wheelRadius_m);
  m->wheelCentres.emplace_back(x, -y, m->wheelRadius_m);
}

void buildBus(LargeVehicleMesh* m, std::mt19937_64& rng) {
  const bool coach = m->kind == LargeVehicleKind::Coach;
  const double half = 0.5 * m->length_m;
  const double clearance =
      uniform(rng, coach ? DimensionRange{0.35, 0.42} : DimensionRange{0.28, 0.35});
  const double bumperTop = clearance + uniform(rng, {0.30, 0.40});
  const double belt = uniform(rng, coach ? DimensionRange{1.10, 1.40} : DimensionRange{0.95, 1.15});
  const double windowTop = m->height_m - uniform(rng, {0.25, 0.40});
  BandedBody b;
  b.z = {clearance, bumperTop, belt, windowTop, m->height_m};
  b.frontX = {half, half, half - 0.03, half - 0.12, half - 0.18};
  b.rearX = {-half, -half, -half, -half + 0.05, -half + 0.10};
  b.halfWidth = 0.5 * m->width_m;
  using P = SurfacePart;
  b.side = {P::Paint, P::Paint, P::SideWindow, P::Paint};
  b.front = {P::Paint, P::Paint, P::Windscreen, P::Paint};
  b.rear = {P::Paint, P::Paint, P::RearWindow, P::Paint};
  b.headLightBand = 1;
  b.tailLightBand = 1;
  b.lightWidth = uniform(rng, {0.30, 0.45});
  addBody(m, b);
  const double frontAxle = half - uniform(rng, {2.50, 2.80});
  const double rearAxle = -half + uniform(rng, {2.90, 3.50});
  addAxle(m, frontAxle);
  if (m->kind == LargeVehicleKind::ArticulatedBus) {
    addAxle(m, 0.5 * (frontAxle + rearAxle) + uniform(rng, {0.0, 0.6}));  // middle axle
  }
  addAxle(m, rearAxle);
  if (coach && m->length_m > 13.0) {
    addAxle(m, rearAxle - 1.35);  // tag axle of a three-axle coach
  }
}

// A driver's cab: bumper band with the headlights, windscreen band, roof band.
void addCab(LargeVehicleMesh* m, double xFront, double length, double top, std::mt19937_64& rng) {
  const double bottom = uniform(rng, {0.45, 0.60});
  const double bumperTop = bottom + uniform(rng, {0.35, 0.45});
  const double belt = uniform(rng, {1.45, 1.75});
  const double windowTop = top - uniform(rng, {0.25, 0.40});
  BandedBody b;
  b.z = {bottom, bumperTop, belt, windowTop, top};
  b.frontX = {xFront, xFront, xFront - 0.04, xFront - 0.12, xFront - 0.16};
  b.rearX.assign(5, xFront - length);
  b.halfWidth = 0.5 * m->width_m - uniform(rng, {0.0, 0.05});
  using P = SurfacePart;
  b.side = {P::Paint, P::Paint, P::SideWindow, P::Paint};
  b.front = {P::Paint, P::Paint, P::Windscreen, P::Paint};
  b.rear = {P::Paint, P::Paint, P::Paint, P::Paint};
  b.headLightBand = 1;
  b.lightWidth = uniform(rng, {0.25, 0.40});
  addBody(m, b);
}

// A painted box from xFront to xRear in two bands, split at zSplit, with the tail lights in
// band lightBand (0: below the split, 1: above it).
BandedBody tailLitBox(double xFront, double xRear, double zBottom, double zSplit, double zTop,
                      double halfWidth, int lightBand, double lightWidth) {
  BandedBody b = box(xFront, xRear, zBottom, zTop, halfWidth, SurfacePart::Paint);
  b.z = {zBottom, zSplit, zTop};
  b.frontX.assign(3, xFront);
  b.rearX.assign(3, xRear);
  b.side = b.front = b.rear = {SurfacePart::Paint, SurfacePart::Paint};
  b.tailLightBand = lightBand;
  b.lightWidth = lightWidth;
  return b;
}

// A cargo box (truck body or semi-trailer) with the tail lights in its lowest band.
void addCargoBox(LargeVehicleMesh* m, double xFront, double floor, std::mt19937_64& rng) {
  addBody(m, tailLitBox(xFront, -0.5 * m->length_m, floor, floor + 0.30, m->height_m,
                        0.5 * m->width_m, 0, uniform(rng, {0.25, 0.35})));
}

void buildTruck(LargeVehicleMesh* m, std::mt19937_64& rng) {
  const double half = 0.5 * m->length_m;
  const bool semi = m->kind == LargeVehicleKind::SemiTrailer;
  const double cabLength =
      uniform(rng, semi ? DimensionRange{2.20, 2.50} : DimensionRange{1.60, 2.30});
  const double cabTop = std::min(
      m->height_m, uniform(rng, semi ? DimensionRange{3.20, 3.90} : DimensionRange{2.60, 3.30}));
  addCab(m, half, cabLength, cabTop, rng);
  const double cabRear = half - cabLength;
  const double floor = uniform(rng, semi ? DimensionRange{1.15, 1.30} : DimensionRange{1.00, 1.30});
  const double chassisTop = floor - 0.05;
  const double frontAxle = half - uniform(rng, {1.20, 1.50});
  addAxle(m, frontAxle);
  if (semi) {
    // Tractor: drive axle and the frame under the trailer's front; trailer: three axles.
    const double boxFront = cabRear - uniform(rng, {0.30, 0.60});
    const double driveAxle = frontAxle - uniform(rng, {3.60, 3.90});
    addBody(m, box(cabRear, driveAxle - 1.0, 0.55, chassisTop, 0.45, SurfacePart::Underbody));
    addCargoBox(m, boxFront, floor, rng);
    addAxle(m, driveAxle);
    const double lastAxle = -half + uniform(rng, {1.30, 1.80});
    for (int i = 2; i >= 0; --i) {
      addAxle(m, lastAxle + 1.31 * i);  // 1.31 m: the usual tri-axle spread
    }
  } else {
    const double boxFront = cabRear - uniform(rng, {0.10, 0.30});
    addBody(m, box(cabRear, -half + 0.20, 0.55, chassisTop, 0.45, SurfacePart::Underbody));
    addCargoBox(m, boxFront, floor, rng);
    const double rearAxle = -half + uniform(rng, {1.60, 2.40});
    if (m->length_m >= 10.0) {
      addAxle(m, rearAxle + 1.35);  // tandem rear axles on the longer rigid trucks
    }
    addAxle(m, rearAxle);
  }
}

void buildPickup(PickupMesh* m, std::mt19937_64& rng) {
  const double half = 0.5 * m->length_m;
  const double clearance = uniform(rng, {0.30, 0.40});
  const double bumperTop = clearance + uniform(rng, {0.35, 0.45});
  const double bonnet = uniform(rng, {1.05, 1.25});  // bonnet height at the grille
  const double belt = bonnet + uniform(rng, {0.04, 0.10});
  const double windowTop = m->height_m - uniform(rng, {0.08, 0.14});
  const double bonnetLength = uniform(rng, {1.45, 1.80});
  // Regular to crew cab, windscreen included, leaving a bed of at least 1.4 m.
  const double cabLength =
      std::min(uniform(rng, {1.70, 2.60}), m->length_m - bonnetLength - uniform(rng, {1.40, 1.70}));
  const double cabRear = half - bonnetLength - cabLength;
  BandedBody cab;
  cab.z = {clearance, bumperTop, bonnet, belt, windowTop, m->height_m};
  cab.frontX = {half,
                half - 0.02,
                half - uniform(rng, {0.06, 0.12}),
                half - bonnetLength,
                half - bonnetLength - uniform(rng, {0.65, 0.85}),
                half - bonnetLength - uniform(rng, {0.90, 1.00})};
  cab.rearX.assign(cab.z.size(), cabRear);
  cab.halfWidth = 0.5 * m->width_m;
  using P = SurfacePart;
  cab.side = {P::Paint, P::Paint, P::Paint, P::SideWindow, P::Paint};
  cab.front = {P::Paint, P::Paint, P::Paint, P::Windscreen, P::Paint};
  cab.rear = {P::Paint, P::Paint, P::Paint, P::RearWindow, P::Paint};
  cab.headLightBand = 1;
  cab.lightWidth = uniform(rng, {0.25, 0.35});
  addBody(m, cab);
  // The bed: a floor sunk below the rim (a dark liner, or bare paint) closed by two side walls,
  // the bulkhead behind the cab and the tailgate; the tail lights sit in the floor box's upper
  // band. From above it reads as a shaded tray behind the cab.
  const double bedTop = belt + uniform(rng, {-0.05, 0.05});
  const double floor = bedTop - uniform(rng, {0.42, 0.55});
  const double bedFront = cabRear - uniform(rng, {0.02, 0.08});
  const double wall = uniform(rng, {0.06, 0.10});
  const double halfWidth = 0.5 * m->width_m;
  const SurfacePart floorPart = uniform01(rng) < 0.6 ? P::Underbody : P::Paint;
  BandedBody tub = tailLitBox(bedFront, -half, clearance, bumperTop, floor, halfWidth, 1,
                              uniform(rng, {0.15, 0.25}));
  tub.roof = floorPart;
  addBody(m, tub);
  for (const double side : {1.0, -1.0}) {
    BandedBody w = box(bedFront, -half, floor, bedTop, 0.5 * wall, P::Paint);
    w.centreY = side * (halfWidth - 0.5 * wall);
    addBody(m, w);
  }
  const double innerHalf = halfWidth - wall;
  addBody(m, box(bedFront, bedFront - wall, floor, bedTop, innerHalf, P::Paint));  // bulkhead
  addBody(m, box(-half + wall, -half, floor, bedTop, innerHalf, P::Paint));        // tailgate
  m->bedFrontX_m = bedFront;
  m->bedTopZ_m = bedTop;
  m->bedFloorZ_m = floor;
  addAxle(m, half - uniform(rng, {0.85, 1.05}));
  addAxle(m, -half + uniform(rng, {1.15, 1.45}));
}

}  // namespace

PickupMesh generatePickup(std::mt19937_64& rng) {
  PickupMesh m;
  m.length_m = uniform(rng, kPickupSpec.length_m);
  m.width_m = uniform(rng, kPickupSpec.width_m);
  m.height_m = uniform(rng, kPickupSpec.height_m);
  m.wheelRadius_m = uniform(rng, kPickupSpec.wheelRadius_m);
  m.wheelWidth_m = 0.27;
  buildPickup(&m, rng);
  return m;
}

const char* toString(LargeVehicleKind kind) {
  switch (kind) {
    case LargeVehicleKind::CityBus:
      return "city_bus";
    case LargeVehicleKind::ArticulatedBus:
      return "articulated_bus";
    case LargeVehicleKind::Coach:
      return "coach";
    case LargeVehicleKind::RigidTruck:
      return "rigid_truck";
    case LargeVehicleKind::SemiTrailer:
      return "semi_trailer";
  }
  return "unknown";
}

const LargeVehicleSpec& largeVehicleSpec(LargeVehicleKind kind) {
  return kLargeSpecs[static_cast<std::size_t>(
      std::min(static_cast<int>(kind), kLargeVehicleKindCount - 1))];
}

LargeVehicleMesh generateLargeVehicle(LargeVehicleKind kind, std::mt19937_64& rng) {
  const LargeVehicleSpec& spec = largeVehicleSpec(kind);
  LargeVehicleMesh m;
  m.kind = spec.kind;
  m.length_m = uniform(rng, spec.length_m);
  m.width_m = uniform(rng, spec.width_m);
  m.height_m = uniform(rng, spec.height_m);
  m.wheelRadius_m = uniform(rng, spec.wheelRadius_m);
  m.wheelWidth_m = 0.30;
  if (kind == LargeVehicleKind::RigidTruck || kind == LargeVehicleKind::SemiTrailer) {
    buildTruck(&m, rng);
  } else {
    buildBus(&m, rng);
  }
  return m;
}

namespace {

// A closed box on the roof: x from xRear to xFront, y centreY +- halfWidth, z from the roof up.
void addRoofBox(LargeVehicleMesh* m, double xFront, double xRear, double centreY, double halfWidth,
                double roofZ, double height, SurfacePart part) {
  BandedBody b = box(xFront, xRear, roofZ, roofZ + height, halfWidth, part);
  b.centreY = centreY;
  b.bottom = part;  // sits on the roof: its bottom is never seen
  addBody(m, b);
}

// Seven-segment strokes of each digit (a, b, c, d, e, f, g: top, upper right, lower right,
// bottom, lower left, upper left, middle).
constexpr std::array<std::uint8_t, 10> kSegments = {0x3F, 0x06, 0x5B, 0x4F, 0x66,
                                                    0x6D, 0x7D, 0x07, 0x7F, 0x6F};

// One digit of height h and width w whose reading direction is +x (its "up" is +y), lower-left
// corner at (x0, y0), strokes t wide, painted as thin dark boxes on the roof; with turned, every
// stroke is turned by 180 deg about (cx, cy) (a number read from the other side).
void addDigit(LargeVehicleMesh* m, int digit, double x0, double y0, double w, double h, double t,
              double roofZ, bool turned, double cx, double cy) {
  const double paint = 0.01;  // thick enough to win the depth test against the roof
  const std::uint8_t segments = kSegments[static_cast<std::size_t>(digit)];
  const double half = 0.5 * h;
  struct Stroke {
    double xa, xb, ya, yb;
  };
  const std::array<Stroke, 7> strokes = {{
      {x0, x0 + w, y0 + h - t, y0 + h},                        // a: top
      {x0 + w - t, x0 + w, y0 + half, y0 + h},                 // b: upper right
      {x0 + w - t, x0 + w, y0, y0 + half},                     // c: lower right
      {x0, x0 + w, y0, y0 + t},                                // d: bottom
      {x0, x0 + t, y0, y0 + half},                             // e: lower left
      {x0, x0 + t, y0 + half, y0 + h},                         // f: upper left
      {x0, x0 + w, y0 + half - 0.5 * t, y0 + half + 0.5 * t},  // g: middle
  }};
  for (std::size_t i = 0; i < strokes.size(); ++i) {
    if ((segments >> i) & 1U) {
      Stroke k = strokes[i];
      if (turned) {
        k = {2.0 * cx - k.xb, 2.0 * cx - k.xa, 2.0 * cy - k.yb, 2.0 * cy - k.ya};
      }
      addRoofBox(m, k.xb, k.xa, 0.5 * (k.ya + k.yb), 0.5 * (k.yb - k.ya), roofZ, paint,
                 SurfacePart::Underbody);
    }
  }
}

}  // namespace

void addBusRoofDetails(LargeVehicleMesh* m, std::mt19937_64& rng) {
  const double half = 0.5 * m->length_m;
  const double roofZ = m->height_m;
  const double halfWidth = 0.5 * m->width_m;
  // The flat roof runs from about -half + 0.1 to half - 0.2 (buildBus's profile).
  const double roofFront = half - 0.25;
  const double roofRear = -half + 0.15;
  // Which end carries the unit and which the number: either, as on real fleets.
  const double unitEnd = uniform01(rng) < 0.7 ? -1.0 : 1.0;  // mostly over the rear engine
  const double unitLength = uniform(rng, {2.2, 3.6});
  const double unitHalfWidth = halfWidth * uniform(rng, {0.70, 0.85});
  const double unitHeight = uniform(rng, {0.18, 0.30});
  const bool unitInMiddle = uniform01(rng) < 0.25;
  const double unitCentre =
      unitInMiddle ? uniform(rng, {-1.0, 1.0}) : unitEnd * (half - 0.6 - 0.5 * unitLength);
  addRoofBox(m, unitCentre + 0.5 * unitLength, unitCentre - 0.5 * unitLength, 0.0, unitHalfWidth,
             roofZ, unitHeight, SurfacePart::Paint);
  // Fans on the unit: a row of dark squares across it.
  const int fans = 2 + static_cast<int>(uniform01(rng) * 3.0);  // 2..4
  const double fanPitch = 1.8 * unitHalfWidth / fans;           // apart, not one dark bar
  const double fan = fanPitch * uniform(rng, {0.45, 0.65});
  const double fanX = unitCentre + unitEnd * uniform(rng, {0.0, 0.25}) * unitLength;
  for (int i = 0; i < fans; ++i) {
    const double y = fanPitch * (i + 0.5 - 0.5 * fans);
    addRoofBox(m, fanX + 0.5 * fan, fanX - 0.5 * fan, y, 0.5 * fan, roofZ + unitHeight, 0.02,
               SurfacePart::Underbody);
  }
  // Hatches on the centre line, away from the unit.
  const int hatches = 2 + static_cast<int>(uniform01(rng) * 2.0);  // 2..3
  const double hatch = uniform(rng, {0.55, 0.80});
  const double hatchSpan = std::min(3.5, m->length_m - unitLength - 3.0);
  const double hatchCentre = -unitEnd * uniform(rng, {0.5, 2.0});
  for (int i = 0; i < hatches; ++i) {
    const double x = hatchCentre + hatchSpan * ((i + 0.5) / hatches - 0.5);
    if (std::abs(x - unitCentre) < 0.5 * unitLength + hatch) {
      continue;  // under the unit
    }
    addRoofBox(m, x + 0.5 * hatch, x - 0.5 * hatch, 0.0, 0.5 * hatch, roofZ, 0.03,
               SurfacePart::Underbody);
  }
  // The fleet number: large dark digits reading along the bus, at the end without the unit.
  if (uniform01(rng) < 0.75) {
    const int digits = uniform01(rng) < 0.5 ? 3 : 4;
    const double h = m->width_m * uniform(rng, {0.45, 0.60});
    const double w = 0.55 * h;
    const double t = 0.18 * h;
    const double gap = 0.25 * w;
    const double total = digits * w + (digits - 1) * gap;
    const double numberEnd = unitInMiddle ? unitEnd : -unitEnd;
    const double inset = uniform(rng, {0.4, 1.2});
    const double x0 = numberEnd > 0 ? roofFront - inset - total : roofRear + inset;
    const double y0 = -0.5 * h + uniform(rng, {-0.1, 0.1}) * m->width_m;
    const bool turned = uniform01(rng) < 0.5;  // read from either side
    for (int i = 0; i < digits; ++i) {
      const int digit = static_cast<int>(uniform01(rng) * 10.0) % 10;
      addDigit(m, digit, x0 + i * (w + gap), y0, w, h, t, roofZ, turned, x0 + 0.5 * total,
               y0 + 0.5 * h);
    }
  }
}

double meshVolume(std::span<const Eigen::Vector3d> vertices, std::span<const Triangle> triangles) {
  double sixVolume = 0.0;
  for (const Triangle& t : triangles) {
    sixVolume += vertices[t.v[0]].dot(vertices[t.v[1]].cross(vertices[t.v[2]]));
  }
  return sixVolume / 6.0;
}

}  // namespace vp::shape
