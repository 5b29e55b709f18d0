#include "tracking/trajectory_csv.hpp"

#include <algorithm>
#include <cstdio>

#include "geometry/rotated_box.hpp"

namespace vp::tracking {
namespace {

// Appends with snprintf; remembers overflow so the caller gets one -1 at the end.
class LineWriter {
 public:
  explicit LineWriter(std::span<char> out) : out_(out) {}

  template <class... Args>
  void add(const char* format, Args... args) {
    if (failed_ || out_.empty()) {
      failed_ = true;
      return;
    }
    const std::size_t room = out_.size() - used_;
    // The format strings are the literals below (checked by the callers' -Wformat).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
    const int n = std::snprintf(out_.data() + used_, room, format, args...);
#pragma GCC diagnostic pop
    if (n < 0 || static_cast<std::size_t>(n) >= room) {
      failed_ = true;
      return;
    }
    used_ += static_cast<std::size_t>(n);
  }
  int result() const {
    return failed_ ? -1 : static_cast<int>(used_);
  }

 private:
  std::span<char> out_;
  std::size_t used_ = 0;
  bool failed_ = false;
};

constexpr const char* kTypeColumns[shape::kVehicleTypeCount] = {
    "p_estate", "p_compact", "p_sports", "p_sedan", "p_suv", "p_van", "p_large"};

}  // namespace

int trajectoryCsvHeader(std::span<char> out, int shapeComponents) {
  const int ns = std::clamp(shapeComponents, 0, shape::kMaxShapeComponents);
  LineWriter w(out);
  w.add("%s",
        "frame_id,class_id,track_id,velocity,coordinate_world_x_opt,coordinate_world_y_opt,"
        "coordinate_world_x,coordinate_world_y,time_s,status,latitude_deg,longitude_deg,"
        "height_m,heading_enu_deg,velocity_sigma,acceleration,acceleration_sigma,yaw_rate_dps,"
        "length_m,width_m,wheelbase_m,class_name,length_variance_m2,width_variance_m2,utm_zone,"
        "utm_hemisphere,utm_easting_m,utm_northing_m,rear_axle_latitude_deg,"
        "rear_axle_longitude_deg,rear_axle_height_m");
  for (const char* name : kTypeColumns) {
    w.add(",%s", name);
  }
  for (int s = 0; s < ns; ++s) {
    w.add(",gamma_%d", s + 1);
  }
  w.add("%s", "\n");
  return w.result();
}

int trajectoryCsvRow(std::span<char> out, std::int64_t frameId, const TrackState& t,
                     const Wgs84Position* centreWgs84, int shapeComponents,
                     const TrajectoryPlace* place) {
  const int ns = std::clamp(shapeComponents, 0, shape::kMaxShapeComponents);
  constexpr double kDeg = 180.0 / geometry::kPi;
  LineWriter w(out);
  w.add("%lld,%d,%u,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%s", static_cast<long long>(frameId),
        static_cast<int>(t.type), static_cast<unsigned>(t.id), t.speed_mps, t.rearAxleEnu.x(),
        t.rearAxleEnu.y(), t.centreEnu.x(), t.centreEnu.y(),
        static_cast<double>(t.timestamp_ns) * 1e-9, toString(t.status));
  if (centreWgs84 != nullptr) {
    w.add(",%.8f,%.8f,%.3f", centreWgs84->latitude_deg, centreWgs84->longitude_deg,
          centreWgs84->height_m);
  } else {
    w.add("%s", ",,,");
  }
  w.add(",%.2f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f", t.headingEnu_rad * kDeg, t.speedSigma_mps,
        t.acceleration_mps2, t.accelerationSigma_mps2, t.yawRate_radps * kDeg, t.length_m,
        t.width_m, t.wheelbase_m);
  w.add(",%s,%.6f,%.6f", shape::toString(t.type), t.lengthVariance_m2, t.widthVariance_m2);
  if (place != nullptr && place->utmZone > 0) {
    w.add(",%d,%s,%.3f,%.3f", place->utmZone, place->utmNorth ? "N" : "S", place->utmEasting_m,
          place->utmNorthing_m);
  } else {
    w.add("%s", ",,,,");
  }
  if (place != nullptr && place->hasRearAxle) {
    w.add(",%.8f,%.8f,%.3f", place->rearAxle.latitude_deg, place->rearAxle.longitude_deg,
          place->rearAxle.height_m);
  } else {
    w.add("%s", ",,,");
  }
  for (float p : t.typeProbabilities) {
    w.add(",%.4f", static_cast<double>(p));
  }
  for (int s = 0; s < ns; ++s) {
    const bool has = s < t.shape.count;
    if (has) {
      w.add(",%.4f", static_cast<double>(t.shape.gamma[static_cast<std::size_t>(s)]));
    } else {
      w.add("%s", ",");
    }
  }
  w.add("%s", "\n");
  return w.result();
}

}  // namespace vp::tracking
