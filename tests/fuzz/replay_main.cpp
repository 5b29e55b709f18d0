// fuzz/replay_main: a standalone driver for the fuzz harnesses, for builds without libFuzzer
// (g++, CI). It calls LLVMFuzzerTestOneInput on every file given (directories: every regular
// file in them, in name order), then on `--mutations N` deterministic mutations of each
// (bit flips, byte changes, insertions, deletions, duplicated chunks, truncation; the same
// sequence on every run and machine). A finding aborts the process, so the test fails.
//   fuzz_replay_<target> [--mutations N] PATH...
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

// xorshift64*: small, fast, identical everywhere.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed != 0 ? seed : 0x9E3779B97F4A7C15ULL) {}
  std::uint64_t next() {
    state_ ^= state_ >> 12;
    state_ ^= state_ << 25;
    state_ ^= state_ >> 27;
    return state_ * 0x2545F4914F6CDD1DULL;
  }
  // Uniform enough in [0, n) for n > 0.
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }

 private:
  std::uint64_t state_;
};

std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t hash = 0xCBF29CE484222325ULL;
  for (const char c : bytes) {
    hash = (hash ^ static_cast<unsigned char>(c)) * 0x100000001B3ULL;
  }
  return hash;
}

// Bytes that matter to the product's parsers: digits and separators of CSV and YAML, signs,
// exponents, NUL (the part separator of multi-file inputs) and integer edge values.
constexpr char kInterestingBytes[] = "0123456789.-+eE,:\n #'\"[]{}\0\x7f\x80\xff";
constexpr std::string_view kInteresting(kInterestingBytes, sizeof(kInterestingBytes) - 1);

void mutateOnce(std::string& bytes, Random& random) {
  const std::size_t size = bytes.size();
  switch (random.below(size == 0 ? 1 : 8)) {
    case 0:  // insert one byte
      bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(random.below(size + 1)),
                   kInteresting[random.below(kInteresting.size())]);
      break;
    case 1:  // flip a bit
      bytes[random.below(size)] ^= static_cast<char>(1U << random.below(8));
      break;
    case 2:  // any byte
      bytes[random.below(size)] = static_cast<char>(random.below(256));
      break;
    case 3:  // an interesting byte
      bytes[random.below(size)] = kInteresting[random.below(kInteresting.size())];
      break;
    case 4: {  // erase a range
      const std::size_t at = random.below(size);
      bytes.erase(at, 1 + random.below(std::min<std::size_t>(size - at, 16)));
      break;
    }
    case 5: {  // duplicate a chunk somewhere else
      const std::size_t from = random.below(size);
      const std::string chunk = bytes.substr(from, 1 + random.below(64));
      bytes.insert(random.below(size + 1), chunk);
      break;
    }
    case 6:  // truncate
      bytes.resize(random.below(size));
      break;
    default: {  // a little-endian 32-bit edge value (sizes, counts, offsets of binary formats)
      static constexpr std::uint32_t kEdges[] = {0,      1,          0x7F,       0x80,      0xFF,
                                                 0xFFFF, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF};
      const std::uint32_t value = kEdges[random.below(std::size(kEdges))];
      const std::size_t at = random.below(size);
      for (std::size_t i = 0; i < 4 && at + i < size; ++i) {
        bytes[at + i] = static_cast<char>((value >> (8 * i)) & 0xFFU);
      }
      break;
    }
  }
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "fuzz replay: cannot read %s\n", path.c_str());
    std::exit(2);
  }
  std::ostringstream text;  // (istreambuf_iterator trips g++ 12's -Wnull-dereference)
  text << in.rdbuf();
  return text.str();
}

void run(const std::string& bytes) {
  LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace

int main(int argc, char** argv) {
  long mutations = 0;
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mutations" && i + 1 < argc) {
      mutations = std::strtol(argv[++i], nullptr, 10);
      continue;
    }
    std::error_code error;
    if (fs::is_directory(arg, error)) {
      std::vector<fs::path> inDirectory;
      for (const auto& entry : fs::directory_iterator(arg)) {
        if (entry.is_regular_file()) {
          inDirectory.push_back(entry.path());
        }
      }
      std::sort(inDirectory.begin(), inDirectory.end());
      files.insert(files.end(), inDirectory.begin(), inDirectory.end());
    } else if (fs::is_regular_file(arg, error)) {
      files.emplace_back(arg);
    } else {
      std::fprintf(stderr, "fuzz replay: no such file or directory %s\n", arg.c_str());
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: %s [--mutations N] FILE_OR_DIRECTORY...\n", argv[0]);
    return 2;
  }
  long executions = 0;
  for (const fs::path& file : files) {
    const std::string original = readFile(file);
    run(original);
    ++executions;
    Random random(fnv1a(original));
    for (long m = 0; m < mutations; ++m) {
      std::string mutated = original;
      const std::size_t edits = 1 + random.below(4);
      for (std::size_t e = 0; e < edits; ++e) {
        mutateOnce(mutated, random);
      }
      run(mutated);
      ++executions;
    }
  }
  std::printf("fuzz replay: %zu inputs, %ld executions, no finding\n", files.size(), executions);
  return 0;
}
