#include "vehicles.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "car_generator.hpp"

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kWheelSegments = 14;

Material materialOf(shape::SurfacePart part) {
  switch (part) {
    case shape::SurfacePart::Paint:
      return Material::Paint;
    case shape::SurfacePart::Windscreen:
    case shape::SurfacePart::RearWindow:
    case shape::SurfacePart::SideWindow:
      return Material::Glass;
    case shape::SurfacePart::Wheel:
      return Material::Underbody;  // the dark wheel wells
    case shape::SurfacePart::HeadLight:
      return Material::HeadLight;
    case shape::SurfacePart::TailLight:
      return Material::TailLight;
    case shape::SurfacePart::Underbody:
      return Material::Underbody;
  }
  return Material::Paint;
}

// The roof panel is the paint between the four roof corners (vehicle_model.cpp's side profile).
bool isRoofKeypoint(int index) {
  static const std::array<bool, shape::kKeypointCount> kRoof = [] {
    std::array<bool, shape::kKeypointCount> roof{};
    const auto& names = shape::keypointNames();
    for (int i = 0; i < shape::kKeypointCount; ++i) {
      roof[static_cast<std::size_t>(i)] =
          std::string_view(names[static_cast<std::size_t>(i)]).rfind("roof_", 0) == 0;
    }
    return roof;
  }();
  return index >= 0 && index < shape::kKeypointCount && kRoof[static_cast<std::size_t>(index)];
}

void addTriangle(VehicleModel& m, int a, int b, int c, Material material) {
  m.triangles.push_back(VehicleTriangle{
      {static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(b), static_cast<std::uint16_t>(c)},
      material});
}

// A wheel: the outer face (rim disc inside a tyre annulus) centred on `centre`, the tread
// cylinder extending `width` towards the car's centre line. Outward winding.
void addWheel(VehicleModel& m, const Eigen::Vector3d& centre, double radius, double width) {
  const double side = centre.y() >= 0.0 ? 1.0 : -1.0;  // outward direction along y
  const Eigen::Vector3d inner = centre - Eigen::Vector3d(0, side * width, 0);
  const int base = static_cast<int>(m.vertices.size());
  m.vertices.push_back(centre);  // base: outer hub
  for (int i = 0; i < kWheelSegments; ++i) {
    const double a = 2.0 * kPi * i / kWheelSegments;
    const Eigen::Vector3d r(std::cos(a) * radius, 0.0, std::sin(a) * radius);
    m.vertices.push_back(centre + 0.62 * r);  // base + 1 + 3i: rim edge
    m.vertices.push_back(centre + r);         // base + 2 + 3i: outer tyre edge
    m.vertices.push_back(inner + r);          // base + 3 + 3i: inner tyre edge
  }
  for (int i = 0; i < kWheelSegments; ++i) {
    const int j = (i + 1) % kWheelSegments;
    const int rimI = base + 1 + 3 * i;
    const int rimJ = base + 1 + 3 * j;
    const int outI = rimI + 1;
    const int outJ = rimJ + 1;
    const int inI = rimI + 2;
    const int inJ = rimJ + 2;
    // Angles run from +x towards +z; seen from +y that is clockwise, so the left wheel
    // (outward +y) takes the reversed order.
    if (side > 0) {
      addTriangle(m, base, rimJ, rimI, Material::Rim);
      addTriangle(m, rimI, rimJ, outJ, Material::Tyre);
      addTriangle(m, rimI, outJ, outI, Material::Tyre);
      addTriangle(m, outI, outJ, inJ, Material::Tyre);
      addTriangle(m, outI, inJ, inI, Material::Tyre);
    } else {
      addTriangle(m, base, rimI, rimJ, Material::Rim);
      addTriangle(m, rimI, outJ, rimJ, Material::Tyre);
      addTriangle(m, rimI, outI, outJ, Material::Tyre);
      addTriangle(m, outI, inJ, outJ, Material::Tyre);
      addTriangle(m, outI, inI, inJ, Material::Tyre);
    }
  }
}

// Corner normals, smooth across edges whose faces differ by less than the crease angle (so
// the body shades smoothly while its sharp edges and the wheels keep their facets).
void computeNormals(VehicleModel& m) {
  const std::size_t nt = m.triangles.size();
  std::vector<Eigen::Vector3d> face(nt);
  std::vector<std::vector<std::size_t>> around(m.vertices.size());
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& v = m.triangles[t].v;
    const Eigen::Vector3d n =
        (m.vertices[v[1]] - m.vertices[v[0]]).cross(m.vertices[v[2]] - m.vertices[v[0]]);
    face[t] = n;  // area weighted
    for (const auto k : v) {
      around[k].push_back(t);
    }
  }
  const double creaseCos = std::cos(50.0 * kPi / 180.0);
  m.normals.assign(3 * nt, Eigen::Vector3d::UnitZ());
  for (std::size_t t = 0; t < nt; ++t) {
    const Eigen::Vector3d ft = face[t].normalized();
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (const std::size_t o : around[m.triangles[t].v[static_cast<std::size_t>(c)]]) {
        const bool sameGroup = (m.triangles[o].material == Material::Tyre) ==
                               (m.triangles[t].material == Material::Tyre);
        if (sameGroup && face[o].normalized().dot(ft) > creaseCos) {
          sum += face[o];
        }
      }
      m.normals[3 * t + static_cast<std::size_t>(c)] = sum.norm() > 1e-12 ? sum.normalized() : ft;
    }
  }
}

void finishExtents(VehicleModel& m) {
  Eigen::Vector3d lo = m.vertices[0];
  Eigen::Vector3d hi = m.vertices[0];
  for (const auto& v : m.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  m.frontXM = hi.x();
  m.rearXM = lo.x();
  m.halfWidth_m = 0.5 * (hi.y() - lo.y());
}

Eigen::Vector3f srgbToLinear(double r, double g, double b) {
  const auto f = [](double c) { return static_cast<float>(std::pow(c / 255.0, 2.2)); };
  return {f(r), f(g), f(b)};
}

// One FNV-1a step. The hashes below seed streams that belong to one vehicle, for draws that
// must leave the sequence stream untouched.
std::uint64_t fnvMix(std::uint64_t h, std::uint64_t bits) {
  return (h ^ bits) * 1099511628211ULL;
}

// Over the bits of a car's first n shape parameters from the given basis.
std::uint64_t shapeHash(std::uint64_t basis, const shape::ShapeParams& gamma, int n) {
  std::uint64_t h = basis;
  for (int s = 0; s < n; ++s) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &gamma.gamma[static_cast<std::size_t>(s)], sizeof bits);
    h = fnvMix(h, bits);
  }
  return h;
}

// Over a bus's or truck's drawn dimensions.
std::uint64_t dimensionsHash(const shape::BodyMesh& mesh) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const double v : {mesh.length_m, mesh.width_m, mesh.height_m, mesh.wheelRadius_m}) {
    h = fnvMix(h, std::bit_cast<std::uint64_t>(v));
  }
  return h;
}

}  // namespace

AxleGeometry axleGeometry(const shape::KeypointModel& keypoints) {
  const auto& w = shape::wheelCentreKeypoints();
  const double front = 0.5 * (keypoints(0, w[0]) + keypoints(0, w[1]));
  const double rear = 0.5 * (keypoints(0, w[2]) + keypoints(0, w[3]));
  AxleGeometry g;
  g.wheelbase_m = front - rear;
  g.rearAxleXM = rear;
  return g;
}

VehicleLook drawLook(Rng& rng) {
  // Approximate shares of car colours in traffic (industry surveys, 2020s).
  struct Paint {
    const char* name;
    double share;
    double r, g, b;  // sRGB of the base colour
    float metallic;
  };
  static const std::array<Paint, 11> kPaints = {{
      {"white", 0.27, 235, 236, 234, 0.25F},
      {"black", 0.19, 22, 22, 24, 0.55F},
      {"grey", 0.17, 110, 112, 115, 0.45F},
      {"silver", 0.11, 175, 178, 182, 0.7F},
      {"blue", 0.08, 25, 50, 120, 0.5F},
      {"red", 0.08, 170, 20, 22, 0.45F},
      {"beige", 0.03, 180, 160, 125, 0.3F},
      {"brown", 0.02, 85, 55, 35, 0.4F},
      {"green", 0.02, 30, 80, 45, 0.4F},
      {"yellow", 0.015, 230, 180, 20, 0.3F},
      {"orange", 0.015, 220, 100, 20, 0.35F},
  }};
  std::array<double, kPaints.size()> weights{};
  for (std::size_t i = 0; i < kPaints.size(); ++i) {
    weights[i] = kPaints[i].share;
  }
  const Paint& p = kPaints[static_cast<std::size_t>(rng.weighted(weights))];
  VehicleLook look;
  look.colourName = p.name;
  const double shade = rng.uniform(0.85, 1.12);
  look.paint = srgbToLinear(std::min(255.0, p.r * shade * rng.uniform(0.96, 1.04)),
                            std::min(255.0, p.g * shade * rng.uniform(0.96, 1.04)),
                            std::min(255.0, p.b * shade * rng.uniform(0.96, 1.04)));
  look.metallic = p.metallic * static_cast<float>(rng.uniform(0.7, 1.3));
  const double tint = rng.uniform(0.015, 0.05);
  look.glassTint = Eigen::Vector3f(static_cast<float>(tint), static_cast<float>(tint * 1.1),
                                   static_cast<float>(tint * rng.uniform(1.0, 1.4)));
  return look;
}

void makeTwoTone(VehicleLook& look, Rng& rng) {
  const Eigen::Vector3f& body = look.paint;
  const float luminance = 0.2126F * body.x() + 0.7152F * body.y() + 0.0722F * body.z();
  look.twoTone = true;
  if (luminance < 0.25F) {  // linear light: every paint but white, silver, beige and yellow
    look.roofPaint = rng.chance(0.75) ? srgbToLinear(235, 236, 234) : srgbToLinear(175, 178, 182);
  } else {
    const double black = rng.uniform(14, 30);
    look.roofPaint = srgbToLinear(black, black, black * 1.05);
  }
}

shape::VehicleType VehicleFactory::drawCarType(Rng& rng) const {
  // Seed 000's UAV data are dominated by estate, compact, sedan and van; sports cars and SUVs
  // are rarer. We keep every type well represented for training.
  static const std::array<double, shape::kCarTypeCount> kShares = {0.2,  0.24, 0.06,
                                                                   0.22, 0.16, 0.12};
  return static_cast<shape::VehicleType>(rng.weighted(kShares));
}

std::shared_ptr<const VehicleModel> VehicleFactory::carFromGamma(shape::VehicleType type,
                                                                 const shape::ShapeParams& gamma,
                                                                 const VehicleLook& look,
                                                                 double lengthScale,
                                                                 double widthScale) const {
  auto m = std::make_shared<VehicleModel>();
  m->type = type;
  m->gamma = gamma;
  m->hasKeypoints = true;
  m->look = look;
  shape::KeypointModel k = asm_->shape(gamma);
  if (lengthScale != 1.0 || widthScale != 1.0) {
    k.row(0) *= lengthScale;  // vehicle frame: x forward, y left, z up
    k.row(1) *= widthScale;
    m->gamma.count = 0;  // no gamma describes the scaled shape
  }
  for (int i = 0; i < shape::kKeypointCount; ++i) {
    m->vertices.emplace_back(k.col(i));
  }
  for (const shape::Triangle& t : shape::mesh()) {
    const bool roof = look.twoTone && t.part == shape::SurfacePart::Paint &&
                      isRoofKeypoint(t.v[0]) && isRoofKeypoint(t.v[1]) && isRoofKeypoint(t.v[2]);
    addTriangle(*m, t.v[0], t.v[1], t.v[2], roof ? Material::RoofPaint : materialOf(t.part));
  }
  const auto& wheels = shape::wheelCentreKeypoints();
  for (int w = 0; w < shape::kWheelCount; ++w) {
    const double r = shape::wheelRadius(k, w);
    addWheel(*m, k.col(wheels[static_cast<std::size_t>(w)]), r, shape::kWheelWidth_m);
  }
  m->dimensions_m = shape::boundingBoxSize(k);
  const AxleGeometry axles = axleGeometry(k);
  m->wheelbase_m = axles.wheelbase_m;
  m->rearAxleXM = axles.rearAxleXM;
  computeNormals(*m);
  finishExtents(*m);
  return m;
}

std::shared_ptr<const VehicleModel> VehicleFactory::makeCar(Rng& rng,
                                                            shape::VehicleType type) const {
  const int n = asm_->componentCount();
  const shape::TypePrior& prior = asm_->typePrior(type);
  shape::ShapeParams gamma;
  gamma.count = n;
  Eigen::VectorXd z(n);
  for (int s = 0; s < n; ++s) {
    z[s] = std::clamp(rng.normal(), -2.5, 2.5);
  }
  if (prior.sampleCount > 0) {
    const Eigen::MatrixXd cov =
        prior.covariance.topLeftCorner(n, n) + 1e-9 * Eigen::MatrixXd::Identity(n, n);
    const Eigen::LLT<Eigen::MatrixXd> llt(cov);
    const Eigen::VectorXd g = llt.matrixL() * z;
    for (int s = 0; s < n; ++s) {
      gamma.gamma[static_cast<std::size_t>(s)] =
          static_cast<float>(prior.mean[static_cast<std::size_t>(s)] + g[s]);
    }
  } else {
    for (int s = 0; s < n; ++s) {
      gamma.gamma[static_cast<std::size_t>(s)] = static_cast<float>(z[s]);
    }
  }
  VehicleLook look = drawLook(rng);
  if (twoToneShare_ > 0.0) {
    // Drawn from the car's own shape, not the sequence stream: the scene (every car, its place
    // and its motion) stays the one the seed gives without two-tone roofs; only roofs change.
    Rng own(shapeHash(1469598103934665603ULL ^ static_cast<std::uint64_t>(type), gamma, n));
    if (own.chance(twoToneShare_)) {
      makeTwoTone(look, own);
    }
  }
  double lengthScale = 1.0;
  double widthScale = 1.0;
  if (cityCarShare_ > 0.0 && type == shape::VehicleType::Compact) {
    // Its own stream from the car's shape too (another hash basis than the two-tone draw's):
    // which compact cars become city cars does not depend on the two-tone share.
    Rng own(shapeHash(0x84222325cbf29ce4ULL, gamma, n));
    if (own.chance(cityCarShare_)) {
      const double length_m = shape::boundingBoxSize(asm_->shape(gamma)).x();
      lengthScale = own.uniform(kCityCarLength_m.min_m, kCityCarLength_m.max_m) / length_m;
      widthScale = own.uniform(kCityCarWidthScaleMin, 1.0);
    }
  }
  if (pickupShare_ > 0.0 && type == shape::VehicleType::Suv) {
    // Its own stream from the car's shape again (a third hash basis), so that the scene and
    // every other car stay those of the seed; the pickup keeps the SUV's look.
    Rng own(shapeHash(0x9e3779b97f4a7c15ULL, gamma, n));
    if (own.chance(pickupShare_)) {
      return makePickup(own, look);
    }
  }
  return carFromGamma(type, gamma, look, lengthScale, widthScale);
}

namespace {

// A vehicle without ASM keypoints (bus, truck, pickup) from the car generator's mesh: its
// wheels, axles (the front-most one steers, the mean of the others is the rear axle), box,
// normals and extents; the caller gives it its look.
std::shared_ptr<VehicleModel> modelFromBody(const shape::BodyMesh& mesh, shape::VehicleType type) {
  auto m = std::make_shared<VehicleModel>();
  m->type = type;
  m->hasKeypoints = false;
  m->vertices = mesh.vertices;
  for (const shape::Triangle& t : mesh.triangles) {
    addTriangle(*m, t.v[0], t.v[1], t.v[2], materialOf(t.part));
  }
  double frontAxle = -1e9;
  double rearSum = 0.0;
  int rearCount = 0;
  for (const Eigen::Vector3d& c : mesh.wheelCentres) {
    frontAxle = std::max(frontAxle, c.x());
  }
  for (const Eigen::Vector3d& c : mesh.wheelCentres) {
    addWheel(*m, c, mesh.wheelRadius_m, mesh.wheelWidth_m);
    if (c.x() < frontAxle - 0.5) {
      rearSum += c.x();
      ++rearCount;
    }
  }
  m->rearAxleXM = rearCount > 0 ? rearSum / rearCount : -0.3 * mesh.length_m;
  m->wheelbase_m = frontAxle - m->rearAxleXM;
  m->dimensions_m = Eigen::Vector3d(mesh.length_m, mesh.width_m, mesh.height_m);
  computeNormals(*m);
  finishExtents(*m);
  return m;
}

}  // namespace

std::shared_ptr<const VehicleModel> VehicleFactory::makeLarge(Rng& rng) const {
  static const std::array<double, shape::kLargeVehicleKindCount> kShares = {0.35, 0.1, 0.1, 0.3,
                                                                            0.15};
  const auto kind = static_cast<shape::LargeVehicleKind>(rng.weighted(kShares));
  shape::LargeVehicleMesh mesh = shape::generateLargeVehicle(kind, rng.engine());
  const bool bus = kind == shape::LargeVehicleKind::CityBus ||
                   kind == shape::LargeVehicleKind::ArticulatedBus ||
                   kind == shape::LargeVehicleKind::Coach;
  if (bus && busRoofShare_ > 0.0) {
    // Its own stream from the bus's drawn dimensions, so that the scene's stream (and with it
    // every other vehicle) stays the seed's.
    Rng own(dimensionsHash(mesh));
    if (own.chance(busRoofShare_)) {
      shape::addBusRoofDetails(&mesh, own.engine());
    }
  }
  std::shared_ptr<VehicleModel> m = modelFromBody(mesh, shape::VehicleType::Large);
  VehicleLook look = drawLook(rng);
  if (rng.chance(bus ? 0.5 : 0.7)) {
    look.paint = srgbToLinear(232, 232, 228);
    look.colourName = "white";
  } else if (bus && rng.chance(0.4)) {
    look.paint = srgbToLinear(220, 170, 20);
    look.colourName = "yellow";
  }
  m->look = look;
  return m;
}

std::shared_ptr<const VehicleModel> VehicleFactory::makePickup(Rng& rng,
                                                               const VehicleLook& look) const {
  std::shared_ptr<VehicleModel> m =
      modelFromBody(shape::generatePickup(rng.engine()), shape::VehicleType::Suv);
  m->look = look;
  return m;
}

}  // namespace vp::sim
