#include "app.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

#include "csv/csv_io.hpp"
#include "detection/detection.hpp"
#include "io/dtm_file.hpp"
#include "loop_log.hpp"
#include "platform/system/realtime.hpp"

namespace vp::app {

namespace {

// The longest the processing thread sleeps without a frame before it looks at the periodic
// reports (watchdog, drone status): well under half the shortest sensible WatchdogSec.
constexpr std::int64_t kIdleTick_ns = 250'000'000;

}  // namespace

App::App() = default;

App::~App() {
  // The capture thread ends (its waits see the stop through the clock) and is joined before
  // the clock forgets the stop condition: a borrowed clock may outlive the app.
  capture_.stop();
  if (clock_ != nullptr) {
    clock_->setStopCondition(nullptr);
  }
}

bool App::init(const config::AppConfig& config, const RunSettings& run, AppSeams seams,
               std::string* why) {
  config_ = config;
  run_ = run;
  seams_ = std::move(seams);
  if (seams_.clock != nullptr) {
    clock_ = seams_.clock;
  } else {
    ownClock_ = std::make_unique<platform::MonotonicClock>();
    clock_ = ownClock_.get();
  }
  // Every wait on the loop's clock (replay pacing, capture backoff, camera reopen) ends when a
  // stop is requested (requestStop() or SIGINT/SIGTERM), however far its deadline lies.
  clock_->setStopCondition(&capture_);
  monotonicToUtcNs_ = realtimeNow_ns() - platform::monotonicNow_ns();
  if (!initSource(why) || !initWorld(why) || !initPose(why)) {
    return false;
  }
  if (!config_.app.record.dir.empty()) {
    // Opened last (openRecorder), once everything else started: a failed start-up leaves no
    // recording behind. The pose input is handed to the step now, so its tap is set now.
    recorder_ = std::make_unique<Recorder>();
    poseInput_->setTap(recorder_.get());
  }
  if (config_.dds.enabled) {
    dds_ = std::make_unique<DdsWriters>();  // opened below, after the tracker, as always
  }

  FrameStepWiring wiring;
  wiring.clock = clock_;
  wiring.counters = &counters_;
  wiring.stats = &stats_;
  wiring.dds = dds_.get();
  wiring.observer = seams_.observer;
  wiring.world = &frame_;
  wiring.terrain = &terrain_;
  wiring.shapeModel = &asm_;
  wiring.site = config_.site.file.empty() ? nullptr : &site_;
  wiring.siteOptions = &config_.site;
  wiring.traffic = &config_.traffic;
  wiring.dsm = config_.terrain.dsmPath.empty() ? nullptr : &dsm_;
  wiring.lift = config_.perception.lift;
  wiring.droneId = config_.dds.droneId;
  wiring.sourceOnMonotonicClock = capture_.source().capturesOnMonotonicClock();
  wiring.fixedView = !config_.georef.gcpFile.empty();
  wiring.monotonicToUtc_ns = monotonicToUtcNs_;
  // The `tracking:` section is the tracker's own options; the app adds what it owns.
  tracking::TrackerConfig tracker = config_.tracking;
  tracker.maxDetections = detection::kMaxDetectionsPerFrame;
  tracker.asmModel = &asm_;
  if (!step_.init(wiring, std::move(perception_), std::move(poseInput_), tracker, why)) {
    return false;
  }
  if (config_.app.pipeline == config::PipelineMode::On &&
      !step_.perceptionStage().prepareHandOff(kHandOffSlots, why)) {
    return false;
  }
  if (dds_ && !dds_->open(config_.dds, why)) {
    return false;
  }

  OutputSpec outputs;
  outputs.trajectoryCsv = config_.app.trajectoryCsv;
  outputs.detectionsCsv = config_.app.detectionsCsv;
  outputs.annotatedVideo = config_.app.annotatedVideo;
  outputs.videoFps = config_.app.annotatedVideoFps;
  outputs.frameSize = cv::Size(capture_.pool().width_px(), capture_.pool().height_px());
  outputs.gammaColumns = asm_.componentCount();
  outputs.model = step_.perception().modelId();
  outputs.source = sourceName();
  if (!step_.openOutputs(outputs, why) ||
      !step_.openTraffic(config_.app.trafficDir, config_.dds, why)) {
    return false;
  }
  std::string problem;
  if (!notifier_.open(&problem)) {
    if (why) {
      *why = "systemd notify: " + problem;
    }
    return false;
  }

  PeriodicWiring reports;
  reports.dds = &config_.dds;
  reports.statsPeriod_s = config_.app.statsPeriod_s;
  reports.quiet = run_.quiet;
  reports.writers = dds_.get();
  reports.notifier = &notifier_;
  reports.stats = &stats_;
  reports.counters = &counters_;
  reports.allCounters = this;
  reports.modelId = step_.perception().modelId();
  reports.monotonicToUtc_ns = monotonicToUtcNs_;
  reports_.init(reports);
  return openRecorder(why);
}

bool App::openRecorder(std::string* why) {
  if (!recorder_) {
    return true;
  }
  RecorderSetup setup;
  setup.options = config_.app.record;
  // The rig the loop runs with (a replay's is its recording's rig.yaml, copied by initSource).
  setup.rig.origin = config_.origin;
  setup.rig.camera = config_.camera;
  setup.rig.mount = config_.mount;
  setup.rig.terrain = config_.terrain;
  setup.sitePath = config_.site.file;  // the configuration's, or the replayed recording's
  const FrameSource& source = capture_.source();
  setup.source = replay_ != nullptr ? "the replay of " + config_.source.sequenceDir
                 : config_.source.v4l2.busInfo.empty()
                     ? "camera " + config_.source.v4l2.device
                     : "camera at bus " + config_.source.v4l2.busInfo;
  setup.frameRate_hz = source.nominalFrameRate_hz();
  setup.writeDelay_ns = seams_.recordWriteDelay_ns;
  return recorder_->open(setup, why);
}

const std::string& App::sourceName() const {
  if (replay_ != nullptr) {
    return config_.source.sequenceDir;
  }
  return video_ != nullptr ? config_.source.video.path : config_.source.v4l2.device;
}

bool App::initSource(std::string* why) {
  if (seams_.v4l2Device == nullptr && config_.source.kind == config::FrameSourceKind::V4l2) {
    ownDevice_ = std::make_unique<platform::v4l2::SystemV4l2Device>();
  }
  platform::v4l2::V4l2Device* device =
      seams_.v4l2Device != nullptr ? seams_.v4l2Device : ownDevice_.get();
  std::unique_ptr<FrameSource> source = openFrameSource(config_.source, *clock_, device, why);
  if (!source) {
    return false;
  }
  if (config_.source.kind == config::FrameSourceKind::Replay) {
    // The rig of a recording is the one it was recorded with (its rig.yaml).
    replay_ = static_cast<ReplayFrameSource*>(source.get());
    const sequence::Rig& rig = replay_->replay().reader().rig();
    config_.origin = rig.origin;
    config_.camera = {rig.intrinsics, rig.distortion};
    config_.mount = {rig.mount, rig.gimbal};
    config_.terrain.dtmPath = rig.dtmPath;  // the DTM load options stay the application's
    config_.terrain.crs = rig.crs;
    // The recording's surface model, unless the configuration names one (as the site map) or
    // a fixed view placed by ground control points lifts through a plane (no viewing rays).
    if (config_.terrain.dsmPath.empty() && config_.georef.gcpFile.empty()) {
      config_.terrain.dsmPath = rig.dsmPath;
    }
    // The recording's site map (its rig.yaml's site.file), unless the configuration names one.
    if (config_.site.file.empty()) {
      config_.site.file = rig.sitePath;
    }
  }
  if (config_.source.kind == config::FrameSourceKind::Video) {
    // A video has no rig: camera, mount and DTM are the configuration's.
    video_ = static_cast<VideoFrameSource*>(source.get());
    for (const std::string& warning : video_->warnings()) {
      logLine("warning: %s", warning.c_str());
    }
  }
  const camera::Intrinsics& in = config_.camera.intrinsics;
  if (in.width_px != source->width_px() || in.height_px != source->height_px()) {
    if (why) {
      *why = "camera.width_px x camera.height_px is " + std::to_string(in.width_px) + "x" +
             std::to_string(in.height_px) + " but the source delivers " +
             std::to_string(source->width_px()) + "x" + std::to_string(source->height_px()) +
             " frames (calibrate at the capture size)";
    }
    return false;
  }
  const int depth = config_.app.queueDepth;
  // Waiting + processing + capturing frames, and with the pipeline the one between its threads.
  const int inFlight = config_.app.pipeline == config::PipelineMode::On ? 3 : 2;
  const int poolSize = config_.app.framePoolSize > 0 ? config_.app.framePoolSize : depth + inFlight;
  return capture_.open(std::move(source), *clock_, poolSize, depth, why);
}

bool App::initWorld(std::string* why) {
  std::string problem;
  frame_ = geodesy::LocalFrame(config_.origin);
  terrain::TerrainGrid grid;
  // The DTM and ASM readers name their file in every message: the key is the context added.
  if (!io::loadDtm(config_.terrain.dtmPath, config_.terrain.crs, grid, &problem,
                   config_.terrain.load)) {
    if (why) {
      *why = "terrain.dtm_path: " + problem;
    }
    return false;
  }
  if (!terrain_.init(std::move(grid), frame_, &problem)) {
    if (why) {
      *why = "terrain.dtm_path " + csv::shortened(config_.terrain.dtmPath) + ": " + problem;
    }
    return false;
  }
  if (!initSurface(why)) {
    return false;
  }
  if (!camera_.init(config_.camera.intrinsics, config_.camera.distortion, &problem)) {
    if (why) {
      *why = "camera: " + problem;
    }
    return false;
  }
  if (!asm_.load(config_.asmPath, &problem)) {
    if (why) {
      *why = "perception.asm: " + problem;
    }
    return false;
  }
  if (!initGroundView(why) || !initSite(why)) {
    return false;
  }
  if (seams_.perception) {
    perception_ = std::move(seams_.perception);
    return true;
  }
  auto pipeline = std::make_unique<PipelinePerception>();
  perception::PipelineOptions options = config_.perception;
  if (config_.app.pipeline == config::PipelineMode::On) {
    // Pipelined, the processing thread (crops, lifting, tracker, outputs) keeps one of the
    // perception.threads cores busy: the detector thread's pools (detector engine, preprocessing
    // rows) get the others, at least its own thread (docs/firmware_app.md).
    const int threads = std::max(1, options.detection.engine.threads - 1);
    options.detection.engine.threads = threads;
    options.preprocess.threads = threads;
  }
  if (!pipeline->init(options, camera_, config_.mount.mount, terrain_, frame_, asm_,
                      config_.georef.gcpFile.empty() ? nullptr : &groundView_, &problem)) {
    if (why) {
      *why = "perception: " + problem;
    }
    return false;
  }
  perception_ = std::move(pipeline);
  if (seams_.wrapPerception) {
    perception_ = seams_.wrapPerception(std::move(perception_));
  }
  return true;
}

bool App::initSurface(std::string* why) {
  // The surface model (docs/field_data.md): buildings, bridges and decks above the DTM.
  const std::string& path = config_.terrain.dsmPath;
  if (path.empty()) {
    return true;
  }
  if (!config_.georef.gcpFile.empty()) {
    if (why) {
      *why =
          "terrain.dsm_path: the surface model follows viewing rays from the camera's pose; a "
          "fixed view placed by ground control points (georef.gcp_file) lifts through a plane";
    }
    return false;
  }
  std::string problem;
  terrain::TerrainGrid grid;
  if (!io::loadDtm(path, config_.terrain.crs, grid, &problem, config_.terrain.load)) {
    if (why) {
      *why = "terrain.dsm_path: " + problem;
    }
    return false;
  }
  if (!dsm_.init(std::move(grid), frame_, &problem)) {
    if (why) {
      *why = "terrain.dsm_path " + csv::shortened(path) + ": " + problem;
    }
    return false;
  }
  // It must have a height wherever the DTM has one: the prior compares the two.
  const terrain::Coverage c = terrain::coverage(terrain_, dsm_);
  const auto box = [](const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
    char text[160];
    std::snprintf(text, sizeof(text), "east %.1f..%.1f m, north %.1f..%.1f m of the world frame",
                  lo.x(), hi.x(), lo.y(), hi.y());
    return std::string(text);
  };
  if (c.outside > 0) {
    if (why) {
      *why = "terrain.dsm_path " + csv::shortened(path) + ": does not cover the DTM " +
             csv::shortened(config_.terrain.dtmPath) + ": " + std::to_string(c.outside) + " of " +
             std::to_string(c.checked) + " DTM points checked lie off it (" +
             box(c.outsideMin_m, c.outsideMax_m) + ")";
    }
    return false;
  }
  if (c.noData > 0) {
    logLine(
        "warning: terrain.dsm_path %s has no data at %zu of %zu DTM points checked (%s): no "
        "structure is seen there",
        csv::shortened(path).c_str(), c.noData, c.checked,
        box(c.noDataMin_m, c.noDataMax_m).c_str());
  }
  logLine(
      "surface model: %s (%dx%d samples, heights %.1f..%.1f m); detections more than %.1f m "
      "above the DTM: on a deck when a drivable or parking area marks it, else on a structure "
      "(%s)",
      csv::shortened(path).c_str(), dsm_.grid().cols, dsm_.grid().rows,
      static_cast<double>(dsm_.minHeight_m()), static_cast<double>(dsm_.maxHeight_m()),
      config_.site.maxStructureHeight_m, site::toString(config_.site.onStructure));
  return true;
}

bool App::initSite(std::string* why) {
  // The site map (docs/site_map.md): its areas screen the lifted detections before the tracker.
  if (config_.site.file.empty()) {
    return true;
  }
  std::string problem;
  if (!site::loadSite(config_.site.file, frame_, &site_, &problem)) {
    if (why) {
      *why = "site.file: " + problem;
    }
    return false;
  }
  logLine(
      "site: %zu features from %s (%zu drivable, %zu parking, %zu exclusion, %zu lanes, %zu "
      "gates, %zu zones); off-road detections: %s",
      site_.features().size(), csv::shortened(config_.site.file).c_str(),
      site_.count(site::FeatureKind::Drivable), site_.count(site::FeatureKind::Parking),
      site_.count(site::FeatureKind::Exclusion), site_.count(site::FeatureKind::Lane),
      site_.count(site::FeatureKind::Gate), site_.count(site::FeatureKind::Zone),
      site::toString(config_.site.offRoad));
  return true;
}

bool App::initGroundView(std::string* why) {
  // Without telemetry, ground control points place the fixed view (docs/field_data.md).
  const georef::GeorefOptions& georef = config_.georef;
  if (georef.gcpFile.empty()) {
    return true;
  }
  std::string problem;
  if (config_.telemetry.source != config::TelemetrySourceKind::None) {
    problem = std::string(
                  "ground control points place a fixed view without telemetry: set "
                  "telemetry.source: none (it is ") +
              config::toString(config_.telemetry.source) + ")";
  } else if (georef::loadGroundView(georef, camera_, frame_, &terrain_, &groundView_, &problem) &&
             georef::checkResiduals(groundView_, georef.maxResidual_m, &problem)) {
    const georef::GroundHomography& h = groundView_.homography;
    logLine(
        "georef: %zu ground control points from %s: RMS residual %.3f m, largest %.3f m (point "
        "'%s'); camera %.1f m above the ground",
        h.residuals.size(), csv::shortened(georef.gcpFile).c_str(), h.rms_m, h.max_m,
        h.residuals[h.maxIndex].id.c_str(),
        groundView_.camera ? groundView_.camera->heightAboveGround_m : 0.0);
    return true;
  }
  if (why) {
    *why = "georef.gcp_file: " + problem;
  }
  return false;
}

bool App::initPose(std::string* why) {
  if (!step_.initPoseBuffer(config_.pose, why)) {
    return false;
  }
  if (seams_.poseInput) {
    poseInput_ = std::move(seams_.poseInput);
    return true;
  }
  std::string problem;
  const config::TelemetryLinkConfig& link = config_.telemetry;
  switch (link.source) {
    case config::TelemetrySourceKind::Recording: {
      if (replay_ == nullptr && video_ == nullptr) {
        if (why) {
          *why =
              "telemetry.source: recording needs a replayed sequence or video (source.kind "
              "replay or video); with a camera use mavlink_udp, mavlink_serial or dds";
        }
        return false;
      }
      auto recording = std::make_unique<RecordingPoseInput>();
      if (replay_ != nullptr) {
        recording->open(replay_->replay(), config_.source.loop, link.replayLookahead_s,
                        config_.pose.limits);
      } else {
        recording->open(video_->telemetry(), video_->telemetryPath(), config_.source.loop,
                        video_->video().loopPeriod_ns(), link.replayLookahead_s,
                        config_.pose.limits);
      }
      for (const std::string& warning : recording->warnings()) {
        logLine("warning: %s", warning.c_str());
      }
      poseInput_ = std::move(recording);
      return true;
    }
    case config::TelemetrySourceKind::MavlinkUdp:
    case config::TelemetrySourceKind::MavlinkSerial: {
      auto mavlink = std::make_unique<MavlinkPoseInput>(*clock_, config_.mount.gimbal);
      if (!mavlink->open(link, &problem)) {
        if (why) {
          *why = std::string("telemetry (") + config::toString(link.source) + "): " + problem;
        }
        return false;
      }
      poseInput_ = std::move(mavlink);
      return true;
    }
    case config::TelemetrySourceKind::Dds: {
      auto dds = std::make_unique<DdsPoseInput>(*clock_, config_.mount.gimbal, monotonicToUtcNs_);
      if (!dds->open(config_.dds.telemetry, why)) {
        return false;
      }
      poseInput_ = std::move(dds);
      return true;
    }
    case config::TelemetrySourceKind::None:
      poseInput_ = std::make_unique<NoPoseInput>();
      return true;
  }
  return false;
}

bool App::startRealtime(std::string* why) {
  std::string problem;
  if (config_.app.lockMemory && !platform::lockAllMemory(&problem)) {
    if (why) {
      *why = "app.lock_memory: " + problem;
    }
    return false;
  }
  if (!config_.app.processingCpus.empty() &&
      !platform::setCurrentThreadAffinity(config_.app.processingCpus, &problem)) {
    if (why) {
      *why = "app.processing_cpus: " + problem;
    }
    return false;
  }
  if (config_.app.realtimePriority > 0 &&
      !platform::setCurrentThreadRealtime(config_.app.realtimePriority, &problem)) {
    if (why) {
      *why = "app.realtime_priority: " + problem;
    }
    return false;
  }
  return true;
}

bool App::run(std::string* why) {
  if (ran_) {
    if (why) {
      *why = "run() was already called";
    }
    return false;
  }
  ran_ = true;
  if (!startRealtime(why)) {
    return false;
  }
  const std::int64_t start_ns = clock_->now_ns();
  reports_.start(start_ns);
  const FramePool& pool = capture_.pool();
  const bool pipelined = config_.app.pipeline == config::PipelineMode::On;
  logLine("running: %s %s, pose from %s, DDS %s, queue depth %d, pipeline %s, %zu frames of %dx%d",
          replay_ != nullptr ? "replay of" : (video_ != nullptr ? "video" : "camera"),
          sourceName().c_str(), step_.poseInput()->name(), dds_ ? "on" : "off",
          config_.app.queueDepth, config::toString(config_.app.pipeline), pool.capacity(),
          pool.width_px(), pool.height_px());
  notifier_.ready();
  capture_.start({run_.maxFrames, run_.everyFrame, config_.app.captureCpus, recorder_.get()});
  if (pipelined) {
    runPipelined();
  } else {
    runSerial();
  }

  stoppedByRequest_ = capture_.stopRequested();
  loopEnded_ = true;
  notifier_.stopping();
  capture_.stop();  // the capture thread ends, every waiting frame back in the pool (dropped)
  step_.finish();   // every DDS instance disposed, the files closed
  if (recorder_) {
    recorder_->finish();  // the queued frames written, sequence.yaml last
  }
  runWall_s_ = static_cast<double>(clock_->now_ns() - start_ns) / 1e9;
  return true;
}

void App::runSerial() {
  // The loop: take the freshest frame, do its step, report; sleep until the next one.
  for (;;) {
    const std::uint32_t seen = capture_.wakeCount();
    if (const std::optional<FrameIndex> index = capture_.take()) {
      processFrame(*index);
      if (capture_.stopRequested()) {
        break;
      }
      continue;
    }
    if (capture_.done()) {
      if (const std::optional<FrameIndex> last = capture_.take()) {
        processFrame(*last);
        continue;
      }
      break;
    }
    if (capture_.stopRequested()) {
      break;
    }
    // The capture thread bumps the count after each frame, bad frame and retry and when it ends;
    // it checks the stop flag at every step and within kStopPoll_ns of every wait.
    capture_.waitFor(seen, kIdleTick_ns);
    idleTick();
  }
}

void App::idleTick() {
  // No frame for a while (a silent camera, a reopen backing off, a paced recording's pause):
  // the periodic reports go on - the watchdog, the drone status, the statistics line - as long
  // as the capture thread shows it is alive; a hung capture thread lets the watchdog fire.
  const std::uint64_t beat = capture_.heartbeat();
  if (beat == lastHeartbeat_) {
    return;
  }
  lastHeartbeat_ = beat;
  FrameOutcome idle;
  idle.pose = lastPose_;
  reports_.tick(clock_->now_ns(), idle);
}

void App::processFrame(FrameIndex index) {
  const FrameOutcome outcome = step_.process(capture_.frame(index), capture_.capture_ns(index));
  capture_.release(index);
  reportFrame(outcome);
}

void App::startDetectorRealtime() {
  // The detector thread is a processing thread: the same CPUs and priority. They were applied to
  // the processing thread at the start of run(), so a failure here is unexpected: logged once.
  std::string problem;
  if (!config_.app.processingCpus.empty() &&
      !platform::setCurrentThreadAffinity(config_.app.processingCpus, &problem)) {
    logLine("detector thread: app.processing_cpus: %s", problem.c_str());
  }
  if (config_.app.realtimePriority > 0 &&
      !platform::setCurrentThreadRealtime(config_.app.realtimePriority, &problem)) {
    logLine("detector thread: app.realtime_priority: %s", problem.c_str());
  }
}

void App::detectorLoop() {
  startDetectorRealtime();
  if (seams_.observer != nullptr) {
    seams_.observer->onDetectorThreadStart();
  }
  std::size_t slot = 0;
  for (;;) {
    // A free slot before a frame is taken: at most one frame waits between the two threads, and
    // until then the freshest frame stays in the channel (where a newer one replaces it).
    {
      std::unique_lock<std::mutex> lock(handOffMutex_);
      handOffChanged_.wait(lock, [&] { return !slotFull_[slot]; });
    }
    if (capture_.stopRequested()) {
      break;
    }
    const std::uint32_t seen = capture_.wakeCount();
    std::optional<FrameIndex> index = capture_.take();
    if (!index && capture_.done()) {
      index = capture_.take();  // the last frame, published just before the end
      if (!index) {
        break;
      }
    }
    if (index) {
      HandOff& handOff = handOff_[slot];
      handOff.index = *index;
      handOff.capture_ns = capture_.capture_ns(*index);
      step_.detect(capture_.frame(*index), slot, &handOff.front);
      {
        const std::lock_guard<std::mutex> lock(handOffMutex_);
        slotFull_[slot] = true;
      }
      handOffChanged_.notify_all();
      slot = (slot + 1) % kHandOffSlots;
      if (capture_.stopRequested()) {
        break;
      }
      continue;
    }
    if (capture_.stopRequested()) {
      break;
    }
    capture_.waitFor(seen, kIdleTick_ns);
  }
  {
    const std::lock_guard<std::mutex> lock(handOffMutex_);
    detectorDone_ = true;
  }
  handOffChanged_.notify_all();
}

void App::runPipelined() {
  detector_ = std::thread([this] { detectorLoop(); });
  // The processing side: the frames in the order the detector thread took them; every frame it
  // took is completed (a stop ends the taking, not the frames already taken).
  std::size_t slot = 0;
  for (;;) {
    bool ready = false;
    bool done = false;
    {
      std::unique_lock<std::mutex> lock(handOffMutex_);
      handOffChanged_.wait_for(lock, std::chrono::nanoseconds(kIdleTick_ns),
                               [&] { return slotFull_[slot] || detectorDone_; });
      ready = slotFull_[slot];
      done = detectorDone_;
    }
    if (ready) {
      const HandOff& handOff = handOff_[slot];
      const FrameOutcome outcome =
          step_.complete(capture_.frame(handOff.index), handOff.capture_ns, slot, handOff.front);
      capture_.release(handOff.index);
      {
        const std::lock_guard<std::mutex> lock(handOffMutex_);
        slotFull_[slot] = false;
      }
      handOffChanged_.notify_all();
      slot = (slot + 1) % kHandOffSlots;
      reportFrame(outcome);
      continue;
    }
    if (done) {
      break;
    }
    idleTick();
  }
  detector_.join();
}

void App::reportFrame(const FrameOutcome& outcome) {
  if (!outcome.processed) {
    return;
  }
  lastPose_ = outcome.pose;
  reports_.tick(clock_->now_ns(), outcome);
  if (seams_.observer != nullptr) {
    seams_.observer->onFrameDone(counters_.framesProcessed);
  }
}

LoopCounters App::counters() const {
  LoopCounters c = counters_;
  capture_.addCounters(c);
  if (step_.poseInput() != nullptr) {
    // The processing thread's copy (the detector thread polls the input when pipelined).
    const PoseInputCounters& pose = step_.poseCounters();
    c.telemetrySamples = pose.received;
    c.telemetryRejected = pose.linkRejected + pose.bufferRejected;
  }
  if (recorder_) {
    const RecordCounters r = recorder_->counters();
    c.recording = true;
    c.recordFrames = r.recorded;
    c.recordDropped = r.dropped;
    c.recordSkipped = r.skipped;
    c.recordRemoved = r.removed;
    c.recordTelemetry = r.telemetryRecorded;
    c.recordTelemetryDropped = r.telemetryDropped;
    c.recordErrors = r.writeErrors;
  }
  return c;
}

std::string App::summaryLine() const {
  std::array<char, 2048> line{};
  formatSummaryLine(line, counters(), stats_, runWall_s_);
  return line.data();
}

}  // namespace vp::app
