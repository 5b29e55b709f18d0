// firmware_app/loop_stats: what the loop counts and times, and the one-line reports.
//
// Contract: CaptureCounters are written by the capture thread only (relaxed atomics, read by
// the processing thread for reports). LoopCounters is a plain snapshot of everything counted
// since start-up. LoopStats holds one latency histogram per stage (diagnostics::
// LatencyHistogram, fixed memory) twice: for the whole run and for the current reporting
// period; record() and the formatting into a caller buffer never allocate, so the loop can
// report from the processing thread. Stages: preprocess, detector, decode (+ NMS), crops,
// lift, track, publish (DDS + files), end-to-end (capture -> published) and queue (capture ->
// processing start).
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>

#include "diagnostics/latency_histogram.hpp"

namespace vp::app {

struct CaptureCounters {
  std::atomic<std::uint64_t> framesIn{0};   // frames the source gave, good (to the channel) or bad
  std::atomic<std::uint64_t> badFrames{0};  // corrupt, truncated, damaged, capture errors
  std::atomic<std::uint64_t> timeouts{0};
  std::atomic<std::uint64_t> deviceLosses{0};
  std::atomic<std::uint64_t> reopens{0};
  std::atomic<std::uint64_t> poolEmpty{0};  // no free frame (pool smaller than depth + 2)
};

// At the end of a run: framesIn == framesProcessed + framesDropped + badFrames + pipelineErrors.
struct LoopCounters {
  std::uint64_t framesIn = 0;  // every frame taken from the source (good or bad)
  std::uint64_t framesProcessed = 0;
  std::uint64_t framesDropped = 0;  // evicted from the channel (processing fell behind) or
                                    // still waiting in it at stop
  std::uint64_t badFrames = 0;
  std::uint64_t sourceTimeouts = 0;
  std::uint64_t deviceLosses = 0;
  std::uint64_t deviceReopens = 0;
  std::uint64_t noPose = 0;  // frames by pose status
  std::uint64_t stalePose = 0;
  std::uint64_t invalidPose = 0;
  std::uint64_t telemetrySamples = 0;
  std::uint64_t telemetryRejected = 0;  // by the link or the pose buffer
  std::uint64_t pipelineErrors = 0;     // frames refused (perception, timestamp not increasing)
  std::uint64_t trackerErrors = 0;
  std::uint64_t detections = 0;  // observations (lifted or not)
  std::uint64_t lifted = 0;
  std::uint64_t outsideDtm = 0;  // observations off the DTM (outside_dtm, no_data, no_intersection)
  std::uint64_t offSite = 0;  // lifted observations off the site's roads (site.off_road: drop/flag)
  // With a surface model (terrain.dsm_path): lifted observations lifted again onto a deck that a
  // drivable or parking area marks, and those on a structure no such area marks (a roof).
  std::uint64_t onDeck = 0;
  std::uint64_t onStructure = 0;
  // With a site's lanes (site.lane_direction_prior): lifted observations turned round to face
  // the way of the lane they stand in.
  std::uint64_t laneTurned = 0;
  // With perception.footprint_type: lifted cars whose most likely type the footprint changed.
  std::uint64_t retyped = 0;
  std::uint64_t statesPublished = 0;
  std::uint64_t tracksDisposed = 0;
  std::uint64_t publishErrors = 0;
  std::uint64_t outputErrors = 0;  // CSV / video write failures
  // The traffic analysis (traffic: with a site that has gates, zones or lanes):
  bool traffic = false;
  std::uint64_t gateCrossings = 0;
  std::uint64_t trafficEvents = 0;   // every kind, crossings included
  std::uint64_t trafficPeriods = 0;  // statistics periods closed (written and published)
  std::uint64_t trafficErrors = 0;   // steps refused, events dropped, refused or failed writes
  // The recording (app.record, recorder.hpp); at the end of a run that records:
  // framesIn == recordFrames + recordDropped + recordSkipped.
  bool recording = false;
  std::uint64_t recordFrames = 0;   // written
  std::uint64_t recordDropped = 0;  // no free buffer (the writer behind), or a failed write
  std::uint64_t recordSkipped = 0;  // every_nth_frame, bad frames, after the recording ended
  std::uint64_t recordRemoved = 0;  // on_full ring: oldest frames deleted
  std::uint64_t recordTelemetry = 0;
  std::uint64_t recordTelemetryDropped = 0;
  std::uint64_t recordErrors = 0;  // failed writes (each ends the recording)
};

enum class Stage : std::uint8_t {
  Preprocess,
  Detector,
  Decode,
  Crops,
  Lift,
  Track,
  Publish,
  EndToEnd,
  Queue,
};
constexpr std::size_t kStageCount = 9;
const char* toString(Stage stage);  // "preprocess", ..., "e2e", "queue"

class LoopStats {
 public:
  void record(Stage stage, std::int64_t ns) {
    total_[static_cast<std::size_t>(stage)].record(ns);
    period_[static_cast<std::size_t>(stage)].record(ns);
  }
  void record_ms(Stage stage, double ms) { record(stage, static_cast<std::int64_t>(ms * 1e6)); }
  const diagnostics::LatencyHistogram& total(Stage stage) const {
    return total_[static_cast<std::size_t>(stage)];
  }
  const diagnostics::LatencyHistogram& period(Stage stage) const {
    return period_[static_cast<std::size_t>(stage)];
  }
  void startPeriod() {
    for (auto& histogram : period_) {
      histogram.reset();
    }
  }

 private:
  std::array<diagnostics::LatencyHistogram, kStageCount> total_{};
  std::array<diagnostics::LatencyHistogram, kStageCount> period_{};
};

// "stats: 10.0 fps | in 120 processed 118 dropped 2 bad 0 | pose stale 0 ... | e2e 85.1/120.3 ms
// ..." into out (NUL-terminated, cut when too long); returns the length written.
int formatStatsLine(std::span<char> out, const LoopCounters& counters, const LoopStats& stats,
                    double periodFrames, double period_s);
// "summary: frames_in=... e2e_median_ms=..." (key=value pairs for scripts).
int formatSummaryLine(std::span<char> out, const LoopCounters& counters, const LoopStats& stats,
                      double wall_s);

}  // namespace vp::app
