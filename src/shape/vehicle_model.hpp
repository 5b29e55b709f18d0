// shape/vehicle_model: vehicle types, the fixed keypoint topology of a car and its mesh (TIN),
// and the Active Shape Model (ASM) of seed 000, Eq. 1: M(gamma) = m + sum_s gamma_s sigma_s e_s.
//
// Contract: the vehicle frame (docs/conventions.md) has its origin at the centre of the car's
// footprint on the road surface, x forward (driving direction), y left, z up, metres. Every
// car model has the same kKeypointCount keypoints in the same order (keypointNames()) and the
// same triangle mesh over them (mesh()), each triangle labelled with the surface part it
// belongs to (paint, glass, wheel, light), which is what makes front and back differ in an
// image. evaluationKeypoints() are the 24 keypoints the seed evaluates (E_D2D, E_dH).
// ActiveShapeModel::shape() evaluates Eq. 1 without allocating; fit() returns gamma for a
// (possibly partial) set of observed 3D keypoints. Large vehicles (bus/truck) have a type but
// no ASM shape.
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
std::optional<VehicleType> vehicleTypeFromString(std::string_view name);

constexpr int kKeypointCount = 36;  // keypoints of the topology
constexpr int kEvaluationKeypointCount = 24;
constexpr int kMaxShapeComponents = 8;  // upper bound on n_s (memory is fixed)

using KeypointModel = Eigen::Matrix<double, 3, kKeypointCount>;  // columns = keypoints

enum class SurfacePart : std::uint8_t {
  Paint,
  Windscreen,
  RearWindow,
  SideWindow,
  Wheel,
  HeadLight,
  TailLight,
  Underbody
};

struct Triangle {
  std::array<std::uint16_t, 3> v{};  // keypoint indices, counter-clockwise seen from outside
  SurfacePart part = SurfacePart::Paint;
};

const std::array<const char*, kKeypointCount>& keypointNames();
std::span<const Triangle> mesh();
const std::array<int, kEvaluationKeypointCount>& evaluationKeypoints();

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

// Axis-aligned extent of a keypoint model in the vehicle frame: length (x), width (y), height (z).
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

  // Per car type (index = static_cast<int>(VehicleType), < kCarTypeCount).
  const TypePrior& typePrior(VehicleType type) const;
  void setTypePrior(VehicleType type, const TypePrior& prior);

  // Eq. 1; extra or missing gamma entries count as 0. No allocation.
  KeypointModel shape(const ShapeParams& params) const;

  // Least-squares gamma for the observed keypoints where mask[k] is true, with a Tikhonov
  // prior of weight `prior` on gamma (gamma ~ N(0, 1) per component; 0 = no prior).
  // Returns nullopt when fewer than 2 keypoints are observed. No allocation.
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
};

}  // namespace vp::shape
