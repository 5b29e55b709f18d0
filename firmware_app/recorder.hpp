// firmware_app/recorder: the loop records what it sees (app.record, `--record DIR`) as a
// recorded sequence (docs/recorded_sequence.md, docs/field_data.md) without ever making the
// loop wait for the disk.
//
// Contract: open() (start-up) creates the sequence with sequence::SequenceWriter (rig.yaml
// from the running rig, the DTM copied beside it as dtm.tif, the site file, if the loop has
// one, as site.geojson named by rig.yaml's site.file), allocates `queue_frames`
// camera-size frame buffers and the telemetry ring, and starts the writer thread; it fails
// naming app.record.dir and the problem. Then, from two threads, without allocating, locking
// against the writer or waiting for it:
//   offerFrame() / offerBadFrame()  capture thread: every frame taken from the source. A frame
//       that every_nth_frame picks is copied into a free buffer and queued for the writer; with
//       no buffer free (the writer is behind) it is dropped and counted.
//   onSample()  processing thread (PoseInput, through PoseSampleTap): each pose sample as the
//       link delivered it, copied into a bounded ring (full: dropped and counted).
// The writer thread does the slow part: JPEG encoding (cv::imencode, which allocates on that
// thread), the image written to a temporary file renamed into place, its frames.csv row and
// the telemetry rows flushed whole (one write(2) each). It keeps the disk budget (max_disk_mib
// and min_free_disk_mib) before each frame: `stop` finishes the sequence and records nothing
// more; `ring` deletes the oldest frame images (frames.csv lists only the kept ones when the
// sequence is finished). finish() (shutdown, after the capture thread has ended) lets the
// writer write every queued frame and sample, writes sequence.yaml last, and joins the thread.
//
// Accounting after finish(): framesIn == recorded + dropped + skipped, where framesIn counts
// every frame offered (good or bad), dropped the frames there was no buffer for (or whose id
// or time did not advance, or whose write failed) and skipped the frames not meant to be
// recorded: those every_nth_frame passes over, bad frames (no image) and frames after the
// recording ended (budget reached with `stop`, or a write error).
//
// Time: frames keep the source's timestamps and ids; pose samples keep their own timestamps,
// which the pose inputs give on the frames' clock (camera: CLOCK_MONOTONIC; replay: the
// recording's clock).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "config/config.hpp"
#include "core/frame_pool.hpp"
#include "core/spsc_queue.hpp"
#include "loop_inputs.hpp"
#include "sequence/recorded_sequence.hpp"
#include "telemetry/pose_check.hpp"

namespace vp::app {

struct RecordCounters {
  std::uint64_t framesIn = 0;  // frames offered: every frame taken from the source
  std::uint64_t recorded = 0;  // written (ring: including those deleted later)
  std::uint64_t dropped = 0;   // no free buffer, id/time not advancing, write failed
  std::uint64_t skipped = 0;   // every_nth_frame, bad frames, after the recording ended
  std::uint64_t removed = 0;   // ring: oldest frames deleted to stay within the budget
  std::uint64_t telemetryRecorded = 0;
  std::uint64_t telemetryDropped = 0;  // ring full, or refused by the format's checks
  std::uint64_t writeErrors = 0;       // failed writes (each ends the recording)
  std::uint64_t bytes = 0;             // on disk, at the last frame written
};

struct RecorderSetup {
  config::RecordConfig options;
  config::RigConfig rig;           // the running rig: origin, camera, mount, terrain
  std::string source;              // what is recorded, for sequence.yaml (device or sequence)
  double frameRate_hz = 10.0;      // the source's nominal rate
  std::int64_t writeDelay_ns = 0;  // tests: the writer waits this long per frame (a slow disk)
  // The site file the loop runs with (site.file, absolute; empty: none): copied into the
  // sequence as site.geojson and named by its rig.yaml (site.file), so that a replay of the
  // recording uses the same site. The surface model (rig.terrain.dsmPath) likewise, as dsm.tif
  // named by terrain.dsm_path.
  std::string sitePath;
};

class Recorder final : public PoseSampleTap {
 public:
  // Telemetry samples waiting for the writer: 40 s at 50 Hz.
  static constexpr std::size_t kTelemetryRing = 2048;

  Recorder() = default;
  ~Recorder() override;
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  bool open(const RecorderSetup& setup, std::string* why);

  // Capture thread.
  void offerFrame(const Frame& frame);
  void offerBadFrame();
  // Processing thread.
  void onSample(const telemetry::PoseSample& sample) override;

  void finish();
  RecordCounters counters() const;
  const std::string& directory() const { return directory_; }

 private:
  void writerLoop();
  void writeFrame(FrameIndex index);
  void drainTelemetry();
  bool makeRoom(std::uint64_t bytes);
  void endRecording(const char* reason);
  std::string notes() const;
  void wake();

  config::RecordConfig options_{};
  std::string directory_;
  std::int64_t writeDelay_ns_ = 0;
  std::uint64_t siteBytes_ = 0;      // the site file's and DSM's copies (not the writer's)
  sequence::SequenceWriter writer_;  // writer thread only, after open()
  sequence::EncodedFrame encoded_;
  std::string why_;      // writer thread's scratch message
  bool closed_ = false;  // writer thread: the sequence is finished (sequence.yaml written)

  // Frames: free buffers in the pool, filled ones in `ready_` (capture -> writer).
  FramePool buffers_;
  SpscQueue<FrameIndex, FramePool::kMaxFrames> ready_;
  std::uint64_t offeredGood_ = 0;  // capture thread: good frames offered (every_nth_frame)
  bool haveLast_ = false;          // capture thread: the last frame queued, to refuse a
  std::int64_t lastId_ = 0;        // frame whose id or time does not advance
  std::int64_t lastTimestamp_ns_ = 0;
  bool loggedDrop_ = false;   // capture thread: the first drop is logged, later ones counted
  bool loggedOrder_ = false;  // capture thread: the same for ids or times not advancing

  // Telemetry ring (processing thread -> writer thread).
  std::vector<telemetry::PoseSample> samples_;
  std::atomic<std::uint64_t> sampleHead_{0};  // next to read (writer)
  std::atomic<std::uint64_t> sampleTail_{0};  // next to write (processing thread)
  bool loggedSampleDrop_ = false;             // processing thread
  bool loggedSampleRefusal_ = false;          // writer thread

  std::atomic<std::uint64_t> framesIn_{0};
  std::atomic<std::uint64_t> recorded_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> skipped_{0};
  std::atomic<std::uint64_t> removed_{0};
  std::atomic<std::uint64_t> telemetryRecorded_{0};
  std::atomic<std::uint64_t> telemetryDropped_{0};
  std::atomic<std::uint64_t> writeErrors_{0};
  std::atomic<std::uint64_t> bytes_{0};

  std::atomic<bool> ended_{false};  // the sequence is finished: nothing more is recorded
  std::atomic<bool> finishing_{false};
  std::atomic<std::uint32_t> wake_{0};
  std::mutex mutex_;
  std::condition_variable wakeup_;
  std::thread thread_;
};

}  // namespace vp::app
