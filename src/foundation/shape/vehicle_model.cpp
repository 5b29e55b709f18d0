// The fixed keypoint topology, its mesh, the vehicle types and the ASM's mathematics; the ASM
// file (save/load) is asm_file.cpp.
#include "shape/vehicle_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "shape/mesh_builder.hpp"

namespace vp::shape {

namespace {

constexpr double kUnitTolerance = 1e-6;  // |e_s| = 1 and e_s . e_t = 0 within this

// Keypoints come in left/right pairs: left = 2 * pair, right = 2 * pair + 1, the left one on
// the +y side. The first 24 (pairs 0..11) are the evaluation keypoints.
const std::array<const char*, kKeypointCount> kNames = {"wheel_centre_front_left",
                                                        "wheel_centre_front_right",
                                                        "wheel_centre_rear_left",
                                                        "wheel_centre_rear_right",
                                                        "front_bumper_corner_left",
                                                        "front_bumper_corner_right",
                                                        "bonnet_front_corner_left",
                                                        "bonnet_front_corner_right",
                                                        "windscreen_base_left",
                                                        "windscreen_base_right",
                                                        "roof_front_left",
                                                        "roof_front_right",
                                                        "roof_rear_left",
                                                        "roof_rear_right",
                                                        "rear_window_base_left",
                                                        "rear_window_base_right",
                                                        "tail_top_corner_left",
                                                        "tail_top_corner_right",
                                                        "rear_bumper_corner_left",
                                                        "rear_bumper_corner_right",
                                                        "wheel_arch_top_front_left",
                                                        "wheel_arch_top_front_right",
                                                        "wheel_arch_top_rear_left",
                                                        "wheel_arch_top_rear_right",
                                                        "wheel_arch_front_fore_left",
                                                        "wheel_arch_front_fore_right",
                                                        "wheel_arch_front_aft_left",
                                                        "wheel_arch_front_aft_right",
                                                        "wheel_arch_rear_fore_left",
                                                        "wheel_arch_rear_fore_right",
                                                        "wheel_arch_rear_aft_left",
                                                        "wheel_arch_rear_aft_right",
                                                        "headlight_inner_left",
                                                        "headlight_inner_right",
                                                        "taillight_inner_left",
                                                        "taillight_inner_right"};

constexpr detail::Pair pair(int p) {
  return {2 * p, 2 * p + 1};
}

// The side profile, counter-clockwise in (x, z): up the front, over the roof, down the rear,
// then forward along the bottom through the rear and the front wheel arch.
const detail::Pair kFrontBumper = pair(2);     // P0
const detail::Pair kBonnetFront = pair(3);     // P1
const detail::Pair kWindscreenBase = pair(4);  // P2
const detail::Pair kRoofFront = pair(5);       // P3
const detail::Pair kRoofRear = pair(6);        // P4
const detail::Pair kRearWindowBase = pair(7);  // P5
const detail::Pair kTailTop = pair(8);         // P6
const detail::Pair kRearBumper = pair(9);      // P7
const detail::Pair kArchRearAft = pair(15);    // P8
const detail::Pair kArchTopRear = pair(11);    // P9
const detail::Pair kArchRearFore = pair(14);   // P10
const detail::Pair kArchFrontAft = pair(13);   // P11
const detail::Pair kArchTopFront = pair(10);   // P12
const detail::Pair kArchFrontFore = pair(12);  // P13
const detail::Pair kHeadLightInner = pair(16);
const detail::Pair kTailLightInner = pair(17);

std::vector<Triangle> buildMesh() {
  std::vector<Triangle> triangles;
  detail::MeshBuilder b(&triangles);
  using P = SurfacePart;
  // Sides: three fans that stay valid for every generated car because the generator keeps
  // the windscreen base behind the front axle, the rear window base behind the rear axle and
  // both arch tops below the belt line (tools/simulator/car_generator.cpp checks each car).
  b.side(kArchTopFront, kArchFrontFore, kFrontBumper, P::Paint);  // fan around the front arch
  b.side(kFrontBumper, kBonnetFront, kArchTopFront, P::Paint);
  b.side(kBonnetFront, kWindscreenBase, kArchTopFront, P::Paint);
  b.side(kWindscreenBase, kArchFrontAft, kArchTopFront, P::Paint);  // fan around the doors
  b.side(kWindscreenBase, kArchRearFore, kArchFrontAft, P::Paint);
  b.side(kWindscreenBase, kArchTopRear, kArchRearFore, P::Paint);
  b.side(kWindscreenBase, kRearWindowBase, kArchTopRear, P::Paint);
  b.side(kRearWindowBase, kTailTop, kArchTopRear, P::Paint);  // fan around the rear arch
  b.side(kTailTop, kRearBumper, kArchTopRear, P::Paint);
  b.side(kRearBumper, kArchRearAft, kArchTopRear, P::Paint);
  b.side(kWindscreenBase, kRoofFront, kRoofRear, P::SideWindow);  // greenhouse
  b.side(kWindscreenBase, kRoofRear, kRearWindowBase, P::SideWindow);
  // Around the profile, between the left and the right copy of each edge.
  b.lightStrip(kFrontBumper, kBonnetFront, kHeadLightInner, P::HeadLight, P::Paint);
  b.strip(kBonnetFront, kWindscreenBase, P::Paint);
  b.strip(kWindscreenBase, kRoofFront, P::Windscreen);
  b.strip(kRoofFront, kRoofRear, P::Paint);
  b.strip(kRoofRear, kRearWindowBase, P::RearWindow);
  b.strip(kRearWindowBase, kTailTop, P::Paint);
  b.lightStrip(kTailTop, kRearBumper, kTailLightInner, P::TailLight, P::Paint);
  b.strip(kRearBumper, kArchRearAft, P::Paint);
  b.strip(kArchRearAft, kArchTopRear, P::Wheel);
  b.strip(kArchTopRear, kArchRearFore, P::Wheel);
  b.strip(kArchRearFore, kArchFrontAft, P::Underbody);
  b.strip(kArchFrontAft, kArchTopFront, P::Wheel);
  b.strip(kArchTopFront, kArchFrontFore, P::Wheel);
  b.strip(kArchFrontFore, kFrontBumper, P::Paint);
  return triangles;
}

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}
}  // namespace

const char* toString(VehicleType type) {
  switch (type) {
    case VehicleType::Estate:
      return "estate";
    case VehicleType::Compact:
      return "compact";
    case VehicleType::Sports:
      return "sports";
    case VehicleType::Sedan:
      return "sedan";
    case VehicleType::Suv:
      return "suv";
    case VehicleType::Van:
      return "van";
    case VehicleType::Large:
      return "large";
  }
  return "unknown";
}

std::optional<VehicleType> vehicleTypeFromString(std::string_view name) {
  const std::string key = lower(name);
  for (int t = 0; t < kVehicleTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    if (key == toString(type)) {
      return type;
    }
  }
  return std::nullopt;
}

const char* toString(VehicleCategory category) {
  return category == VehicleCategory::Transporter ? "transporter" : "car";
}

const char* toString(SurfacePart part) {
  switch (part) {
    case SurfacePart::Paint:
      return "paint";
    case SurfacePart::Windscreen:
      return "windscreen";
    case SurfacePart::RearWindow:
      return "rear_window";
    case SurfacePart::SideWindow:
      return "side_window";
    case SurfacePart::Wheel:
      return "wheel";
    case SurfacePart::HeadLight:
      return "head_light";
    case SurfacePart::TailLight:
      return "tail_light";
    case SurfacePart::Underbody:
      return "underbody";
  }
  return "unknown";
}

const std::array<const char*, kKeypointCount>& keypointNames() {
  return kNames;
}

std::optional<int> keypointIndex(std::string_view name) {
  for (int k = 0; k < kKeypointCount; ++k) {
    if (name == kNames[static_cast<std::size_t>(k)]) {
      return k;
    }
  }
  return std::nullopt;
}

std::span<const Triangle> mesh() {
  static const std::vector<Triangle> triangles = buildMesh();
  return triangles;
}

const std::array<int, kEvaluationKeypointCount>& evaluationKeypoints() {
  static const std::array<int, kEvaluationKeypointCount> indices = [] {
    std::array<int, kEvaluationKeypointCount> out{};
    for (int i = 0; i < kEvaluationKeypointCount; ++i) {
      out[static_cast<std::size_t>(i)] = i;
    }
    return out;
  }();
  return indices;
}

const std::array<int, kWheelCount>& wheelCentreKeypoints() {
  static const std::array<int, kWheelCount> indices = {0, 1, 2, 3};
  return indices;
}

double wheelRadius(const KeypointModel& model, int wheel) {
  return model(2, wheelCentreKeypoints()[static_cast<std::size_t>(wheel)]);
}

double meshVolume(const KeypointModel& model) {
  double sixVolume = 0.0;
  for (const Triangle& t : mesh()) {
    sixVolume += model.col(t.v[0]).dot(model.col(t.v[1]).cross(model.col(t.v[2])));
  }
  return sixVolume / 6.0;
}

Eigen::Vector3d boundingBoxSize(const KeypointModel& model) {
  const Eigen::Vector3d lo = model.rowwise().minCoeff();
  const Eigen::Vector3d hi = model.rowwise().maxCoeff();
  return {hi.x() - lo.x(), hi.y() - lo.y(), hi.z() - std::min(lo.z(), 0.0)};
}

bool ActiveShapeModel::init(const KeypointModel& mean, std::span<const double> eigenvalues,
                            std::span<const KeypointModel> eigenvectors,
                            double explainedVarianceShare, std::string* why) {
  std::array<double, kMaxShapeComponents> sigmas{};
  if (eigenvalues.size() > sigmas.size()) {
    return fail(why, "ASM: more than " + std::to_string(kMaxShapeComponents) + " components");
  }
  for (std::size_t s = 0; s < eigenvalues.size(); ++s) {
    if (!std::isfinite(eigenvalues[s]) || eigenvalues[s] < 0.0) {
      return fail(why, "ASM: eigenvalue " + std::to_string(s) + " is negative or not finite");
    }
    sigmas[s] = std::sqrt(eigenvalues[s]);
  }
  return setModel(mean, std::span<const double>(sigmas.data(), eigenvalues.size()), eigenvectors,
                  explainedVarianceShare, why);
}

bool ActiveShapeModel::setModel(const KeypointModel& mean, std::span<const double> sigmas,
                                std::span<const KeypointModel> eigenvectors,
                                double explainedVarianceShare, std::string* why) {
  const std::size_t n = sigmas.size();
  if (n == 0 || n > static_cast<std::size_t>(kMaxShapeComponents)) {
    return fail(why, "ASM: component count must be 1.." + std::to_string(kMaxShapeComponents) +
                         ", got " + std::to_string(n));
  }
  if (eigenvectors.size() != n) {
    return fail(why, "ASM: " + std::to_string(n) + " sigmas but " +
                         std::to_string(eigenvectors.size()) + " eigenvectors");
  }
  if (!mean.allFinite()) {
    return fail(why, "ASM: the mean shape is not finite");
  }
  if (!std::isfinite(explainedVarianceShare) || explainedVarianceShare < 0.0 ||
      explainedVarianceShare > 1.0) {
    return fail(why, "ASM: explained variance share must be in [0, 1]");
  }
  for (std::size_t s = 0; s < n; ++s) {
    if (!std::isfinite(sigmas[s]) || sigmas[s] < 0.0) {
      return fail(why, "ASM: sigma " + std::to_string(s) + " is negative or not finite");
    }
    if (!eigenvectors[s].allFinite()) {
      return fail(why, "ASM: eigenvector " + std::to_string(s) + " is not finite");
    }
    for (std::size_t t = 0; t <= s; ++t) {
      const double dot = eigenvectors[s].cwiseProduct(eigenvectors[t]).sum();
      const double expected = s == t ? 1.0 : 0.0;
      if (std::abs(dot - expected) > kUnitTolerance) {
        return fail(why, "ASM: eigenvectors " + std::to_string(t) + " and " + std::to_string(s) +
                             " are not orthonormal (dot product " + std::to_string(dot) + ")");
      }
    }
  }
  mean_ = mean;
  sigmas_.fill(0.0);
  for (KeypointModel& e : eigenvectors_) {
    e.setZero();
  }
  for (std::size_t s = 0; s < n; ++s) {
    sigmas_[s] = sigmas[s];
    eigenvectors_[s] = eigenvectors[s];
  }
  componentCount_ = static_cast<int>(n);
  explainedVarianceShare_ = explainedVarianceShare;
  typePriors_.fill(TypePrior{});
  heldOutError_ = ReconstructionError{};
  return true;
}

const TypePrior& ActiveShapeModel::typePrior(VehicleType type) const {
  static const TypePrior kNone{};
  const int index = static_cast<int>(type);
  return index < kCarTypeCount ? typePriors_[static_cast<std::size_t>(index)] : kNone;
}

void ActiveShapeModel::setTypePrior(VehicleType type, const TypePrior& prior) {
  const int index = static_cast<int>(type);
  if (index < kCarTypeCount) {
    typePriors_[static_cast<std::size_t>(index)] = prior;
  }
}

KeypointModel ActiveShapeModel::shape(const ShapeParams& params) const {
  KeypointModel out = mean_;
  const int n = std::clamp(params.count, 0, componentCount_);
  for (int s = 0; s < n; ++s) {
    const auto i = static_cast<std::size_t>(s);
    out += (static_cast<double>(params.gamma[i]) * sigmas_[i]) * eigenvectors_[i];
  }
  return out;
}

std::optional<ShapeParams> ActiveShapeModel::fit(const KeypointModel& observed,
                                                 const std::array<bool, kKeypointCount>& mask,
                                                 double prior) const {
  // Fixed maximum sizes keep Eigen's storage (and the LDLT's) on the stack.
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxShapeComponents,
                               kMaxShapeComponents>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxShapeComponents, 1>;
  const int n = componentCount_;
  Matrix normal = Matrix::Zero(n, n);
  Vector rhs = Vector::Zero(n);
  int observedCount = 0;
  for (int k = 0; k < kKeypointCount; ++k) {
    if (!mask[static_cast<std::size_t>(k)]) {
      continue;
    }
    if (!observed.col(k).allFinite()) {
      return std::nullopt;
    }
    ++observedCount;
    // Column s of the keypoint's design block is sigma_s e_s(k): accumulate B^T B and B^T r.
    Eigen::Matrix<double, 3, kMaxShapeComponents> block;
    for (int s = 0; s < n; ++s) {
      const auto i = static_cast<std::size_t>(s);
      block.col(s) = sigmas_[i] * eigenvectors_[i].col(k);
    }
    const Eigen::Vector3d residual = observed.col(k) - mean_.col(k);
    for (int s = 0; s < n; ++s) {
      rhs(s) += block.col(s).dot(residual);
      for (int t = 0; t <= s; ++t) {
        normal(s, t) += block.col(s).dot(block.col(t));
      }
    }
  }
  if (observedCount < 2) {
    return std::nullopt;
  }
  ShapeParams params;
  params.count = n;
  if (n == 0) {
    return params;
  }
  for (int s = 0; s < n; ++s) {
    normal(s, s) += std::max(prior, 0.0);
    for (int t = 0; t < s; ++t) {
      normal(t, s) = normal(s, t);
    }
  }
  const Eigen::LDLT<Matrix> ldlt(normal);
  const double largest = ldlt.vectorD().cwiseAbs().maxCoeff();
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * largest)) {
    return std::nullopt;  // singular: these keypoints do not determine every component
  }
  const Vector gamma = ldlt.solve(rhs);
  if (!gamma.allFinite()) {
    return std::nullopt;
  }
  for (int s = 0; s < n; ++s) {
    params.gamma[static_cast<std::size_t>(s)] = static_cast<float>(gamma(s));
  }
  return params;
}

}  // namespace vp::shape
