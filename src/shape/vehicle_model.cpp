#include "shape/vehicle_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "shape/mesh_builder.hpp"

namespace vp::shape {

namespace {

constexpr int kFormatVersion = 1;
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
  // both arch tops below the belt line (car_generator.cpp checks each car).
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

// Reads the fields of one ASM file; every error names the file and the field.
class FieldReader {
 public:
  FieldReader(const std::string& path, std::string* why) : path_(path), why_(why) {}

  bool error(const std::string& field, const std::string& message) const {
    return fail(why_, path_ + ": field '" + field + "': " + message);
  }

  bool number(const YAML::Node& node, const std::string& field, double* out) const {
    if (!node || !node.IsScalar()) {
      return error(field, node ? "expected a number" : "missing");
    }
    try {
      *out = node.as<double>();
    } catch (const YAML::Exception&) {
      return error(field, "expected a number, got '" + node.Scalar() + "'");
    }
    if (!std::isfinite(*out)) {
      return error(field, "not a finite number");
    }
    return true;
  }

  bool integer(const YAML::Node& node, const std::string& field, int* out) const {
    if (!node || !node.IsScalar()) {
      return error(field, node ? "expected an integer" : "missing");
    }
    try {
      *out = node.as<int>();
    } catch (const YAML::Exception&) {
      return error(field, "expected an integer, got '" + node.Scalar() + "'");
    }
    return true;
  }

  bool sequence(const YAML::Node& node, const std::string& field, std::size_t size) const {
    if (!node) {
      return error(field, "missing");
    }
    if (!node.IsSequence()) {
      return error(field, "expected a sequence");
    }
    if (node.size() != size) {
      return error(field, "expected " + std::to_string(size) + " entries, got " +
                              std::to_string(node.size()));
    }
    return true;
  }

  bool numbers(const YAML::Node& node, const std::string& field, std::span<double> out) const {
    if (!sequence(node, field, out.size())) {
      return false;
    }
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (!number(node[i], field + "[" + std::to_string(i) + "]", &out[i])) {
        return false;
      }
    }
    return true;
  }

  bool keypoints(const YAML::Node& node, const std::string& field, KeypointModel* out) const {
    if (!sequence(node, field, kKeypointCount)) {
      return false;
    }
    for (int k = 0; k < kKeypointCount; ++k) {
      std::array<double, 3> xyz{};
      if (!numbers(node[static_cast<std::size_t>(k)], field + "[" + std::to_string(k) + "]", xyz)) {
        return false;
      }
      out->col(k) = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
    }
    return true;
  }

 private:
  const std::string& path_;
  std::string* why_;
};

void emitKeypoints(YAML::Emitter& out, const KeypointModel& model) {
  out << YAML::BeginSeq;
  for (int k = 0; k < kKeypointCount; ++k) {
    out << YAML::Flow << YAML::BeginSeq << model(0, k) << model(1, k) << model(2, k)
        << YAML::EndSeq;
  }
  out << YAML::EndSeq;
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

bool ActiveShapeModel::save(const std::string& path, std::string* why) const {
  if (componentCount_ == 0) {
    return fail(why, path + ": cannot save an empty ASM (init() or load() first)");
  }
  const int n = componentCount_;
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // 17 significant digits: doubles survive the round trip
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kFormatVersion;
  out << YAML::Key << "keypoint_names" << YAML::Value << YAML::BeginSeq;
  for (const char* name : kNames) {
    out << name;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "component_count" << YAML::Value << n;
  out << YAML::Key << "explained_variance_share" << YAML::Value << explainedVarianceShare_;
  out << YAML::Key << "mean" << YAML::Value;
  emitKeypoints(out, mean_);
  out << YAML::Key << "sigma" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (int s = 0; s < n; ++s) {
    out << sigmas_[static_cast<std::size_t>(s)];
  }
  out << YAML::EndSeq;
  out << YAML::Key << "eigenvectors" << YAML::Value << YAML::BeginSeq;
  for (int s = 0; s < n; ++s) {
    emitKeypoints(out, eigenvectors_[static_cast<std::size_t>(s)]);
  }
  out << YAML::EndSeq;
  out << YAML::Key << "type_priors" << YAML::Value << YAML::BeginMap;
  for (int t = 0; t < kCarTypeCount; ++t) {
    const TypePrior& prior = typePriors_[static_cast<std::size_t>(t)];
    if (prior.sampleCount == 0) {
      continue;
    }
    out << YAML::Key << toString(static_cast<VehicleType>(t)) << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "sample_count" << YAML::Value << prior.sampleCount;
    out << YAML::Key << "mean" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int s = 0; s < n; ++s) {
      out << prior.mean[static_cast<std::size_t>(s)];
    }
    out << YAML::EndSeq;
    out << YAML::Key << "covariance" << YAML::Value << YAML::BeginSeq;
    for (int s = 0; s < n; ++s) {
      out << YAML::Flow << YAML::BeginSeq;
      for (int u = 0; u < n; ++u) {
        out << prior.covariance(s, u);
      }
      out << YAML::EndSeq;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (heldOutError_.modelCount > 0) {
    out << YAML::Key << "held_out_error" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "model_count" << YAML::Value << heldOutError_.modelCount;
    out << YAML::Key << "rms_m" << YAML::Value << heldOutError_.rms_m;
    out << YAML::Key << "max_m" << YAML::Value << heldOutError_.max_m;
    out << YAML::Key << "planimetric_rms_m" << YAML::Value << heldOutError_.planimetricRms_m;
    out << YAML::Key << "height_rms_m" << YAML::Value << heldOutError_.heightRms_m;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!out.good()) {
    return fail(why, path + ": YAML emitter error: " + out.GetLastError());
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << out.c_str() << '\n';
  file.close();
  if (!file) {
    return fail(why, path + ": cannot write the file");
  }
  return true;
}

bool ActiveShapeModel::load(const std::string& path, std::string* why) {
  YAML::Node root;
  {
    std::ifstream probe(path);
    if (!probe) {
      return fail(why, path + ": cannot open the ASM file");
    }
  }
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    return fail(why, path + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) {
    return fail(why, path + ": expected a YAML mapping at the top level");
  }
  const FieldReader read(path, why);
  int version = 0;
  if (!read.integer(root["format_version"], "format_version", &version)) {
    return false;
  }
  if (version != kFormatVersion) {
    return read.error("format_version", "unsupported version " + std::to_string(version) +
                                            " (this build reads " + std::to_string(kFormatVersion) +
                                            ")");
  }
  const YAML::Node names = root["keypoint_names"];
  if (!read.sequence(names, "keypoint_names", kKeypointCount)) {
    return false;
  }
  for (std::size_t k = 0; k < kNames.size(); ++k) {
    const std::string name = names[k].IsScalar() ? names[k].Scalar() : std::string("?");
    if (name != kNames[k]) {
      return read.error("keypoint_names", "entry " + std::to_string(k) + " is '" + name +
                                              "', expected '" + kNames[k] +
                                              "' (the file was made for another topology)");
    }
  }
  int n = 0;
  if (!read.integer(root["component_count"], "component_count", &n)) {
    return false;
  }
  if (n < 1 || n > kMaxShapeComponents) {
    return read.error("component_count", "must be 1.." + std::to_string(kMaxShapeComponents) +
                                             ", got " + std::to_string(n));
  }
  const auto count = static_cast<std::size_t>(n);
  double share = 0.0;
  if (!read.number(root["explained_variance_share"], "explained_variance_share", &share)) {
    return false;
  }
  if (share < 0.0 || share > 1.0) {
    return read.error("explained_variance_share", "must be in [0, 1]");
  }
  KeypointModel mean;
  if (!read.keypoints(root["mean"], "mean", &mean)) {
    return false;
  }
  std::array<double, kMaxShapeComponents> sigmas{};
  if (!read.numbers(root["sigma"], "sigma", std::span<double>(sigmas.data(), count))) {
    return false;
  }
  std::array<KeypointModel, kMaxShapeComponents> vectors{};
  const YAML::Node eigen = root["eigenvectors"];
  if (!read.sequence(eigen, "eigenvectors", count)) {
    return false;
  }
  for (std::size_t s = 0; s < count; ++s) {
    if (!read.keypoints(eigen[s], "eigenvectors[" + std::to_string(s) + "]", &vectors[s])) {
      return false;
    }
  }
  // Built aside so that a failed load leaves this model as it was.
  ActiveShapeModel next;
  std::string problem;
  if (!next.setModel(mean, std::span<const double>(sigmas.data(), count),
                     std::span<const KeypointModel>(vectors.data(), count), share, &problem)) {
    return read.error("eigenvectors/sigma", problem);
  }
  const YAML::Node priors = root["type_priors"];
  if (priors && !priors.IsMap()) {
    return read.error("type_priors", "expected a mapping from car type to prior");
  }
  if (priors) {
    for (const auto& entry : priors) {
      const std::string key = entry.first.Scalar();
      const std::string field = "type_priors." + key;
      const std::optional<VehicleType> type = vehicleTypeFromString(key);
      if (!type || static_cast<int>(*type) >= kCarTypeCount) {
        return read.error(field, "not a car type (estate, compact, sports, sedan, suv, van)");
      }
      TypePrior prior;
      if (!read.integer(entry.second["sample_count"], field + ".sample_count",
                        &prior.sampleCount)) {
        return false;
      }
      if (prior.sampleCount < 0) {
        return read.error(field + ".sample_count", "must be >= 0");
      }
      if (!read.numbers(entry.second["mean"], field + ".mean",
                        std::span<double>(prior.mean.data(), count))) {
        return false;
      }
      const YAML::Node covariance = entry.second["covariance"];
      if (!read.sequence(covariance, field + ".covariance", count)) {
        return false;
      }
      for (std::size_t s = 0; s < count; ++s) {
        std::array<double, kMaxShapeComponents> row{};
        if (!read.numbers(covariance[s], field + ".covariance[" + std::to_string(s) + "]",
                          std::span<double>(row.data(), count))) {
          return false;
        }
        for (std::size_t u = 0; u < count; ++u) {
          prior.covariance(static_cast<Eigen::Index>(s), static_cast<Eigen::Index>(u)) = row[u];
        }
      }
      next.typePriors_[static_cast<std::size_t>(*type)] = prior;
    }
  }
  const YAML::Node error = root["held_out_error"];
  if (error) {
    ReconstructionError e;
    if (!read.integer(error["model_count"], "held_out_error.model_count", &e.modelCount) ||
        !read.number(error["rms_m"], "held_out_error.rms_m", &e.rms_m) ||
        !read.number(error["max_m"], "held_out_error.max_m", &e.max_m) ||
        !read.number(error["planimetric_rms_m"], "held_out_error.planimetric_rms_m",
                     &e.planimetricRms_m) ||
        !read.number(error["height_rms_m"], "held_out_error.height_rms_m", &e.heightRms_m)) {
      return false;
    }
    next.heldOutError_ = e;
  }
  *this = next;
  return true;
}

}  // namespace vp::shape
