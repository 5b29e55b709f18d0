// config/source_section: `source:` (replay or V4L2 camera) into the firmware app's
// SourceConfig (config/loop_config.hpp).
#include <string>
#include <string_view>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kCameraBuffersRange = Range::closed(2.0, 16.0);
const Range kDequeueTimeoutRange_ms = Range::closed(1.0, 60000.0);

constexpr std::string_view kSourceKindNames = "replay, v4l2, video";
constexpr std::string_view kAltitudeNames = "abs, rel";
const Range kGeoidSeparationRange_m = Range::closed(-200.0, 200.0);
const Range kHomeHeightRange_m = Range::closed(-500.0, 9000.0);
const Range kYawMinSpeedRange_mps = Range{0.0, 100.0, true};  // (0, 100]
constexpr std::string_view kPixelFormatNames = "yuyv, nv12, mjpeg";

std::optional<FrameSourceKind> sourceKindFromString(const std::string& text) {
  return enumFromString(
      text, std::array{FrameSourceKind::Replay, FrameSourceKind::V4l2, FrameSourceKind::Video},
      [](FrameSourceKind kind) { return toString(kind); });
}
std::optional<CameraPixelFormat> pixelFormatFromString(const std::string& text) {
  return enumFromString(
      text, std::array{CameraPixelFormat::Yuyv, CameraPixelFormat::Nv12, CameraPixelFormat::Mjpeg},
      [](CameraPixelFormat format) { return toString(format); });
}

V4l2SourceConfig readV4l2(MapReader section) {
  const V4l2SourceConfig d;
  V4l2SourceConfig v;
  v.device = section.text("device", d.device);
  v.busInfo = section.text("bus_info", d.busInfo);
  v.width_px = section.integer("width_px", kImageSizeRange_px, d.width_px);
  v.height_px = section.integer("height_px", kImageSizeRange_px, d.height_px);
  if (section.has("formats")) {
    v.formats =
        section.choices<CameraPixelFormat>("formats", pixelFormatFromString, kPixelFormatNames);
  }
  v.buffers = section.integer("buffers", kCameraBuffersRange, d.buffers);
  v.dequeueTimeout_ms =
      section.integer("dequeue_timeout_ms", kDequeueTimeoutRange_ms, d.dequeueTimeout_ms);
  section.warnUnknownKeys();
  return v;
}

VideoSourceConfig readVideo(MapReader section, const std::string& baseDir) {
  const VideoSourceConfig d;
  VideoSourceConfig v;
  v.path = readOptionalPath(section, "path", baseDir, "");
  v.srt = readOptionalPath(section, "srt", baseDir, "");
  v.telemetryCsv = readOptionalPath(section, "telemetry_csv", baseDir, "");
  v.subtitles.altitude = section.choice<subtitle::AltitudeSource>(
      "altitude", [](const std::string& text) { return subtitle::altitudeSourceFromString(text); },
      kAltitudeNames, d.subtitles.altitude);
  v.subtitles.geoidSeparation_m =
      section.number("geoid_separation_m", kGeoidSeparationRange_m, d.subtitles.geoidSeparation_m);
  v.subtitles.homeHeight_m =
      section.number("home_height_m", kHomeHeightRange_m, d.subtitles.homeHeight_m);
  v.subtitles.yawMinSpeed_mps =
      section.number("yaw_min_speed_mps", kYawMinSpeedRange_mps, d.subtitles.yawMinSpeed_mps);
  section.warnUnknownKeys();
  return v;
}

}  // namespace

SourceConfig readSource(MapReader section, const std::string& baseDir) {
  const SourceConfig d;
  SourceConfig s;
  s.kind = section.choice<FrameSourceKind>("kind", sourceKindFromString, kSourceKindNames, d.kind);
  s.sequenceDir = readOptionalPath(section, "sequence_dir", baseDir, "");
  s.paced = section.boolean("paced", d.paced);
  s.loop = section.boolean("loop", d.loop);
  s.v4l2 = readV4l2(section.section("v4l2"));
  s.video = readVideo(section.section("video"), baseDir);
  section.warnUnknownKeys();
  return s;
}

}  // namespace vp::config::detail
