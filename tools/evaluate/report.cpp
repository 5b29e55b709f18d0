#include "report.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "evaluation/mot_metrics.hpp"
#include "evaluation/seed_reference.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::evaluate {
namespace {

namespace fs = std::filesystem;

enum class Unit { Count, Percent, Ratio, Metre, Degree, Pixel, MetrePerSecond };

// One measure of the report: its section, words, JSON key, value, unit and sample count.
struct Row {
  const char* section;
  std::string label;
  std::string key;
  double value;
  Unit unit;
  int samples = -1;  // -1: not applicable
};

std::string shortest(double value) {
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << value;
  return out.str();
}

std::string display(double value, Unit unit) {
  if (!std::isfinite(value)) {
    return "n/a";
  }
  switch (unit) {
    case Unit::Count:
      return std::to_string(static_cast<long long>(std::llround(value)));
    case Unit::Percent:
      return fixed(100.0 * value, 1) + " %";
    case Unit::Ratio:
      return fixed(value, 3);
    case Unit::Metre:
      return fixed(value, 3) + " m";
    case Unit::Degree:
      return fixed(value, 2) + " °";
    case Unit::Pixel:
      return fixed(value, 2) + " px";
    case Unit::MetrePerSecond:
      return fixed(value, 3) + " m/s";
  }
  return "n/a";
}

std::string jsonNumber(double value) {
  return std::isfinite(value) ? shortest(value) : "null";
}

std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          std::array<char, 8> hex{};
          std::snprintf(hex.data(), hex.size(), "\\u%04x", static_cast<unsigned>(c));
          out += hex.data();
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::vector<Row> measureRows(const ReportContext& context) {
  const evaluation::EvaluationSummary& s = context.total;
  const bool yolo = context.mode == "yolo";
  std::vector<Row> rows{
      {"Detection", "true positives", "tp", static_cast<double>(s.truePositives), Unit::Count},
      {"Detection", "false positives", "fp", static_cast<double>(s.falsePositives), Unit::Count},
      {"Detection", "false negatives", "fn", static_cast<double>(s.falseNegatives), Unit::Count},
      {"Detection", "precision", "precision", s.precision, Unit::Percent},
      {"Detection", "recall", "recall", s.recall, Unit::Percent},
      {"Detection", "F1", "f1", s.f1, Unit::Percent},
      {"Detection", "mean IoU of the matches", "mean_matched_iou", s.meanMatchedIou, Unit::Ratio,
       s.truePositives},
      {"Pose", "position error, median", "position_median_px", s.position_px.median, Unit::Pixel,
       s.position_px.count},
      {"Pose", "position error, MAD", "position_mad_px", s.position_px.mad, Unit::Pixel,
       s.position_px.count},
  };
  if (context.frameEdgeKnown) {
    // Sets differ in whether they label vehicles cut by the frame's border: the false boxes
    // reaching it, apart (the rule's precision stays the one above).
    const std::vector<Row> edge{
        {"Detection", "false positives at the frame edge (at_frame_edge)", "fp_at_frame_edge",
         static_cast<double>(s.falsePositivesAtFrameEdge), Unit::Count},
        {"Detection", "precision without them", "precision_inside", s.precisionInside,
         Unit::Percent},
    };
    const auto afterF1 =
        std::find_if(rows.begin(), rows.end(), [](const Row& row) { return row.key == "f1"; }) + 1;
    rows.insert(afterF1, edge.begin(), edge.end());
  }
  if (yolo) {
    // YOLO labels stop at the image's edge; the misses among vehicles cut by it, apart.
    rows.push_back({"Detection", "false negatives cut by the image border", "fn_cut_by_border",
                    static_cast<double>(s.falseNegativesCutByBorder), Unit::Count});
    return rows;
  }
  const std::vector<Row> more{
      {"Pose", "position error (px x GSD), median eps_mae^t", "position_median_m",
       s.position_m.median, Unit::Metre, s.position_m.count},
      {"Pose", "position error (px x GSD), MAD sigma_MAD^t", "position_mad_m", s.position_m.mad,
       Unit::Metre, s.position_m.count},
      {"Pose", "lifted world position error, median", "position_world_median_m",
       s.positionWorld_m.median, Unit::Metre, s.positionWorld_m.count},
      {"Pose", "lifted world position error, MAD", "position_world_mad_m", s.positionWorld_m.mad,
       Unit::Metre, s.positionWorld_m.count},
      {"Pose", "orientation error Δθ over 360°, median eps_mae^theta", "orientation_median_deg",
       s.orientation_deg.median, Unit::Degree, s.orientation_deg.count},
      {"Pose", "orientation error, MAD sigma_MAD^theta", "orientation_mad_deg",
       s.orientation_deg.mad, Unit::Degree, s.orientation_deg.count},
      {"Pose", "share of Δθ ≤ 10°", "orientation_share_below_10deg", s.shareBelow10_deg,
       Unit::Percent, s.orientation_deg.count},
      {"Pose", "share of Δθ > 90° (front/back swapped)", "orientation_flip_share", s.flipShare,
       Unit::Percent, s.orientation_deg.count},
      {"Pose", "axis error ignoring front/back, median", "axis_orientation_median_deg",
       s.axisOrientation_deg.median, Unit::Degree, s.axisOrientation_deg.count},
      {"Pose", "lifted world heading error, median", "heading_world_median_deg",
       s.headingWorld_deg.median, Unit::Degree, s.headingWorld_deg.count},
      {"Pose", "lifted world heading error, MAD", "heading_world_mad_deg", s.headingWorld_deg.mad,
       Unit::Degree, s.headingWorld_deg.count},
      {"Pose", "matches whose prediction has no known direction", "direction_unknown_count",
       static_cast<double>(s.directionUnknownPredictions), Unit::Count},
      {"Type", "matches with a known reference type", "type_count",
       static_cast<double>(s.typeSamples), Unit::Count},
      {"Type", "OA-1 (top-1 accuracy)", "type_oa1", s.typeOa1, Unit::Percent, s.typeSamples},
      {"Type", "OA-2 (reference among the top two)", "type_oa2", s.typeOa2, Unit::Percent,
       s.typeSamples},
  };
  rows.insert(rows.end(), more.begin(), more.end());
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    const evaluation::ClassScore& c = s.typeF1[static_cast<std::size_t>(t)];
    const std::string name = shape::toString(static_cast<shape::VehicleType>(t));
    rows.push_back({"Type", "F1 " + name, "type_f1_" + name, c.f1, Unit::Percent,
                    c.truePositives + c.falseNegatives});
  }
  const std::vector<Row> shapeRows{
      {"Shape", "matches where both have an ASM shape", "shape_count",
       static_cast<double>(s.shapeSamples), Unit::Count},
      {"Shape", "E_l: RMS length of the enclosing 3D box of M(gamma)", "rms_length_m",
       s.rmsLength_m, Unit::Metre, s.shapeSamples},
      {"Shape", "E_w: RMS width", "rms_width_m", s.rmsWidth_m, Unit::Metre, s.shapeSamples},
      {"Shape", "E_h: RMS height", "rms_height_m", s.rmsHeight_m, Unit::Metre, s.shapeSamples},
      {"Shape", "E_D2D: RMS planimetric keypoint distance (models in their image boxes)", "e_d2d_m",
       s.keypointsBox.planimetricRms_m, Unit::Metre, s.keypointsBox.vehicles},
      {"Shape", "E_dH: RMS keypoint height difference (models in their image boxes)", "e_dh_m",
       s.keypointsBox.heightRms_m, Unit::Metre, s.keypointsBox.vehicles},
      {"Shape", "E_D2D at the lifted world pose", "e_d2d_world_m",
       s.keypointsWorld.planimetricRms_m, Unit::Metre, s.keypointsWorld.vehicles},
      {"Shape", "E_dH at the lifted world pose", "e_dh_world_m", s.keypointsWorld.heightRms_m,
       Unit::Metre, s.keypointsWorld.vehicles},
      {"Shape", "E_D2D shape only (vehicle frame)", "e_d2d_vehicle_m",
       s.keypointsVehicle.planimetricRms_m, Unit::Metre, s.keypointsVehicle.vehicles},
      {"Shape", "E_dH shape only (vehicle frame)", "e_dh_vehicle_m", s.keypointsVehicle.heightRms_m,
       Unit::Metre, s.keypointsVehicle.vehicles},
      {"Shape", "lifted length vs reference, RMS", "lifted_rms_length_m", s.rmsLiftedLength_m,
       Unit::Metre, s.liftedDimensionSamples},
      {"Shape", "lifted width vs reference, RMS", "lifted_rms_width_m", s.rmsLiftedWidth_m,
       Unit::Metre, s.liftedDimensionSamples},
      {"Shape", "lifted height vs reference, RMS", "lifted_rms_height_m", s.rmsLiftedHeight_m,
       Unit::Metre, s.liftedDimensionSamples},
  };
  rows.insert(rows.end(), shapeRows.begin(), shapeRows.end());
  return rows;
}

std::string seedCell(const std::string& key, Unit unit) {
  const std::optional<evaluation::SeedFigure> figure = evaluation::seedFigure(key);
  if (!figure) {
    return "";
  }
  return (figure->approximate ? "≈ " : "") + display(figure->value, unit);
}

std::string seedSource(const std::string& key) {
  const std::optional<evaluation::SeedFigure> figure = evaluation::seedFigure(key);
  return figure ? std::string(figure->source) : std::string();
}

std::vector<Row> trackingRows(const evaluation::TrackingSummary& t) {
  const evaluation::MotSummary& m = t.mot;
  const char* mot = "Tracking";
  const char* versus = "Tracks vs detector";
  return {
      {mot, "MOTA = 1 − (misses + false positives + ID switches) / vehicle-frames", "mota", m.mota,
       Unit::Ratio, m.truthObjects},
      {mot, "MOTP: mean distance of the matched pairs", "motp_m", m.motp_m, Unit::Metre, m.matches},
      {mot, "IDF1 = 2 IDTP / (vehicle-frames + track-frames)", "idf1", m.idf1, Unit::Ratio},
      {mot, "ID precision", "id_precision", m.idPrecision, Unit::Ratio},
      {mot, "ID recall", "id_recall", m.idRecall, Unit::Ratio},
      {mot, "ID switches", "id_switches", static_cast<double>(m.idSwitches), Unit::Count},
      {mot, "fragmentations", "fragmentations", static_cast<double>(m.fragmentations), Unit::Count},
      {mot, "ground-truth vehicles", "truth_vehicles", static_cast<double>(m.truthTracks),
       Unit::Count},
      {mot, "mostly tracked (matched in ≥ 80 % of their frames)", "mostly_tracked",
       static_cast<double>(m.mostlyTracked), Unit::Count},
      {mot, "partially tracked", "partially_tracked", static_cast<double>(m.partiallyTracked),
       Unit::Count},
      {mot, "mostly lost (matched in ≤ 20 %)", "mostly_lost", static_cast<double>(m.mostlyLost),
       Unit::Count},
      {mot, "ground-truth vehicle-frames", "truth_objects", static_cast<double>(m.truthObjects),
       Unit::Count},
      {mot, "confirmed track-frames (hypotheses)", "hypotheses", static_cast<double>(m.hypotheses),
       Unit::Count},
      {mot, "matches", "matches", static_cast<double>(m.matches), Unit::Count},
      {mot, "misses", "misses", static_cast<double>(m.misses), Unit::Count},
      {mot, "false positives", "false_positives", static_cast<double>(m.falsePositives),
       Unit::Count},
      {mot, "ignored vehicle-frames (hardly visible, not counted)", "ignored_truth",
       static_cast<double>(t.ignoredTruth), Unit::Count},
      {mot, "track-frames on ignored vehicles (not counted)", "ignored_track_rows",
       static_cast<double>(t.ignoredTrackRows), Unit::Count},
      {mot, "confirmed tracks", "tracks", static_cast<double>(t.tracks), Unit::Count},
      {mot, "confirmed tracks never matched", "unmatched_tracks",
       static_cast<double>(t.unmatchedTracks), Unit::Count},
      {versus, "speed RMSE of moving vehicles", "speed_rmse_mps", t.speedRmse_mps,
       Unit::MetrePerSecond, t.speedSamples},
      {versus, "heading error > 90° on moving vehicles, tracks", "heading_flip_share_tracks",
       t.trackFlipShare, Unit::Percent, t.trackHeadingSamples},
      {versus, "heading error > 90° on moving vehicles, detector alone",
       "heading_flip_share_detector", t.detectorFlipShare, Unit::Percent, t.detectorHeadingSamples},
      {versus, "matched detections of moving vehicles without front/back",
       "detector_direction_unknown", static_cast<double>(t.detectorDirectionUnknown), Unit::Count},
      {versus, "type OA-1 per confirmed track", "type_oa1_per_track", t.trackTypeOa1, Unit::Percent,
       t.typedTracks},
      {versus, "type OA-1 per track-frame", "type_oa1_per_track_frame", t.trackFrameTypeOa1,
       Unit::Percent, t.trackFrameTypeSamples},
      {versus, "type OA-1 per frame, detector alone", "type_oa1_detector_per_frame",
       t.detectorTypeOa1, Unit::Percent, t.detectorTypeSamples},
      {versus, "lifted detections in the evaluated frames", "detections",
       static_cast<double>(t.detections), Unit::Count},
      {versus, "lifted detections matched to a vehicle", "detections_matched",
       static_cast<double>(t.detectionsMatched), Unit::Count},
  };
}

std::string samplesCell(int samples) {
  return samples >= 0 ? std::to_string(samples) : std::string();
}

// The tracks that carry most of the speed error: one badly tracked vehicle can decide the RMSE.
void writeLargestSpeedErrors(std::ostream& md, const ReportContext& context) {
  const evaluation::TrackingSummary& t = context.tracking;
  if (t.largestSpeedErrors.empty() || !(t.speedSquaredErrorSum > 0.0)) {
    return;
  }
  md << "\n### Largest speed errors (confirmed tracks on moving vehicles)\n\n"
        "| input | track | vehicle | type | moving track-frames | speed RMSE | share of the "
        "squared error | heading flips |\n| --- | ---: | ---: | --- | ---: | ---: | ---: | ---: "
        "|\n";
  for (const evaluation::TrackSpeedError& e : t.largestSpeedErrors) {
    const auto seq = static_cast<std::size_t>(e.sequence);
    const std::string label =
        seq < context.trackingInputs.size() ? context.trackingInputs[seq].label : "?";
    md << "| " << label << " | " << e.trackId << " | " << e.vehicleId << " | "
       << (e.vehicleType >= 0 ? shape::toString(static_cast<shape::VehicleType>(e.vehicleType))
                              : "unknown")
       << " | " << e.samples << " | "
       << display(std::sqrt(e.squaredErrorSum / e.samples), Unit::MetrePerSecond) << " | "
       << display(e.squaredErrorSum / t.speedSquaredErrorSum, Unit::Percent) << " | "
       << e.headingFlips << " |\n";
  }
}

std::string trackingMarkdown(const ReportContext& context) {
  const evaluation::TrackingSummary& t = context.tracking;
  const bool detector = t.detectorFrames > 0;
  std::ostringstream md;
  md << "\n## Tracking\n\n";
  md << "- hypotheses: the `confirmed` rows of the trajectory files (tentative and lost rows are "
        "not); truth: every ground-truth vehicle of each evaluated frame, except those with "
        "occlusion > "
     << shortest(context.maxOcclusion) << " or truncation > " << shortest(context.maxTruncation)
     << ": they and the tracks (detections) paired with them are ignored, neither misses nor "
        "false positives\n";
  md << "- matching: per frame in world ENU, footprint centres at most "
     << shortest(context.trackMatchDistance_m)
     << " m apart; last frame's pairs kept while within that distance, the rest by minimum "
        "total distance (CLEAR MOT); lifted detections matched the same way, without identity\n";
  md << "- moving: ground-truth speed > " << shortest(context.movingSpeed_mps)
     << " m/s; speed errors on |speed|; type per track: its last fused type vs the vehicle it "
        "was matched to in most frames\n";
  md << "- definitions: docs/evaluation.md (Tracking)\n\n";
  md << "| input | trajectory file | detections | frames | vehicle-frames | confirmed rows | "
        "tentative / lost rows | confirmed tracks | MOTA | IDF1 | ID switches | speed RMSE |\n"
        "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const TrackingInputSummary& input : context.trackingInputs) {
    const evaluation::TrackingSummary& e = input.summary;
    md << "| " << input.label << " | " << input.tracksFile << " | " << input.detectionsFile << " | "
       << input.frames << " | " << e.mot.truthObjects << " | " << input.confirmedRows << " | "
       << input.tentativeRows << " / " << input.lostRows << " | " << e.tracks << " | "
       << display(e.mot.mota, Unit::Ratio) << " | " << display(e.mot.idf1, Unit::Ratio) << " | "
       << e.mot.idSwitches << " | " << display(e.speedRmse_mps, Unit::MetrePerSecond) << " |\n";
    if (input.skippedRows > 0) {
      md << "| | " << input.skippedRows
         << " trajectory rows outside the evaluated frames skipped | | | | | | | | | | |\n";
    }
  }
  const std::vector<Row> rows = trackingRows(t);
  md << "\n### Multi-object tracking (CLEAR MOT, identity)\n\n| measure | value | n |\n"
        "| --- | ---: | ---: |\n";
  for (const Row& row : rows) {
    if (std::string(row.section) == "Tracking") {
      md << "| " << row.label << " | " << display(row.value, row.unit) << " | "
         << samplesCell(row.samples) << " |\n";
    }
  }
  const std::string none = detector ? "" : "n/a (no --detections)";
  const auto detectorCell = [&](double value, Unit unit) {
    return detector ? display(value, unit) : none;
  };
  md << "\n### Tracks beside the detector alone (moving: ground truth > "
     << shortest(context.movingSpeed_mps) << " m/s)\n\n"
     << "| measure | tracks | n | detector alone | n |\n| --- | ---: | ---: | ---: | ---: |\n";
  md << "| speed RMSE of moving vehicles | " << display(t.speedRmse_mps, Unit::MetrePerSecond)
     << " | " << t.speedSamples << " | | |\n";
  md << "| heading error > 90° on moving vehicles (front/back swapped) | "
     << display(t.trackFlipShare, Unit::Percent) << " | " << t.trackHeadingSamples << " | "
     << detectorCell(t.detectorFlipShare, Unit::Percent) << " | "
     << (detector ? std::to_string(t.detectorHeadingSamples) : std::string()) << " |\n";
  md << "| type OA-1: tracks per confirmed track, detector per frame | "
     << display(t.trackTypeOa1, Unit::Percent) << " | " << t.typedTracks << " | "
     << detectorCell(t.detectorTypeOa1, Unit::Percent) << " | "
     << (detector ? std::to_string(t.detectorTypeSamples) : std::string()) << " |\n";
  md << "| type OA-1 per track-frame | " << display(t.trackFrameTypeOa1, Unit::Percent) << " | "
     << t.trackFrameTypeSamples << " | | |\n";
  writeLargestSpeedErrors(md, context);
  if (detector) {
    md << "\nDetector alone: " << t.detections << " lifted detections in the evaluated frames, "
       << t.detectionsMatched << " matched to a vehicle; " << t.detectorDirectionUnknown
       << " matched detections of moving vehicles without a known front/back are left out of "
          "the flip share.\n";
  }
  return md.str();
}

// The "measures" object (every row) and the "samples" object (the rows that count samples) of
// a JSON object whose members stand at `indent`: one member a line, nested one level deeper.
void writeMeasuresAndSamples(std::ostream& js, const std::vector<Row>& rows,
                             const std::string& indent) {
  const std::string inner = indent + "  ";
  js << "\"measures\": {";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    js << (i == 0 ? "\n" : ",\n") << inner << jsonString(rows[i].key) << ": "
       << jsonNumber(rows[i].value);
  }
  js << "\n" << indent << "},\n" << indent << "\"samples\": {";
  bool first = true;
  for (const Row& row : rows) {
    if (row.samples >= 0) {
      js << (first ? "\n" : ",\n") << inner << jsonString(row.key) << ": " << row.samples;
      first = false;
    }
  }
  js << "\n" << indent << "}";
}

std::string trackingJson(const ReportContext& context) {
  const std::vector<Row> rows = trackingRows(context.tracking);
  std::ostringstream js;
  js << "{\n    \"match_distance_m\": " << jsonNumber(context.trackMatchDistance_m)
     << ",\n    \"moving_speed_mps\": " << jsonNumber(context.movingSpeed_mps)
     << ",\n    \"detector\": " << (context.tracking.detectorFrames > 0 ? "true" : "false")
     << ",\n    ";
  writeMeasuresAndSamples(js, rows, "    ");
  js << ",\n    \"inputs\": [";
  for (std::size_t i = 0; i < context.trackingInputs.size(); ++i) {
    const TrackingInputSummary& in = context.trackingInputs[i];
    const evaluation::TrackingSummary& e = in.summary;
    js << (i == 0 ? "\n" : ",\n") << "      {\"input\": " << jsonString(in.label)
       << ", \"tracks\": " << jsonString(in.tracksFile)
       << ", \"detections\": " << jsonString(in.detectionsFile) << ", \"frames\": " << in.frames
       << ", \"confirmed_rows\": " << in.confirmedRows
       << ", \"tentative_rows\": " << in.tentativeRows << ", \"lost_rows\": " << in.lostRows
       << ", \"skipped_rows\": " << in.skippedRows << ", \"mota\": " << jsonNumber(e.mot.mota)
       << ", \"idf1\": " << jsonNumber(e.mot.idf1) << ", \"id_switches\": " << e.mot.idSwitches
       << ", \"speed_rmse_mps\": " << jsonNumber(e.speedRmse_mps) << "}";
  }
  js << "\n    ],\n    \"largest_speed_errors\": [";
  const evaluation::TrackingSummary& t = context.tracking;
  for (std::size_t i = 0; i < t.largestSpeedErrors.size(); ++i) {
    const evaluation::TrackSpeedError& e = t.largestSpeedErrors[i];
    const auto seq = static_cast<std::size_t>(e.sequence);
    js << (i == 0 ? "\n" : ",\n") << "      {\"input\": "
       << jsonString(seq < context.trackingInputs.size() ? context.trackingInputs[seq].label : "")
       << ", \"track_id\": " << e.trackId << ", \"vehicle_id\": " << e.vehicleId
       << ", \"vehicle_type\": " << e.vehicleType << ", \"samples\": " << e.samples
       << ", \"squared_error_sum\": " << jsonNumber(e.squaredErrorSum)
       << ", \"heading_flips\": " << e.headingFlips << "}";
  }
  js << (t.largestSpeedErrors.empty() ? "]" : "\n    ]") << "\n  }";
  return js.str();
}

}  // namespace

std::string reportMarkdown(const ReportContext& context) {
  const evaluation::EvaluationSummary& s = context.total;
  const bool yolo = context.mode == "yolo";
  std::ostringstream md;
  md << "# Evaluation report\n\n";
  md << "- command: `" << context.commandLine << "`\n";
  if (context.hasDetections) {
    md << "- model: " << context.modelId << "\n";
    md << "- data: " << s.images << (yolo ? " images" : " frames") << ", " << s.references
       << " reference vehicles (" << s.ignoredReferences << " ignored), " << s.predictions
       << " predictions (" << s.ignoredPredictions << " on ignored references)\n";
    if (yolo) {
      md << "- matching: greedy by score, axis-aligned IoU >= " << shortest(context.iouThreshold)
         << " between the box enclosing each rotated prediction and the YOLO box; "
         << (context.valList.empty() ? std::string("all images of the folder (no --val-list: "
                                                   "not a held-out split)")
                                     : "validation images of " + context.valList)
         << "\n";
    } else {
      md << "- matching: greedy by score, rotated IoU >= " << shortest(context.iouThreshold)
         << " (seed 000, sec. 5.1); references with occlusion > " << shortest(context.maxOcclusion)
         << " or truncation > " << shortest(context.maxTruncation)
         << " are ignored (a prediction on them is neither TP nor FP)\n";
      md << "- shape model: " << (context.asmPath.empty() ? "none" : context.asmPath) << "\n";
    }
    md << "- definitions: docs/evaluation.md. Seed figures: seed 000, UAV data set (3 cm GSD), "
          "variant V_L1 — their data, not ours: a yardstick.\n\n";

    md << "## Inputs\n\n| input | detections | model | " << (yolo ? "images" : "frames")
       << " | references | predictions | TP | FP | FN | precision | recall | F1 |\n"
          "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for (const InputSummary& input : context.inputs) {
      const evaluation::EvaluationSummary& e = input.summary;
      md << "| " << input.label << " | " << input.detectionsFile << " | " << input.model << " | "
         << e.images << " | " << e.references << " | " << e.predictions << " | " << e.truePositives
         << " | " << e.falsePositives << " | " << e.falseNegatives << " | "
         << display(e.precision, Unit::Percent) << " | " << display(e.recall, Unit::Percent)
         << " | " << display(e.f1, Unit::Percent) << " |\n";
      if (input.skippedRows > 0) {
        md << "| | " << input.skippedRows
           << " detection rows outside the evaluated frames/images skipped | | | | | | | | | | |\n";
      }
    }
    const char* section = "";
    for (const Row& row : measureRows(context)) {
      if (std::string(section) != row.section) {
        section = row.section;
        md << "\n## " << section << "\n\n| measure | ours | n | seed 000 | seed source |\n"
           << "| --- | ---: | ---: | ---: | --- |\n";
      }
      md << "| " << row.label << " | " << display(row.value, row.unit) << " | "
         << (row.samples >= 0 ? std::to_string(row.samples) : std::string()) << " | "
         << seedCell(row.key, row.unit) << " | " << seedSource(row.key) << " |\n";
    }
    if (!yolo) {
      md << "\n## Type confusion (rows: reference, columns: top-1 prediction)\n\n| |";
      for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
        md << " " << shape::toString(static_cast<shape::VehicleType>(t)) << " |";
      }
      md << "\n| --- |";
      for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
        md << " ---: |";
      }
      md << "\n";
      for (int r = 0; r < shape::kVehicleTypeCount; ++r) {
        md << "| " << shape::toString(static_cast<shape::VehicleType>(r)) << " |";
        for (int c = 0; c < shape::kVehicleTypeCount; ++c) {
          md << " " << s.confusion[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)]
             << " |";
        }
        md << "\n";
      }
      md << "\n## Cumulative histogram of the absolute orientation errors Δθ (seed 000, Figure "
            "2)\n\n"
            "![cumulative histogram of the orientation errors](orientation_cdf.png)\n\n"
            "| Δθ ≤ | 2° | 5° | 10° | 20° | 45° | 90° | 170° |\n"
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n| share |";
      for (const int deg : {2, 5, 10, 20, 45, 90, 170}) {
        const double share = s.orientationCumulative.empty()
                                 ? std::numeric_limits<double>::quiet_NaN()
                                 : s.orientationCumulative[static_cast<std::size_t>(deg)];
        md << " " << display(share, Unit::Percent) << " |";
      }
      md << "\n";
    }
  }
  if (context.hasTracking) {
    md << trackingMarkdown(context);
  }
  return md.str();
}

std::string reportJson(const ReportContext& context) {
  const evaluation::EvaluationSummary& s = context.total;
  std::ostringstream js;
  js << "{\n  \"format\": \"vp_evaluate report 1\",\n";
  js << "  \"command_line\": " << jsonString(context.commandLine) << ",\n";
  js << "  \"model\": " << jsonString(context.modelId) << ",\n";
  js << "  \"mode\": " << jsonString(context.mode) << ",\n";
  js << "  \"asm\": " << jsonString(context.asmPath) << ",\n";
  js << "  \"val_list\": " << jsonString(context.valList) << ",\n";
  js << "  \"iou_threshold\": " << jsonNumber(context.iouThreshold) << ",\n";
  js << "  \"max_occlusion\": " << jsonNumber(context.maxOcclusion) << ",\n";
  js << "  \"max_truncation\": " << jsonNumber(context.maxTruncation);
  if (context.hasDetections) {
    js << ",\n";
    js << "  \"counts\": {\"images\": " << s.images << ", \"references\": " << s.references
       << ", \"ignored_references\": " << s.ignoredReferences
       << ", \"predictions\": " << s.predictions
       << ", \"ignored_predictions\": " << s.ignoredPredictions << "},\n";
    const std::vector<Row> rows = measureRows(context);
    js << "  ";
    writeMeasuresAndSamples(js, rows, "  ");
    js << ",\n  \"seed\": {";
    bool first = true;
    for (const Row& row : rows) {
      if (const auto figure = evaluation::seedFigure(row.key)) {
        js << (first ? "\n" : ",\n") << "    " << jsonString(row.key)
           << ": {\"value\": " << jsonNumber(figure->value)
           << ", \"source\": " << jsonString(std::string(figure->source))
           << ", \"approximate\": " << (figure->approximate ? "true" : "false") << "}";
        first = false;
      }
    }
    js << "\n  },\n  \"type_confusion\": [";
    for (int r = 0; r < shape::kVehicleTypeCount; ++r) {
      js << (r == 0 ? "" : ", ") << "[";
      for (int c = 0; c < shape::kVehicleTypeCount; ++c) {
        js << (c == 0 ? "" : ", ")
           << s.confusion[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
      }
      js << "]";
    }
    js << "],\n  \"orientation_cumulative\": [";
    for (std::size_t i = 0; i < s.orientationCumulative.size(); ++i) {
      js << (i == 0 ? "" : ", ") << jsonNumber(s.orientationCumulative[i]);
    }
    js << "],\n  \"inputs\": [";
    for (std::size_t i = 0; i < context.inputs.size(); ++i) {
      const InputSummary& in = context.inputs[i];
      const evaluation::EvaluationSummary& e = in.summary;
      js << (i == 0 ? "\n" : ",\n") << "    {\"input\": " << jsonString(in.label)
         << ", \"detections\": " << jsonString(in.detectionsFile)
         << ", \"model\": " << jsonString(in.model) << ", \"skipped_rows\": " << in.skippedRows
         << ", \"images\": " << e.images << ", \"references\": " << e.references
         << ", \"predictions\": " << e.predictions << ", \"tp\": " << e.truePositives
         << ", \"fp\": " << e.falsePositives << ", \"fn\": " << e.falseNegatives
         << ", \"precision\": " << jsonNumber(e.precision)
         << ", \"recall\": " << jsonNumber(e.recall) << ", \"f1\": " << jsonNumber(e.f1) << "}";
    }
    js << "\n  ]";
  }
  if (context.hasTracking) {
    js << ",\n  \"tracking\": " << trackingJson(context);
  }
  js << "\n}\n";
  return js.str();
}

bool writeOrientationPlot(const evaluation::EvaluationSummary& summary, const std::string& path,
                          std::string* why) {
  constexpr int kWidth = 720;
  constexpr int kHeight = 460;
  constexpr int kLeft = 70;  // plot area margins, px
  constexpr int kRight = 20;
  constexpr int kTop = 40;
  constexpr int kBottom = 60;
  const cv::Scalar black(0, 0, 0);
  const cv::Scalar grey(215, 215, 215);
  const cv::Scalar blue(200, 90, 20);
  const cv::Scalar red(40, 40, 220);
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const int plotWidth = kWidth - kLeft - kRight;
  const int plotHeight = kHeight - kTop - kBottom;
  const auto toPixel = [&](double deg, double share) {
    return cv::Point(kLeft + static_cast<int>(std::lround(deg / 180.0 * plotWidth)),
                     kTop + plotHeight - static_cast<int>(std::lround(share * plotHeight)));
  };
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (int deg = 0; deg <= 180; deg += 30) {
    cv::line(image, toPixel(deg, 0), toPixel(deg, 1), grey, 1);
    const std::string text = std::to_string(deg);
    cv::putText(image, text, toPixel(deg, 0) + cv::Point(-4 * static_cast<int>(text.size()), 20),
                font, 0.45, black, 1, cv::LINE_AA);
  }
  for (int percent = 0; percent <= 100; percent += 20) {
    cv::line(image, toPixel(0, percent / 100.0), toPixel(180, percent / 100.0), grey, 1);
    cv::putText(image, std::to_string(percent), toPixel(0, percent / 100.0) + cv::Point(-35, 5),
                font, 0.45, black, 1, cv::LINE_AA);
  }
  cv::rectangle(image, toPixel(0, 1), toPixel(180, 0), black, 1);
  cv::putText(image, "|d_theta| [deg]", cv::Point(kLeft + plotWidth / 2 - 60, kHeight - 15), font,
              0.55, black, 1, cv::LINE_AA);
  cv::putText(image, "share [%]", cv::Point(5, kTop - 12), font, 0.5, black, 1, cv::LINE_AA);
  cv::putText(image,
              "Cumulative histogram of orientation errors (n = " +
                  std::to_string(summary.orientation_deg.count) + ")",
              cv::Point(kLeft + 40, kTop - 14), font, 0.5, black, 1, cv::LINE_AA);
  // Our curve: share of errors <= x, a step function through the sorted errors.
  const std::vector<double>& errors = summary.orientationErrors_deg;
  if (!errors.empty()) {
    std::vector<cv::Point> curve{toPixel(0, 0)};
    const double n = static_cast<double>(errors.size());
    for (std::size_t i = 0; i < errors.size(); ++i) {
      curve.push_back(toPixel(errors[i], static_cast<double>(i) / n));
      curve.push_back(toPixel(errors[i], static_cast<double>(i + 1) / n));
    }
    curve.push_back(toPixel(180, 1));
    cv::polylines(image, curve, false, blue, 2, cv::LINE_AA);
  }
  // The seed's two figures read from its text (V_L1): ~85 % below 10 deg, ~5 % near 180 deg.
  const auto below10 = evaluation::seedFigure("orientation_share_below_10deg");
  const auto flips = evaluation::seedFigure("orientation_flip_share");
  if (below10 && flips) {
    for (const cv::Point& p : {toPixel(10, below10->value), toPixel(170, 1.0 - flips->value)}) {
      cv::drawMarker(image, p, red, cv::MARKER_DIAMOND, 12, 2);
    }
  }
  cv::line(image, cv::Point(kLeft + plotWidth - 285, kTop + plotHeight - 45),
           cv::Point(kLeft + plotWidth - 255, kTop + plotHeight - 45), blue, 2);
  cv::putText(image, "ours", cv::Point(kLeft + plotWidth - 247, kTop + plotHeight - 40), font, 0.45,
              black, 1, cv::LINE_AA);
  cv::drawMarker(image, cv::Point(kLeft + plotWidth - 270, kTop + plotHeight - 22), red,
                 cv::MARKER_DIAMOND, 10, 2);
  cv::putText(image, "seed 000 V_L1 (text, approx.)",
              cv::Point(kLeft + plotWidth - 247, kTop + plotHeight - 17), font, 0.45, black, 1,
              cv::LINE_AA);
  try {
    if (!cv::imwrite(path, image)) {
      *why = path + ": cannot write the plot";
      return false;
    }
  } catch (const cv::Exception& error) {
    *why = path + ": cannot write the plot: " + error.what();
    return false;
  }
  return true;
}

bool writeReport(const ReportContext& context, const std::string& outDir, std::string* why) {
  std::error_code error;
  fs::create_directories(outDir, error);
  if (error || !fs::is_directory(outDir)) {
    *why = outDir + ": cannot create the output folder" +
           (error ? ": " + error.message() : std::string());
    return false;
  }
  const auto writeText = [&](const std::string& name, const std::string& text) {
    const fs::path path = fs::path(outDir) / name;
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file << text;
    file.close();
    if (!file) {
      *why = path.string() + ": cannot write";
      return false;
    }
    return true;
  };
  if (!writeText("report.md", reportMarkdown(context)) ||
      !writeText("report.json", reportJson(context))) {
    return false;
  }
  if (context.hasDetections && context.mode != "yolo") {
    return writeOrientationPlot(context.total, (fs::path(outDir) / "orientation_cdf.png").string(),
                                why);
  }
  return true;
}

}  // namespace vp::evaluate
