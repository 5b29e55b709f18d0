// firmware_app/frame_step: the work of one frame on the processing thread: pose -> perception
// -> tracker -> outputs (DDS vehicle states, trajectory and detections rows, annotated frame)
// -> traffic analysis of the published tracks (events and period statistics to the traffic
// files and topics).
//
// Contract: start-up runs in the order its errors are reported: initPoseBuffer() ("pose:
// ..."), init() (takes the perception stage and the pose input over: FrameStep owns them, the
// PoseBuffer, the tracker, the files and the per-frame arrays; "tracking: ..."), then, once
// the app has opened DDS, openOutputs() (names the file). Everything in FrameStepWiring is
// borrowed and must outlive the FrameStep. process() is the real-time path: it never throws
// and allocates nothing (Cyclone's write path aside, docs/dds.md); a frame it cannot use (a
// timestamp not after the previous one, a frame perception refuses) is logged, counted and
// reported as not processed, the caller gives the frame back to the pool either way. A
// tracker error or a failed write is logged once where it happens, counted, and the frame
// goes on. The FrameOutcome stays valid until the next process(). finish() (shutdown)
// closes the traffic analysis' last period (written and published), disposes every published
// DDS instance and closes the files.
// Traffic: with wiring.traffic enabled and a site with gates, zones or lanes, init() starts a
// traffic::TrafficAnalyzer on the site ("traffic: ..." on a bad option or feature) and
// openTraffic() opens its files and topics; process() steps it with the frame's published
// tracks after the tracker, and its events and completed periods go to the files and the
// topics in the same frame (the files commit with the frame's other rows).
//
// Pipelined (app.pipeline: on): process() is split in two halves run on two threads, one frame
// apart: detect() on the detector thread - the timestamp check, the pose (pose input, PoseBuffer),
// FramePerception::detect() into a hand-off slot - and complete() on the processing thread - the
// counts and log lines of the first half, FramePerception::finish(), the priors, the tracker, the
// outputs, traffic. detect() owns the pose input, the PoseBuffer and the timestamp check;
// complete() everything else; the FrameFront carries the first half's results across, so the
// counters, the log and every output are those of process() (which is detect() then complete()).
// The pose input's counters are read through poseCounters(), the processing thread's copy.
//
// Time: the first frame fixes the UTC offset of its source (camera: CLOCK_REALTIME -
// CLOCK_MONOTONIC; replay: the wall clock at that frame minus its recorded time).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/frame_pool.hpp"
#include "dds_link.hpp"
#include "geodesy/geodesy.hpp"
#include "loop_inputs.hpp"
#include "loop_outputs.hpp"
#include "loop_stats.hpp"
#include "messages/messages.hpp"
#include "perception/lane_prior.hpp"
#include "perception/site_prior.hpp"
#include "perception/surface_prior.hpp"
#include "perception_stage.hpp"
#include "shape/vehicle_model.hpp"
#include "site/site.hpp"
#include "telemetry/pose_buffer.hpp"
#include "terrain/terrain_model.hpp"
#include "tracking/track_manager.hpp"
#include "traffic/traffic_analyzer.hpp"

namespace vp::app {

// Called on the processing thread; implementations must not allocate when the caller counts.
class LoopObserver {
 public:
  virtual ~LoopObserver() = default;
  virtual void onPublished(const messages::VehicleState& /*state*/) {}
  virtual void onFrameDone(std::uint64_t /*framesProcessed*/) {}
  // Once, on the detector thread as it starts (app.pipeline: on), before it takes a frame.
  virtual void onDetectorThreadStart() {}
};

// What one frame leaves for the periodic reports.
struct FrameOutcome {
  bool processed = false;                          // false: skipped (logged and counted)
  std::int64_t timeUtc_ns = 0;                     // the frame's time on the DDS (UTC) clock
  telemetry::PoseEstimate pose{};                  // the pose at the frame time
  std::span<const messages::VehicleState> states;  // the published (confirmed, lost) tracks
  std::span<const Eigen::Vector2d> footprint;      // the ground the frame shows (perception's)
};

// What the first half of a frame leaves for the second (FrameStep::detect -> complete).
struct FrameFront {
  std::int64_t start_ns = 0;  // when the frame's work began (its queue wait ended)
  bool outOfOrder = false;    // its timestamp is not after the previous frame's: skipped
  std::int64_t previousTimestamp_ns = 0;
  telemetry::PoseEstimate pose{};
  PoseInputCounters poseCounters{};  // the pose input's, after this frame's poll
};

// What FrameStep borrows (all outlive it; dds and observer may be null).
struct FrameStepWiring {
  platform::Clock* clock = nullptr;
  LoopCounters* counters = nullptr;  // the processing thread's counts (the app's)
  LoopStats* stats = nullptr;
  DdsWriters* dds = nullptr;  // null with DDS off
  LoopObserver* observer = nullptr;
  const geodesy::LocalFrame* world = nullptr;
  const terrain::TerrainModel* terrain = nullptr;
  const shape::ActiveShapeModel* shapeModel = nullptr;
  const site::Site* site = nullptr;                          // the site map (null: no scene prior)
  const traffic::TrafficAnalyzerOptions* traffic = nullptr;  // null: no traffic analysis
  // The `site:` section (the priors' policies and values; null: the defaults).
  const site::SiteOptions* siteOptions = nullptr;
  // The surface model (terrain.dsm_path; null: none), with the perception stage's lift options
  // (a deck's vehicle is lifted again as perception lifts).
  const terrain::TerrainModel* dsm = nullptr;
  perception::DetectionLifterOptions lift{};
  std::uint32_t droneId = 0;
  bool sourceOnMonotonicClock = false;  // camera stamps: CLOCK_MONOTONIC
  bool fixedView = false;               // georeferenced by ground control points: no pose is needed
  std::int64_t monotonicToUtc_ns = 0;
};

class FrameStep {
 public:
  bool initPoseBuffer(const telemetry::PoseBufferConfig& config, std::string* why);
  bool init(const FrameStepWiring& wiring, std::unique_ptr<FramePerception> perception,
            std::unique_ptr<PoseInput> poseInput, const tracking::TrackerConfig& tracker,
            std::string* why);
  bool openOutputs(const OutputSpec& spec, std::string* why);
  // After openOutputs() and the DDS writers' open(): the traffic files in dir (empty: none)
  // and the traffic topics (with DDS). Does nothing when the analysis is not active.
  bool openTraffic(const std::string& dir, const config::DdsConfig& dds, std::string* why);
  bool trafficActive() const { return traffic_.active(); }
  const traffic::TrafficAnalyzer& trafficAnalyzer() const { return traffic_; }

  FrameOutcome process(const Frame& frame, std::int64_t capture_ns);
  // The pipelined halves of process() (see the contract): detect() on the detector thread with
  // perception hand-off slot `slot` (FramePerception::prepareHandOff), complete() later on the
  // processing thread with the same frame, slot and front; frames in the order taken.
  void detect(const Frame& frame, std::size_t slot, FrameFront* front);
  FrameOutcome complete(const Frame& frame, std::int64_t capture_ns, std::size_t slot,
                        const FrameFront& front);
  void finish();

  const PoseInput* poseInput() const { return poseInput_.get(); }  // null before init()
  // The pose input's counters as of the last completed frame (processing thread).
  const PoseInputCounters& poseCounters() const { return poseCounters_; }
  FramePerception& perceptionStage() { return *perception_; }
  const FramePerception& perception() const { return *perception_; }

 private:
  void countObservations();
  // The observations the tracker and the files get: perception's, screened by the surface
  // model's prior and the site's.
  std::span<const perception::VehicleObservation> screenObservations();
  void logPoseEpisode(telemetry::PoseStatus status, std::int64_t frameId,
                      const telemetry::PoseEstimate& pose);
  // detect()'s work without the perception stage (the serial step runs process() instead).
  void detectPose(const Frame& frame, FrameFront* front);
  FrameOutcome completeWith(const Frame& frame, std::int64_t capture_ns, const FrameFront& front,
                            bool pipelined, std::size_t slot);
  std::span<const messages::VehicleState> publish(std::int64_t timestamp_ns, std::int64_t frameId);
  void logWorkingScale(std::int64_t frameId);
  void stepTraffic(std::int64_t timestamp_ns, std::size_t published);
  void reportTraffic();  // the analyzer's events and completed period to files and topics

  FrameStepWiring wiring_{};
  std::unique_ptr<FramePerception> perception_;
  telemetry::PoseBuffer poses_;
  std::unique_ptr<PoseInput> poseInput_;
  tracking::TrackManager tracker_;
  LoopOutputs outputs_;
  traffic::TrafficAnalyzer traffic_;
  output_files::TrafficFeatureIds trafficIds_;  // the analysis' gates, zones, lanes (site order)
  std::uint64_t trafficDdsErrors_ = 0;

  // Per-frame arrays, sized at init.
  std::vector<tracking::WorldDetection> worldDetections_;
  perception::LanePrior lanePrior_;
  std::vector<perception::VehicleObservation> laned_;  // the lane prior's output (active)
  perception::SurfacePrior surfacePrior_;
  std::vector<perception::VehicleObservation> surfaced_;  // the surface prior's output (active)
  perception::SitePrior sitePrior_;
  std::vector<perception::VehicleObservation> screened_;  // the prior's output (when active)
  std::vector<messages::VehicleState> states_;   // this frame's published (confirmed, lost) tracks
  std::vector<tracking::TrackState> published_;  // the same tracks as the tracker has them

  std::int64_t toUtcNs_ = 0;
  bool haveUtcOffset_ = false;
  std::int64_t lastTimestampNs_ = 0;
  // detect()'s own: the last accepted timestamp
  bool haveDetectTimestamp_ = false;
  std::int64_t detectTimestampNs_ = 0;
  PoseInputCounters poseCounters_{};
  telemetry::PoseStatus lastPoseStatus_ = telemetry::PoseStatus::Ok;
  std::uint64_t poseEpisodeFrames_ = 0;
  double lastWorkingScale_ = 0.0;
};

}  // namespace vp::app
