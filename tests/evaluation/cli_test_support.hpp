// evaluation/cli_test_support: what the vp_evaluate end-to-end tests share (header only, for
// tests that define VP_EVALUATE_EXE and VP_FIXTURE_DIR).
//
// Contract: EvaluateCliTest gives each test a fresh, empty folder dir_ (named after the test,
// removed afterwards) and tests/fixtures/sequence_min open in reader_; run() runs vp_evaluate
// with the given arguments, its stdout and stderr going to files in dir_, and returns the exit
// code (-1 when it did not exit normally) with both texts. perfectDetection() is the
// detections file row that the ground truth of one object would give.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "output_files/detections_file.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::evaluate {

inline const std::string kSequence = std::string(VP_FIXTURE_DIR) + "/sequence_min";

struct CommandResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};

// The whole file ("" when it cannot be read).
inline std::string readText(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// A lifted detection exactly on the object (score 0.9, certain of its type, its shape), for
// the tests to perturb.
inline output_files::DetectionRecord perfectDetection(std::int64_t frameId, int detId,
                                                      const sequence::ObjectTruth& object) {
  output_files::DetectionRecord r;
  r.frameId = frameId;
  r.detId = detId;
  r.score = 0.9F;
  r.box = object.imageBox;
  r.directionKnown = true;
  r.typeProbabilities.fill(0.0F);
  r.typeProbabilities[static_cast<std::size_t>(object.type)] = 1.0F;
  r.gamma = object.shape;
  r.liftStatus = output_files::LiftStatus::Ok;
  r.positionEnu = object.positionEnu;
  r.latitude_deg = 43.0731;
  r.longitude_deg = -89.4012;
  r.height_m = object.positionEnu.z();
  r.headingEnu_rad = object.headingEnu_rad;
  r.dimensions_m = object.dimensions_m;
  return r;
}

class EvaluateCliTest : public ::testing::Test {
 protected:
  // dirPrefix keeps the temporary folders of different test programs apart.
  explicit EvaluateCliTest(std::string dirPrefix) : dirPrefix_(std::move(dirPrefix)) {}

  void SetUp() override {
    dir_ =
        std::filesystem::temp_directory_path() /
        (dirPrefix_ + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    std::string why;
    ASSERT_TRUE(reader_.open(kSequence, &why)) << why;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  CommandResult run(const std::string& arguments) const {
    const std::filesystem::path out = dir_ / "stdout.txt";
    const std::filesystem::path err = dir_ / "stderr.txt";
    const std::string command = std::string(VP_EVALUATE_EXE) + " " + arguments + " > " +
                                out.string() + " 2> " + err.string();
    const int status = std::system(command.c_str());
    CommandResult result;
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = readText(out);
    result.err = readText(err);
    return result;
  }

  std::filesystem::path dir_;
  sequence::SequenceReader reader_;

 private:
  std::string dirPrefix_;
};

}  // namespace vp::evaluate
