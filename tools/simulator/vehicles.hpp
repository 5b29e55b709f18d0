// simulator/vehicles: the geometry and appearance of simulated vehicles.
//
// Contract: a VehicleModel is a triangle mesh in the vehicle frame (docs/conventions.md:
// origin at the centre of the footprint on the road, x forward, y left, z up, metres) with a
// surface part per triangle. Cars are the ASM mesh M(gamma) with gamma drawn from the type's
// prior, so their ground-truth gamma and keypoints are exact: vertices [0, kKeypointCount)
// are the ASM keypoints in keypointNames() order; further vertices are the wheels (dark
// cylinders whose outer face is centred on the wheel-centre keypoints, as vehicle_model.hpp
// prescribes). Large vehicles (buses, trucks) are the car generator's meshes (no keypoints). Paint
// colours follow the real traffic distribution (white, black, grey and silver dominate).
// VehicleFactory draws everything from the sequence Rng.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"
#include "sim_random.hpp"

namespace vp::sim {

enum class Material : std::uint8_t {
  Ground,
  Paint,
  Glass,
  Tyre,
  Rim,
  HeadLight,
  TailLight,
  Underbody,
  Wall,
  Roof,
  Canopy,
  Trunk,
  RoofUnit,
  Furniture,   // street furniture: plain albedo
  Stairs,      // stair/underpass opening: dark steps (axis: down the stairs)
  SolarPanel,  // dark blue cells in a grid (axis: along the panel rows)
};

struct VehicleTriangle {
  std::array<std::uint16_t, 3> v{};
  Material material = Material::Paint;
};

struct VehicleLook {
  Eigen::Vector3f paint{0.5F, 0.5F, 0.5F};
  float metallic = 0.3F;  // specular strength of the clear coat
  Eigen::Vector3f glassTint{0.02F, 0.025F, 0.03F};
  std::string colourName = "grey";
};

struct VehicleModel {
  shape::VehicleType type = shape::VehicleType::Sedan;
  shape::ShapeParams gamma{};
  bool hasKeypoints = false;  // cars: vertices [0, kKeypointCount) are the ASM keypoints
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3d>
      normals;  // per triangle corner (3 per triangle), smooth within creases
  std::vector<VehicleTriangle> triangles;
  Eigen::Vector3d dimensions_m{0, 0, 0};  // length, width, height of the 3D bounding box
  double wheelbase_m = 2.7;
  double rearAxleXM = -1.35;  // x of the rear axle in the vehicle frame
  double frontXM = 2.3;       // x of the front bumper
  double rearXM = -2.3;
  double halfWidth_m = 0.9;
  VehicleLook look{};
};

// Kinematic bicycle wheelbase L (seed 001) and rear-axle position of an ASM shape, from the
// wheel-centre keypoints.
struct AxleGeometry {
  double wheelbase_m = 2.7;
  double rearAxleXM = -1.35;
};
AxleGeometry axleGeometry(const shape::KeypointModel& keypoints);

class VehicleFactory {
 public:
  explicit VehicleFactory(const shape::ActiveShapeModel& asmModel) : asm_(&asmModel) {}

  // A car of the given type (one of the six ASM types) with gamma drawn from its prior.
  std::shared_ptr<const VehicleModel> makeCar(Rng& rng, shape::VehicleType type) const;
  // A bus or truck.
  std::shared_ptr<const VehicleModel> makeLarge(Rng& rng) const;
  // Builds the model of a car from given gamma (tests, figures).
  std::shared_ptr<const VehicleModel> carFromGamma(shape::VehicleType type,
                                                   const shape::ShapeParams& gamma,
                                                   const VehicleLook& look) const;
  // Type drawn from the traffic mix (parked: no large vehicles).
  shape::VehicleType drawCarType(Rng& rng) const;

  const shape::ActiveShapeModel& asmModel() const { return *asm_; }

 private:
  const shape::ActiveShapeModel* asm_;
};

VehicleLook drawLook(Rng& rng);

}  // namespace vp::sim
