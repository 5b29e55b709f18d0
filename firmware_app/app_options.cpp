#include "app_options.hpp"

#include <charconv>
#include <filesystem>
#include <string_view>

namespace vp::app {

namespace {

constexpr int kMaxThreads = 16;  // perception.threads' range

std::string absolute(const std::string& path) {
  std::error_code error;
  const std::filesystem::path result = std::filesystem::absolute(path, error);
  return error ? path : result.lexically_normal().string();
}

template <class T>
bool parseInteger(std::string_view text, T* out) {
  const auto result = std::from_chars(text.data(), text.data() + text.size(), *out);
  return result.ec == std::errc() && result.ptr == text.data() + text.size();
}

}  // namespace

const char* helpText() {
  return R"(vp_firmware_app: on-board vehicle perception: camera frames -> int8 CNN -> rotated
vehicle boxes with driving direction, type and 3D shape -> world (drone pose + DTM) -> tracks
-> DDS vehicle states, drone status and occupancy grid.

Usage: vp_firmware_app --config FILE [options]

  --config FILE          the YAML configuration (docs/configuration.md; config/default.yaml).
                         Required. Command-line values override the file's.
  --sequence DIR         replay a recorded sequence (docs/recorded_sequence.md) instead of a
                         camera: source.kind replay. The rig (origin, camera, mount, terrain)
                         comes from DIR/rig.yaml, everything else from --config.
  --camera /dev/videoN   capture from this V4L2 device: source.kind v4l2
  --camera-bus BUS       capture from the V4L2 camera whose bus_info is BUS
                         (v4l2-ctl --list-devices), e.g. usb-0000:00:14.0-2
  --fast                 replay as fast as frames decode (source.paced false); frames the
                         loop cannot keep up with are dropped and counted
  --every-frame          replay: the source waits for the loop instead of dropping (offline
                         evaluation and throughput runs; not for a live camera)
  --loop                 replay: start over after the last frame (source.loop true)
  --max-frames N         stop after N frames taken from the source (0 = no limit)
  --trajectory-csv F     write the trajectory CSV (docs/tracking.md) to F
  --detections-csv F     write the detections file (docs/detections_file.md) to F
  --traffic-dir D        write the traffic files (docs/traffic_files.md) into folder D
  --annotated-video F    write the annotated frames to F (MJPG in AVI; allocates per frame)
  --record DIR           record what the loop sees (frames as JPEG, their times, the pose
                         samples as received, the rig and the DTM) as a recorded sequence in
                         DIR (app.record.dir; DIR must not exist or be empty); see
                         docs/field_data.md
  --no-dds               publish nothing over DDS (dds.enabled false)
  --threads N            perception threads, 1..16 (perception.threads)
  --backend NAME         inference backend of both networks: int8, fp32, opencv, int8-dnnl,
                         auto (perception.backend, default auto: int8-dnnl on CPUs with
                         VNNI, else int8; docs/inference.md)
  --pipeline off|on      off: one processing thread; on: the next frame's preprocess and
                         detector overlap this frame's crops, tracker and outputs on a second
                         processing thread, the same outputs (app.pipeline)
  --quiet                no periodic statistics line (the final summary is still printed)
  --help                 this text

Outputs: DDS topics <prefix>/vehicle_state (confirmed and lost tracks; deleted tracks are
disposed), <prefix>/drone_status, <prefix>/occupancy (docs/dds.md); the files above; one
statistics line on stderr every app.stats_period_s and a "summary:" line at the end.
Signals: SIGINT/SIGTERM stop cleanly (queued frames returned, DDS instances disposed, files
closed, a recording finished with its sequence.yaml). Under systemd (Type=notify) it reports READY, WATCHDOG, STATUS and STOPPING.
Exit status: 0 ok, 1 runtime error (start-up; no frame processed before the source ended;
a failed output or recording write; frames not returned), 2 usage or configuration error.
See docs/firmware_app.md.
)";
}

ParseOutcome parseCommandLine(int argc, const char* const* argv, CommandLine* out,
                              std::string* why) {
  CommandLine line;
  const auto fail = [&](const std::string& message) {
    if (why) {
      *why = message;
    }
    return ParseOutcome::UsageError;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const auto value = [&](std::string* text) {
      if (i + 1 >= argc || std::string_view(argv[i + 1]).empty()) {
        return false;
      }
      *text = argv[++i];
      return true;
    };
    std::string text;
    if (arg == "--help" || arg == "-h") {
      return ParseOutcome::Help;
    } else if (arg == "--fast") {
      line.fast = true;
    } else if (arg == "--every-frame") {
      line.everyFrame = true;
    } else if (arg == "--loop") {
      line.loop = true;
    } else if (arg == "--no-dds") {
      line.noDds = true;
    } else if (arg == "--quiet") {
      line.quiet = true;
    } else if (arg == "--config" || arg == "--sequence" || arg == "--camera" ||
               arg == "--camera-bus" || arg == "--trajectory-csv" || arg == "--detections-csv" ||
               arg == "--traffic-dir" || arg == "--annotated-video" || arg == "--record" ||
               arg == "--max-frames" || arg == "--threads" || arg == "--backend" ||
               arg == "--pipeline") {
      if (!value(&text)) {
        return fail(std::string(arg) + ": needs a value");
      }
      if (arg == "--config") {
        line.configPath = text;
      } else if (arg == "--sequence") {
        line.sequenceDir = text;
      } else if (arg == "--camera") {
        line.cameraDevice = text;
      } else if (arg == "--camera-bus") {
        line.cameraBus = text;
      } else if (arg == "--trajectory-csv") {
        line.trajectoryCsv = text;
      } else if (arg == "--detections-csv") {
        line.detectionsCsv = text;
      } else if (arg == "--traffic-dir") {
        line.trafficDir = text;
      } else if (arg == "--annotated-video") {
        line.annotatedVideo = text;
      } else if (arg == "--record") {
        line.recordDir = text;
      } else if (arg == "--max-frames") {
        if (!parseInteger(text, &line.maxFrames) || line.maxFrames < 0) {
          return fail("--max-frames: expected an integer >= 0, got '" + text + "'");
        }
      } else if (arg == "--pipeline") {
        if (text != "off" && text != "on") {
          return fail("--pipeline: expected off or on, got '" + text + "'");
        }
        line.pipeline = text == "on" ? config::PipelineMode::On : config::PipelineMode::Off;
      } else if (arg == "--backend") {
        line.backend = inference::backendFromString(text);
        if (!line.backend) {
          return fail("--backend: expected int8, fp32, opencv, int8-dnnl or auto, got '" + text +
                      "'");
        }
      } else {
        int threads = 0;
        if (!parseInteger(text, &threads) || threads < 1 || threads > kMaxThreads) {
          return fail("--threads: expected an integer in [1, 16], got '" + text + "'");
        }
        line.threads = threads;
      }
    } else {
      return fail("unknown option '" + std::string(arg) + "' (see --help)");
    }
  }
  if (line.configPath.empty()) {
    return fail("--config FILE is required (e.g. --config config/default.yaml)");
  }
  const int sources =
      (line.sequenceDir ? 1 : 0) + (line.cameraDevice ? 1 : 0) + (line.cameraBus ? 1 : 0);
  if (sources > 1) {
    return fail("--sequence, --camera and --camera-bus exclude each other");
  }
  if ((line.cameraDevice || line.cameraBus) && (line.fast || line.loop || line.everyFrame)) {
    return fail("--fast, --loop and --every-frame apply to a replayed sequence, not a camera");
  }
  *out = std::move(line);
  return ParseOutcome::Run;
}

void applyCommandLine(const CommandLine& line, config::AppConfig& config) {
  if (line.sequenceDir) {
    config.source.kind = config::FrameSourceKind::Replay;
    config.source.sequenceDir = absolute(*line.sequenceDir);
  }
  if (line.cameraDevice) {
    config.source.kind = config::FrameSourceKind::V4l2;
    config.source.v4l2.device = *line.cameraDevice;
    config.source.v4l2.busInfo.clear();
  }
  if (line.cameraBus) {
    config.source.kind = config::FrameSourceKind::V4l2;
    config.source.v4l2.busInfo = *line.cameraBus;
  }
  if (line.fast) {
    config.source.paced = false;
  }
  if (line.loop) {
    config.source.loop = true;
  }
  if (line.noDds) {
    config.dds.enabled = false;
  }
  if (line.threads) {
    // As perception.threads: the detector's and the preprocessing's threads.
    config.perception.detection.engine.threads = *line.threads;
    config.perception.preprocess.threads = *line.threads;
  }
  if (line.pipeline) {
    config.app.pipeline = *line.pipeline;
  }
  if (line.backend) {
    // As perception.backend: the detector's engine; the crop network follows it.
    config.perception.detection.engine.backend = *line.backend;
  }
  if (line.trajectoryCsv) {
    config.app.trajectoryCsv = absolute(*line.trajectoryCsv);
  }
  if (line.detectionsCsv) {
    config.app.detectionsCsv = absolute(*line.detectionsCsv);
  }
  if (line.trafficDir) {
    config.app.trafficDir = absolute(*line.trafficDir);
  }
  if (line.annotatedVideo) {
    config.app.annotatedVideo = absolute(*line.annotatedVideo);
  }
  if (line.recordDir) {
    config.app.record.dir = absolute(*line.recordDir);
  }
}

RunSettings runSettings(const CommandLine& line) {
  RunSettings run;
  run.maxFrames = line.maxFrames;
  run.everyFrame = line.everyFrame;
  run.quiet = line.quiet;
  return run;
}

std::string checkConsistency(const config::AppConfig& config) {
  const bool replay = config.source.kind == config::FrameSourceKind::Replay;
  if (replay && config.source.sequenceDir.empty()) {
    return "source.sequence_dir: no recorded sequence to replay (give --sequence DIR, or "
           "--camera /dev/videoN for a camera)";
  }
  const bool video = config.source.kind == config::FrameSourceKind::Video;
  if (video && config.source.video.path.empty()) {
    return "source.video.path: no video to replay";
  }
  if (!replay && !video && config.telemetry.source == config::TelemetrySourceKind::Recording) {
    return "telemetry.source: recording needs a replayed sequence or video; with a camera use "
           "mavlink_udp, mavlink_serial, dds or none";
  }
  // --pipeline on over a file's frame_pool_size sized for the serial loop.
  const int pool = config.app.framePoolSize;
  if (config.app.pipeline == config::PipelineMode::On && pool != 0 &&
      pool < config.app.queueDepth + 3) {
    return "app.frame_pool_size: must be 0 (automatic) or >= queue_depth + 3 (pipeline on) = " +
           std::to_string(config.app.queueDepth + 3) + ", got " + std::to_string(pool);
  }
  return "";
}

int runExitStatus(const LoopCounters& counters, bool stopRequested, std::size_t framesNotReturned,
                  std::size_t poolCapacity, std::string* why) {
  int status = kExitOk;
  std::string lines;
  if (framesNotReturned > 0) {
    lines += std::to_string(framesNotReturned) + " of " + std::to_string(poolCapacity) +
             " frames not returned to the pool\n";
    status = kExitRuntimeError;
  }
  if (counters.outputErrors > 0) {
    lines += std::to_string(counters.outputErrors) +
             " output write(s) failed (the first one of each file is logged above): the output "
             "files are incomplete\n";
    status = kExitRuntimeError;
  }
  if (counters.recordErrors > 0) {
    lines += std::to_string(counters.recordErrors) +
             " recording write(s) failed (logged above): the recording ended early\n";
    status = kExitRuntimeError;
  }
  if (counters.framesProcessed == 0 && !stopRequested) {
    lines += "no frame was processed (" + std::to_string(counters.framesIn) +
             " frames in: " + std::to_string(counters.badFrames) + " bad, " +
             std::to_string(counters.pipelineErrors) + " refused, " +
             std::to_string(counters.framesDropped) + " dropped)\n";
    status = kExitRuntimeError;
  }
  if (why != nullptr) {
    *why = lines;
  }
  return status;
}

}  // namespace vp::app
