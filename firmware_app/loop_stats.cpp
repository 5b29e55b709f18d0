#include "loop_stats.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>

namespace vp::app {

namespace {

constexpr double kMsPer_ns = 1e-6;

// Appends printf-formatted text at *length, never past the buffer's end.
void append(std::span<char> out, int* length, const char* format, ...)
    __attribute__((format(printf, 3, 4)));
void append(std::span<char> out, int* length, const char* format, ...) {
  const auto size = static_cast<int>(out.size());
  if (*length >= size - 1) {
    return;
  }
  va_list args;
  va_start(args, format);
  const int n =
      std::vsnprintf(out.data() + *length, static_cast<std::size_t>(size - *length), format, args);
  va_end(args);
  if (n > 0) {
    *length = std::min(size - 1, *length + n);
  }
}

}  // namespace

const char* toString(Stage stage) {
  switch (stage) {
    case Stage::Preprocess:
      return "preprocess";
    case Stage::Detector:
      return "detector";
    case Stage::Decode:
      return "decode";
    case Stage::Crops:
      return "crops";
    case Stage::Lift:
      return "lift";
    case Stage::Track:
      return "track";
    case Stage::Publish:
      return "publish";
    case Stage::EndToEnd:
      return "e2e";
    case Stage::Queue:
      return "queue";
  }
  return "unknown";
}

int formatStatsLine(std::span<char> out, const LoopCounters& c, const LoopStats& stats,
                    double periodFrames, double period_s) {
  if (out.empty()) {
    return 0;
  }
  out[0] = '\0';
  int length = 0;
  append(
      out, &length,
      "stats: %.1f fps | frames in %llu processed %llu dropped %llu bad %llu | pose no %llu "
      "stale %llu invalid %llu | detections %llu lifted %llu outside_dtm %llu off_site %llu "
      "on_deck %llu on_structure %llu lane_turned %llu retyped %llu | "
      "published "
      "%llu disposed %llu publish_errors %llu | ms median/p99:",
      period_s > 0.0 ? periodFrames / period_s : 0.0, static_cast<unsigned long long>(c.framesIn),
      static_cast<unsigned long long>(c.framesProcessed),
      static_cast<unsigned long long>(c.framesDropped),
      static_cast<unsigned long long>(c.badFrames), static_cast<unsigned long long>(c.noPose),
      static_cast<unsigned long long>(c.stalePose), static_cast<unsigned long long>(c.invalidPose),
      static_cast<unsigned long long>(c.detections), static_cast<unsigned long long>(c.lifted),
      static_cast<unsigned long long>(c.outsideDtm), static_cast<unsigned long long>(c.offSite),
      static_cast<unsigned long long>(c.onDeck), static_cast<unsigned long long>(c.onStructure),
      static_cast<unsigned long long>(c.laneTurned), static_cast<unsigned long long>(c.retyped),
      static_cast<unsigned long long>(c.statesPublished),
      static_cast<unsigned long long>(c.tracksDisposed),
      static_cast<unsigned long long>(c.publishErrors));
  if (c.traffic) {
    append(out, &length, " | crossings %llu traffic_events %llu periods %llu",
           static_cast<unsigned long long>(c.gateCrossings),
           static_cast<unsigned long long>(c.trafficEvents),
           static_cast<unsigned long long>(c.trafficPeriods));
  }
  if (c.recording) {
    append(out, &length, " | recorded %llu record_dropped %llu",
           static_cast<unsigned long long>(c.recordFrames),
           static_cast<unsigned long long>(c.recordDropped));
  }
  for (std::size_t s = 0; s < kStageCount; ++s) {
    const auto stage = static_cast<Stage>(s);
    const diagnostics::LatencyHistogram& h = stats.period(stage);
    append(out, &length, " %s %.1f/%.1f", toString(stage),
           static_cast<double>(h.median_ns()) * kMsPer_ns,
           static_cast<double>(h.p99_ns()) * kMsPer_ns);
  }
  return length;
}

int formatSummaryLine(std::span<char> out, const LoopCounters& c, const LoopStats& stats,
                      double wall_s) {
  if (out.empty()) {
    return 0;
  }
  out[0] = '\0';
  int length = 0;
  append(
      out, &length,
      "summary: wall_s=%.3f fps=%.2f frames_in=%llu processed=%llu dropped=%llu bad=%llu "
      "no_pose=%llu stale_pose=%llu invalid_pose=%llu pipeline_errors=%llu detections=%llu "
      "lifted=%llu outside_dtm=%llu off_site=%llu on_deck=%llu on_structure=%llu lane_turned=%llu "
      "retyped=%llu "
      "states_published=%llu tracks_disposed=%llu "
      "publish_errors=%llu output_errors=%llu",
      wall_s, wall_s > 0.0 ? static_cast<double>(c.framesProcessed) / wall_s : 0.0,
      static_cast<unsigned long long>(c.framesIn),
      static_cast<unsigned long long>(c.framesProcessed),
      static_cast<unsigned long long>(c.framesDropped),
      static_cast<unsigned long long>(c.badFrames), static_cast<unsigned long long>(c.noPose),
      static_cast<unsigned long long>(c.stalePose), static_cast<unsigned long long>(c.invalidPose),
      static_cast<unsigned long long>(c.pipelineErrors),
      static_cast<unsigned long long>(c.detections), static_cast<unsigned long long>(c.lifted),
      static_cast<unsigned long long>(c.outsideDtm), static_cast<unsigned long long>(c.offSite),
      static_cast<unsigned long long>(c.onDeck), static_cast<unsigned long long>(c.onStructure),
      static_cast<unsigned long long>(c.laneTurned), static_cast<unsigned long long>(c.retyped),
      static_cast<unsigned long long>(c.statesPublished),
      static_cast<unsigned long long>(c.tracksDisposed),
      static_cast<unsigned long long>(c.publishErrors),
      static_cast<unsigned long long>(c.outputErrors));
  // Pose samples, not frames: what the telemetry delivered and what was refused (by the link's
  // or the pose buffer's checks, docs/telemetry.md).
  append(out, &length, " telemetry_samples=%llu telemetry_rejected=%llu",
         static_cast<unsigned long long>(c.telemetrySamples),
         static_cast<unsigned long long>(c.telemetryRejected));
  if (c.traffic) {
    append(out, &length,
           " gate_crossings=%llu traffic_events=%llu traffic_periods=%llu traffic_errors=%llu",
           static_cast<unsigned long long>(c.gateCrossings),
           static_cast<unsigned long long>(c.trafficEvents),
           static_cast<unsigned long long>(c.trafficPeriods),
           static_cast<unsigned long long>(c.trafficErrors));
  }
  if (c.recording) {
    append(out, &length,
           " record_frames=%llu record_dropped=%llu record_skipped=%llu record_removed=%llu "
           "record_telemetry=%llu record_telemetry_dropped=%llu record_errors=%llu",
           static_cast<unsigned long long>(c.recordFrames),
           static_cast<unsigned long long>(c.recordDropped),
           static_cast<unsigned long long>(c.recordSkipped),
           static_cast<unsigned long long>(c.recordRemoved),
           static_cast<unsigned long long>(c.recordTelemetry),
           static_cast<unsigned long long>(c.recordTelemetryDropped),
           static_cast<unsigned long long>(c.recordErrors));
  }
  for (std::size_t s = 0; s < kStageCount; ++s) {
    const auto stage = static_cast<Stage>(s);
    const diagnostics::LatencyHistogram& h = stats.total(stage);
    append(out, &length, " %s_median_ms=%.3f %s_p99_ms=%.3f", toString(stage),
           static_cast<double>(h.median_ns()) * kMsPer_ns, toString(stage),
           static_cast<double>(h.p99_ns()) * kMsPer_ns);
  }
  return length;
}

}  // namespace vp::app
