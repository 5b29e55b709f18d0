// input/subtitle_telemetry: subtitle samples into recorded-sequence telemetry (see the header).
#include <cmath>

#include "geodesy/geodesy.hpp"
#include "subtitle_telemetry/subtitle_telemetry.hpp"

namespace vp::subtitle {

namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
// The course is taken over about a second of flight: DJI writes positions to 1e-6 deg
// (~0.1 m), so consecutive 30 Hz samples are often equal.
constexpr std::int64_t kCourseHalfWindow_ns = 500'000'000;

// Course over ground (deg clockwise from north) around sample i, when the drone moves faster
// than minSpeed_mps.
std::optional<double> course_deg(const std::vector<SubtitleSample>& s, std::size_t i,
                                 double minSpeed_mps) {
  std::size_t a = i;
  while (a > 0 && s[i].start_ns - s[a - 1].start_ns <= kCourseHalfWindow_ns) {
    --a;
  }
  std::size_t b = i;
  while (b + 1 < s.size() && s[b + 1].start_ns - s[i].start_ns <= kCourseHalfWindow_ns) {
    ++b;
  }
  if (a == b) {
    return std::nullopt;
  }
  const geodesy::LocalFrame frame(
      geodesy::GeodeticPoint{s[a].latitude_deg, s[a].longitude_deg, 0.0});
  const Eigen::Vector3d d =
      frame.toEnu(geodesy::GeodeticPoint{s[b].latitude_deg, s[b].longitude_deg, 0.0});
  const double dt_s = static_cast<double>(s[b].start_ns - s[a].start_ns) * 1e-9;
  if (dt_s <= 0.0 || std::hypot(d.x(), d.y()) / dt_s < minSpeed_mps) {
    return std::nullopt;
  }
  return std::atan2(d.x(), d.y()) * kRadToDeg;
}

}  // namespace

const char* toString(AltitudeSource source) {
  return source == AltitudeSource::Absolute ? "abs" : "rel";
}

std::optional<AltitudeSource> altitudeSourceFromString(std::string_view text) {
  if (text == "abs") {
    return AltitudeSource::Absolute;
  }
  if (text == "rel") {
    return AltitudeSource::Relative;
  }
  return std::nullopt;
}

SubtitleTelemetry toTelemetry(const SubtitleFile& file, const SubtitleTelemetryOptions& options,
                              const std::string& name) {
  SubtitleTelemetry out;
  out.records.reserve(file.samples.size());
  std::optional<double> lastCourse_deg;
  for (std::size_t i = 0; i < file.samples.size(); ++i) {
    const SubtitleSample& s = file.samples[i];
    std::optional<double> height_m;
    if (options.altitude == AltitudeSource::Absolute) {
      if (s.absoluteAltitude_m) {
        height_m = *s.absoluteAltitude_m + options.geoidSeparation_m;
      } else {
        out.problems.push_back(name + ":" + std::to_string(s.line) +
                               ": no absolute altitude (abs_alt, or GPS(...)'s third value); "
                               "sample skipped");
      }
    } else if (s.relativeAltitude_m) {
      height_m = *s.relativeAltitude_m + options.homeHeight_m;
    } else {
      out.problems.push_back(name + ":" + std::to_string(s.line) +
                             ": no relative altitude (rel_alt, H or BAROMETER); sample skipped");
    }
    // The course is followed even through skipped samples, so a nadir yaw never lags.
    const std::optional<double> course =
        s.gimbal ? std::nullopt : course_deg(file.samples, i, options.yawMinSpeed_mps);
    if (course) {
      lastCourse_deg = course;
    }
    if (!height_m) {
      continue;
    }
    sequence::TelemetryRecord r;
    r.timestamp_ns = s.start_ns;
    r.position = geodesy::GeodeticPoint{s.latitude_deg, s.longitude_deg, *height_m};
    r.gimbal.reference = geodesy::GimbalReference::Earth;
    if (s.gimbal) {
      r.gimbal.angles = *s.gimbal;
    } else {
      r.gimbal.angles = geodesy::EulerAnglesDeg{0.0, -90.0, lastCourse_deg.value_or(0.0)};
      ++out.nadirAssumed;
      if (lastCourse_deg) {
        ++out.yawFromMotion;
      }
    }
    // Level body heading like the camera: the SRT has no body attitude, and an
    // earth-referenced gimbal does not use it (only the drone status shows it).
    r.bodyToNed = Eigen::Quaterniond(
        geodesy::rotationFromEuler(geodesy::EulerAnglesDeg{0.0, 0.0, r.gimbal.angles.yaw_deg}));
    out.records.push_back(r);
  }
  return out;
}

}  // namespace vp::subtitle
