// config/pose_section: `pose:` into the pose buffer's own options (telemetry::PoseBufferConfig).
// The file gives seconds, the buffer keeps nanoseconds.
#include <cstddef>
#include <cstdint>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

// A pose further than 10 s from the frame is useless for a moving drone.
const Range kPoseMaxAgeRangeS = Range{0.0, 10.0, true};
const Range kPoseCapacityRange = Range::closed(2.0, 100000.0);

}  // namespace

telemetry::PoseBufferConfig readPose(MapReader section) {
  const telemetry::PoseBufferConfig d;
  telemetry::PoseBufferConfig p;
  // Converted only when given: the default stays the buffer's own nanoseconds.
  if (section.has("max_age_s")) {
    p.maxAge_ns =
        static_cast<std::int64_t>(section.number("max_age_s", kPoseMaxAgeRangeS, kRequired) * 1e9);
  }
  p.capacity = static_cast<std::size_t>(
      section.integer("buffer_capacity", kPoseCapacityRange, static_cast<int>(d.capacity)));
  section.warnUnknownKeys();
  return p;
}

}  // namespace vp::config::detail
