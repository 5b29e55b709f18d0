// tests/firmware_app/app_test_support: what the loop's tests share: simulated sequences
// rendered at test time (tools/simulator), configurations for them, and TruthPerception, the
// perception seam that injects a sequence's ground-truth vehicles as detections (so the loop's
// tests do not depend on the detector's accuracy) and lifts them with the product's
// DetectionLifter on the recorded rig and telemetry.
#pragma once

#include <sys/types.h>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "app.hpp"
#include "georef/georeference.hpp"
#include "lifting/plane_lifter.hpp"
#include "perception/detection_lifter.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::test {

// Renders (once per process and name) a simulated sequence into a temporary directory and
// returns it. Pinhole-free: the simulator's own rig (lens distortion included).
std::string simulatedSequence(const std::string& name, int frames, int width_px, int height_px,
                              std::uint64_t seed);

// The sequence the loop's tests share (rendered once per process): intersection, seed 7,
// kLoopFrames frames of kLoopWidth_px x kLoopHeight_px (one detector tile at working scale 1).
constexpr int kLoopFrames = 24;
constexpr int kLoopWidth_px = 320;
constexpr int kLoopHeight_px = 256;
std::string loopSequence();

// Copies a sequence directory (to damage the copy).
std::string copySequence(const std::string& from, const std::string& name);

// The repository's config/default.yaml, loaded, with the given sequence to replay.
config::AppConfig defaultConfigFor(const std::string& sequenceDir);

// A fresh temporary directory for one test's outputs.
std::string scratchDir(const std::string& name);

// Ground-truth vehicles of each frame as detections (score 0.9, direction known, the true type
// at probability 0.94, the true ASM gamma), lifted with the recorded rig. process() never
// allocates after init(): the frames' truth is indexed at init.
// Where the truth is replayed from when it is not the truth sequence itself (an imported or
// directly replayed video of it): lift with that rig, and match frames by time + offset.
struct TruthReplay {
  const sequence::Rig* rig = nullptr;  // lift with this rig (default: the truth sequence's)
  std::int64_t timeOffset_ns = 0;      // truth frame time = replayed frame time + this
};

class TruthPerception final : public app::FramePerception {
 public:
  bool init(const std::string& sequenceDir, std::string* why, const TruthReplay& replay = {});
  // The same lifted with the given options and, with georef, through the ground control points'
  // fixed view (georef::loadGroundView on the recorded rig, as the app loads it) instead of the
  // recorded telemetry.
  bool init(const std::string& sequenceDir, const georef::GeorefOptions* georef,
            const perception::DetectionLifterOptions& lift, std::string* why,
            const TruthReplay& replay = {});
  // Lifted truth vehicles compared with their true footprint centres (horizontal, m).
  double maxLiftError_m() const { return maxLiftError_m_; }
  double meanLiftError_m() const { return liftChecked_ ? sumLiftError_m_ / liftChecked_ : 0.0; }
  std::size_t liftChecked() const { return liftChecked_; }
  // Where truth object `object` of the truth's frame `frameIndex` (frames.csv order) was lifted
  // last (WGS84 footprint centre), or nullptr when it was not lifted.
  const geodesy::GeodeticPoint* liftedCentre(std::size_t frameIndex, std::size_t object) const;
  std::size_t frameCount() const { return timestamps_.size(); }
  std::size_t objectCount(std::size_t frameIndex) const;

  perception::PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose) override;
  std::span<const perception::VehicleObservation> observations() const override {
    return {observations_.data(), summary_.written};
  }
  const perception::FrameLiftSummary& liftSummary() const override { return summary_; }
  const perception::FrameFootprint& footprint() const override { return footprint_; }
  const perception::PipelineTimings& timings() const override { return timings_; }
  const char* lastError() const override { return "truth perception"; }
  const cv::Mat& correctedFrame() const override { return frame_; }
  const lifting::Lifter& lifter() const override { return lifter_; }
  const char* modelId() const override { return "ground truth"; }

 private:
  sequence::SequenceReader reader_;
  georef::GroundView groundView_;
  lifting::PlaneLifter plane_;
  bool planar_ = false;
  geodesy::LocalFrame truthWorld_;  // the truth's positions are in its rig's world
  std::int64_t timeOffsetNs_ = 0;
  std::vector<std::size_t> objectOf_;  // truth object index of each detection
  double maxLiftError_m_ = 0.0;
  double sumLiftError_m_ = 0.0;
  std::size_t liftChecked_ = 0;
  std::vector<geodesy::GeodeticPoint> liftedCentres_;  // frame index x kMaxDetectionsPerFrame
  std::vector<char> lifted_;                           // the same, 1 when set
  geodesy::LocalFrame world_;
  terrain::TerrainModel terrain_;
  camera::CameraModel camera_;
  shape::ActiveShapeModel asm_;
  lifting::Lifter lifter_;
  perception::DetectionLifter detectionLifter_;
  std::vector<std::int64_t> timestamps_;  // frames.csv order
  std::int64_t loopPeriodNs_ = 0;
  std::vector<detection::Detection> detections_;
  std::vector<perception::VehicleObservation> observations_;
  perception::FrameLiftSummary summary_{};
  perception::FrameFootprint footprint_{};
  perception::PipelineTimings timings_{};
  cv::Mat frame_;
};

// Offline run settings: the source waits for the loop (no frame dropped), no log lines.
app::RunSettings everyFrame();

// Counts the processing thread's heap allocations from the end of frame `from` to the end of
// frame `to` (the warm-up before may allocate: first-touch caches, stdio), and the states
// published meanwhile; with the pipelined loop the detector thread's too.
class AllocationWindow final : public app::LoopObserver {
 public:
  AllocationWindow(std::uint64_t from, std::uint64_t to) : from_(from), to_(to) {}
  void onFrameDone(std::uint64_t processed) override;
  void onPublished(const messages::VehicleState& /*state*/) override { ++published_; }
  void onDetectorThreadStart() override;
  std::size_t count() const { return counter_.count(); }
  bool sawDetectorThread() const { return detectorThread_ != 0; }
  bool counted() const { return counted_; }
  std::uint64_t published() const { return published_; }

 private:
  std::uint64_t from_;
  std::uint64_t to_;
  AllocationCounter counter_;
  bool counted_ = false;
  std::uint64_t published_ = 0;
  std::atomic<unsigned long> detectorThread_{0};
};

// A perception stage that hands every call to another one: tests derive from it to watch or
// slow down process() and keep the rest as the inner stage has it.
class ForwardingPerception : public app::FramePerception {
 public:
  explicit ForwardingPerception(std::unique_ptr<app::FramePerception> inner)
      : inner_(std::move(inner)) {}
  perception::PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose) override {
    return inner_->process(bgrFrame, timestamp_ns, pose);
  }
  std::span<const perception::VehicleObservation> observations() const override {
    return inner_->observations();
  }
  const perception::FrameLiftSummary& liftSummary() const override { return inner_->liftSummary(); }
  const perception::FrameFootprint& footprint() const override { return inner_->footprint(); }
  const perception::PipelineTimings& timings() const override { return inner_->timings(); }
  const char* lastError() const override { return inner_->lastError(); }
  const cv::Mat& correctedFrame() const override { return inner_->correctedFrame(); }
  const lifting::Lifter& lifter() const override { return inner_->lifter(); }
  const char* modelId() const override { return inner_->modelId(); }
  double workingScale() const override { return inner_->workingScale(); }
  double frameGsd_m() const override { return inner_->frameGsd_m(); }
  bool prepareHandOff(std::size_t slots, std::string* why) override {
    return inner_->prepareHandOff(slots, why);
  }
  perception::PipelineStatus detect(std::size_t slot, const cv::Mat& bgrFrame,
                                    std::int64_t timestamp_ns,
                                    const telemetry::PoseEstimate& pose) override {
    return inner_->detect(slot, bgrFrame, timestamp_ns, pose);
  }
  perception::PipelineStatus finish(std::size_t slot) override { return inner_->finish(slot); }

 private:
  std::unique_ptr<app::FramePerception> inner_;
};

// The truth's observations and, in a frame with a lifted truth vehicle, at most one more that
// extra() makes from the first lifted one (the site's and the surface model's roof tests).
class TruthPlusOnePerception : public app::FramePerception {
 public:
  TruthPlusOnePerception(std::unique_ptr<TruthPerception> truth, const char* modelId)
      : truth_(std::move(truth)), modelId_(modelId) {}
  perception::PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose) override;
  std::span<const perception::VehicleObservation> observations() const override {
    return {observations_.data(), summary_.written};
  }
  const perception::FrameLiftSummary& liftSummary() const override { return summary_; }
  const perception::FrameFootprint& footprint() const override { return truth_->footprint(); }
  const perception::PipelineTimings& timings() const override { return truth_->timings(); }
  const char* lastError() const override { return truth_->lastError(); }
  const cv::Mat& correctedFrame() const override { return truth_->correctedFrame(); }
  const lifting::Lifter& lifter() const override { return truth_->lifter(); }
  const char* modelId() const override { return modelId_; }

  std::uint64_t injected() const { return injected_; }
  std::uint64_t truthLifted() const { return truthLifted_; }

 protected:
  // The extra vehicle of this frame from the first lifted truth vehicle; false: none.
  virtual bool extra(const cv::Mat& bgrFrame, const perception::VehicleObservation& firstLifted,
                     perception::VehicleObservation* vehicle) = 0;
  const perception::FrameLiftSummary& summary() const { return summary_; }

 private:
  std::unique_ptr<TruthPerception> truth_;
  const char* modelId_;
  std::array<perception::VehicleObservation, detection::kMaxDetectionsPerFrame> observations_{};
  perception::FrameLiftSummary summary_{};
  std::uint64_t injected_ = 0;
  std::uint64_t truthLifted_ = 0;
};

// The whole file as text ("" when it cannot be read).
std::string readText(const std::string& path);
// Starts vp_firmware_app with `args` (args[0] the program) and its stderr written to
// `stderrLog`; the process id, or -1 when it could not be started.
pid_t spawnApp(std::vector<std::string> args, const std::string& stderrLog);
// Waits until the app's log shows its loop running ("running: "), at most `timeout`.
bool waitUntilRunning(const std::string& stderrLog, std::chrono::seconds timeout);

}  // namespace vp::test
