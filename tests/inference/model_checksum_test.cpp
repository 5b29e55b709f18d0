// Tests of inference/model_checksum: SHA-256 on the standard's test vectors, and Engine::load()
// refusing a model whose bytes do not match its checksum file.
#include "inference/model_checksum.hpp"

#include <onnx/onnx_pb.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <system_error>

#include <gtest/gtest.h>

#include "inference/engine.hpp"

namespace vp::inference {
namespace {

namespace fs = std::filesystem;

const fs::path kModel = fs::path(VP_FIXTURE_DIR) / "models" / "classifier.onnx";

std::string contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;  // (istreambuf_iterator trips g++ 12's -Wnull-dereference)
  text << in.rdbuf();
  return text.str();
}

void write(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

class ModelChecksum : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("vp_model_checksum_test_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  fs::path dir_;
};

// FIPS 180-2 appendix B and the empty message; lengths around the padding boundaries.
TEST(Sha256, StandardTestVectors) {
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // 55, 56 and 64 bytes: the length fits in the last block, just does not, a whole block.
  EXPECT_EQ(sha256Hex(std::string(55, 'a')),
            "9f4390f8d30c2dd92ec9f095b65e2b9ae9b0a925a5258e241c9f1e910f734318");
  EXPECT_EQ(sha256Hex(std::string(56, 'a')),
            "b35439a4ac6f0948b6d6f9e3c6af0f5f590ce20f1bde7090ef7970686ec6738a");
  EXPECT_EQ(sha256Hex(std::string(64, 'a')),
            "ffe054fe7ae0cb6dc65c3af9b61d5209f439851db43d0ba5997337df154668eb");
}

// The committed checksum files match the committed models (scripts/model_checksums.sh).
TEST(Sha256, ShippedChecksumFilesMatch) {
  for (const fs::path& model :
       {kModel, fs::path(VP_SOURCE_DIR) / "models" / "detector" / "detector_int8.onnx",
        fs::path(VP_SOURCE_DIR) / "models" / "detector" / "crop_int8.onnx"}) {
    std::string why;
    EXPECT_EQ(verifyModelChecksum(model.string(), contents(model), &why), ChecksumResult::Verified)
        << model << ": " << why;
    EXPECT_EQ(contents(checksumPath(model.string())),
              sha256Hex(contents(model)) + "  " + model.filename().string() + "\n");
  }
}

// One int8 weight changed: the file still parses and loads, and only the checksum sees it.
TEST_F(ModelChecksum, CorruptedWeightsFailTheLoad) {
  onnx::ModelProto model;
  {
    std::ifstream in(kModel, std::ios::binary);
    ASSERT_TRUE(model.ParseFromIstream(&in));
  }
  bool changed = false;
  for (auto& tensor : *model.mutable_graph()->mutable_initializer()) {
    if (tensor.data_type() == onnx::TensorProto::INT8 && tensor.raw_data().size() > 16) {
      std::string& raw = *tensor.mutable_raw_data();
      raw[raw.size() / 2] = static_cast<char>(raw[raw.size() / 2] ^ 0x01);
      changed = true;
      break;
    }
  }
  ASSERT_TRUE(changed) << "no int8 weight tensor in " << kModel;
  const fs::path corrupt = dir_ / "classifier.onnx";
  {
    std::ofstream out(corrupt, std::ios::binary);
    ASSERT_TRUE(model.SerializeToOstream(&out));
  }
  const std::string expected = sha256Hex(contents(kModel));
  const std::string actual = sha256Hex(contents(corrupt));
  ASSERT_NE(expected, actual);

  Engine engine;
  std::string why;
  // Without a checksum file the damage goes unnoticed: the model loads.
  ASSERT_TRUE(engine.load(corrupt.string(), EngineOptions{}, &why)) << why;
  // With the shipped checksum beside it, the load fails naming the file and both digests.
  fs::copy_file(checksumPath(kModel.string()), checksumPath(corrupt.string()));
  EXPECT_FALSE(engine.load(corrupt.string(), EngineOptions{}, &why));
  EXPECT_FALSE(engine.loaded());
  EXPECT_EQ(why, corrupt.string() + ": SHA-256 mismatch: expected " + expected +
                     " (classifier.onnx.sha256), actual " + actual +
                     ": the model file is corrupt or was changed");
  // The intact model with the same checksum file loads.
  fs::copy_file(kModel, corrupt, fs::copy_options::overwrite_existing);
  EXPECT_TRUE(engine.load(corrupt.string(), EngineOptions{}, &why)) << why;
}

TEST_F(ModelChecksum, MalformedChecksumFileFailsTheLoad) {
  const fs::path copy = dir_ / "classifier.onnx";
  fs::copy_file(kModel, copy);
  write(checksumPath(copy.string()), "not a digest\n");
  Engine engine;
  std::string why;
  EXPECT_FALSE(engine.load(copy.string(), EngineOptions{}, &why));
  EXPECT_EQ(why, checksumPath(copy.string()) +
                     ": not a SHA-256 checksum file (expected 64 hex digits, then the file name, "
                     "as written by sha256sum)");
  // Upper-case hex digits and a bare digest (no file name) are sha256sum-compatible.
  std::string digest = sha256Hex(contents(copy));
  for (char& c : digest) {
    c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  write(checksumPath(copy.string()), digest);
  EXPECT_TRUE(engine.load(copy.string(), EngineOptions{}, &why)) << why;
}

}  // namespace
}  // namespace vp::inference
