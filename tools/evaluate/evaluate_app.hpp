// tools/evaluate/evaluate_app: the vp_evaluate command (docs/evaluation.md). It reads recorded
// sequences with ground truth and the detections files run on them (or a YOLO image folder
// with its detections file), computes every measure of seed 000, section 5.1 with
// src/evaluation/evaluation, and writes report.md, report.json and orientation_cdf.png to an output
// folder, with the seed's own figures beside ours. Given the trajectory files of the tracker
// (--tracks), it adds the tracking measures (MOTA, IDF1, speed, heading flips, type per track)
// beside the detector's own figures where a detections file is given too.
//
// Contract: parseArguments() turns the command line into EvaluateOptions or a clear error;
// loadSequenceImages() / loadYoloImages() build the per-image references and predictions
// (every frame of a sequence is evaluated, so frames without detections count their
// references as missed); loadSequenceTracking() builds the per-frame truth, confirmed tracks
// and lifted detections; runEvaluate() does the whole job and returns the process exit code
// (0 success, 1 bad input, 2 usage). Offline tool: it allocates, reads files, may throw inside
// and reports every failure as a message naming the file (and line) at fault.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "evaluation/measures.hpp"
#include "evaluation/tracking_measures.hpp"

namespace vp::evaluate {

struct SequenceInput {
  std::string sequenceDir;
  std::string detectionsFile;  // empty: no detection measures for this input
  std::string tracksFile;      // empty: no tracking measures for this input
};

struct EvaluateOptions {
  std::vector<SequenceInput> sequences;  // --sequence with its --detections / --tracks, in order
  std::string yoloDir;                   // --yolo (then exactly one --detections)
  std::string valList;                   // --val-list: stems of the validation images
  std::string outDir;
  std::string asmPath;  // --asm; default: models/asm/default_asm.yaml of the source tree
  double iouThreshold = evaluation::kDefaultIouThreshold;
  double maxOcclusion = 0.7;   // references above are `ignore` (as tools/detector/datasets.py)
  double maxTruncation = 0.5;  // references above are `ignore`
  std::optional<std::int64_t> firstFrame;  // --frames A:B (inclusive frame ids)
  std::optional<std::int64_t> lastFrame;
  double trackMatchDistance_m = evaluation::kDefaultTrackMatchDistance_m;  // --track-gate
  double movingSpeed_mps = evaluation::kDefaultMovingSpeed_mps;            // --moving-speed
  std::string modelId;      // --model-id; default: the detections files' "# model:" line
  std::string commandLine;  // as typed, for the report
  bool help = false;
};

std::string usage();
bool parseArguments(std::span<const std::string> args, EvaluateOptions* options, std::string* why);

// One evaluated image: its references and predictions.
struct ImageData {
  std::string name;  // "<sequence>:<frame_id>" or the image stem
  std::vector<evaluation::ReferenceObject> references;
  std::vector<evaluation::PredictedObject> predictions;
};

struct LoadedInput {
  std::string label;  // sequence directory or YOLO folder
  std::string detectionsFile;
  std::string model;      // the detections file's "# model:" line
  int formatVersion = 0;  // the detections file's (2: with at_frame_edge)
  std::vector<ImageData> images;
  int skippedRows = 0;  // detection rows outside the evaluated frames / validation images
};

bool loadSequenceImages(const SequenceInput& input, const EvaluateOptions& options,
                        LoadedInput* out, std::string* why);
bool loadYoloImages(const EvaluateOptions& options, LoadedInput* out, std::string* why);
// One frame of a sequence for the tracking measures.
struct TrackingFrame {
  std::int64_t frameId = 0;
  std::vector<evaluation::TruthVehicle> truth;               // every ground-truth vehicle
  std::vector<evaluation::TrackObservation> tracks;          // the confirmed rows
  std::vector<evaluation::DetectionObservation> detections;  // lifted rows (detections file)
};

struct LoadedTracking {
  std::string label;  // sequence directory
  std::string tracksFile;
  std::string detectionsFile;  // empty: no detector-alone figures
  std::vector<TrackingFrame> frames;
  int confirmedRows = 0;       // rows used (inside the evaluated frames)
  int tentativeRows = 0;       // not hypotheses
  int lostRows = 0;            // not hypotheses
  int skippedRows = 0;         // rows outside --frames
  int unliftedDetections = 0;  // detection rows without a world position
};

bool loadSequenceTracking(const SequenceInput& input, const EvaluateOptions& options,
                          LoadedTracking* out, std::string* why);
// Validation stems: a text file (one stem or file name per line, '#' comments) or a JSON
// file with a "val_stems" array (train.py's split.json once it lists them).
bool readValidationList(const std::string& path, std::vector<std::string>* stems, std::string* why);

int runEvaluate(const EvaluateOptions& options, std::ostream& out, std::ostream& err);

}  // namespace vp::evaluate
