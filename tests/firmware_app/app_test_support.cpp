#include "app_test_support.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <unistd.h>
#include <fstream>
#include <sstream>

#include <algorithm>
#include <filesystem>
#include <map>
#include <mutex>

#include <gtest/gtest.h>

#include "io/dtm_file.hpp"
#include "simulator.hpp"

namespace vp::test {

namespace fs = std::filesystem;

namespace {

constexpr float kTruthScore = 0.9F;
constexpr float kTruthTypeProbability = 0.94F;  // the other six share the rest
constexpr double kMaxTruncation = 0.3;          // vehicles mostly outside the image are skipped

}  // namespace

std::string scratchDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("vp_app_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string simulatedSequence(const std::string& name, int frames, int width_px, int height_px,
                              std::uint64_t seed) {
  static std::mutex mutex;
  static std::map<std::string, std::string> rendered;
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto found = rendered.find(name); found != rendered.end()) {
    return found->second;
  }
  const fs::path dir =
      fs::temp_directory_path() / ("vp_app_test_" + std::to_string(::getpid())) / ("seq_" + name);
  fs::remove_all(dir);
  sim::SimOptions options;
  options.scene = sim::SceneKind::Intersection;
  options.seed = seed;
  options.frames = frames;
  options.outDir = dir.string();
  options.width = width_px;
  options.height = height_px;
  options.png = true;
  options.supersampling = 1;
  options.asmPath = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";
  sim::Simulator simulator;
  std::string why;
  if (!simulator.init(options, &why) || !simulator.write(&why)) {
    ADD_FAILURE() << "simulating " << name << ": " << why;
    return "";
  }
  rendered[name] = dir.string();
  return dir.string();
}

std::string loopSequence() {
  return simulatedSequence("loop", kLoopFrames, kLoopWidth_px, kLoopHeight_px, 7);
}

std::string copySequence(const std::string& from, const std::string& name) {
  const std::string to = scratchDir(name);
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  return to;
}

config::AppConfig defaultConfigFor(const std::string& sequenceDir) {
  config::AppConfig config =
      config::loadConfig(std::string(VP_SOURCE_DIR) + "/config/default.yaml");
  config.source.kind = config::FrameSourceKind::Replay;
  config.source.sequenceDir = sequenceDir;
  return config;
}

bool TruthPerception::init(const std::string& sequenceDir, std::string* why,
                           const TruthReplay& replay) {
  // The truth boxes are footprints: lifted on the ground.
  return init(sequenceDir, nullptr, perception::DetectionLifterOptions{.boxHeightShare = 0.0}, why,
              replay);
}

bool TruthPerception::init(const std::string& sequenceDir, const georef::GeorefOptions* georef,
                           const perception::DetectionLifterOptions& lift, std::string* why,
                           const TruthReplay& replay) {
  if (!reader_.open(sequenceDir, why)) {
    return false;
  }
  truthWorld_ = geodesy::LocalFrame(reader_.rig().origin);
  timeOffsetNs_ = replay.timeOffset_ns;
  const sequence::Rig& rig = replay.rig != nullptr ? *replay.rig : reader_.rig();
  world_ = geodesy::LocalFrame(rig.origin);
  terrain::TerrainGrid grid;
  if (!io::loadDtm(rig.dtmPath, rig.crs, grid, why) ||
      !terrain_.init(std::move(grid), world_, why) ||
      !camera_.init(rig.intrinsics, rig.distortion, why) ||
      !asm_.load(std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml", why) ||
      !lifter_.init(camera_, rig.mount, terrain_, world_, why)) {
    return false;
  }
  planar_ = georef != nullptr;
  if (planar_) {
    if (!georef::loadGroundView(*georef, camera_, world_, &terrain_, &groundView_, why) ||
        !plane_.init(groundView_.homography, groundView_.camera, camera_, world_, why) ||
        !detectionLifter_.init(plane_, world_, asm_, lift, why)) {
      return false;
    }
  } else if (!detectionLifter_.init(terrain_, world_, asm_, lift, why)) {
    return false;
  }
  for (const sequence::FrameRecord& frame : reader_.frames()) {
    timestamps_.push_back(frame.timestamp_ns);
  }
  loopPeriodNs_ = platform::replay::loopPeriod_ns(reader_);
  detections_.resize(detection::kMaxDetectionsPerFrame);
  objectOf_.resize(detection::kMaxDetectionsPerFrame);
  liftedCentres_.resize(timestamps_.size() * detection::kMaxDetectionsPerFrame);
  lifted_.assign(liftedCentres_.size(), 0);
  observations_.resize(detection::kMaxDetectionsPerFrame);
  return true;
}

perception::PipelineStatus TruthPerception::process(const cv::Mat& bgrFrame,
                                                    std::int64_t timestamp_ns,
                                                    const telemetry::PoseEstimate& pose) {
  frame_ = bgrFrame;  // a header: shares the pool's pixels, no copy
  summary_ = perception::FrameLiftSummary{};
  footprint_ = perception::FrameFootprint{};
  if (timestamps_.empty()) {
    return perception::PipelineStatus::DetectionFailed;
  }
  // A looping replay shifts every timestamp by whole loop periods.
  std::int64_t t = timestamp_ns + timeOffsetNs_;
  const std::int64_t first = timestamps_.front();
  if (t > timestamps_.back() && loopPeriodNs_ > 0) {
    t = first + (t - first) % loopPeriodNs_;
  }
  const auto at = std::lower_bound(timestamps_.begin(), timestamps_.end(), t);
  if (at == timestamps_.end() || *at != t) {
    return perception::PipelineStatus::DetectionFailed;
  }
  const std::size_t frameIndex = static_cast<std::size_t>(at - timestamps_.begin());
  const std::int64_t frameId = reader_.frames()[frameIndex].frameId;
  std::size_t count = 0;
  const std::span<const sequence::ObjectTruth> objects = reader_.objects(frameId);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const sequence::ObjectTruth& object = objects[i];
    if (object.truncation > kMaxTruncation || count >= detections_.size()) {
      continue;
    }
    objectOf_[count] = i;
    detection::Detection& d = detections_[count++];
    d = detection::Detection{};
    d.box = object.imageBox;
    d.score = kTruthScore;
    d.directionKnown = true;
    d.typeProbabilities.fill((1.0F - kTruthTypeProbability) / (shape::kVehicleTypeCount - 1));
    d.typeProbabilities[static_cast<std::size_t>(object.type)] = kTruthTypeProbability;
    d.gamma = object.shape;
  }
  summary_ = detectionLifter_.liftFrame(
      lifter_, timestamp_ns, pose, std::span<const detection::Detection>(detections_.data(), count),
      observations_);
  footprint_ = planar_
                   ? perception::frameFootprint(plane_, bgrFrame.cols, bgrFrame.rows)
                   : perception::frameFootprint(lifter_, summary_, bgrFrame.cols, bgrFrame.rows);
  for (std::size_t k = 0; k < summary_.written; ++k) {
    if (observations_[k].liftStatus != perception::LiftStatus::Ok) {
      continue;
    }
    // The true centre, from the truth's world into the lifter's (they differ for an import).
    const Eigen::Vector3d truth =
        world_.toEnu(truthWorld_.toGeodetic(objects[objectOf_[k]].positionEnu));
    const double error_m = (observations_[k].ground.centreEnu - truth).head<2>().norm();
    maxLiftError_m_ = std::max(maxLiftError_m_, error_m);
    const std::size_t slot = frameIndex * detection::kMaxDetectionsPerFrame + objectOf_[k];
    if (objectOf_[k] < detection::kMaxDetectionsPerFrame) {
      liftedCentres_[slot] = observations_[k].ground.centreWgs84;
      lifted_[slot] = 1;
    }
    sumLiftError_m_ += error_m;
    ++liftChecked_;
  }
  return perception::PipelineStatus::Ok;
}

const geodesy::GeodeticPoint* TruthPerception::liftedCentre(std::size_t frameIndex,
                                                            std::size_t object) const {
  const std::size_t slot = frameIndex * detection::kMaxDetectionsPerFrame + object;
  if (object >= detection::kMaxDetectionsPerFrame || slot >= lifted_.size() || !lifted_[slot]) {
    return nullptr;
  }
  return &liftedCentres_[slot];
}

std::size_t TruthPerception::objectCount(std::size_t frameIndex) const {
  return frameIndex < timestamps_.size()
             ? reader_.objects(reader_.frames()[frameIndex].frameId).size()
             : 0;
}

app::RunSettings everyFrame() {
  app::RunSettings run;
  run.everyFrame = true;
  run.quiet = true;
  return run;
}

void AllocationWindow::onDetectorThreadStart() {
  detectorThread_.store(static_cast<unsigned long>(pthread_self()));
}

void AllocationWindow::onFrameDone(std::uint64_t processed) {
  if (processed == from_) {
    counter_.startOnThreads(static_cast<unsigned long>(pthread_self()), detectorThread_.load());
  } else if (processed == to_) {
    counter_.stop();
    counted_ = true;
  }
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

pid_t spawnApp(std::vector<std::string> args, const std::string& stderrLog) {
  std::vector<char*> argv;
  for (std::string& arg : args) {
    argv.push_back(arg.data());
  }
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, stderrLog.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

bool waitUntilRunning(const std::string& stderrLog, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (readText(stderrLog).find("running: ") == std::string::npos) {
    if (std::chrono::steady_clock::now() >= deadline) {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

perception::PipelineStatus TruthPlusOnePerception::process(const cv::Mat& bgrFrame,
                                                           std::int64_t timestamp_ns,
                                                           const telemetry::PoseEstimate& pose) {
  const perception::PipelineStatus status = truth_->process(bgrFrame, timestamp_ns, pose);
  summary_ = truth_->liftSummary();
  std::size_t n = 0;
  const perception::VehicleObservation* firstLifted = nullptr;
  for (const perception::VehicleObservation& o : truth_->observations()) {
    if (n < observations_.size()) {
      observations_[n++] = o;
    }
    if (o.liftStatus == perception::LiftStatus::Ok) {
      ++truthLifted_;
      firstLifted = firstLifted ? firstLifted : &o;
    }
  }
  if (firstLifted != nullptr && n < observations_.size() &&
      extra(bgrFrame, *firstLifted, &observations_[n])) {
    ++n;
    ++injected_;
  }
  summary_.written = n;
  return status;
}

}  // namespace vp::test
