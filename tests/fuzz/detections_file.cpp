// fuzz/detections_file: the detections file reader and writer (src/output/output_files) on
// arbitrary file contents.
// Contract checked: readDetectionsFile() returns true, or false with a message naming the file;
// a file it accepts, written again by DetectionsFileWriter, is accepted again, and writing
// what was read back from that reproduces it byte for byte (the reader and the writer check
// the same rules; numbers round-trip exactly).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_support.hpp"
#include "output_files/detections_file.hpp"

namespace {

namespace fs = std::filesystem;
using vp::output_files::DetectionsFile;
constexpr const char* kTarget = "detections_file";

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
  return vp::fuzz::checkRoundTrip<DetectionsFile>(kTarget, "detections", data, size,
                                                  vp::output_files::readDetectionsFile, rewrite);
}
