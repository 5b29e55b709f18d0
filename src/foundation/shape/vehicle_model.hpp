// shape/vehicle_model: vehicle types, the fixed keypoint topology of a car and its mesh (TIN),
// and the Active Shape Model (ASM) of seed 000, Eq. 1: M(gamma) = m + sum_s gamma_s sigma_s e_s.
//
// Contract: the vehicle frame (docs/conventions.md) has its origin at the centre of the car's
// footprint on the road surface, x forward (driving direction), y left, z up, metres. Every
// car model has the same kKeypointCount keypoints in the same order (keypointNames(),
// docs/asm.md) and the same closed triangle mesh over them (mesh()), each triangle labelled
// with the surface part it belongs to (paint, glass, wheel arch, light), which is what makes
// front and back differ in an image. evaluationKeypoints() are the 24 keypoints the seed
// evaluates (E_D2D, E_dH). The four wheel centres are keypoints but no mesh vertices: a
// renderer draws each wheel as a cylinder of radius wheelRadius() whose outer face is centred
// on the wheel-centre keypoint and which extends kWheelWidth_m towards the car's centre line.
// ActiveShapeModel::shape() evaluates Eq. 1 without allocating; fit() returns gamma for a
// (possibly partial) set of observed 3D keypoints, also without allocating. Large vehicles
// (bus/truck) have a type but no ASM shape (tools/simulator/car_generator.hpp builds their meshes).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace vp::shape {

// The six car types of seed 000, plus large vehicles (bus, truck) without an ASM shape.
enum class VehicleType : std::uint8_t { Estate, Compact, Sports, Sedan, Suv, Van, Large };
constexpr int kCarTypeCount = 6;
constexpr int kVehicleTypeCount = 7;
const char* toString(VehicleType type);  // "estate", "compact", ..., "large"
std::optional<VehicleType> vehicleTypeFromString(std::string_view name);  // case-insensitive

// Seed 002's counting categories: cars, and transporters (trucks and buses). Every car type is a
// car (a van included: it is counted with the cars there); Large is a transporter.
enum class VehicleCategory : std::uint8_t { Car, Transporter };
constexpr int kVehicleCategoryCount = 2;
constexpr VehicleCategory categoryOf(VehicleType type) {
  return type == VehicleType::Large ? VehicleCategory::Transporter : VehicleCategory::Car;
}
const char* toString(VehicleCategory category);  // "car", "transporter"

constexpr int kKeypointCount = 36;  // keypoints of the topology
constexpr int kEvaluationKeypointCount = 24;
constexpr int kMaxShapeComponents = 8;  // upper bound on n_s (memory is fixed)
constexpr int kWheelCount = 4;
constexpr double kWheelWidth_m = 0.22;  // tyre width drawn inwards from the wheel-centre keypoint

using KeypointModel = Eigen::Matrix<double, 3, kKeypointCount>;  // columns = keypoints

enum class SurfacePart : std::uint8_t {
  Paint,
  Windscreen,
  RearWindow,
  SideWindow,
  Wheel,  // the wheel arches (wheel wells); the wheels themselves are cylinders, see above
  HeadLight,
  TailLight,
  Underbody
};
const char* toString(SurfacePart part);  // "paint", "windscreen", ...

struct Triangle {
  std::array<std::uint16_t, 3> v{};  // keypoint indices, counter-clockwise seen from outside
  SurfacePart part = SurfacePart::Paint;
};

const std::array<const char*, kKeypointCount>& keypointNames();
std::optional<int> keypointIndex(std::string_view name);
std::span<const Triangle> mesh();
const std::array<int, kEvaluationKeypointCount>& evaluationKeypoints();

// Wheel centres: front left, front right, rear left, rear right (keypoint indices).
const std::array<int, kWheelCount>& wheelCentreKeypoints();
// The wheels stand on the road (z = 0), so a wheel's radius is its centre's height.
double wheelRadius(const KeypointModel& model, int wheel);  // wheel in [0, kWheelCount)

// Signed volume enclosed by mesh() over the model, m^3: > 0 when the winding is outward.
double meshVolume(const KeypointModel& model);

// gamma of one vehicle; count = n_s of the model that produced it.
struct ShapeParams {
  std::array<float, kMaxShapeComponents> gamma{};
  int count = 0;
};

// Distribution of gamma over the training models of one car type (stored in the ASM file):
// lets the simulator draw type-typical shapes and the trainer check type/shape consistency.
struct TypePrior {
  std::array<double, kMaxShapeComponents> mean{};
  Eigen::Matrix<double, kMaxShapeComponents, kMaxShapeComponents> covariance =
      Eigen::Matrix<double, kMaxShapeComponents, kMaxShapeComponents>::Zero();
  int sampleCount = 0;  // 0: no prior for this type
};

// Reconstruction error of the model on held-out generated cars (reported by vp_asm_learn and
// stored in the ASM file), over the evaluation keypoints: 3D RMS and maximum distance, and the
// seed's planimetric (E_D2D, xy) and height (E_dH, z) RMS errors. modelCount 0 = unknown.
struct ReconstructionError {
  double rms_m = 0.0;
  double max_m = 0.0;
  double planimetricRms_m = 0.0;
  double heightRms_m = 0.0;
  int modelCount = 0;
};

// Extent of a keypoint model in the vehicle frame: length (x) and width (y) are the
// axis-aligned extents of the keypoints; height (z) is measured from the road (z = 0, on
// which the wheels stand) to the highest keypoint, since no keypoint lies on the road.
Eigen::Vector3d boundingBoxSize(const KeypointModel& model);

class ActiveShapeModel {
 public:
  ActiveShapeModel() = default;

  // Reads / writes the versioned, documented ASM file (docs/asm.md). Start-up only.
  bool load(const std::string& path, std::string* why);
  bool save(const std::string& path, std::string* why) const;

  // Builds the model from learned statistics (used by the learning tool and tests).
  bool init(const KeypointModel& mean, std::span<const double> eigenvalues,
            std::span<const KeypointModel> eigenvectors, double explainedVarianceShare,
            std::string* why);

  int componentCount() const { return componentCount_; }
  const KeypointModel& mean() const { return mean_; }
  double sigma(int s) const { return sigmas_[static_cast<std::size_t>(s)]; }  // sqrt(eigenvalue)
  const KeypointModel& eigenvector(int s) const {
    return eigenvectors_[static_cast<std::size_t>(s)];
  }
  double explainedVarianceShare() const { return explainedVarianceShare_; }

  // Per car type (index = static_cast<int>(VehicleType), < kCarTypeCount). Large vehicles
  // have no prior (sampleCount 0); setting one for them is ignored.
  const TypePrior& typePrior(VehicleType type) const;
  void setTypePrior(VehicleType type, const TypePrior& prior);

  const ReconstructionError& heldOutError() const { return heldOutError_; }
  void setHeldOutError(const ReconstructionError& error) { heldOutError_ = error; }

  // Eq. 1; extra or missing gamma entries count as 0. No allocation.
  KeypointModel shape(const ShapeParams& params) const;

  // Least-squares gamma for the observed keypoints where mask[k] is true, with a Tikhonov
  // prior of weight `prior` (m^2) on gamma (gamma ~ N(0, 1) per component; 0 = no prior):
  // minimises sum_k |M(gamma)_k - observed_k|^2 + prior * |gamma|^2. Returns nullopt when
  // fewer than 2 keypoints are observed, an observed coordinate is not finite, or the system
  // is singular (prior 0 with too few keypoints). No allocation.
  std::optional<ShapeParams> fit(const KeypointModel& observed,
                                 const std::array<bool, kKeypointCount>& mask,
                                 double prior = 1e-3) const;

 private:
  KeypointModel mean_ = KeypointModel::Zero();
  std::array<double, kMaxShapeComponents> sigmas_{};
  std::array<KeypointModel, kMaxShapeComponents> eigenvectors_{};
  int componentCount_ = 0;
  double explainedVarianceShare_ = 0.0;
  std::array<TypePrior, kCarTypeCount> typePriors_{};
  ReconstructionError heldOutError_{};

  // init()/load() share this; load() keeps the file's sigmas bit for bit.
  bool setModel(const KeypointModel& mean, std::span<const double> sigmas,
                std::span<const KeypointModel> eigenvectors, double explainedVarianceShare,
                std::string* why);
};

}  // namespace vp::shape
