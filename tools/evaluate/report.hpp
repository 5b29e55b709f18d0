// tools/evaluate/report: the evaluation report: Markdown and JSON text of the measures with
// seed 000's own figures beside them, and the cumulative histogram of |d_theta| as a PNG plot.
//
// Contract: reportMarkdown() and reportJson() are pure text builders (NaN -> "n/a" / null);
// writeOrientationPlot() draws the plot with OpenCV (axes, ticks, labels, our curve, the
// seed's approximate points) and writes it; writeReport() writes all three files into the
// output folder (created when missing). Errors name the file.
#pragma once

#include <string>
#include <vector>

#include "evaluation/measures.hpp"

namespace vp::evaluate {

// One input (sequence or image folder) and its own detection figures.
struct InputSummary {
  std::string label;
  std::string detectionsFile;
  std::string model;
  int skippedRows = 0;
  evaluation::EvaluationSummary summary;
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
};

std::string reportMarkdown(const ReportContext& context);
std::string reportJson(const ReportContext& context);
bool writeOrientationPlot(const evaluation::EvaluationSummary& summary, const std::string& path,
                          std::string* why);
bool writeReport(const ReportContext& context, const std::string& outDir, std::string* why);

}  // namespace vp::evaluate
