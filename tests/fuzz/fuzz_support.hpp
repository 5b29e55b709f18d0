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

}  // namespace vp::fuzz
