// firmware_app/app: the product's real-time loop, from a frame source (V4L2 camera or recorded
// sequence) to DDS, wired from the configuration (docs/firmware_app.md).
//
// Contract: App::init() builds everything the loop needs, in fixed memory: the frame source,
// the frame pool and channel, the DTM, camera, ASM, perception pipeline, pose buffer and pose
// input, tracker, DDS writers and the file outputs; it fails with *why naming the part and the
// problem (a configuration inconsistency is reported as ConfigError-style "key: problem").
// run() starts the capture thread (source -> pool frame -> FrameChannel, drop-oldest) and runs
// the processing loop on the calling thread until the source ends, max frames were taken, or
// requestStop() / a stop signal; it then stops the capture thread, returns every queued frame
// to the pool, disposes every published DDS instance and closes the files. Per frame the
// processing thread: takes the next frame, polls the pose input into the PoseBuffer, asks the
// pose at the frame time, runs perception, steps the tracker, publishes the confirmed and lost
// tracks (endFrame() disposes the deleted ones), writes the CSV rows and the annotated frame,
// and returns the frame to the pool. Bad input (a corrupt frame, NaN/stale/missing pose, a
// detection off the DTM, a camera that disappears) is counted, logged with its context once
// per episode, and the loop goes on. After init(), the processing thread performs no heap
// allocation per frame with DDS off and the annotated video off (tests count it); Cyclone's
// write path allocates 2 per sample (docs/dds.md), the replay decoder allocates on the capture
// thread, cv::VideoWriter allocates per frame.
//
// Time: frame timestamps are the source's (V4L2: CLOCK_MONOTONIC; replay: the recording's
// clock); DDS times are UTC: utc = frame time + an offset fixed at the first frame (camera:
// CLOCK_REALTIME - CLOCK_MONOTONIC; replay: the wall-clock time the first frame was captured
// minus its recorded time, so a replay looks live to subscribers).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "camera/camera_model.hpp"
#include "config/config.hpp"
#include "core/frame_pool.hpp"
#include "dds_link.hpp"
#include "geodesy/geodesy.hpp"
#include "loop_inputs.hpp"
#include "loop_outputs.hpp"
#include "loop_stats.hpp"
#include "messages/messages.hpp"
#include "perception_stage.hpp"
#include "platform/system/systemd_notify.hpp"
#include "shape/vehicle_model.hpp"
#include "telemetry/pose_buffer.hpp"
#include "terrain/terrain_model.hpp"
#include "tracking/track_manager.hpp"
#include "vehicle_state.hpp"

namespace vp::app {

class FrameQueue;  // the FrameChannel of the configured depth (app.cpp)

// Settings of one run that are not in the configuration (command line).
struct RunSettings {
  std::int64_t maxFrames = 0;  // frames taken from the source; 0 = unlimited
  bool everyFrame = false;     // replay: the source waits for the loop instead of dropping
  bool quiet = false;          // no periodic statistics line (tests)
};

// Called on the processing thread; implementations must not allocate when the caller counts.
class LoopObserver {
 public:
  virtual ~LoopObserver() = default;
  virtual void onPublished(const messages::VehicleState& /*state*/) {}
  virtual void onFrameDone(std::uint64_t /*framesProcessed*/) {}
};

// What tests may substitute; everything left empty is built from the configuration.
struct AppSeams {
  std::unique_ptr<FramePerception> perception;
  std::unique_ptr<PoseInput> poseInput;
  platform::v4l2::V4l2Device* v4l2Device = nullptr;  // default: the kernel
  platform::Clock* clock = nullptr;                  // default: CLOCK_MONOTONIC
  LoopObserver* observer = nullptr;
};

class App {
 public:
  App();
  ~App();
  App(const App&) = delete;
  App& operator=(const App&) = delete;

  bool init(const config::AppConfig& config, const RunSettings& run, AppSeams seams,
            std::string* why);
  // Runs the loop until the end (see the contract); false when the loop could not start.
  bool run(std::string* why);
  void requestStop() { stop_.store(true, std::memory_order_relaxed); }

  LoopCounters counters() const;
  const LoopStats& stats() const { return stats_; }
  std::size_t framesInPool() const { return pool_.available(); }
  std::size_t poolCapacity() const { return pool_.capacity(); }
  const config::AppConfig& config() const { return config_; }
  std::string summaryLine() const;  // machine-readable totals of the run (for the benchmark)
  // The vehicle-state writer (0 with DDS off), e.g. to wait until a reader has matched.
  dds_entity_t vehicleStateWriter() const { return dds_ ? dds_->states().writer() : 0; }

 private:
  bool initSource(std::string* why);
  bool initWorld(std::string* why);
  bool initPose(std::string* why);
  void captureLoop();
  bool stopRequested() const;
  void processFrame(FrameIndex index);
  void publishFrame(std::int64_t timestampNs, std::int64_t frameId);
  void publishStatus(std::int64_t nowUtcNs, const telemetry::PoseEstimate& pose);
  void countObservations();
  void logPoseEpisode(telemetry::PoseStatus status, std::int64_t frameId,
                      const telemetry::PoseEstimate& pose);
  void periodic(std::int64_t nowNs, const telemetry::PoseEstimate& pose);
  void shutdown();

  config::AppConfig config_;
  RunSettings run_{};
  AppSeams seams_;
  std::unique_ptr<platform::Clock> ownClock_;
  platform::Clock* clock_ = nullptr;
  std::unique_ptr<platform::v4l2::V4l2Device> ownDevice_;

  std::unique_ptr<FrameSource> source_;
  ReplayFrameSource* replay_ = nullptr;  // the source when replaying
  FramePool pool_;
  std::unique_ptr<FrameQueue> queue_;
  std::array<std::int64_t, FramePool::kMaxFrames> captureNs_{};  // loop clock, per pool frame

  geodesy::LocalFrame frame_;
  terrain::TerrainModel terrain_;
  camera::CameraModel camera_;
  shape::ActiveShapeModel asm_;
  std::unique_ptr<FramePerception> perception_;
  telemetry::PoseBuffer poses_;
  std::unique_ptr<PoseInput> poseInput_;
  tracking::TrackManager tracker_;
  std::unique_ptr<DdsWriters> dds_;
  LoopOutputs outputs_;
  platform::SystemdNotifier notifier_;

  // Per-frame scratch, sized at init.
  std::vector<tracking::WorldDetection> worldDetections_;
  std::vector<messages::VehicleState> states_;   // this frame's published (confirmed, lost) tracks
  std::vector<tracking::TrackState> published_;  // the same tracks as the tracker has them
  std::size_t stateCount_ = 0;
  LoopCounters counters_{};  // processing thread's counts (capture's are in captureCounters_)
  messages::OccupancyGrid grid_;

  std::atomic<bool> stop_{false};
  std::atomic<bool> captureDone_{false};
  std::thread capture_;
  CaptureCounters captureCounters_;
  LoopStats stats_;
  std::int64_t toUtcNs_ = 0;
  bool haveUtcOffset_ = false;
  std::int64_t monotonicToUtcNs_ = 0;
  telemetry::PoseStatus lastPoseStatus_ = telemetry::PoseStatus::Ok;
  std::uint64_t poseEpisodeFrames_ = 0;
  telemetry::PoseEstimate lastPose_{};
  std::int64_t nextStatsNs_ = 0;
  std::int64_t nextStatusNs_ = 0;
  std::int64_t nextOccupancyNs_ = 0;
  std::int64_t nextWatchdogNs_ = 0;
  std::int64_t lastTimestampNs_ = 0;
  std::uint64_t framesAtStats_ = 0;   // processed frames at the last statistics line
  std::uint64_t framesAtStatus_ = 0;  // ... at the last drone status
  double runWall_s_ = 0.0;
  bool ran_ = false;
};

}  // namespace vp::app
