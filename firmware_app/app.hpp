// firmware_app/app: the product's real-time loop, from a frame source (V4L2 camera or recorded
// sequence) to DDS, wired from the configuration (docs/firmware_app.md).
//
// Contract: App only wires and runs a short loop; the work lives in three units, each owning
// its state:
//   FrameCapture    (frame_capture.hpp)    source, frame pool, frame channel, capture thread
//   FrameStep       (frame_step.hpp)       one frame: pose -> perception -> tracker -> outputs
//   PeriodicReports (periodic_reports.hpp) drone status, occupancy, watchdog, statistics line
// App owns them, the world the perception and the tracker borrow (local frame, DTM, camera,
// ASM), the DDS writers, the systemd notifier and the loop's books (the processing thread's
// LoopCounters and the LoopStats), which the units borrow by reference. Parts are handed over
// as unique_ptr (the source to FrameCapture; the perception stage and the pose input to
// FrameStep); everything else a unit gets is borrowed and outlives it.
//
// init() builds everything the loop needs, in fixed memory; run() starts the capture thread
// (and, with app.pipeline: on, the detector thread: FrameStep::detect() of each frame, handed to
// the processing loop through two slots, one frame at most waiting between the two threads; a
// frame taken is always completed, in the order taken) and runs the processing loop on the
// calling thread until the source ends, max frames were
// taken, or requestStop() / a stop signal (every wait of the loop, however long, ends within
// platform::kStopPoll_ns of the request); it then stops the capture thread, returns every
// queued frame to the pool (counted as dropped), disposes every published DDS instance and
// closes the files, and finishes the recording (app.record: every queued frame written,
// sequence.yaml last; recorder.hpp). After
// init(), the processing thread performs no heap allocation per frame with DDS off and the
// annotated video off (tests count it); Cyclone's write path allocates 2 per sample
// (docs/dds.md), the replay decoder allocates on the capture thread, cv::VideoWriter
// allocates per frame.
//
// Errors, one rule: start-up (init(), the real-time settings at the start of run()) fails with
// false and *why naming the file, key or device and the problem (config::ConfigError-style
// "key: problem"; exceptions from libraries at start-up reach main, which names them); the
// real-time path never throws: a bad frame, a NaN/stale/missing pose, a detection off the DTM,
// a camera that disappears, a failed write is a status value, logged once where it happens
// (per episode for the pose), counted in LoopCounters, and the next frame goes on.
//
// Time: frame timestamps are the source's (V4L2: CLOCK_MONOTONIC; replay: the recording's
// clock); DDS times are UTC: camera: frame time + (CLOCK_REALTIME - CLOCK_MONOTONIC) fixed at
// start-up; replay: the wall-clock time each frame was captured, so a replay looks live to
// subscribers and their latency is the app's capture -> publish time plus transport.
#pragma once

#include <array>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "camera/camera_model.hpp"
#include "config/config.hpp"
#include "dds_link.hpp"
#include "frame_capture.hpp"
#include "frame_step.hpp"
#include "geodesy/geodesy.hpp"
#include "georef/georeference.hpp"
#include "loop_inputs.hpp"
#include "loop_stats.hpp"
#include "perception_stage.hpp"
#include "periodic_reports.hpp"
#include "platform/system/systemd_notify.hpp"
#include "recorder.hpp"
#include "shape/vehicle_model.hpp"
#include "site/site.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::app {

// Settings of one run that are not in the configuration (command line).
struct RunSettings {
  std::int64_t maxFrames = 0;  // frames taken from the source; 0 = unlimited
  bool everyFrame = false;     // replay: the source waits for the loop instead of dropping
  bool quiet = false;          // no periodic statistics line (tests)
};

// What tests may substitute; everything left empty is built from the configuration.
struct AppSeams {
  std::unique_ptr<FramePerception> perception;
  // Wraps the stage built from the configuration (when `perception` is empty): tests watch the
  // shipped pipeline through it.
  std::function<std::unique_ptr<FramePerception>(std::unique_ptr<FramePerception>)> wrapPerception;
  std::unique_ptr<PoseInput> poseInput;
  platform::v4l2::V4l2Device* v4l2Device = nullptr;  // default: the kernel
  platform::Clock* clock = nullptr;                  // default: CLOCK_MONOTONIC
  LoopObserver* observer = nullptr;
  std::int64_t recordWriteDelay_ns = 0;  // app.record: the writer waits this long per frame
};

class App final : public CounterSource {
 public:
  App();
  ~App();
  App(const App&) = delete;
  App& operator=(const App&) = delete;

  bool init(const config::AppConfig& config, const RunSettings& run, AppSeams seams,
            std::string* why);
  // Runs the loop until the end (see the contract); false when the loop could not start.
  bool run(std::string* why);
  void requestStop() { capture_.requestStop(); }
  // requestStop() or a stop signal came before the loop ended (it did not end by itself).
  bool stopRequested() const { return loopEnded_ ? stoppedByRequest_ : capture_.stopRequested(); }

  LoopCounters counters() const override;
  const LoopStats& stats() const { return stats_; }
  std::size_t framesInPool() const { return capture_.pool().available(); }
  std::size_t poolCapacity() const { return capture_.pool().capacity(); }
  const config::AppConfig& config() const { return config_; }
  std::string summaryLine() const;  // machine-readable totals of the run (for the benchmark)
  // The vehicle-state writer (0 with DDS off), e.g. to wait until a reader has matched.
  dds_entity_t vehicleStateWriter() const { return dds_ ? dds_->states().writer() : 0; }
  // The native traffic writers (0 with DDS off or without the traffic analysis).
  dds_entity_t trafficStatisticsWriter() const {
    return dds_ ? dds_->traffic().statisticsWriter() : 0;
  }
  dds_entity_t trafficEventsWriter() const { return dds_ ? dds_->traffic().eventsWriter() : 0; }

 private:
  bool initSource(std::string* why);
  bool initWorld(std::string* why);
  bool initGroundView(std::string* why);
  bool initSite(std::string* why);
  bool initSurface(std::string* why);
  bool initPose(std::string* why);
  bool startRealtime(std::string* why);
  bool openRecorder(std::string* why);
  void processFrame(FrameIndex index);
  void reportFrame(const FrameOutcome& outcome);
  void idleTick();
  void runSerial();  // app.pipeline: off: the whole loop on the calling thread
  // app.pipeline: on: the processing side of the loop, and the detector thread's.
  void runPipelined();
  void detectorLoop();
  void startDetectorRealtime();

  config::AppConfig config_;
  RunSettings run_{};
  AppSeams seams_;
  std::unique_ptr<platform::Clock> ownClock_;
  platform::Clock* clock_ = nullptr;
  std::unique_ptr<platform::v4l2::V4l2Device> ownDevice_;
  std::int64_t monotonicToUtcNs_ = 0;

  // The world perception and tracking borrow.
  geodesy::LocalFrame frame_;
  terrain::TerrainModel terrain_;
  camera::CameraModel camera_;
  shape::ActiveShapeModel asm_;
  georef::GroundView groundView_;  // with georef.gcp_file: the fixed view lifting uses
  site::Site site_;                // with site.file: the site map the scene prior uses
  terrain::TerrainModel dsm_;      // with terrain.dsm_path: the surface model the prior uses

  // The loop's books, borrowed by the units (processing thread; capture's counts are its own).
  LoopCounters counters_{};
  LoopStats stats_;

  std::unique_ptr<DdsWriters> dds_;
  platform::SystemdNotifier notifier_;
  FrameCapture capture_;
  ReplayFrameSource* replay_ = nullptr;          // the capture's source when replaying (borrowed)
  VideoFrameSource* video_ = nullptr;            // the same when replaying a video
  const std::string& sourceName() const;         // sequence, video or camera device
  std::unique_ptr<FramePerception> perception_;  // until init() hands it to the step
  std::unique_ptr<PoseInput> poseInput_;         // the same
  FrameStep step_;
  PeriodicReports reports_;
  std::unique_ptr<Recorder> recorder_;  // app.record.dir set; declared last: stopped first

  double runWall_s_ = 0.0;
  bool ran_ = false;
  std::uint64_t lastHeartbeat_ = 0;     // the capture thread's, at the last idle tick
  telemetry::PoseEstimate lastPose_{};  // of the last processed frame (the idle drone status)
  // The hand-off between the detector thread and the processing thread (pipeline on): slot k
  // is full from the detector's detect() until the processing side released its frame.
  struct HandOff {
    FrameIndex index = 0;
    std::int64_t capture_ns = 0;
    FrameFront front{};
  };
  static constexpr std::size_t kHandOffSlots = 2;
  std::array<HandOff, kHandOffSlots> handOff_{};
  std::array<bool, kHandOffSlots> slotFull_{};  // guarded by handOffMutex_
  bool detectorDone_ = false;                   // guarded by handOffMutex_
  std::mutex handOffMutex_;
  std::condition_variable handOffChanged_;
  std::thread detector_;
  bool loopEnded_ = false;
  bool stoppedByRequest_ = false;  // at the loop's end (stop() then stops the capture anyway)
};

}  // namespace vp::app
