#include "frame_step.hpp"

#include <algorithm>
#include <utility>

#include "detection/detection.hpp"
#include "loop_log.hpp"
#include "tracking/from_perception.hpp"
#include "vehicle_state.hpp"

namespace vp::app {

namespace {

bool isOffDtm(perception::LiftStatus status) {
  return status == perception::LiftStatus::OutsideDtm || status == perception::LiftStatus::NoData ||
         status == perception::LiftStatus::NoIntersection;
}

}  // namespace

bool FrameStep::initPoseBuffer(const telemetry::PoseBufferConfig& config, std::string* why) {
  std::string problem;
  if (!poses_.init(config, &problem)) {
    if (why) {
      *why = "pose: " + problem;
    }
    return false;
  }
  return true;
}

bool FrameStep::init(const FrameStepWiring& wiring, std::unique_ptr<FramePerception> perception,
                     std::unique_ptr<PoseInput> poseInput, const tracking::TrackerConfig& tracker,
                     std::string* why) {
  wiring_ = wiring;
  perception_ = std::move(perception);
  poseInput_ = std::move(poseInput);
  std::string problem;
  if (!tracker_.init(tracker, &problem)) {
    if (why) {
      *why = "tracking: " + problem;
    }
    return false;
  }
  worldDetections_.resize(detection::kMaxDetectionsPerFrame);
  static const site::SiteOptions kDefaultSiteOptions{};
  const site::SiteOptions& siteOptions =
      wiring_.siteOptions != nullptr ? *wiring_.siteOptions : kDefaultSiteOptions;
  if (wiring_.dsm != nullptr) {
    if (!surfacePrior_.init(*wiring_.terrain, wiring_.dsm, perception_->lifter(), *wiring_.world,
                            *wiring_.shapeModel, wiring_.lift, wiring_.site, siteOptions,
                            &problem)) {
      if (why) {
        *why = "terrain.dsm_path: " + problem;
      }
      return false;
    }
    surfaced_.resize(detection::kMaxDetectionsPerFrame);
  }
  if (!lanePrior_.init(wiring_.site, siteOptions.laneDirectionPrior, perception_->detectionLifter(),
                       &problem)) {
    if (why) {
      *why = problem;
    }
    return false;
  }
  if (lanePrior_.active()) {
    laned_.resize(detection::kMaxDetectionsPerFrame);
  }
  sitePrior_.init(wiring_.site, siteOptions.offRoad);
  if (sitePrior_.active()) {
    screened_.resize(detection::kMaxDetectionsPerFrame);
  }
  states_.resize(static_cast<std::size_t>(tracker.maxTracks));
  published_.resize(static_cast<std::size_t>(tracker.maxTracks));
  if (wiring_.traffic != nullptr && wiring_.site != nullptr) {
    if (!traffic_.init(*wiring_.site, *wiring_.traffic, &problem)) {
      if (why) {
        *why = "traffic: " + problem;
      }
      return false;
    }
    if (traffic_.active()) {
      for (const site::Feature* gate : traffic_.gates()) {
        trafficIds_.gates.push_back(gate->id);
      }
      for (const site::Feature* zone : traffic_.zones()) {
        trafficIds_.zones.push_back(zone->id);
      }
      for (const site::Feature* lane : traffic_.lanes()) {
        trafficIds_.lanes.push_back(lane->id);
      }
      wiring_.counters->traffic = true;
      logLine("traffic: analysing %zu gates, %zu zones, %zu lanes; period %.0f s",
              trafficIds_.gates.size(), trafficIds_.zones.size(), trafficIds_.lanes.size(),
              wiring_.traffic->period_s);
    }
  }
  return true;
}

bool FrameStep::openOutputs(const OutputSpec& spec, std::string* why) {
  return outputs_.open(spec, why);
}

bool FrameStep::openTraffic(const std::string& dir, const config::DdsConfig& dds,
                            std::string* why) {
  if (!traffic_.active()) {
    return true;
  }
  if (!dir.empty()) {
    std::string problem;
    if (!outputs_.openTraffic(dir, trafficIds_, *wiring_.world, &problem)) {
      if (why) {
        *why = "app.traffic_dir: " + problem;
      }
      return false;
    }
  }
  if (wiring_.dds != nullptr &&
      !wiring_.dds->openTraffic(dds,
                                platform::dds::TrafficFeatureIdViews{
                                    trafficIds_.gates, trafficIds_.zones, trafficIds_.lanes},
                                *wiring_.world, why)) {
    return false;
  }
  return true;
}

void FrameStep::stepTraffic(std::int64_t timestamp_ns, std::size_t published) {
  if (!traffic_.active()) {
    return;
  }
  LoopCounters& counters = *wiring_.counters;
  if (!traffic_.step(timestamp_ns,
                     std::span<const tracking::TrackState>(published_.data(), published))) {
    // Cannot happen behind the frame-time check above; counted all the same.
    ++counters.trafficErrors;
    return;
  }
  reportTraffic();
}

void FrameStep::reportTraffic() {
  LoopCounters& counters = *wiring_.counters;
  DdsWriters* dds = wiring_.dds != nullptr && wiring_.dds->trafficOpen() ? wiring_.dds : nullptr;
  const auto ddsFailed = [&](const platform::dds::DdsResult& result, const char* what) {
    ++counters.trafficErrors;
    if (trafficDdsErrors_++ == 0) {
      logLine("publishing the traffic %s failed: %s (further failures are only counted)", what,
              platform::dds::describe(result).c_str());
    }
  };
  for (const traffic::TrafficEvent& event : traffic_.events()) {
    ++counters.trafficEvents;
    outputs_.writeTrafficEvent(event);
    if (dds != nullptr) {
      const platform::dds::DdsResult result =
          dds->writeTrafficEvent(event, event.time_ns + toUtcNs_);
      if (!result.ok()) {
        ddsFailed(result, "event");
      }
    }
  }
  const traffic::TrafficStatistics* period = traffic_.completedPeriod();
  if (period != nullptr) {
    ++counters.trafficPeriods;
    outputs_.writeTrafficStatistics(*period);
    if (dds != nullptr) {
      const platform::dds::DdsResult result =
          dds->writeTrafficStatistics(*period, period->end_ns + toUtcNs_);
      if (!result.ok()) {
        ddsFailed(result, "statistics");
      }
    }
  }
  const traffic::TrafficAnalyzerStats& stats = traffic_.stats();
  counters.gateCrossings = traffic_.gateCounter().stats().crossings;
  counters.trafficErrors =
      trafficDdsErrors_ + outputs_.trafficErrors() + stats.stepsRefused + stats.eventsDropped;
}

FrameOutcome FrameStep::process(const Frame& frame, std::int64_t capture_ns) {
  FrameFront front;
  detectPose(frame, &front);
  return completeWith(frame, capture_ns, front, false, 0);
}

void FrameStep::detect(const Frame& frame, std::size_t slot, FrameFront* front) {
  detectPose(frame, front);
  if (!front->outOfOrder) {
    // Its status comes back from finish() on the processing thread (counted and logged there).
    perception_->detect(slot, frame.image, frame.timestamp_ns, front->pose);
  }
}

FrameOutcome FrameStep::complete(const Frame& frame, std::int64_t capture_ns, std::size_t slot,
                                 const FrameFront& front) {
  return completeWith(frame, capture_ns, front, true, slot);
}

void FrameStep::detectPose(const Frame& frame, FrameFront* front) {
  front->start_ns = wiring_.clock->now_ns();
  const std::int64_t t = frame.timestamp_ns;
  front->outOfOrder = haveDetectTimestamp_ && t <= detectTimestampNs_;
  front->previousTimestamp_ns = detectTimestampNs_;
  if (front->outOfOrder) {
    return;
  }
  haveDetectTimestamp_ = true;
  detectTimestampNs_ = t;
  poseInput_->poll(t, poses_);
  front->pose = poses_.poseAt(t);
  front->poseCounters = poseInput_->counters();
}

FrameOutcome FrameStep::completeWith(const Frame& frame, std::int64_t capture_ns,
                                     const FrameFront& front, bool pipelined, std::size_t slot) {
  platform::Clock& clock = *wiring_.clock;
  LoopCounters& counters = *wiring_.counters;
  LoopStats& stats = *wiring_.stats;
  const std::int64_t t = frame.timestamp_ns;
  stats.record(Stage::Queue, front.start_ns - capture_ns);
  if (front.outOfOrder) {
    ++counters.pipelineErrors;
    logLine("frame %lld skipped: timestamp %lld ns is not after the previous frame's %lld ns",
            static_cast<long long>(frame.frameId), static_cast<long long>(t),
            static_cast<long long>(front.previousTimestamp_ns));
    return {};
  }
  // The frame's time on the UTC clock (see the contract). Camera stamps are CLOCK_MONOTONIC: one
  // offset. A replay's are the recording's: each frame is placed at the wall-clock time it was
  // captured, so that a receiver's latency (reception - measurement time) is this frame's
  // capture -> publish time plus transport, as with a camera. An offset fixed at the first
  // frame's processing would not be: a replay faster than the recording, or a first frame that
  // waited, puts later measurement times ahead of their capture (latencies below zero).
  toUtcNs_ = wiring_.sourceOnMonotonicClock ? wiring_.monotonicToUtc_ns
                                            : capture_ns + (realtimeNow_ns() - clock.now_ns()) - t;
  haveUtcOffset_ = true;
  lastTimestampNs_ = t;
  poseCounters_ = front.poseCounters;

  const telemetry::PoseEstimate& pose = front.pose;
  // A georeferenced fixed view needs no pose: its absence is neither counted nor logged.
  switch (wiring_.fixedView ? telemetry::PoseStatus::Ok : pose.status) {
    case telemetry::PoseStatus::Ok:
      break;
    case telemetry::PoseStatus::NoPose:
      ++counters.noPose;
      break;
    case telemetry::PoseStatus::Stale:
      ++counters.stalePose;
      break;
    case telemetry::PoseStatus::Invalid:
      ++counters.invalidPose;
      break;
  }
  if (!wiring_.fixedView) {
    logPoseEpisode(pose.status, frame.frameId, pose);
  }

  const perception::PipelineStatus status =
      pipelined ? perception_->finish(slot) : perception_->process(frame.image, t, pose);
  const perception::PipelineTimings& timings = perception_->timings();
  if (status != perception::PipelineStatus::Ok) {
    ++counters.pipelineErrors;
    logLine("frame %lld not processed: %s", static_cast<long long>(frame.frameId),
            perception_->lastError());
    return {};
  }
  logWorkingScale(frame.frameId);
  stats.record_ms(Stage::Preprocess, timings.preprocess_ms);
  stats.record_ms(Stage::Detector, timings.detector_ms);
  stats.record_ms(Stage::Decode, timings.decode_ms);
  stats.record_ms(Stage::Crops, timings.crops_ms);
  stats.record_ms(Stage::Lift, timings.lift_ms);
  countObservations();
  // What the tracker and the files get: the site's prior has dropped detections off its roads.
  const std::span<const perception::VehicleObservation> observations = screenObservations();

  const std::int64_t trackStart_ns = clock.now_ns();
  const std::size_t detections = tracking::toWorldDetections(observations, worldDetections_);
  const auto report = tracker_.step(
      t, std::span<const tracking::WorldDetection>(worldDetections_.data(), detections));
  if (!report) {
    ++counters.trackerErrors;
    logLine("frame %lld: tracker: %s", static_cast<long long>(frame.frameId),
            tracking::toString(report.error()));
  }
  const std::int64_t publishStart_ns = clock.now_ns();
  stats.record(Stage::Track, publishStart_ns - trackStart_ns);
  const std::span<const messages::VehicleState> states = publish(t, frame.frameId);
  stepTraffic(t, states.size());
  const std::int64_t published_ns = clock.now_ns();
  stats.record(Stage::Publish, published_ns - publishStart_ns);
  stats.record(Stage::EndToEnd, published_ns - capture_ns);

  outputs_.writeDetections(frame.frameId, observations);
  if (outputs_.wantsVideo()) {
    const perception::FrameLiftSummary& lift = perception_->liftSummary();
    const bool posed = lift.poseStatus == perception::LiftStatus::Ok;
    outputs_.writeVideo(perception_->correctedFrame(), observations,
                        posed ? &perception_->lifter() : nullptr,
                        posed ? &lift.cameraPose : nullptr);
  }
  outputs_.endFrame(frame.frameId);  // this frame's rows reach the files now
  counters.outputErrors = outputs_.errors();
  ++counters.framesProcessed;
  return {true, t + toUtcNs_, pose, states, perception_->footprint().corners()};
}

void FrameStep::countObservations() {
  LoopCounters& counters = *wiring_.counters;
  const std::span<const perception::VehicleObservation> observations = perception_->observations();
  counters.detections += observations.size();
  counters.retyped += perception_->retyped();
  for (const perception::VehicleObservation& observation : observations) {
    if (observation.liftStatus == perception::LiftStatus::Ok) {
      ++counters.lifted;
    } else if (isOffDtm(observation.liftStatus)) {
      ++counters.outsideDtm;
    }
  }
}

std::span<const perception::VehicleObservation> FrameStep::screenObservations() {
  std::span<const perception::VehicleObservation> observations = perception_->observations();
  if (lanePrior_.active() && perception_->liftSummary().poseStatus == perception::LiftStatus::Ok) {
    // First, on the DTM lift: the surface prior lifts a deck's vehicle again from its box.
    const std::size_t n = std::min(observations.size(), laned_.size());
    std::copy_n(observations.begin(), n, laned_.begin());
    const std::span<perception::VehicleObservation> laned(laned_.data(), n);
    wiring_.counters->laneTurned +=
        lanePrior_.apply(laned, perception_->lifter(), perception_->liftSummary().cameraPose)
            .turned;
    observations = laned;
  }
  if (surfacePrior_.active()) {
    const perception::SurfaceScreening surface =
        surfacePrior_.screen(perception_->liftSummary().cameraPose, observations, surfaced_);
    wiring_.counters->onDeck += surface.onDeck;
    wiring_.counters->onStructure += surface.onStructure;
    observations = {surfaced_.data(), surface.written};
  }
  if (!sitePrior_.active()) {
    return observations;
  }
  const perception::SiteScreening screening = sitePrior_.screen(observations, screened_);
  wiring_.counters->offSite += screening.offSite;
  return {screened_.data(), screening.written};
}

void FrameStep::logWorkingScale(std::int64_t frameId) {
  // Once per change: the scale follows the drone's height (perception.working_gsd_m).
  const double scale = perception_->workingScale();
  if (scale != lastWorkingScale_ && lastWorkingScale_ > 0.0) {
    logLine("working scale %.3f from frame %lld (was %.3f; GSD %.4f m/px at the image centre)",
            scale, static_cast<long long>(frameId), lastWorkingScale_, perception_->frameGsd_m());
  } else if (lastWorkingScale_ == 0.0 && scale > 0.0) {
    logLine(
        "working scale %.3f from frame %lld (GSD %.4f m/px at the image centre; 0 = no pose yet)",
        scale, static_cast<long long>(frameId), perception_->frameGsd_m());
  }
  lastWorkingScale_ = scale;
}

void FrameStep::logPoseEpisode(telemetry::PoseStatus status, std::int64_t frameId,
                               const telemetry::PoseEstimate& pose) {
  // Once per episode: when the pose goes bad (with its context) and when it is good again.
  if (status == lastPoseStatus_) {
    ++poseEpisodeFrames_;
    return;
  }
  if (status == telemetry::PoseStatus::Ok) {
    logLine("pose ok again at frame %lld after %llu frame(s) with pose %s",
            static_cast<long long>(frameId), static_cast<unsigned long long>(poseEpisodeFrames_),
            telemetry::toString(lastPoseStatus_));
  } else {
    logLine(
        "pose %s from frame %lld (nearest sample %.3f s away; telemetry %s: %llu samples, "
        "%llu refused): detections are kept image-only",
        telemetry::toString(status), static_cast<long long>(frameId),
        pose.age_ns >= 0 ? static_cast<double>(pose.age_ns) / 1e9 : -1.0, poseInput_->name(),
        static_cast<unsigned long long>(poseCounters_.received),
        static_cast<unsigned long long>(poseCounters_.linkRejected + poseCounters_.bufferRejected));
  }
  lastPoseStatus_ = status;
  poseEpisodeFrames_ = 1;
}

std::span<const messages::VehicleState> FrameStep::publish(std::int64_t timestamp_ns,
                                                           std::int64_t frameId) {
  LoopCounters& counters = *wiring_.counters;
  std::size_t count = 0;
  for (const tracking::TrackState& track : tracker_.tracks()) {
    // Tentative tracks are never published (the publisher would skip them too).
    if (track.status == tracking::TrackStatus::Tentative || count >= states_.size()) {
      continue;
    }
    // A track on a deck the site marks stands on the surface model, every other on the DTM.
    const terrain::TerrainModel* ground =
        surfacePrior_.active()
            ? &surfacePrior_.standingSurface({track.centreEnu.x(), track.centreEnu.y(), 0.0})
            : wiring_.terrain;
    states_[count] = toVehicleState(track, wiring_.droneId, toUtcNs_, *wiring_.world, ground,
                                    wiring_.shapeModel);
    published_[count] = track;
    ++count;
  }
  const std::span<const messages::VehicleState> states(states_.data(), count);
  if (DdsWriters* dds = wiring_.dds) {
    for (const messages::VehicleState& state : states) {
      const platform::dds::PublishResult result = dds->publish(state);
      if (!result.ok()) {
        if (counters.publishErrors++ == 0) {
          logLine("publishing track %u failed: %s (further failures are only counted)",
                  static_cast<unsigned>(state.trackId), platform::dds::toString(result.outcome));
        }
        continue;
      }
      ++counters.statesPublished;
      if (wiring_.observer != nullptr) {
        wiring_.observer->onPublished(state);
      }
    }
    const platform::dds::FrameSummary summary = dds->endFrame(timestamp_ns + toUtcNs_);
    counters.tracksDisposed += summary.disposed;
    counters.publishErrors += summary.errors;
  }
  outputs_.writeTracks(frameId, std::span<const tracking::TrackState>(published_.data(), count),
                       states);
  return states;
}

void FrameStep::finish() {
  LoopCounters& counters = *wiring_.counters;
  if (traffic_.active() && haveUtcOffset_) {
    // The last period, closed at the last frame's time (completedPeriod() then), and the
    // events of the tracks it ends (turning movements, dwell).
    traffic_.finish(lastTimestampNs_);
    reportTraffic();
    outputs_.endFrame(-1);
    counters.outputErrors = outputs_.errors();
  }
  if (DdsWriters* dds = wiring_.dds) {
    // A frame without tracks: endFrame() disposes every published instance.
    const platform::dds::FrameSummary summary = dds->endFrame(realtimeNow_ns());
    counters.tracksDisposed += summary.disposed;
    counters.publishErrors += summary.errors;
  }
  std::string problem;
  if (!outputs_.close(&problem)) {
    ++counters.outputErrors;
    logLine("closing outputs: %s", problem.c_str());
  }
}

}  // namespace vp::app
