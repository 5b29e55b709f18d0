// Tests of sequence/recorded_sequence: writer -> reader round trips are exact, the shipped
// minimal fixture opens, every malformed input is reported with its file, line and field,
// and the writer's output is byte-identical for the same content (the simulator relies on it).
#include "sequence/recorded_sequence.hpp"

#include "csv/csv_io.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace vp::sequence {
namespace {

namespace fs = std::filesystem;

const fs::path kFixture = fs::path(VP_FIXTURE_DIR) / "sequence_min";
const fs::path kSampleDtm = fs::path(VP_FIXTURE_DIR) / "dtm" / "sloped_utm16n.tif";

::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

::testing::AssertionResult startsWith(const std::string& text, const std::string& prefix) {
  if (text.starts_with(prefix)) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "'" << text << "' does not start with '" << prefix << "'";
}

// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(test->test_suite_name()) + "_" + test->name();
    for (char& c : name) {
      c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    }
    path_ = fs::temp_directory_path() / ("vp_sequence_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code error;
    fs::remove_all(path_, error);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string readText(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << text;
}

// Replaces the first occurrence of `from` (which must occur) in the file.
void replaceIn(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = readText(path);
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << path;
  text.replace(at, from.size(), to);
  writeText(path, text);
}

// Replaces line `number` (1-based) of the file.
void replaceLine(const fs::path& path, int number, const std::string& line) {
  std::istringstream in(readText(path));
  std::string out;
  std::string current;
  for (int i = 1; std::getline(in, current); ++i) {
    out += (i == number ? line : current) + "\n";
  }
  writeText(path, out);
}

// Copies the fixture to <dir>/seq with the DTM at <dir>/dtm/, where its rig.yaml looks.
fs::path copyFixture(const fs::path& dir) {
  const fs::path sequence = dir / "seq";
  fs::copy(kFixture, sequence, fs::copy_options::recursive);
  fs::create_directories(dir / "dtm");
  fs::copy_file(kSampleDtm, dir / "dtm" / "sloped_utm16n.tif");
  return sequence;
}

// ---- the sample content written by the round-trip and determinism tests --------------------

constexpr const char* kRigYaml = R"(# rig of the round-trip test
origin:
  latitude_deg: 43.0731
  longitude_deg: -89.4012
  height_m: 260.0
camera:
  width_px: 32
  height_px: 24
  fx_px: 40.0
  fy_px: 40.0
terrain:
  dtm_path: dtm.tif
)";

struct Sample {
  SequenceInfo info;
  std::vector<FrameRecord> frames;
  std::vector<cv::Mat> images;
  std::vector<TelemetryRecord> telemetry;
  std::vector<ObjectTruth> objects;
  std::vector<KeypointTruth> keypoints;
};

// Values chosen so that a lossy text format would show: 0.1 + 0.2, 1/3, pi, tiny and large.
Sample makeSample() {
  Sample sample;
  sample.info.name = "round trip";
  sample.info.frameRate_hz = 29.97;
  sample.info.source = "unit test, \"quoted\" text: with a colon";
  sample.info.notes = "line one\nline two\twith a tab";

  cv::RNG rng(12345);
  for (int i = 0; i < 3; ++i) {
    FrameRecord frame;
    frame.frameId = 10 + 2 * i;  // gaps are allowed
    frame.timestamp_ns = 1'700'000'000'000'000'000 + i * 33'366'667;
    sample.frames.push_back(frame);
    cv::Mat image(24, 32, CV_8UC3);
    rng.fill(image, cv::RNG::UNIFORM, 0, 256);
    sample.images.push_back(image);
  }

  for (int i = 0; i < 5; ++i) {
    TelemetryRecord record;
    record.timestamp_ns = 1'700'000'000'000'000'000 + i * 20'000'000 - 5'000'000;
    record.position = {43.0731 + (0.1 + 0.2) * 1e-5 * i, -89.4012 - i / 3.0 * 1e-5,
                       360.0 + std::numbers::pi * i};
    record.bodyToNed = Eigen::Quaterniond(
        Eigen::AngleAxisd(0.1 + 0.3 * i, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()));
    record.gimbal.angles = {0.1 * i, -90.0 + 1.0 / 3.0, 1e-300 * i};
    record.gimbal.reference =
        i % 2 == 0 ? geodesy::GimbalReference::Body : geodesy::GimbalReference::Earth;
    sample.telemetry.push_back(record);
  }

  for (int f = 0; f < 2; ++f) {  // the last frame has no vehicle
    ObjectTruth car;
    car.frameId = sample.frames[static_cast<std::size_t>(f)].frameId;
    car.trackId = 4;
    car.type = shape::VehicleType::Suv;
    car.shape.count = 3;
    car.shape.gamma = {0.1F, -1.0F / 3.0F, 2.5e-7F};
    car.dimensions_m = {4.71, 1.93, 1.71};
    car.positionEnu = {12.5 + f * (0.1 + 0.2), -30.0 / 7.0, 261.125};
    car.headingEnu_rad = std::numbers::pi / 3.0;
    car.speed_mps = 8.333333333333334;
    car.yawRate_radps = -0.0123;
    car.imageBox = {16.1, 12.9, 3.7, 1.4, 2.0 * std::numbers::pi - 1e-9};
    car.truncation = 0.0;
    car.occlusion = 0.3;
    car.parked = false;
    sample.objects.push_back(car);
  }
  ObjectTruth bus;
  bus.frameId = sample.frames[1].frameId;
  bus.trackId = 9;
  bus.type = shape::VehicleType::Large;
  bus.dimensions_m = {11.9, 2.55, 3.2};
  bus.positionEnu = {-40.0, 8.0, 259.0};
  bus.imageBox = {1.0, 2.0, 9.0, 2.0, 0.0};
  bus.truncation = 0.75;
  bus.parked = true;
  sample.objects.push_back(bus);

  for (int f = 0; f < 2; ++f) {
    for (int k : {0, 7, 35}) {
      KeypointTruth keypoint;
      keypoint.frameId = sample.frames[static_cast<std::size_t>(f)].frameId;
      keypoint.trackId = 4;
      keypoint.keypoint = k;
      keypoint.pixel = {15.0 + k / 7.0, -0.5 - f};  // outside the image is allowed
      keypoint.visible = k != 7;
      keypoint.worldEnu = {12.0 + k * 0.1, -4.0 - f * 0.2, 261.0 + 1.0 / (k + 3.0)};
      sample.keypoints.push_back(keypoint);
    }
  }
  return sample;
}

std::vector<ObjectTruth> objectsOf(const Sample& sample, std::int64_t frameId) {
  std::vector<ObjectTruth> out;
  for (const ObjectTruth& object : sample.objects) {
    if (object.frameId == frameId) {
      out.push_back(object);
    }
  }
  return out;
}

std::vector<KeypointTruth> keypointsOf(const Sample& sample, std::int64_t frameId) {
  std::vector<KeypointTruth> out;
  for (const KeypointTruth& keypoint : sample.keypoints) {
    if (keypoint.frameId == frameId) {
      out.push_back(keypoint);
    }
  }
  return out;
}

// Writes the sample the way the simulator does: per frame the image, then its ground truth.
void writeSample(const fs::path& directory, const Sample& sample) {
  SequenceWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(directory.string(), sample.info, kRigYaml, kSampleDtm.string(), &why))
      << why;
  for (const TelemetryRecord& record : sample.telemetry) {
    ASSERT_TRUE(writer.writeTelemetry(record, &why)) << why;
  }
  for (std::size_t i = 0; i < sample.frames.size(); ++i) {
    const FrameRecord& frame = sample.frames[i];
    ASSERT_TRUE(writer.writeFrame(frame, sample.images[i], &why)) << why;
    ASSERT_TRUE(writer.writeObjects(objectsOf(sample, frame.frameId), &why)) << why;
    ASSERT_TRUE(writer.writeKeypoints(keypointsOf(sample, frame.frameId), &why)) << why;
  }
  ASSERT_TRUE(writer.close(&why)) << why;
}

void expectSameObject(const ObjectTruth& got, const ObjectTruth& want) {
  EXPECT_EQ(got.frameId, want.frameId);
  EXPECT_EQ(got.trackId, want.trackId);
  EXPECT_EQ(got.type, want.type);
  ASSERT_EQ(got.shape.count, want.shape.count);
  for (int i = 0; i < want.shape.count; ++i) {
    EXPECT_EQ(got.shape.gamma[static_cast<std::size_t>(i)],
              want.shape.gamma[static_cast<std::size_t>(i)]);
  }
  EXPECT_EQ(got.dimensions_m, want.dimensions_m);
  EXPECT_EQ(got.positionEnu, want.positionEnu);
  EXPECT_EQ(got.headingEnu_rad, want.headingEnu_rad);
  EXPECT_EQ(got.speed_mps, want.speed_mps);
  EXPECT_EQ(got.yawRate_radps, want.yawRate_radps);
  EXPECT_EQ(got.imageBox.cx, want.imageBox.cx);
  EXPECT_EQ(got.imageBox.cy, want.imageBox.cy);
  EXPECT_EQ(got.imageBox.length, want.imageBox.length);
  EXPECT_EQ(got.imageBox.width, want.imageBox.width);
  EXPECT_EQ(got.imageBox.angle, want.imageBox.angle);
  EXPECT_EQ(got.truncation, want.truncation);
  EXPECT_EQ(got.occlusion, want.occlusion);
  EXPECT_EQ(got.parked, want.parked);
}

void expectSameKeypoint(const KeypointTruth& got, const KeypointTruth& want) {
  EXPECT_EQ(got.frameId, want.frameId);
  EXPECT_EQ(got.trackId, want.trackId);
  EXPECT_EQ(got.keypoint, want.keypoint);
  EXPECT_EQ(got.pixel, want.pixel);
  EXPECT_EQ(got.visible, want.visible);
  EXPECT_EQ(got.worldEnu, want.worldEnu);
}

TEST(RecordedSequence, WriterReaderRoundTripIsExact) {
  const TempDir temp;
  const fs::path directory = temp.path() / "seq";
  const Sample sample = makeSample();
  writeSample(directory, sample);

  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  EXPECT_EQ(reader.directory(), directory.string());
  EXPECT_EQ(reader.info().formatVersion, kFormatVersion);
  EXPECT_EQ(reader.info().name, sample.info.name);
  EXPECT_EQ(reader.info().frameRate_hz, sample.info.frameRate_hz);
  EXPECT_EQ(reader.info().source, sample.info.source);
  EXPECT_EQ(reader.info().notes, sample.info.notes);
  EXPECT_TRUE(reader.rig().warnings.empty());
  EXPECT_EQ(reader.rig().intrinsics.width_px, 32);
  EXPECT_EQ(fs::path(reader.rig().dtmPath).filename(), "dtm.tif");
  EXPECT_EQ(readText(reader.rig().dtmPath), readText(kSampleDtm));
  EXPECT_EQ(readText(directory / "rig.yaml"), kRigYaml);

  ASSERT_EQ(reader.frames().size(), sample.frames.size());
  for (std::size_t i = 0; i < sample.frames.size(); ++i) {
    EXPECT_EQ(reader.frames()[i].frameId, sample.frames[i].frameId);
    EXPECT_EQ(reader.frames()[i].timestamp_ns, sample.frames[i].timestamp_ns);
    EXPECT_EQ(reader.frames()[i].file, "frames/0000" + std::to_string(10 + 2 * i) + ".png");
    cv::Mat image;
    ASSERT_TRUE(reader.loadFrame(i, image, &why)) << why;
    ASSERT_EQ(image.type(), CV_8UC3);
    EXPECT_EQ(cv::norm(image, sample.images[i], cv::NORM_INF), 0.0) << "PNG is lossless";
  }

  ASSERT_EQ(reader.telemetry().size(), sample.telemetry.size());
  for (std::size_t i = 0; i < sample.telemetry.size(); ++i) {
    const TelemetryRecord& got = reader.telemetry()[i];
    const TelemetryRecord& want = sample.telemetry[i];
    EXPECT_EQ(got.timestamp_ns, want.timestamp_ns);
    EXPECT_EQ(got.position.latitude_deg, want.position.latitude_deg);
    EXPECT_EQ(got.position.longitude_deg, want.position.longitude_deg);
    EXPECT_EQ(got.position.height_m, want.position.height_m);
    EXPECT_EQ(got.bodyToNed.coeffs(), want.bodyToNed.coeffs());
    EXPECT_EQ(got.gimbal.angles.roll_deg, want.gimbal.angles.roll_deg);
    EXPECT_EQ(got.gimbal.angles.pitch_deg, want.gimbal.angles.pitch_deg);
    EXPECT_EQ(got.gimbal.angles.yaw_deg, want.gimbal.angles.yaw_deg);
    EXPECT_EQ(got.gimbal.reference, want.gimbal.reference);
  }

  ASSERT_TRUE(reader.hasGroundTruth());
  for (const FrameRecord& frame : sample.frames) {
    const std::vector<ObjectTruth> wantObjects = objectsOf(sample, frame.frameId);
    const std::span<const ObjectTruth> gotObjects = reader.objects(frame.frameId);
    ASSERT_EQ(gotObjects.size(), wantObjects.size()) << "frame " << frame.frameId;
    for (std::size_t i = 0; i < wantObjects.size(); ++i) {
      expectSameObject(gotObjects[i], wantObjects[i]);
    }
    const std::vector<KeypointTruth> wantKeypoints = keypointsOf(sample, frame.frameId);
    const std::span<const KeypointTruth> gotKeypoints = reader.keypoints(frame.frameId);
    ASSERT_EQ(gotKeypoints.size(), wantKeypoints.size()) << "frame " << frame.frameId;
    for (std::size_t i = 0; i < wantKeypoints.size(); ++i) {
      expectSameKeypoint(gotKeypoints[i], wantKeypoints[i]);
    }
  }
  EXPECT_TRUE(reader.objects(11).empty());  // between frames
  EXPECT_TRUE(reader.objects(999).empty());
  EXPECT_TRUE(reader.keypoints(-1).empty());
  // 3 gamma columns: the largest shape of the first writeObjects() call.
  EXPECT_TRUE(startsWith(readText(directory / "ground_truth" / "objects.csv"),
                         "frame_id,track_id,type,gamma_0,gamma_1,gamma_2,length_m,"));
}

TEST(RecordedSequence, WritingTwiceGivesIdenticalBytes) {
  const TempDir temp;
  const Sample sample = makeSample();
  writeSample(temp.path() / "a", sample);
  writeSample(temp.path() / "b", sample);

  std::map<std::string, std::string> first;
  for (const auto& entry : fs::recursive_directory_iterator(temp.path() / "a")) {
    if (entry.is_regular_file()) {
      first[fs::relative(entry.path(), temp.path() / "a").string()] = readText(entry.path());
    }
  }
  std::map<std::string, std::string> second;
  for (const auto& entry : fs::recursive_directory_iterator(temp.path() / "b")) {
    if (entry.is_regular_file()) {
      second[fs::relative(entry.path(), temp.path() / "b").string()] = readText(entry.path());
    }
  }
  EXPECT_EQ(first.size(), 10U);  // 2 yaml, the DTM, 4 csv, 3 frames
  ASSERT_EQ(first.size(), second.size());
  for (const auto& [name, bytes] : first) {
    ASSERT_TRUE(second.contains(name)) << name;
    EXPECT_TRUE(bytes == second.at(name)) << name << " differs";
  }
}

TEST(RecordedSequence, JpegFramesDecode) {
  const TempDir temp;
  const fs::path directory = temp.path() / "seq";
  SequenceInfo info;
  info.name = "jpeg";
  SequenceWriter writer;
  writer.imageExtension = ".jpg";
  writer.jpegQuality = 95;
  std::string why;
  ASSERT_TRUE(writer.open(directory.string(), info, kRigYaml, kSampleDtm.string(), &why)) << why;
  const cv::Mat image(24, 32, CV_8UC3, cv::Scalar(30, 120, 210));
  ASSERT_TRUE(writer.writeFrame(FrameRecord{0, 5, ""}, image, &why)) << why;
  ASSERT_TRUE(writer.close(&why)) << why;

  SequenceReader reader;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  EXPECT_FALSE(reader.hasGroundTruth());
  ASSERT_EQ(reader.frames().size(), 1U);
  EXPECT_EQ(reader.frames()[0].file, "frames/000000.jpg");
  cv::Mat decoded;
  ASSERT_TRUE(reader.loadFrame(0, decoded, &why)) << why;
  EXPECT_LE(cv::norm(decoded, image, cv::NORM_INF), 4.0);  // lossy, but close on a flat image
}

TEST(RecordedSequence, OpensTheShippedFixture) {
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(kFixture.string(), &why)) << why;
  EXPECT_EQ(reader.info().name, "sequence_min");
  EXPECT_EQ(reader.info().frameRate_hz, 10.0);
  EXPECT_TRUE(reader.info().notes.empty());
  EXPECT_TRUE(reader.rig().warnings.empty());
  EXPECT_EQ(fs::path(reader.rig().dtmPath).filename(), "sloped_utm16n.tif");
  ASSERT_EQ(reader.frames().size(), 2U);
  EXPECT_EQ(reader.frames()[1].timestamp_ns, 1'700'000'000'100'000'000);
  ASSERT_EQ(reader.telemetry().size(), 4U);
  EXPECT_EQ(reader.telemetry()[1].bodyToNed.z(), 0.7071067811865476);
  EXPECT_EQ(reader.telemetry()[2].gimbal.reference, geodesy::GimbalReference::Earth);
  EXPECT_EQ(reader.telemetry()[3].position.latitude_deg, 43.07310135);

  ASSERT_TRUE(reader.hasGroundTruth());
  ASSERT_EQ(reader.objects(0).size(), 1U);
  ASSERT_EQ(reader.objects(1).size(), 2U);
  EXPECT_EQ(reader.objects(0)[0].type, shape::VehicleType::Sedan);
  EXPECT_EQ(reader.objects(0)[0].shape.count, 3);
  EXPECT_EQ(reader.objects(0)[0].shape.gamma[1], -1.5F);
  EXPECT_EQ(reader.objects(1)[1].type, shape::VehicleType::Large);
  EXPECT_EQ(reader.objects(1)[1].shape.count, 0);
  EXPECT_TRUE(reader.objects(1)[1].parked);
  EXPECT_EQ(reader.keypoints(0).size(), 2U);
  EXPECT_EQ(reader.keypoints(1).size(), 1U);
  EXPECT_FALSE(reader.keypoints(0)[1].visible);

  cv::Mat image;
  for (std::size_t i = 0; i < 2; ++i) {
    ASSERT_TRUE(reader.loadFrame(i, image, &why)) << why;
    EXPECT_EQ(image.cols, 32);
    EXPECT_EQ(image.rows, 24);
  }
  // Frame 1: the blob (RGB 40, 40, 200 in the file) moved up to rows 10..12; BGR in memory.
  EXPECT_EQ(image.at<cv::Vec3b>(10, 16), cv::Vec3b(200, 40, 40));
  EXPECT_EQ(image.at<cv::Vec3b>(13, 16), cv::Vec3b(110, 113, 116));
}

TEST(RecordedSequence, LoadFrameReusesAMatchingBuffer) {
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(kFixture.string(), &why)) << why;
  cv::Mat image(24, 32, CV_8UC3, cv::Scalar::all(0));
  const uchar* buffer = image.data;
  ASSERT_TRUE(reader.loadFrame(1, image, &why)) << why;
  EXPECT_EQ(image.data, buffer);
  EXPECT_EQ(image.at<cv::Vec3b>(10, 16), cv::Vec3b(200, 40, 40));
}

TEST(RecordedSequence, LoadFrameReportsMissingCorruptAndWrongSizedImages) {
  const TempDir temp;
  const fs::path directory = copyFixture(temp.path());
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;

  writeText(directory / "frames" / "000001.png", std::string("\x89PNG\r\n\x1a\ngarbage", 15));
  cv::Mat image;
  EXPECT_FALSE(reader.loadFrame(1, image, &why));
  EXPECT_EQ(why, (directory / "frames" / "000001.png").string() +
                     ": cannot decode image (missing or corrupt)");

  fs::remove(directory / "frames" / "000000.png");
  EXPECT_FALSE(reader.loadFrame(0, image, &why));
  EXPECT_TRUE(contains(why, "frames/000000.png: cannot decode image (missing or corrupt)"));

  cv::imwrite((directory / "frames" / "000000.png").string(), cv::Mat(16, 20, CV_8UC3));
  EXPECT_FALSE(reader.loadFrame(0, image, &why));
  EXPECT_TRUE(contains(why, "frames/000000.png: image is 20x16, rig.yaml camera is 32x24"));

  EXPECT_FALSE(reader.loadFrame(2, image, &why));
  EXPECT_TRUE(contains(why, "frame index 2 out of range (2 frames)"));
}

TEST(RecordedSequence, LoadFrameRefusesATruncatedJpegThatTheDecoderAccepts) {
  const TempDir temp;
  const fs::path directory = copyFixture(temp.path());
  cv::Mat noise(24, 32, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  std::vector<uchar> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", noise, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  const fs::path file = directory / "frames" / "000001.jpg";
  const auto write = [&](std::size_t size, std::size_t zeros) {
    std::string bytes(reinterpret_cast<const char*>(jpeg.data()), size);
    bytes.append(zeros, '\0');
    writeText(file, bytes);
  };
  replaceIn(directory / "frames.csv", "frames/000001.png", "frames/000001.jpg");
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  cv::Mat image;
  write(jpeg.size(), 0);
  EXPECT_TRUE(reader.loadFrame(1, image, &why)) << why;
  write(jpeg.size(), 16);  // zero padding after the end marker, as some cameras write
  EXPECT_TRUE(reader.loadFrame(1, image, &why)) << why;

  const std::size_t cut = jpeg.size() * 6 / 10;
  const std::vector<uchar> truncated(jpeg.begin(), jpeg.begin() + static_cast<long>(cut));
  ASSERT_FALSE(cv::imdecode(truncated, cv::IMREAD_COLOR).empty())
      << "libjpeg refuses the cut file itself: the case below is not the partial decode";
  write(cut, 0);
  EXPECT_FALSE(reader.loadFrame(1, image, &why));
  EXPECT_EQ(why, file.string() +
                     ": truncated JPEG: partial decode refused (the file does not end with the "
                     "end-of-image marker FF D9)");
}

TEST(RecordedSequence, LoadFrameRefusesATruncatedPngNamingIt) {
  const TempDir temp;
  const fs::path directory = copyFixture(temp.path());
  const fs::path file = directory / "frames" / "000001.png";
  fs::resize_file(file, fs::file_size(file) - 12);  // the IEND chunk only
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  cv::Mat image;
  EXPECT_FALSE(reader.loadFrame(1, image, &why));
  EXPECT_TRUE(startsWith(why, file.string() + ": ")) << why;
}

TEST(RecordedSequence, AHugeFileNameIsShortenedInMessages) {
  // A 10 MB name in frames.csv (no such file can exist): the message keeps the start and the
  // end of the path around "..." instead of the whole name.
  const TempDir temp;
  const fs::path directory = copyFixture(temp.path());
  const std::string name = "frames/" + std::string(10'000'000, 'x') + "_end.png";
  replaceIn(directory / "frames.csv", "frames/000001.png", name);
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  cv::Mat image;
  EXPECT_FALSE(reader.loadFrame(1, image, &why));
  EXPECT_LE(why.size(), csv::kMaxMessagePathChars + 64) << why.substr(0, 300);
  EXPECT_NE(why.find("..."), std::string::npos) << why;
  EXPECT_NE(why.find("x_end.png: cannot decode image (missing or corrupt)"), std::string::npos)
      << why;
  // A field quoted in a reader's message is capped too.
  replaceIn(directory / "frames.csv", name, "/" + name);
  EXPECT_FALSE(reader.open(directory.string(), &why));
  EXPECT_LE(why.size(), directory.string().size() + csv::kMaxQuotedChars + 128);
  EXPECT_NE(why.find("frames.csv:3: file: must be relative"), std::string::npos)
      << why.substr(0, 300);
}

// ---- malformed sequences: copy the fixture, break one thing, expect one precise message ----

struct BrokenCase {
  std::string name;
  std::function<void(const fs::path& sequence)> breakIt;
  std::string expected;  // the message after "<directory>/"
};

const fs::path kObjects = fs::path("ground_truth") / "objects.csv";
const fs::path kKeypoints = fs::path("ground_truth") / "keypoints.csv";

std::vector<BrokenCase> brokenCases() {
  return {
      {"MissingSequenceYaml", [](const fs::path& s) { fs::remove(s / "sequence.yaml"); },
       "sequence.yaml: missing (required)"},
      {"MissingRigYaml", [](const fs::path& s) { fs::remove(s / "rig.yaml"); },
       "rig.yaml: missing (required)"},
      {"MissingFramesCsv", [](const fs::path& s) { fs::remove(s / "frames.csv"); },
       "frames.csv: missing (required)"},
      {"MissingTelemetryCsv", [](const fs::path& s) { fs::remove(s / "telemetry.csv"); },
       "telemetry.csv: missing (required)"},
      {"MissingDtm",
       [](const fs::path& s) { fs::remove(s.parent_path() / "dtm" / "sloped_utm16n.tif"); },
       "rig.yaml: terrain.dtm_path: no such file"},
      {"BadFormatVersion",
       [](const fs::path& s) {
         replaceIn(s / "sequence.yaml", "format_version: 1", "format_version: 2");
       },
       "sequence.yaml: format_version: 2 not supported (this reader reads 1)"},
      {"WrongFrameCount",
       [](const fs::path& s) {
         replaceIn(s / "sequence.yaml", "frame_count: 2", "frame_count: 3");
       },
       "sequence.yaml: frame_count: 3 but frames.csv has 2 frames"},
      {"UnknownSequenceKey",
       [](const fs::path& s) { replaceIn(s / "sequence.yaml", "name:", "colour: red\nname:"); },
       "sequence.yaml: unknown key 'colour'"},
      {"QuotedFrameRate",
       [](const fs::path& s) {
         replaceIn(s / "sequence.yaml", "frame_rate_hz: 10", "frame_rate_hz: \"10\"");
       },
       "sequence.yaml: frame_rate_hz: expected a finite number, got the quoted string '10'"},
      {"BadRigKey",
       [](const fs::path& s) { replaceIn(s / "rig.yaml", "fx_px: 40.0", "fx_px: -3"); },
       "rig.yaml: camera.fx_px: must be > 0, got -3"},
      {"WrongFramesHeader",
       [](const fs::path& s) { replaceLine(s / "frames.csv", 1, "frame,timestamp_ns,file"); },
       "frames.csv:1: header: expected 'frame_id,timestamp_ns,file', got "
       "'frame,timestamp_ns,file'"},
      {"WrongObjectsHeader", [](const fs::path& s) { replaceIn(s / kObjects, "gamma_1,", ""); },
       "ground_truth/objects.csv:1: header: expected "
       "'frame_id,track_id,type,gamma_0,...,gamma_{n-1},length_m"},
      {"FrameIdsNotIncreasing",
       [](const fs::path& s) {
         replaceIn(s / "frames.csv", "1,1700000000100000000", "0,1700000000100000000");
       },
       "frames.csv:3: frame_id: not increasing (0 after 0)"},
      {"FrameTimestampsNotIncreasing",
       [](const fs::path& s) { replaceIn(s / "frames.csv", "1,1700000000100000000", "1,1000"); },
       "frames.csv:3: timestamp_ns: not increasing (1000 after 1700000000000000000)"},
      {"FrameTimestampsJumpTooFar",
       [](const fs::path& s) {
         replaceIn(s / "frames.csv", "1,1700000000100000000", "1,1700000100000000000");
       },
       "frames.csv:3: timestamp_ns: jumps 100.000 s after the previous frame "
       "(1700000100000000000 after 1700000000000000000 ns); a recording may pause at most 60 s"},
      {"FirstFrameYearsBeforeTheNext",
       [](const fs::path& s) {
         replaceIn(s / "frames.csv", "0,1700000000000000000", "0,-100000000");
       },
       "frames.csv:3: timestamp_ns: jumps 1700000000.200 s after the previous frame"},
      {"TelemetryTimestampsJumpTooFar",
       [](const fs::path& s) {
         replaceIn(s / "telemetry.csv", "1700000000050000000", "1700000090050000000");
       },
       "telemetry.csv:4: timestamp_ns: jumps 90.050 s after the previous sample"},
      {"QuotedField",
       [](const fs::path& s) {
         replaceIn(s / "frames.csv", "frames/000000.png", "\"frames/000000.png\"");
       },
       "frames.csv:2: file: quoted fields are not supported"},
      {"AbsoluteFramePath",
       [](const fs::path& s) {
         replaceIn(s / "frames.csv", "frames/000001.png", "/tmp/000001.png");
       },
       "frames.csv:3: file: must be relative to the sequence directory, got '/tmp/000001.png'"},
      {"FramePathLeavesSequence",
       [](const fs::path& s) { replaceIn(s / "frames.csv", "frames/000001.png", "../000001.png"); },
       "frames.csv:3: file: must stay inside the sequence directory"},
      {"EmptyLine", [](const fs::path& s) { replaceIn(s / "frames.csv", "file\n", "file\n\n"); },
       "frames.csv:2: empty line"},
      {"BadNumber",
       [](const fs::path& s) {
         replaceIn(s / "telemetry.csv", "360.25,0.7071067811865476", "360.25,x");
       },
       "telemetry.csv:3: qw: not a number 'x'"},
      {"NanInTelemetry",
       [](const fs::path& s) { replaceIn(s / "telemetry.csv", ",43.0731,", ",nan,"); },
       "telemetry.csv:2: latitude_deg: not finite 'nan' (there are no missing values: omit the "
       "row)"},
      {"LatitudeOutOfRange",
       [](const fs::path& s) { replaceIn(s / "telemetry.csv", ",43.0731,", ",93.0731,"); },
       "telemetry.csv:2: latitude_deg: must be in [-90, 90], got 93.0731"},
      {"BadQuaternionNorm",
       [](const fs::path& s) {
         replaceIn(s / "telemetry.csv", "360.25,1,0,0,0", "360.25,0.5,0,0,0");
       },
       "telemetry.csv:2: qw,qx,qy,qz: quaternion norm 0.5 is not 1 (tolerance 0.001)"},
      {"TelemetryTimestampsDecreasing",
       [](const fs::path& s) {
         replaceIn(s / "telemetry.csv", "1700000000050000000", "1699999999000000000");
       },
       "telemetry.csv:4: timestamp_ns: decreasing (1699999999000000000 after 1700000000000000000)"},
      {"WrongColumnCount",
       [](const fs::path& s) {
         replaceIn(s / "telemetry.csv", "-90,0,body\n1700000000000000000",
                   "-90,body\n1700000000000000000");
       },
       "telemetry.csv:2: expected 12 fields, got 11"},
      {"UnknownGimbalReference",
       [](const fs::path& s) { replaceIn(s / "telemetry.csv", ",earth", ",world"); },
       "telemetry.csv:4: gimbal_reference: expected body or earth, got 'world'"},
      {"UnknownType", [](const fs::path& s) { replaceIn(s / kObjects, "large", "truckk"); },
       "ground_truth/objects.csv:4: type: unknown vehicle type 'truckk'"},
      {"UnknownFrameIdInObjects",
       [](const fs::path& s) { replaceIn(s / kObjects, "1,2,large", "7,2,large"); },
       "ground_truth/objects.csv:4: frame_id: no frame 7 in frames.csv"},
      {"ObjectsOutOfFrameOrder",
       [](const fs::path& s) { replaceIn(s / kObjects, "1,2,large", "0,2,large"); },
       "ground_truth/objects.csv:4: frame_id: not in frame order (0 after 1)"},
      {"DuplicateTrack",
       [](const fs::path& s) { replaceIn(s / kObjects, "1,2,large", "1,1,large"); },
       "ground_truth/objects.csv:4: track_id: track 1 appears twice in frame 1"},
      {"GammaAfterEmptyGamma",
       [](const fs::path& s) {
         replaceIn(s / kObjects, "0,1,sedan,0.25,-1.5,", "0,1,sedan,0.25,,");
       },
       "ground_truth/objects.csv:2: gamma_2: value after an empty gamma field"},
      {"LargeVehicleWithShape",
       [](const fs::path& s) { replaceIn(s / kObjects, "large,,", "large,0.5,"); },
       "ground_truth/objects.csv:4: gamma_0: large vehicles have no shape"},
      {"OcclusionOutOfRange",
       [](const fs::path& s) { replaceIn(s / kObjects, "0,0.1,0\n", "0,1.1,0\n"); },
       "ground_truth/objects.csv:3: occlusion: must be in [0, 1], got 1.1"},
      {"BadParkedFlag",
       [](const fs::path& s) { replaceIn(s / kObjects, "0,0.25,0,1\n", "0,0.25,0,yes\n"); },
       "ground_truth/objects.csv:4: parked: expected 0 or 1, got 'yes'"},
      {"KeypointOfUnknownObject",
       [](const fs::path& s) { replaceIn(s / kKeypoints, "1,1,0,16.2", "1,9,0,16.2"); },
       "ground_truth/keypoints.csv:4: track_id: no object 9 in frame 1 of objects.csv"},
      {"KeypointIndexOutOfRange",
       [](const fs::path& s) { replaceIn(s / kKeypoints, "0,1,1,16.8", "0,1,36,16.8"); },
       "ground_truth/keypoints.csv:3: keypoint: must be in [0, 35], got 36"},
      {"DuplicateKeypoint",
       [](const fs::path& s) { replaceIn(s / kKeypoints, "0,1,1,16.8", "0,1,0,16.8"); },
       "ground_truth/keypoints.csv:3: keypoint: keypoint 0 of track 1 appears twice in frame 0"},
      {"KeypointsWithoutObjects", [](const fs::path& s) { fs::remove(s / kObjects); },
       "ground_truth/keypoints.csv: present without"},
  };
}

class BrokenSequence : public ::testing::TestWithParam<BrokenCase> {};

TEST_P(BrokenSequence, IsRejectedWithFileLineAndField) {
  const TempDir temp;
  const fs::path directory = copyFixture(temp.path());
  GetParam().breakIt(directory);

  SequenceReader reader;
  std::string why;
  EXPECT_FALSE(reader.open(directory.string(), &why));
  EXPECT_TRUE(startsWith(why, (directory / GetParam().expected).string()));
  EXPECT_TRUE(reader.frames().empty()) << "a failed open leaves the reader empty";
  EXPECT_TRUE(reader.telemetry().empty());
}

INSTANTIATE_TEST_SUITE_P(Malformed, BrokenSequence, ::testing::ValuesIn(brokenCases()),
                         [](const ::testing::TestParamInfo<BrokenCase>& param) {
                           return param.param.name;
                         });

TEST(RecordedSequence, FailedOpenClearsAnEarlierSequence) {
  const TempDir temp;
  SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(kFixture.string(), &why)) << why;
  EXPECT_FALSE(reader.open((temp.path() / "nothing").string(), &why));
  EXPECT_TRUE(contains(why, "sequence.yaml: missing (required)"));
  EXPECT_TRUE(reader.frames().empty());
  EXPECT_FALSE(reader.hasGroundTruth());
  EXPECT_TRUE(reader.objects(0).empty());
}

// ---- the writer refuses what the reader would reject --------------------------------------

TEST(RecordedSequence, WriterRejectsInvalidInput) {
  const TempDir temp;
  SequenceInfo info;
  info.name = "writer errors";
  std::string why;

  {  // an existing, non-empty directory is never overwritten
    fs::create_directories(temp.path() / "full");
    writeText(temp.path() / "full" / "old.txt", "x");
    SequenceWriter writer;
    EXPECT_FALSE(
        writer.open((temp.path() / "full").string(), info, kRigYaml, kSampleDtm.string(), &why));
    EXPECT_TRUE(contains(why, "exists and is not an empty directory"));
  }
  {  // rig.yaml must name the copied DTM
    std::string rig = kRigYaml;
    rig.replace(rig.find("dtm.tif"), 7, "elsewhere.tif");
    SequenceWriter writer;
    EXPECT_FALSE(writer.open((temp.path() / "rig").string(), info, rig, kSampleDtm.string(), &why));
    EXPECT_TRUE(contains(why, "rig.yaml: terrain.dtm_path: must be dtm.tif"));
  }
  {  // rig.yaml is checked with the configuration schema
    std::string rig = kRigYaml;
    rig.replace(rig.find("fx_px: 40.0"), 11, "fx_px: abc");
    SequenceWriter writer;
    EXPECT_FALSE(
        writer.open((temp.path() / "rig2").string(), info, rig, kSampleDtm.string(), &why));
    EXPECT_TRUE(contains(why, "rig.yaml: camera.fx_px: expected a number, got 'abc'"));
  }

  const fs::path directory = temp.path() / "seq";
  SequenceWriter writer;
  ASSERT_TRUE(writer.open(directory.string(), info, kRigYaml, kSampleDtm.string(), &why)) << why;
  const cv::Mat image(24, 32, CV_8UC3, cv::Scalar::all(90));
  ASSERT_TRUE(writer.writeFrame(FrameRecord{5, 100, ""}, image, &why)) << why;

  EXPECT_FALSE(writer.writeFrame(FrameRecord{5, 200, ""}, image, &why));
  EXPECT_EQ(why, (directory / "frames.csv").string() + ":3: frame_id: not increasing (5 after 5)");
  EXPECT_FALSE(writer.writeFrame(FrameRecord{6, 100, ""}, image, &why));
  EXPECT_TRUE(contains(why, "frames.csv:3: timestamp_ns: not increasing (100 after 100)"));
  EXPECT_FALSE(writer.writeFrame(FrameRecord{6, 200, ""}, cv::Mat(10, 10, CV_8UC3), &why));
  EXPECT_TRUE(contains(why, "frames.csv:3: image: image is 10x10, rig.yaml camera is 32x24"));
  EXPECT_FALSE(writer.writeFrame(FrameRecord{6, 200, ""}, cv::Mat(24, 32, CV_32FC1), &why));
  EXPECT_TRUE(contains(why, "frames.csv:3: image: expected an 8-bit BGR or grey image"));
  EXPECT_FALSE(writer.writeFrame(FrameRecord{6, 200, "frames/a,b.png"}, image, &why));
  EXPECT_TRUE(contains(why, "frames.csv:3: file: must not contain"));
  EXPECT_FALSE(writer.writeFrame(FrameRecord{6, 200, "frames/6.bmp"}, image, &why));
  EXPECT_TRUE(contains(why, "frames.csv:3: file: unsupported image extension '.bmp'"));

  TelemetryRecord telemetry;
  telemetry.bodyToNed = Eigen::Quaterniond(0.5, 0.0, 0.0, 0.0);
  EXPECT_FALSE(writer.writeTelemetry(telemetry, &why));
  EXPECT_TRUE(contains(why, "telemetry.csv:2: qw,qx,qy,qz: quaternion norm 0.5 is not 1"));
  telemetry.bodyToNed = Eigen::Quaterniond::Identity();
  telemetry.position.height_m = std::nan("");
  EXPECT_FALSE(writer.writeTelemetry(telemetry, &why));
  EXPECT_TRUE(contains(why, "telemetry.csv:2: height_m: not finite 'nan'"));

  ObjectTruth object;
  object.frameId = 6;  // not written
  EXPECT_FALSE(writer.writeObjects(std::span(&object, 1), &why));
  EXPECT_TRUE(contains(why, "ground_truth/objects.csv:2: frame_id: no frame 6 in frames.csv"));
  object.frameId = 5;
  object.type = shape::VehicleType::Large;
  object.shape.count = 2;
  EXPECT_FALSE(writer.writeObjects(std::span(&object, 1), &why));
  EXPECT_TRUE(contains(why, "objects.csv:2: gamma_0: large vehicles have no shape"));
  object.shape.count = 0;
  ASSERT_TRUE(writer.writeObjects(std::span(&object, 1), &why)) << why;

  KeypointTruth keypoint;
  keypoint.frameId = 5;
  keypoint.trackId = 3;
  EXPECT_FALSE(writer.writeKeypoints(std::span(&keypoint, 1), &why));
  EXPECT_TRUE(contains(why, "keypoints.csv:2: track_id: no object 3 in frame 5 of objects.csv"));
  ASSERT_TRUE(writer.close(&why)) << why;

  // What was accepted reads back (the rejected rows left no trace).
  SequenceReader reader;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  EXPECT_EQ(reader.frames().size(), 1U);
  EXPECT_TRUE(reader.telemetry().empty());
  ASSERT_EQ(reader.objects(5).size(), 1U);
  // 8 gamma columns: the first writeObjects() call held no shape.
  EXPECT_TRUE(contains(readText(directory / "ground_truth" / "objects.csv"), ",gamma_7,length_m"));
}

TEST(RecordedSequence, RecordingCutShortIsRejected) {
  const TempDir temp;
  const fs::path directory = temp.path() / "seq";
  SequenceInfo info;
  info.name = "cut short";
  std::string why;
  {
    SequenceWriter writer;
    ASSERT_TRUE(writer.open(directory.string(), info, kRigYaml, kSampleDtm.string(), &why));
    // No close(): sequence.yaml is written only by close() (the destructor closes too, so
    // simulate a crash by checking before it runs).
    SequenceReader reader;
    EXPECT_FALSE(reader.open(directory.string(), &why));
    EXPECT_TRUE(contains(why, "sequence.yaml: missing (required)"));
  }
  SequenceReader reader;
  EXPECT_TRUE(reader.open(directory.string(), &why)) << why;  // the destructor closed it
}

// The recorder's mode: encode first (the size in hand), write through a temporary file, rows
// flushed at once, the oldest frames removed to stay within a budget; frames.csv then lists
// the kept frames only and sequence.yaml counts them.
TEST(RecordedSequence, IncrementalWriterKeepsABudgetByRemovingTheOldestFrames) {
  const TempDir temp;
  const fs::path directory = temp.path() / "seq";
  SequenceInfo info;
  info.name = "ring";
  SequenceWriter writer;
  writer.imageExtension = ".jpg";
  writer.jpegQuality = 90;
  writer.flushRows = true;
  std::string why;
  ASSERT_TRUE(writer.open(directory.string(), info, kRigYaml, kSampleDtm.string(), &why)) << why;
  const std::uint64_t start = writer.bytesOnDisk();
  EXPECT_GE(start, fs::file_size(directory / "dtm.tif") + fs::file_size(directory / "rig.yaml"));
  EncodedFrame encoded;
  std::uint64_t imageBytes = 0;
  for (int i = 0; i < 6; ++i) {
    const cv::Mat image(24, 32, CV_8UC3, cv::Scalar(10 * i, 100, 200));
    ASSERT_TRUE(writer.encodeFrame(FrameRecord{i, 1000 + i, ""}, image, encoded, &why)) << why;
    EXPECT_EQ(encoded.record.file, "frames/00000" + std::to_string(i) + ".jpg");
    EXPECT_FALSE(fs::exists(directory / encoded.record.file));  // encoding writes nothing
    ASSERT_TRUE(writer.writeEncodedFrame(encoded, &why)) << why;
    EXPECT_EQ(fs::file_size(directory / encoded.record.file), encoded.bytes.size());
    EXPECT_FALSE(fs::exists(directory / (encoded.record.file + ".tmp")));
    imageBytes += encoded.bytes.size();
    // Flushed rows: the file holds every row written so far, whole.
    const std::string rows = readText(directory / "frames.csv");
    EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), i + 2);
    EXPECT_EQ(rows.back(), '\n');
  }
  EXPECT_EQ(writer.framesKept(), 6U);
  const std::uint64_t full = writer.bytesOnDisk();
  EXPECT_GE(full, start + imageBytes);
  const std::uint64_t oldest = fs::file_size(directory / "frames/000000.jpg");
  ASSERT_TRUE(writer.removeOldestFrame(&why)) << why;
  ASSERT_TRUE(writer.removeOldestFrame(&why)) << why;
  EXPECT_FALSE(fs::exists(directory / "frames/000000.jpg"));
  EXPECT_FALSE(fs::exists(directory / "frames/000001.jpg"));
  EXPECT_LE(writer.bytesOnDisk(), full - oldest);
  EXPECT_EQ(writer.framesKept(), 4U);
  EXPECT_EQ(writer.framesRemoved(), 2U);
  // A frame not after the last one written is refused before anything is written.
  const cv::Mat image(24, 32, CV_8UC3, cv::Scalar(0, 0, 0));
  EXPECT_FALSE(writer.encodeFrame(FrameRecord{5, 2000, ""}, image, encoded, &why));
  EXPECT_TRUE(contains(why, "frames.csv:8: frame_id: not increasing (5 after 5)")) << why;
  writer.setNotes("ring: 2 oldest frames removed");
  ASSERT_TRUE(writer.close(&why)) << why;

  SequenceReader reader;
  ASSERT_TRUE(reader.open(directory.string(), &why)) << why;
  ASSERT_EQ(reader.frames().size(), 4U);
  EXPECT_EQ(reader.frames().front().frameId, 2);
  EXPECT_EQ(reader.frames().front().timestamp_ns, 1002);
  EXPECT_EQ(reader.frames().back().frameId, 5);
  EXPECT_EQ(reader.info().notes, "ring: 2 oldest frames removed");
  for (std::size_t i = 0; i < reader.frames().size(); ++i) {
    cv::Mat decoded;
    EXPECT_TRUE(reader.loadFrame(i, decoded, &why)) << why;
  }
  EXPECT_FALSE(fs::exists(directory / "frames.csv.tmp"));
  EXPECT_FALSE(fs::exists(directory / "sequence.yaml.tmp"));
}

TEST(RecordedSequence, FramesCannotBeRemovedOnceGroundTruthNamesThem) {
  const TempDir temp;
  SequenceInfo info;
  info.name = "truth";
  SequenceWriter writer;
  std::string why;
  ASSERT_TRUE(
      writer.open((temp.path() / "seq").string(), info, kRigYaml, kSampleDtm.string(), &why))
      << why;
  EXPECT_FALSE(writer.removeOldestFrame(&why));
  EXPECT_TRUE(contains(why, "no frame left to remove")) << why;
  const cv::Mat image(24, 32, CV_8UC3, cv::Scalar(0, 0, 0));
  ASSERT_TRUE(writer.writeFrame(FrameRecord{0, 1, ""}, image, &why)) << why;
  ASSERT_TRUE(writer.writeObjects({}, &why)) << why;
  EXPECT_FALSE(writer.removeOldestFrame(&why));
  EXPECT_TRUE(contains(why, "ground truth")) << why;
}

}  // namespace
}  // namespace vp::sequence
