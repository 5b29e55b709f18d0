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

constexpr std::string_view kSourceKindNames = "replay, v4l2";
constexpr std::string_view kPixelFormatNames = "yuyv, nv12, mjpeg";

std::optional<FrameSourceKind> sourceKindFromString(const std::string& text) {
  return enumFromString(text, std::array{FrameSourceKind::Replay, FrameSourceKind::V4l2},
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

}  // namespace

SourceConfig readSource(MapReader section, const std::string& baseDir) {
  const SourceConfig d;
  SourceConfig s;
  s.kind = section.choice<FrameSourceKind>("kind", sourceKindFromString, kSourceKindNames, d.kind);
  s.sequenceDir = readOptionalPath(section, "sequence_dir", baseDir, "");
  s.paced = section.boolean("paced", d.paced);
  s.loop = section.boolean("loop", d.loop);
  s.v4l2 = readV4l2(section.section("v4l2"));
  section.warnUnknownKeys();
  return s;
}

}  // namespace vp::config::detail
