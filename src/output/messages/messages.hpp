// messages/messages: the plain C++ states the perception loop publishes to the infrastructure
// (vehicle states, drone status, bird's-eye occupancy grid), independent of any transport.
//
// Contract: these structs are what the tracker and the loop fill; platform/dds converts them
// to the IDL samples of platform/dds/idl/vp_perception.idl field by field (docs/dds.md lists
// every field with its unit). They hold no DDS types, own no heap memory except
// OccupancyGrid::cells, which is sized once at start-up (resize()) and then only overwritten.
// Units are SI unless a name says otherwise; frames are those of docs/conventions.md (world =
// local ENU at the configured origin). Times are nanoseconds since the Unix epoch (UTC), the
// clock DDS source timestamps use; measurementTime_ns is the capture time of the frame the
// state was estimated from. validate() checks what a receiver relies on, without allocating.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "geodesy/geodesy.hpp"
#include "shape/vehicle_model.hpp"
#include "tracking/track_status.hpp"

namespace vp::messages {

// Life cycle of a track as the tracker reports it. Only tracks that have been confirmed are
// published; Lost (coasting, not observed in the last frames) is published until deletion so
// that receivers see the state degrade before the instance is disposed.
// The tracker's status, published as is (the stage before knows it; this one reuses it).
using tracking::TrackStatus;

struct VehicleState {
  // Key: a track id is unique per drone only.
  std::uint32_t droneId = 0;
  std::uint32_t trackId = 0;

  std::int64_t measurementTime_ns = 0;  // frame capture time, ns since the Unix epoch (UTC)
  float trackAge_s = 0.0F;              // time since the track was first detected

  // Reference point: centre of the vehicle's footprint on the road (vehicle-frame origin).
  geodesy::GeodeticPoint position{};       // WGS84, ellipsoidal height
  std::array<double, 3> enu_m{};           // the same point in the world ENU frame
  double headingEnu_rad = 0.0;             // forward axis, counter-clockwise from east, [0, 2pi)
  double headingTrueNorth_deg = 0.0;       // clockwise from true north, [0, 360)
  float speed_mps = 0.0F;                  // along the heading, >= 0 (a vehicle backing up: < 0)
  std::array<float, 2> velocityEnu_mps{};  // east, north
  float yawRate_radps = 0.0F;              // counter-clockwise positive (ENU z up)
  float acceleration_mps2 = 0.0F;          // longitudinal

  float length_m = 0.0F;  // enclosing box in the vehicle frame
  float width_m = 0.0F;
  float height_m = 0.0F;

  shape::VehicleType type = shape::VehicleType::Sedan;            // most probable type
  std::array<float, shape::kVehicleTypeCount> typeProbability{};  // indexed by VehicleType
  shape::ShapeParams shape{};  // ASM gamma (count = 0 for large vehicles)

  // Covariance of (east, north, heading) in m and rad: upper triangle row by row
  // [ee, en, eh, nn, nh, hh]; then the variances the other estimates carry.
  std::array<float, 6> poseCovariance{};
  float heightVariance_m2 = 0.0F;
  float speedVariance_m2ps2 = 0.0F;
  float yawRateVariance_rad2ps2 = 0.0F;

  float detectionConfidence = 0.0F;  // [0, 1], the detector's score fused over the track
  TrackStatus status = TrackStatus::Tentative;

  // The reference point in UTM (seed 002's trajectories are UTM): the zone of its longitude
  // (1..60; 0 = not computed), the hemisphere, easting and northing with the standard false
  // easting (500 km) and, south of the equator, false northing (10 000 km).
  std::uint8_t utmZone = 0;
  bool utmNorthernHemisphere = true;
  double utmEasting_m = 0.0;
  double utmNorthing_m = 0.0;
  // Centre of the rear axle on the ground: the reference point of kinematic bicycle models
  // (Autoware, most planners) and of a vehicle's turning circle.
  std::array<double, 3> rearAxleEnu_m{};
  geodesy::GeodeticPoint rearAxlePosition{};
  // Variances of the box length and width estimates, m^2.
  float lengthVariance_m2 = 0.0F;
  float widthVariance_m2 = 0.0F;
  // The vehicle's 3D keypoints (its ASM wireframe) in the world ENU frame, m, in the order of
  // shape::keypointNames(); keypointCount is kKeypointCount for cars with a shape, 0 otherwise.
  std::uint8_t keypointCount = 0;
  std::array<std::array<float, 3>, shape::kKeypointCount> keypointsEnu_m{};
};

// Health of the drone's perception, published at a configured rate.
struct DroneStatus {
  std::uint32_t droneId = 0;
  std::int64_t time_ns = 0;  // when the status was assembled (UTC ns)

  geodesy::GeodeticPoint position{};                     // drone, WGS84 ellipsoidal
  std::array<double, 4> attitudeQuaternion{1, 0, 0, 0};  // q_nb (w, x, y, z), body FRD -> NED
  std::array<float, 3> gimbalEuler_deg{0, -90, 0};       // roll, pitch, yaw of the camera head

  float frameRate_hz = 0.0F;      // processed frames per second over the last second
  float latencyMedian_ms = 0.0F;  // capture -> publish
  float latencyP99_ms = 0.0F;
  float inferenceMedian_ms = 0.0F;

  // Counters since start-up (they only grow).
  std::uint64_t framesProcessed = 0;
  std::uint64_t framesDropped = 0;
  std::uint64_t corruptFrames = 0;
  std::uint64_t stalePoses = 0;
  std::uint64_t outsideDtm = 0;
  std::uint64_t publishErrors = 0;
  std::uint32_t activeTracks = 0;

  static constexpr std::size_t kModelIdCapacity = 64;  // bytes, without the terminating NUL
  std::array<char, kModelIdCapacity + 1> modelId{};    // NUL-terminated, e.g. "det-v3-int8"
  void setModelId(std::string_view id);                // truncates to kModelIdCapacity
};

// Cell values of the occupancy grid (seed 001's "occupancy" picture of the scene).
enum class Occupancy : std::uint8_t { Unobserved = 0, Free = 1, Occupied = 2 };

// Bird's-eye occupancy grid of the observed area, north-up, in the world ENU frame. Cell
// (row, col) covers east [originEast + col * res, + res) and north [originNorth + row * res,
// + res): row 0 is the southern edge. cells holds rows * cols values, row by row.
struct OccupancyGrid {
  std::uint32_t droneId = 0;
  std::int64_t time_ns = 0;
  double originEast_m = 0.0;
  double originNorth_m = 0.0;
  float resolution_m = 0.5F;
  std::uint32_t rows = 0;
  std::uint32_t cols = 0;
  std::vector<std::uint8_t> cells;  // sized by resize(), start-up only

  void resize(std::uint32_t rowCount, std::uint32_t colCount);  // allocates; sets Unobserved
  Occupancy at(std::uint32_t row, std::uint32_t col) const {
    return static_cast<Occupancy>(cells[static_cast<std::size_t>(row) * cols + col]);
  }
};

enum class ValidationError : std::uint8_t {
  None,
  NotFinite,          // a NaN or infinite number
  InvalidPosition,    // latitude/longitude out of range
  HeadingOutOfRange,  // heading not in [0, 2pi) / [0, 360)
  NegativeDimension,  // length, width or height < 0
  ProbabilityOutOfRange,
  ShapeCountOutOfRange,
  GridSizeMismatch,
  UtmZoneOutOfRange,        // utmZone above 60 (0 = not computed, 1..60)
  KeypointCountOutOfRange,  // keypointCount neither 0 nor kKeypointCount
  NegativeVariance,         // a length or width variance < 0
};
const char* toString(ValidationError error);

// Checks a state before it is published; returns the first problem found.
ValidationError validate(const VehicleState& state);
ValidationError validate(const OccupancyGrid& grid);

}  // namespace vp::messages
