// fuzz/detections_file: the detections file reader and writer (src/output/output_files) on
// arbitrary file contents.
// Contract checked: readDetectionsFile() returns true, or false with a message naming the file;
// a file it accepts, written again by DetectionsFileWriter, is accepted again, and writing
// what was read back from that reproduces it byte for byte (the reader and the writer check
// the same rules; numbers round-trip exactly).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "output_files/detections_file.hpp"

namespace {

namespace fs = std::filesystem;
using vp::output_files::DetectionsFile;
constexpr const char* kTarget = "detections_file";

std::string contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;  // (istreambuf_iterator trips g++ 12's -Wnull-dereference)
  text << in.rdbuf();
  return text.str();
}

// Writes `file` to `path`; every row must be accepted.
void rewrite(const DetectionsFile& file, const fs::path& path) {
  vp::output_files::DetectionsFileWriter writer;
  std::string why;
  vp::fuzz::expect(writer.open(path.string(), file.info, &why), kTarget,
                   "the writer refuses the info the reader accepted: " + why);
  for (const auto& row : file.rows) {
    vp::fuzz::expect(writer.writeRow(row, &why), kTarget,
                     "the writer refuses a row the reader accepted: " + why);
  }
  vp::fuzz::expect(writer.close(&why), kTarget, "close() failed: " + why);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path input = vp::fuzz::scratchDirectory() / "detections.csv";
  vp::fuzz::writeFile(input, vp::fuzz::asText(data, size));
  DetectionsFile file;
  std::string why;
  if (!vp::output_files::readDetectionsFile(input.string(), &file, &why)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.starts_with(input.string()), kTarget,
                     "read failed without naming the file: '" + why + "'");
    return 0;
  }
  vp::fuzz::note(kTarget, "accepted " + std::to_string(file.rows.size()) + " rows");
  vp::fuzz::expect(file.rows.size() == file.lines.size(), kTarget, "rows and lines differ");

  const fs::path first = vp::fuzz::scratchDirectory() / "detections_1.csv";
  const fs::path second = vp::fuzz::scratchDirectory() / "detections_2.csv";
  rewrite(file, first);
  DetectionsFile again;
  vp::fuzz::expect(vp::output_files::readDetectionsFile(first.string(), &again, &why), kTarget,
                   "the reader refuses what the writer wrote from an accepted file: " + why);
  vp::fuzz::expect(again.rows.size() == file.rows.size(), kTarget, "row count changed");
  rewrite(again, second);
  vp::fuzz::expect(contents(first) == contents(second), kTarget,
                   "write(read(write(read(file)))) differs from write(read(file))");
  return 0;
}
