// fuzz/sequence_files: the recorded-sequence reader (src/input/sequence, with rig.yaml read by
// src/foundation/rig_config) on arbitrary text files. The input is the sequence's text files
// joined with NUL bytes, in the order sequence.yaml, rig.yaml, frames.csv, telemetry.csv,
// ground_truth/objects.csv, ground_truth/keypoints.csv; a file missing from the end of the
// input is absent from the directory. A valid DTM is always there as dtm.tif.
// Contract checked: open() returns true, or false with a message naming a file of the
// sequence; a successful open holds frames in increasing id and time order and ground truth
// only of listed frames; loadFrame() of a frame whose image is missing is an error value.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "fuzz_support.hpp"
#include "sequence/recorded_sequence.hpp"

namespace {

namespace fs = std::filesystem;
constexpr const char* kTarget = "sequence_files";
constexpr const char* kFiles[] = {"sequence.yaml",
                                  "rig.yaml",
                                  "frames.csv",
                                  "telemetry.csv",
                                  "ground_truth/objects.csv",
                                  "ground_truth/keypoints.csv"};

const fs::path& sequenceDirectory() {
  static const fs::path directory = [] {
    // OpenCV would log every missing frame image (the harness writes none).
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
    const fs::path dir = vp::fuzz::scratchDirectory() / "sequence";
    fs::create_directories(dir / "ground_truth");
    fs::copy_file(fs::path(VP_FIXTURE_DIR) / "dtm" / "sloped_utm16n.tif", dir / "dtm.tif",
                  fs::copy_options::overwrite_existing);
    return dir;
  }();
  return directory;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path& dir = sequenceDirectory();
  const std::vector<std::string_view> parts =
      vp::fuzz::splitParts(vp::fuzz::asText(data, size), std::size(kFiles));
  for (std::size_t i = 0; i < std::size(kFiles); ++i) {
    if (i < parts.size()) {
      vp::fuzz::writeFile(dir / kFiles[i], parts[i]);
    } else {
      vp::fuzz::removeFile(dir / kFiles[i]);
    }
  }

  vp::sequence::SequenceReader reader;
  std::string why;
  if (!reader.open(dir.string(), &why)) {
    vp::fuzz::note(kTarget, why);
    vp::fuzz::expect(why.find(dir.string()) != std::string::npos, kTarget,
                     "open() failed without naming the file: '" + why + "'");
    return 0;
  }
  const auto& frames = reader.frames();
  vp::fuzz::note(kTarget, "opened: " + std::to_string(frames.size()) + " frames");
  for (std::size_t i = 1; i < frames.size(); ++i) {
    vp::fuzz::expect(frames[i].frameId > frames[i - 1].frameId &&
                         frames[i].timestamp_ns > frames[i - 1].timestamp_ns,
                     kTarget, "frames not in increasing order after a successful open()");
  }
  for (const auto& frame : frames) {
    for (const auto& object : reader.objects(frame.frameId)) {
      vp::fuzz::expect(object.frameId == frame.frameId, kTarget, "objects() of another frame");
    }
  }
  cv::Mat image;
  std::string frameWhy;
  if (!frames.empty() && !fs::exists(dir / frames.front().file)) {
    vp::fuzz::expect(!reader.loadFrame(0, image, &frameWhy) && !frameWhy.empty(), kTarget,
                     "loadFrame() of a missing image did not fail with a message");
  }
  return 0;
}
