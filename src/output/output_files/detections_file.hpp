// output_files/detections_file: the detections file, one CSV row per detection per frame (or per
// image), which the perception runner writes and the evaluation tool (vp_evaluate) reads. The
// format is documented in docs/detections_file.md.
//
// Contract: DetectionRecord is a plain fixed-size value (no heap) holding everything a row
// says: the image rotated box, score, driving-direction flag, whether the box reaches the
// frame's border and the verifier's vehicle probability, the 7 type probabilities, the ASM
// gamma and, when lifting succeeded (liftStatus Ok), the world pose and size. The writer
// writes format 2; the reader also reads format 1 (without the border flag and verifier). The
// writer is made for the real-time loop: open() allocates once (row and pending-row buffers) and
// checks the path; writeRow() formats a row with std::to_chars into the preallocated buffer and
// adds it to the pending rows, commit() writes them to the file with one write(2) (the loop commits
// every frame, so a kill loses at most the frame being written and never leaves half a row),
// allocating nothing and returning errors as values when they happen (never throwing);
// close() commits and reports I/O errors (csv::CsvFileWriter). Numbers are written in the shortest
// form that reads back to the same value, so a write/read round trip is exact. readDetectionsFile()
// is an offline (start-up) reader: it checks every field and reports the first problem as
// "<file>:<line>:<column>: <field>: <problem>" (column = 1-based character position of the
// field in the line). The `type` column is the most probable type of the probabilities
// (ties: the first in shape::VehicleType order); the reader rejects a row where it is not.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "csv/csv_io.hpp"
#include "geometry/rotated_box.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::output_files {

constexpr int kDetectionsFormatVersion = 2;        // what the writer writes
constexpr int kOldestDetectionsFormatVersion = 1;  // the reader reads this one up
constexpr std::size_t kMaxImageStemChars = 127;    // longest `image` key (file stem), bytes

// What became of lifting a detection to the world; the file writes the word of toString().
// The same cases as perception::LiftStatus, plus NotLifted for runs without lifting.
enum class LiftStatus : std::uint8_t {
  Ok,              // "ok": east_m ... height_m_vehicle are set
  NotLifted,       // "not_lifted": lifting was not run (image-only runs, real images)
  NoPose,          // "no_pose": no telemetry around the frame's time
  StalePose,       // "stale_pose": the nearest telemetry is too old
  InvalidPose,     // "invalid_pose": NaN / out-of-range pose
  InvalidBox,      // "invalid_box": the box is not finite or has a size <= 0
  OutsideLens,     // "outside_lens": the box lies beyond the lens model's valid field
  BehindCamera,    // "behind_camera"
  OutsideDtm,      // "outside_dtm": the viewing ray misses the DTM
  NoData,          // "no_data": the DTM has no data where the ray meets it
  NoIntersection,  // "no_intersection": the ray does not meet the terrain
};
constexpr int kLiftStatusCount = 11;
const char* toString(LiftStatus status);
std::optional<LiftStatus> liftStatusFromString(std::string_view word);

// Which key the first column holds: frame_id (recorded sequences) or image (a folder of
// images such as a YOLO data set, the key being the file stem).
enum class DetectionsKey : std::uint8_t { FrameId, Image };

struct DetectionsFileInfo {
  DetectionsKey key = DetectionsKey::FrameId;
  int gammaColumns = 3;  // gamma_0 .. gamma_{n-1}, 0 .. shape::kMaxShapeComponents
  std::string model;     // "# model: ..." metadata line (free text, optional)
  std::string source;    // "# source: ..." metadata line: what the detections were run on
};

struct DetectionRecord {
  std::int64_t frameId = 0;                          // key DetectionsKey::FrameId, >= 0
  std::array<char, kMaxImageStemChars + 1> image{};  // key DetectionsKey::Image, NUL-terminated
  int detId = 0;                                     // >= 0, unique within a frame / image
  float score = 0.0F;                                // [0, 1]
  geometry::RotatedBox box{};                        // image px, docs/conventions.md
  bool directionKnown = false;                       // box.angle is the driving direction
  // Format 2 (a format 1 file reads as false / NaN):
  bool atFrameEdge = false;  // the box reaches the frame's border: the vehicle may be cut there
  float vehicleProbability = std::numeric_limits<float>::quiet_NaN();  // verifier, [0, 1]; NaN:
                                                                       // none ran (empty field)
  std::array<float, shape::kVehicleTypeCount> typeProbabilities{};     // index = VehicleType
  shape::ShapeParams gamma{};  // count <= the file's gammaColumns (0 = no shape)
  LiftStatus liftStatus = LiftStatus::NotLifted;
  // Valid when liftStatus == Ok (written as empty fields otherwise):
  Eigen::Vector3d positionEnu{0, 0, 0};  // east_m, north_m, up_m: world ENU of the rig origin
  double latitude_deg = 0.0;             // WGS84
  double longitude_deg = 0.0;
  double height_m = 0.0;                  // ellipsoidal height of the position, m
  double headingEnu_rad = 0.0;            // driving direction, counter-clockwise from east
  Eigen::Vector3d dimensions_m{0, 0, 0};  // length_m, width_m, height_m_vehicle

  std::string_view imageStem() const;
  bool setImageStem(std::string_view stem);  // false when longer than kMaxImageStemChars
  // The most probable type (ties: the first in VehicleType order).
  shape::VehicleType topType() const;
};

// The column names of a file with this key, gamma count and format, in order.
std::vector<std::string> detectionsColumns(DetectionsKey key, int gammaColumns,
                                           int formatVersion = kDetectionsFormatVersion);

class DetectionsFileWriter {
 public:
  DetectionsFileWriter();
  ~DetectionsFileWriter();  // closes an open file, dropping errors
  DetectionsFileWriter(const DetectionsFileWriter&) = delete;
  DetectionsFileWriter& operator=(const DetectionsFileWriter&) = delete;

  // Creates (truncates) the file and writes the metadata lines and the header. Start-up.
  bool open(const std::string& path, const DetectionsFileInfo& info, std::string* why);
  // One row; checks it as the reader would. No heap allocation on success.
  bool writeRow(const DetectionRecord& record, std::string* why);
  // The pending rows to the file in one write(2) (after each frame). False on a write error
  // (errno in lastErrno()); those rows are lost (rowsLost()). No allocation.
  bool commit() { return writer_.commit(); }
  bool flush(std::string* why);
  bool close(std::string* why);
  bool isOpen() const { return writer_.isOpen(); }
  int lastErrno() const { return writer_.lastErrno(); }
  std::int64_t rowsLost() const { return writer_.rowsLost(); }
  std::int64_t rowsWritten() const { return writer_.rowsWritten(); }

 private:
  csv::CsvFileWriter writer_;  // the file, its buffers and I/O state
  DetectionsFileInfo info_{};
};

struct DetectionsFile {
  std::string path;
  int formatVersion = kDetectionsFormatVersion;  // as read: 1 (no frame-edge columns) or 2
  DetectionsFileInfo info{};
  std::vector<DetectionRecord> rows;  // file order
  std::vector<int> lines;             // line of each row in the file (for messages)
};

// Reads and checks a whole detections file. False + *why naming file:line:column on a problem.
bool readDetectionsFile(const std::string& path, DetectionsFile* out, std::string* why);

}  // namespace vp::output_files
