// output_files/trajectory_file: the trajectory file, one CSV row per track per frame, which the
// firmware app writes (--trajectory-csv) and the evaluation tool (vp_evaluate --tracks) reads.
// The columns are tracking/trajectory_csv's (seed 002's eight first, then ours), documented in
// docs/tracking.md.
//
// Contract: the writer is made for the real-time loop: open() allocates once (row and
// pending-row buffers), checks the path and writes the header; writeRow() checks the track as
// the reader would, formats it with tracking::trajectoryCsvRow() into the preallocated buffer
// and adds it to the pending rows, commit() writes them to the file with one write(2) (the loop
// commits every frame: a kill loses at most that frame, never half a row), allocating nothing
// and returning errors as values when they happen (never throwing); close() commits and
// reports I/O errors (csv::CsvFileWriter). The file is plain CSV (no metadata lines), so seed 002's
// readers and spreadsheets open it as is. Numbers have the fixed precision of trajectory_csv (mm,
// 0.01 deg, 1e-4 for probabilities and gamma), so reading gives the written values rounded to that
// precision, and writing what was read (toTrackState()) reproduces the file byte for byte.
// readTrajectoryFile() is an offline (start-up) reader: it checks every field and reports the
// first problem as "<file>:<line>:<column>: <field>: <problem>" (column = 1-based character
// position of the field in the line).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "csv/csv_io.hpp"
#include "shape/vehicle_model.hpp"
#include "tracking/track_manager.hpp"
#include "tracking/trajectory_csv.hpp"

namespace vp::output_files {

// Columns before the gamma columns: 31 fixed + 7 type probabilities.
constexpr int kTrajectoryFixedColumns = 38;

struct TrajectoryFileInfo {
  int gammaColumns = 3;  // gamma_1 .. gamma_n, 0 .. shape::kMaxShapeComponents (the ASM's n_s)
};

// One row as the file holds it (units of the columns: degrees where the column says so).
struct TrajectoryRecord {
  std::int64_t frameId = 0;                             // frame_id, >= 0
  shape::VehicleType type = shape::VehicleType::Sedan;  // class_id: the fused (argmax) type
  std::uint32_t trackId = 0;                            // track_id
  double speed_mps = 0.0;                               // velocity, signed (< 0 reversing)
  Eigen::Vector2d rearAxleEnu{0.0, 0.0};                // coordinate_world_{x,y}_opt, m
  Eigen::Vector2d centreEnu{0.0, 0.0};                  // coordinate_world_{x,y}, m
  double timeS = 0.0;                                   // time_s
  tracking::TrackStatus status = tracking::TrackStatus::Tentative;
  std::optional<tracking::Wgs84Position> centreWgs84;  // empty fields: not given
  double headingEnu_deg = 0.0;                         // [0, 360]
  double speedSigma_mps = 0.0;                         // >= 0
  double acceleration_mps2 = 0.0;
  double accelerationSigma_mps2 = 0.0;  // >= 0
  double yawRateDps = 0.0;
  double length_m = 0.0;     // >= 0
  double width_m = 0.0;      // >= 0
  double wheelbase_m = 0.0;  // >= 0
  // class_name is shape::toString(type) (checked, not stored).
  double lengthVariance_m2 = 0.0;  // >= 0
  double widthVariance_m2 = 0.0;   // >= 0
  // UTM of the centre (zone 0: empty fields) and WGS84 of the rear axle (hasRearAxle).
  tracking::TrajectoryPlace place{};
  std::array<float, shape::kVehicleTypeCount> typeProbabilities{};  // sum 1 (1e-3)
  shape::ShapeParams gamma{};  // count <= the file's gammaColumns

  double headingEnu_rad() const;
};

// The track state that trajectoryCsvRow() turns into this record's row (fields the file does
// not hold keep their defaults), with centreWgs84 and place: for tools that rewrite or
// generate trajectory files.
tracking::TrackState toTrackState(const TrajectoryRecord& record);

// The column names of a file with this many gamma columns, in order.
std::vector<std::string> trajectoryColumns(int gammaColumns);

class TrajectoryFileWriter {
 public:
  TrajectoryFileWriter();
  ~TrajectoryFileWriter();  // closes an open file, dropping errors
  TrajectoryFileWriter(const TrajectoryFileWriter&) = delete;
  TrajectoryFileWriter& operator=(const TrajectoryFileWriter&) = delete;

  // Creates (truncates) the file and writes the header. Start-up.
  bool open(const std::string& path, const TrajectoryFileInfo& info, std::string* why);
  // One row: the track at frame frameId; centreWgs84 may be null (empty WGS84 fields), place
  // too (empty UTM and rear-axle WGS84 fields). Checks the row as the reader would (except the
  // order and uniqueness checks, which need the history). No heap allocation on success.
  bool writeRow(std::int64_t frameId, const tracking::TrackState& track,
                const tracking::Wgs84Position* centreWgs84, std::string* why,
                const tracking::TrajectoryPlace* place = nullptr);
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
  TrajectoryFileInfo info_{};
};

struct TrajectoryFile {
  std::string path;
  TrajectoryFileInfo info{};
  std::vector<TrajectoryRecord> rows;  // file order
  std::vector<int> lines;              // line of each row in the file (for messages)
};

// Reads and checks a whole trajectory file: frame_id non-decreasing, a track_id at most once
// per frame, every field in range, class_id the most probable type. False + *why naming
// file:line:column on the first problem.
bool readTrajectoryFile(const std::string& path, TrajectoryFile* out, std::string* why);

}  // namespace vp::output_files
