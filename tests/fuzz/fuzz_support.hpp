// fuzz/fuzz_support: what the fuzz harnesses of tests/fuzz share.
//
// Contract: each harness (one file per target) defines LLVMFuzzerTestOneInput and checks the
// contract of one parser of the product on arbitrary bytes: it returns or reports an error
// value, never crashes, never throws anything but its documented error type, and its messages
// name the file. The harness is linked either with libFuzzer (preset fuzz, clang) or with
// replay_main.cpp (every build: the CTest regression over the corpus). A broken contract
// aborts with a message (expect()), which libFuzzer records as a finding. Loaders that take a
// path get the bytes through files in a private scratch directory of the process.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vp::fuzz {

// The process's scratch directory (created on first use under $TMPDIR or /tmp, removed at
// exit).
const std::filesystem::path& scratchDirectory();

// Writes `bytes` to `path` (truncating); aborts when the file cannot be written (a harness
// problem, not a finding of the target).
void writeFile(const std::filesystem::path& path, std::string_view bytes);
// Removes `path` when it exists.
void removeFile(const std::filesystem::path& path);

// Splits `data` at NUL bytes into at most `maxParts` parts (the last part keeps any further
// NULs). Inputs of the multi-file targets are their files joined with NUL bytes.
std::vector<std::string_view> splitParts(std::string_view data, std::size_t maxParts);

// Aborts with "<target>: contract broken: <what>" when `condition` is false.
void expect(bool condition, const char* target, const std::string& what);

// With VP_FUZZ_VERBOSE set in the environment, prints "<target>: <what>" (why an input was
// refused, what it loaded): to see how far a seed gets.
void note(const char* target, const std::string& what);

inline std::string_view asText(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// The whole file as bytes ("" when it cannot be read).
std::string readBytes(const std::filesystem::path& path);

// The round trip of a CSV output format on arbitrary contents: read(path, File*, why) returns
// true, or false with a message naming the file; a file it accepts (one line number per row),
// written by write(file, path), is accepted again, and writing what was read back reproduces
// the first write byte for byte. `name` is the scratch files' stem. Returns 0 (libFuzzer's).
template <class File, class Read, class Write>
int checkRoundTrip(const char* target, const std::string& name, const std::uint8_t* data,
                   std::size_t size, Read read, Write write) {
  const std::filesystem::path input = scratchDirectory() / (name + ".csv");
  writeFile(input, asText(data, size));
  File file;
  std::string why;
  if (!read(input.string(), &file, &why)) {
    note(target, why);
    expect(why.starts_with(input.string()), target,
           "read failed without naming the file: '" + why + "'");
    return 0;
  }
  note(target, "accepted " + std::to_string(file.rows.size()) + " rows");
  expect(file.rows.size() == file.lines.size(), target, "rows and lines differ");

  const std::filesystem::path first = scratchDirectory() / (name + "_1.csv");
  const std::filesystem::path second = scratchDirectory() / (name + "_2.csv");
  write(file, first);
  File again;
  expect(read(first.string(), &again, &why), target,
         "the reader refuses what the writer wrote from an accepted file: " + why);
  expect(again.rows.size() == file.rows.size(), target, "row count changed");
  write(again, second);
  expect(readBytes(first) == readBytes(second), target,
         "write(read(write(read(file)))) differs from write(read(file))");
  return 0;
}

}  // namespace vp::fuzz
