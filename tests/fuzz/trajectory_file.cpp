// fuzz/trajectory_file: the trajectory file reader and writer (src/output/output_files) on
// arbitrary file contents.
// Contract checked: readTrajectoryFile() returns true, or false with a message naming the file;
// a file it accepts, written again by TrajectoryFileWriter (rows through toTrackState()), is
// accepted again, and writing what was read back from that reproduces it byte for byte (the
// reader and the writer check the same rules; the writer's fixed precision is stable).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "output_files/trajectory_file.hpp"

namespace {

namespace fs = std::filesystem;
using vp::output_files::TrajectoryFile;
constexpr const char* kTarget = "trajectory_file";

std::string contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;  // (istreambuf_iterator trips g++ 12's -Wnull-dereference)
  text << in.rdbuf();
  return text.str();
}

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
  const fs::path input = vp::fuzz::scratchDirectory() / "trajectory.csv";
  vp::fuzz::writeFile(input, vp::fuzz::asText(data, size));
  TrajectoryFile file;
  std::string why;
  if (!vp::output_files::readTrajectoryFile(input.string(), &file, &why)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.starts_with(input.string()), kTarget,
                     "read failed without naming the file: '" + why + "'");
    return 0;
  }
  vp::fuzz::note(kTarget, "accepted " + std::to_string(file.rows.size()) + " rows");
  vp::fuzz::expect(file.rows.size() == file.lines.size(), kTarget, "rows and lines differ");

  const fs::path first = vp::fuzz::scratchDirectory() / "trajectory_1.csv";
  const fs::path second = vp::fuzz::scratchDirectory() / "trajectory_2.csv";
  rewrite(file, first);
  TrajectoryFile again;
  vp::fuzz::expect(vp::output_files::readTrajectoryFile(first.string(), &again, &why), kTarget,
                   "the reader refuses what the writer wrote from an accepted file: " + why);
  vp::fuzz::expect(again.rows.size() == file.rows.size(), kTarget, "row count changed");
  rewrite(again, second);
  vp::fuzz::expect(contents(first) == contents(second), kTarget,
                   "write(read(write(read(file)))) differs from write(read(file))");
  return 0;
}
