// simulator/vehicles: the geometry and appearance of simulated vehicles.
//
// Contract: a VehicleModel is a triangle mesh in the vehicle frame (docs/conventions.md:
// origin at the centre of the footprint on the road, x forward, y left, z up, metres) with a
// surface part per triangle. Cars are the ASM mesh M(gamma) with gamma drawn from the type's
// prior, so their ground-truth gamma and keypoints are exact: vertices [0, kKeypointCount)
// are the ASM keypoints in keypointNames() order; further vertices are the wheels (dark
// cylinders whose outer face is centred on the wheel-centre keypoints, as vehicle_model.hpp
// prescribes). Large vehicles (buses, trucks) and pickups are the car generator's meshes (no
// keypoints). Paint
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
  RoofPaint,  // the roof panel of a two-tone car (VehicleLook::roofPaint)
  Wall,
  Roof,
  Canopy,
  Trunk,
  RoofUnit,
  Furniture,   // street furniture: plain albedo
  Stairs,      // stair/underpass opening: dark steps (axis: down the stairs)
  SolarPanel,  // dark blue cells in a grid (axis: along the panel rows)
};

// City cars (--city-car-share): compact cars shortened to this overall length and narrowed by
// kCityCarWidthScale, as the two-seaters and small hatchbacks of European towns (2.5 m two-seaters
// to 3.6 m four-seat hatchbacks); the ASM's compact type starts at 3.55 m.
struct CityCarLength {
  double min_m = 2.5;
  double max_m = 3.6;
};
inline constexpr CityCarLength kCityCarLength_m{};
inline constexpr double kCityCarWidthScaleMin = 0.90;

struct VehicleTriangle {
  std::array<std::uint16_t, 3> v{};
  Material material = Material::Paint;
};

struct VehicleLook {
  Eigen::Vector3f paint{0.5F, 0.5F, 0.5F};
  bool twoTone = false;                         // the roof panel in roofPaint, not paint
  Eigen::Vector3f roofPaint{0.5F, 0.5F, 0.5F};  // used only when twoTone
  float metallic = 0.3F;                        // specular strength of the clear coat
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
  // twoToneShare: share of cars whose roof is painted in a contrasting colour (0..1), drawn
  // apart from the sequence stream: the same seed gives the same scene, only roofs repainted.
  // cityCarShare: share of compact cars shortened to a city car (kCityCarLength_m), drawn the
  // same way: every other car, and the scene's draws, stay those of the seed.
  // pickupShare: share of SUVs drawn as pickup trucks with an open bed
  // (shape::generatePickup; type SUV, no keypoints, gamma unknown), drawn the same way.
  // busRoofShare: share of buses and coaches with roof details (shape::addBusRoofDetails),
  // drawn from a stream of the bus's own dimensions: the scene's draws stay the seed's.
  explicit VehicleFactory(const shape::ActiveShapeModel& asmModel, double twoToneShare = 0.0,
                          double cityCarShare = 0.0, double pickupShare = 0.0,
                          double busRoofShare = 0.0)
      : asm_(&asmModel),
        twoToneShare_(twoToneShare),
        cityCarShare_(cityCarShare),
        pickupShare_(pickupShare),
        busRoofShare_(busRoofShare) {}

  // A car of the given type (one of the six ASM types) with gamma drawn from its prior.
  std::shared_ptr<const VehicleModel> makeCar(Rng& rng, shape::VehicleType type) const;
  // A bus or truck.
  std::shared_ptr<const VehicleModel> makeLarge(Rng& rng) const;
  // A pickup truck with the given look, its dimensions drawn from rng (type SUV, no keypoints).
  std::shared_ptr<const VehicleModel> makePickup(Rng& rng, const VehicleLook& look) const;
  // Builds the model of a car from given gamma (tests, figures). lengthScale < 1 shortens the
  // car along its axis and widthScale narrows it (a city car); the result's gamma then has
  // count 0 (no ASM shape describes it: the ground truth leaves gamma unknown).
  std::shared_ptr<const VehicleModel> carFromGamma(shape::VehicleType type,
                                                   const shape::ShapeParams& gamma,
                                                   const VehicleLook& look,
                                                   double lengthScale = 1.0,
                                                   double widthScale = 1.0) const;
  // Type drawn from the traffic mix (parked: no large vehicles).
  shape::VehicleType drawCarType(Rng& rng) const;

  const shape::ActiveShapeModel& asmModel() const { return *asm_; }

 private:
  const shape::ActiveShapeModel* asm_;
  double twoToneShare_ = 0.0;
  double cityCarShare_ = 0.0;
  double pickupShare_ = 0.0;
  double busRoofShare_ = 0.0;
};

VehicleLook drawLook(Rng& rng);
// Paints the roof of a look in a colour that contrasts with its body: white or silver on a dark
// car, gloss black on a light one (the two-tone paint of small cars and panorama roofs).
void makeTwoTone(VehicleLook& look, Rng& rng);

}  // namespace vp::sim
