// tools/evaluate/report: the evaluation report: Markdown and JSON text of the measures with
// seed 000's own figures beside them, and the cumulative histogram of |d_theta| as a PNG plot;
// the tracking measures, when trajectory files were given, in their own section with the
// detector's own figures beside the tracks'.
//
// Contract: reportMarkdown() and reportJson() are pure text builders (NaN -> "n/a" / null);
// writeOrientationPlot() draws the plot with OpenCV (axes, ticks, labels, our curve, the
// seed's approximate points) and writes it; writeReport() writes all three files into the
// output folder (created when missing). Errors name the file.
#pragma once

#include <string>
#include <vector>

#include "evaluation/measures.hpp"
#include "evaluation/tracking_measures.hpp"

namespace vp::evaluate {

// One input (sequence or image folder) and its own detection figures.
struct InputSummary {
  std::string label;
  std::string detectionsFile;
  std::string model;
  int skippedRows = 0;
  evaluation::EvaluationSummary summary;
};

// One sequence and its own tracking figures.
struct TrackingInputSummary {
  std::string label;
  std::string tracksFile;
  std::string detectionsFile;  // empty: no detector-alone figures
  int frames = 0;
  int confirmedRows = 0;
  int tentativeRows = 0;
  int lostRows = 0;
  int skippedRows = 0;  // outside --frames
  evaluation::TrackingSummary summary;
};

struct ReportContext {
  std::string commandLine;
  std::string modelId;
  std::string mode;     // "sequences" (rotated boxes) or "yolo" (axis-aligned)
  std::string asmPath;  // empty: no shape measures
  double iouThreshold = 0.5;
  double maxOcclusion = 0.7;
  double maxTruncation = 0.5;
  std::string valList;  // yolo mode
  std::vector<InputSummary> inputs;
  evaluation::EvaluationSummary total;
  bool hasDetections = true;    // detection sections (inputs with --detections)
  bool frameEdgeKnown = false;  // every detections file says which boxes reach the frame edge
  bool hasTracking = false;     // tracking section (inputs with --tracks)
  double trackMatchDistance_m = evaluation::kDefaultTrackMatchDistance_m;
  double movingSpeed_mps = evaluation::kDefaultMovingSpeed_mps;
  std::vector<TrackingInputSummary> trackingInputs;
  evaluation::TrackingSummary tracking;
};

std::string reportMarkdown(const ReportContext& context);
std::string reportJson(const ReportContext& context);
bool writeOrientationPlot(const evaluation::EvaluationSummary& summary, const std::string& path,
                          std::string* why);
bool writeReport(const ReportContext& context, const std::string& outDir, std::string* why);

}  // namespace vp::evaluate
