// fuzz/fuzz_support: scratch files and checks shared by the harnesses (fuzz_support.hpp).
#include "fuzz_support.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <system_error>

namespace vp::fuzz {
namespace {

// Owns the scratch directory: created by mkdtemp, removed with its files at exit.
class Scratch {
 public:
  Scratch() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern =
        std::string(base != nullptr && base[0] != '\0' ? base : "/tmp") + "/vp_fuzz_XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) {
      std::fprintf(stderr, "fuzz: cannot create a scratch directory %s\n", pattern.c_str());
      std::abort();
    }
    path_ = pattern;
  }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace

const std::filesystem::path& scratchDirectory() {
  static const Scratch scratch;
  return scratch.path();
}

void writeFile(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
}

void removeFile(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

std::vector<std::string_view> splitParts(std::string_view data, std::size_t maxParts) {
  std::vector<std::string_view> parts;
  while (parts.size() + 1 < maxParts) {
    const std::size_t nul = data.find('\0');
    if (nul == std::string_view::npos) {
      break;
    }
    parts.push_back(data.substr(0, nul));
    data.remove_prefix(nul + 1);
  }
  parts.push_back(data);
  return parts;
}

void expect(bool condition, const char* target, const std::string& what) {
  if (!condition) {
    std::fprintf(stderr, "%s: contract broken: %s\n", target, what.c_str());
    std::abort();
  }
}

void note(const char* target, const std::string& what) {
  static const bool verbose = std::getenv("VP_FUZZ_VERBOSE") != nullptr;
  if (verbose) {
    std::fprintf(stderr, "%s: %s\n", target, what.c_str());
  }
}

std::string readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;  // (istreambuf_iterator trips g++ 12's -Wnull-dereference)
  text << in.rdbuf();
  return text.str();
}

}  // namespace vp::fuzz
