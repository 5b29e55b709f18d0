// output_files/traffic_files: the traffic analysis' five CSV files (docs/traffic_files.md):
// traffic_counts.csv, traffic_movements.csv, traffic_zones.csv, traffic_lanes.csv (one block
// of rows per statistics period) and traffic_events.csv (one row per event as it happens).
//
// Contract: rows name the site's features by their ids (TrafficFeatureIds, taken from the site
// file at start-up: the report types carry indices in the site's order of each kind), times
// are the app's timestamp_ns, vehicle types are shape::toString's words. Each file starts with
// a `#` line naming the product, the file and the format version, then the header line.
// TrafficFilesWriter is made for the real-time loop like the trajectory writer: open()
// allocates everything once (each file's row and pending-row buffers, sized for the longest
// feature id) and creates the files; writeStatistics() / writeEvent() format rows with
// std::to_chars into the preallocated buffers, commit() writes each file's pending rows with one
// write(2); none of them allocates or throws, and a failure is returned as a TrafficWriteStatus
// and counted (errors()); close() commits and reports I/O errors. Rows with a count of 0 are
// not written in traffic_counts.csv and traffic_movements.csv. readTrafficFile() is an offline
// reader (tests, tools): it checks the comment line, the header and the field count and returns
// the fields as text; the messages name file:line.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "csv/csv_io.hpp"
#include "geodesy/geodesy.hpp"
#include "site/site.hpp"
#include "traffic/traffic_report.hpp"

namespace vp::output_files {

constexpr int kTrafficFormatVersion = 1;

enum class TrafficFile : std::uint8_t { Counts = 0, Movements, Zones, Lanes, Events };
constexpr std::size_t kTrafficFileCount = 5;
const char* fileName(TrafficFile file);  // "traffic_counts.csv", ...
// The header line's column names of that file, comma-separated (no line break).
const char* trafficColumns(TrafficFile file);

// The site's feature ids of each kind, in the site file's order: index i of a report's gate,
// zone or lane is gates[i], zones[i], lanes[i].
struct TrafficFeatureIds {
  std::vector<std::string> gates;
  std::vector<std::string> zones;
  std::vector<std::string> lanes;
};
TrafficFeatureIds trafficFeatureIds(const site::Site& site);

enum class TrafficWriteStatus : std::uint8_t {
  Ok,
  NotOpen,
  UnknownFeature,  // an index beyond the ids given to open(), or counts beyond kMaxReport*
  InvalidValue,    // a number that is not finite
  RowTooLong,      // cannot happen with the buffer sized at open(); checked all the same
  WriteFailed,     // disk full or I/O error (the rows pending in that file are lost)
};
const char* toString(TrafficWriteStatus status);

class TrafficFilesWriter {
 public:
  TrafficFilesWriter() = default;
  ~TrafficFilesWriter();  // commits and closes, dropping errors
  TrafficFilesWriter(const TrafficFilesWriter&) = delete;
  TrafficFilesWriter& operator=(const TrafficFilesWriter&) = delete;

  // Creates (truncates) the five files in directory `dir` (which must exist) and writes their
  // first lines. `frame` converts the events' ENU positions to WGS84 (copied). Start-up.
  bool open(const std::string& dir, const TrafficFeatureIds& ids, const geodesy::LocalFrame& frame,
            std::string* why);
  // One period's rows in the four statistics files. Stops at the first refused row (the
  // rows before it stay pending). No allocation.
  TrafficWriteStatus writeStatistics(const traffic::TrafficStatistics& statistics);
  TrafficWriteStatus writeEvent(const traffic::TrafficEvent& event);
  // Every file's pending rows to the kernel (one write(2) per file with rows). No allocation.
  TrafficWriteStatus commit();
  bool close(std::string* why);

  bool isOpen() const { return open_; }
  std::string path(TrafficFile file) const { return files_[index(file)].path(); }
  std::int64_t rowsWritten(TrafficFile file) const { return files_[index(file)].rowsWritten(); }
  std::int64_t rowsLost() const;
  std::uint64_t errors() const { return errors_; }  // refused rows and failed writes
  std::uint64_t periodsWritten() const { return periods_; }
  std::uint64_t eventsWritten() const { return events_; }

 private:
  static std::size_t index(TrafficFile file) { return static_cast<std::size_t>(file); }
  TrafficWriteStatus fail(TrafficWriteStatus status) {
    ++errors_;
    return status;
  }

  std::array<csv::CsvFileWriter, kTrafficFileCount> files_{};
  TrafficFeatureIds ids_;
  geodesy::LocalFrame frame_;
  bool open_ = false;
  std::uint64_t errors_ = 0;
  std::uint64_t periods_ = 0;
  std::uint64_t events_ = 0;
};

// A traffic file as text fields (offline: tests, tools).
struct TrafficFileRows {
  std::string path;
  std::vector<std::vector<std::string>> rows;  // file order, fields as written
};
// Reads `path`, a `file` of this format: the first line must be the product's comment line of
// that file and format version, the second the header; every row needs the header's field
// count. False + *why ("<file>:<line>: ...") on a problem.
bool readTrafficFile(const std::string& path, TrafficFile file, TrafficFileRows* out,
                     std::string* why);

}  // namespace vp::output_files
