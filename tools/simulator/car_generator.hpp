// simulator/car_generator: parametric, realistic-looking vehicles for learning the ASM and for
// the simulator (offline: the product does not ship it; its namespace stays shape, whose types
// it builds): cars of the six seed types as keypoint models over the fixed topology of
// vehicle_model.hpp, and large vehicles (buses, trucks) as their own closed meshes.
//
// Contract: pure functions, deterministic for a given std::mt19937_64 state on every platform
// (they draw raw 64-bit numbers and turn them into uniform and normal variates themselves, as
// the std distributions are implementation-defined). Overall length, width, height and
// wheelbase of a car type are correlated normal variates (a common size factor) truncated to
// the documented ranges of carTypeSpec(); every other shape parameter is uniform in its
// range. A draw whose side profile the fixed mesh cannot triangulate (carProfileValid()) is
// rejected and redrawn. docs/asm.md lists the ranges and where they come from. Frames: the
// vehicle frame of vehicle_model.hpp (origin at the footprint centre on the road, x forward,
// y left, z up, metres).
#pragma once

#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"

namespace vp::shape {

struct DimensionRange {
  double min = 0.0;
  double max = 0.0;
  bool contains(double value) const { return value >= min && value <= max; }
};

// A truncated normal: mean, standard deviation and the hard range.
struct NormalRange {
  double mean = 0.0;
  double sd = 0.0;
  DimensionRange range{};
};

// How the roof ends: notchback (a boot lid behind the rear window: sedan), fastback (a long,
// shallow rear window down to a short deck: sports) or hatch (a tailgate: the others).
enum class RearStyle : std::uint8_t { Notchback, Fastback, Hatch };

struct CarTypeSpec {
  VehicleType type = VehicleType::Sedan;
  NormalRange length_m;
  NormalRange width_m;                 // body, without mirrors
  NormalRange height_m;                // road to roof
  NormalRange wheelbase_m;             // correlated with the length (the size factor)
  DimensionRange frontOverhangShare;   // front overhang / (length - wheelbase)
  DimensionRange wheelRadius_m;        // from the type's usual tyre sizes
  DimensionRange trackInset_m;         // width - track
  DimensionRange sillHeight_m;         // lower edge of the body side
  DimensionRange frontBumperHeight_m;  // foremost corner
  DimensionRange bonnetRise_m;         // bonnet front edge above the bumper corner
  DimensionRange cowlHeight_m;         // windscreen base
  DimensionRange windscreenSetback_m;  // windscreen base behind the front axle
  DimensionRange windscreenRake_deg;   // from the horizontal
  DimensionRange roofTaper_m;          // body width - roof width (tumblehome)
  DimensionRange roofDrop_m;           // roof front - roof rear height
  RearStyle rearStyle = RearStyle::Notchback;
  DimensionRange roofLength_m;         // notchback/fastback: roof front to roof rear
  DimensionRange deckLength_m;         // notchback/fastback: rear window base to the tail
  DimensionRange rearRoofInset_m;      // hatch: roof rear ahead of the rear end
  DimensionRange rearWindowAngle_deg;  // notch/fastback: from horizontal; hatch: from vertical
  DimensionRange deckHeight_m;         // rear window base
  DimensionRange tailDrop_m;           // tail top corner below the rear window base
  DimensionRange rearBumperHeight_m;   // rearmost corner
  DimensionRange cornerInset_m;        // bumper corners inside the body width (rounding)
  DimensionRange lightWidth_m;         // head/tail light width at the corner
};

// The documented ranges of a car type (type < kCarTypeCount).
const CarTypeSpec& carTypeSpec(VehicleType type);

// One drawn car: its parameters (for tests, docs and the simulator) and its keypoints.
struct CarDimensions {
  VehicleType type = VehicleType::Sedan;
  double length_m = 0.0;
  double width_m = 0.0;
  double height_m = 0.0;
  double wheelbase_m = 0.0;
  double frontOverhang_m = 0.0;
  double rearOverhang_m = 0.0;
  double track_m = 0.0;
  double wheelRadius_m = 0.0;
  double sillHeight_m = 0.0;
  double frontBumperHeight_m = 0.0;
  double bonnetFrontHeight_m = 0.0;
  double bonnetSetback_m = 0.0;  // bonnet front edge behind the bumper corner
  double cowlHeight_m = 0.0;
  double windscreenSetback_m = 0.0;
  double windscreenRake_deg = 0.0;
  double roofWidth_m = 0.0;
  double roofDrop_m = 0.0;
  double roofLength_m = 0.0;  // sampled (notch/fastback) or resulting (hatch)
  double deckLength_m = 0.0;  // sampled (notch/fastback); hatch: unused
  double rearRoofInset_m = 0.0;
  double rearWindowAngle_deg = 0.0;  // sampled (hatch) or resulting (notch/fastback)
  double deckHeight_m = 0.0;
  double tailDrop_m = 0.0;
  double tailInset_m = 0.0;
  double rearBumperHeight_m = 0.0;
  double cornerInset_m = 0.0;
  double headLightWidth_m = 0.0;
  double tailLightWidth_m = 0.0;
  double archHalfWidth_m = 0.0;
  double archGap_m = 0.0;  // arch top above the tyre (before clamping below the belt line)
};

struct GeneratedCar {
  CarDimensions dimensions;
  KeypointModel keypoints = KeypointModel::Zero();
};

// Keypoints of a car with the given parameters (no checks: see carProfileValid()).
KeypointModel buildCarKeypoints(const CarDimensions& d);

// True when every side triangle of mesh() faces outwards with a non-degenerate area, i.e. the
// fixed triangulation is valid for this car, and the enclosed volume is positive.
bool carProfileValid(const KeypointModel& keypoints);

// Draws one car of a car type (type < kCarTypeCount).
GeneratedCar generateCar(VehicleType type, std::mt19937_64& rng);

// --- Large vehicles (no ASM) -------------------------------------------------------------

enum class LargeVehicleKind : std::uint8_t {
  CityBus,
  ArticulatedBus,
  Coach,
  RigidTruck,
  SemiTrailer
};
constexpr int kLargeVehicleKindCount = 5;
const char* toString(LargeVehicleKind kind);

struct LargeVehicleSpec {
  LargeVehicleKind kind = LargeVehicleKind::CityBus;
  DimensionRange length_m;
  DimensionRange width_m;
  DimensionRange height_m;
  DimensionRange wheelRadius_m;
};
const LargeVehicleSpec& largeVehicleSpec(LargeVehicleKind kind);

// A closed triangle mesh (one or more closed boxes: body, cab, cargo box, chassis), outward
// counter-clockwise winding, labelled like the car mesh; wheels as for cars: cylinders of
// wheelRadius_m whose outer faces are centred on wheelCentres and extend wheelWidth_m inwards.
struct BodyMesh {
  double length_m = 0.0;
  double width_m = 0.0;
  double height_m = 0.0;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Triangle> triangles;  // indices into vertices
  std::vector<Eigen::Vector3d> wheelCentres;
  double wheelRadius_m = 0.0;
  double wheelWidth_m = 0.0;
};

struct LargeVehicleMesh : BodyMesh {
  LargeVehicleKind kind = LargeVehicleKind::CityBus;
};

LargeVehicleMesh generateLargeVehicle(LargeVehicleKind kind, std::mt19937_64& rng);

// Roof details of a bus or coach as real footage shows them from above (the plain roof of
// generateLargeVehicle differs from a car's only by its length): a raised air-conditioning unit
// at one end or in the middle, two or three dark hatches on the centre line, a row of dark fans
// across the roof at one end and, on most, a fleet number of three or four digits painted large
// and dark near one end. Each detail is a closed box standing on the roof; the vehicle's
// length, width, height and wheels stay as they were. Draws only from rng.
void addBusRoofDetails(LargeVehicleMesh* m, std::mt19937_64& rng);

// --- Pickup trucks (light vehicles with an open load bed; no ASM) -------------------------
//
// A bonnet, a cab with windscreen and rear window, and behind it an open bed: a floor sunk
// below a painted rim (a dark liner on 60 %), tail lights at the rear. Seen from above the dark
// bed lies at the back, where a car's dark glass is at its front: a shape real footage shows
// reversed often.
struct PickupSpec {
  DimensionRange length_m{5.0, 5.9};  // mid-size to full-size crew cabs
  DimensionRange width_m{1.85, 2.05};
  DimensionRange height_m{1.75, 1.95};
  DimensionRange wheelRadius_m{0.37, 0.42};
};
inline constexpr PickupSpec kPickupSpec{};

struct PickupMesh : BodyMesh {
  double bedFrontX_m = 0.0;  // x of the bed's front edge (behind the cab); the bed reaches the rear
  double bedTopZ_m = 0.0;    // height of the bed's rim
  double bedFloorZ_m = 0.0;  // height of its floor (dark liner or paint), 0.42-0.55 m below the rim
};

PickupMesh generatePickup(std::mt19937_64& rng);

// Signed enclosed volume (m^3) of a triangle mesh: > 0 for outward winding.
double meshVolume(std::span<const Eigen::Vector3d> vertices, std::span<const Triangle> triangles);

}  // namespace vp::shape
