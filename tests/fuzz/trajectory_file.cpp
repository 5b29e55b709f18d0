// fuzz/trajectory_file: the trajectory file reader and writer (src/output/output_files) on
// arbitrary file contents.
// Contract checked: readTrajectoryFile() returns true, or false with a message naming the file;
// a file it accepts, written again by TrajectoryFileWriter (rows through toTrackState()), is
// accepted again, and writing what was read back from that reproduces it byte for byte (the
// reader and the writer check the same rules; the writer's fixed precision is stable).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_support.hpp"
#include "output_files/trajectory_file.hpp"

namespace {

namespace fs = std::filesystem;
using vp::output_files::TrajectoryFile;
constexpr const char* kTarget = "trajectory_file";

bool writeTrajectoryRow(vp::output_files::TrajectoryFileWriter& writer,
                        const vp::output_files::TrajectoryRecord& row, std::string* why) {
  return writer.writeRow(row.frameId, vp::output_files::toTrackState(row),
                         row.centreWgs84 ? &*row.centreWgs84 : nullptr, why, &row.place);
}

// Writes `file` to `path`; every row must be accepted.
void rewrite(const TrajectoryFile& file, const fs::path& path) {
  vp::output_files::TrajectoryFileWriter writer;
  std::string why;
  vp::fuzz::expect(writer.open(path.string(), file.info, &why), kTarget,
                   "the writer refuses the info the reader accepted: " + why);
  for (const auto& row : file.rows) {
    vp::fuzz::expect(writeTrajectoryRow(writer, row, &why), kTarget,
                     "the writer refuses a row the reader accepted: " + why);
  }
  vp::fuzz::expect(writer.close(&why), kTarget, "close() failed: " + why);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return vp::fuzz::checkRoundTrip<TrajectoryFile>(kTarget, "trajectory", data, size,
                                                  vp::output_files::readTrajectoryFile, rewrite);
}
