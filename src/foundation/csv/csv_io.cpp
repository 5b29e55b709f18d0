#include "csv/csv_io.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace vp::csv {
namespace {

constexpr std::size_t kIoBufferBytes = 64 * 1024;  // stdio buffer: a few hundred rows

}  // namespace

bool failWith(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

// ---- writer --------------------------------------------------------------------------------

CsvFileWriter::~CsvFileWriter() {
  if (file_ != nullptr) {
    std::fclose(file_);
  }
}

bool CsvFileWriter::checkOpen(const std::string& path, int gammaColumns, int maxGammaColumns,
                              std::string* why) const {
  if (file_ != nullptr) {
    return failWith(why, path + ": writer already open on " + path_);
  }
  if (gammaColumns < 0 || gammaColumns > maxGammaColumns) {
    return failWith(why, path + ": gammaColumns must be in [0, " + std::to_string(maxGammaColumns) +
                             "], got " + std::to_string(gammaColumns));
  }
  return true;
}

bool CsvFileWriter::open(const std::string& path, std::size_t rowBytes, std::string* why) {
  if (file_ != nullptr) {
    return failWith(why, path + ": writer already open on " + path_);
  }
  ioBuffer_ = std::make_unique<char[]>(kIoBufferBytes);
  row_ = std::make_unique<char[]>(rowBytes);
  rowBytes_ = rowBytes;
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) {
    return failWith(why, path + ": cannot create file: " + std::strerror(errno));
  }
  // Our buffer, set before any I/O: stdio then never allocates one on the first write.
  std::setvbuf(file_, ioBuffer_.get(), _IOFBF, kIoBufferBytes);
  path_ = path;
  rowsWritten_ = 0;
  failed_ = false;
  return true;
}

bool CsvFileWriter::writeHeader(std::string_view text, std::string* why) {
  if (text.empty() || std::fwrite(text.data(), 1, text.size(), file_) != text.size()) {
    failed_ = true;
    return failWith(why, path_ + ": write failed: " + std::strerror(errno));
  }
  return true;
}

bool CsvFileWriter::writeRow(std::size_t size) {
  if (std::fwrite(row_.get(), 1, size, file_) != size) {
    failed_ = true;
    return false;
  }
  ++rowsWritten_;
  return true;
}

bool CsvFileWriter::flush(std::string* why) {
  if (file_ == nullptr || std::fflush(file_) != 0 || failed_) {
    return failWith(why,
                    path_ + ": flush failed" + (file_ == nullptr ? " (writer is not open)" : ""));
  }
  return true;
}

bool CsvFileWriter::close(const char* writerName, std::string* why) {
  if (file_ == nullptr) {
    return failWith(why, std::string(writerName) + ": close() without open()");
  }
  const bool flushed = std::fflush(file_) == 0 && std::ferror(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed || failed_) {
    return failWith(why, path_ + ": write failed (disk full?)");
  }
  return true;
}

std::string joinColumns(const std::vector<std::string>& names) {
  std::string line;
  for (const std::string& name : names) {
    line += (line.empty() ? "" : ",") + name;
  }
  return line;
}

// ---- reader --------------------------------------------------------------------------------

std::string quote(std::string_view text) {
  // Built by appending: GCC 12 at -O3 reports a false -Wrestrict on "'" + std::string(...).
  std::string out;
  out.reserve(text.size() + 2);
  out.push_back('\'');
  out.append(text);
  out.push_back('\'');
  return out;
}

std::string location(const std::string& file, int line) {
  return file + ":" + std::to_string(line);
}

void splitFields(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(line.substr(start));
      return;
    }
    fields.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
}

std::string readWholeFile(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) {
    throw ReadError{path + ": cannot open (missing or unreadable)"};
  }
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

RowParser::RowParser(const std::string& file, int line, std::string_view text,
                     const std::vector<std::string>& names)
    : file_(file), line_(line), names_(names) {
  if (text.empty()) {
    throw ReadError{location(file_, line_) + ": empty line"};
  }
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    starts_.push_back(start);
    if (comma == std::string_view::npos) {
      fields_.push_back(text.substr(start));
      break;
    }
    fields_.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    if (fields_[i].find('"') != std::string_view::npos) {
      fail(static_cast<int>(i), "quoted fields are not supported (fields never contain commas)");
    }
  }
  if (fields_.size() != names_.size()) {
    throw ReadError{location(file_, line_) + ": expected " + std::to_string(names_.size()) +
                    " fields, got " + std::to_string(fields_.size())};
  }
}

void RowParser::fail(int column, const std::string& problem) const {
  const auto c = static_cast<std::size_t>(column);
  const std::string name = c < names_.size() ? names_[c] : "field " + std::to_string(c + 1);
  const std::size_t at = c < starts_.size() ? starts_[c] + 1 : 1;
  throw ReadError{location(file_, line_) + ":" + std::to_string(at) + ": " + name + ": " + problem};
}

std::int64_t RowParser::integer(int i, std::int64_t low, std::int64_t high) const {
  const std::string_view t = field(i);
  std::int64_t value = 0;
  const auto [ptr, error] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (t.empty() || error != std::errc() || ptr != t.data() + t.size()) {
    fail(i, "not an integer " + quote(t));
  }
  if (value < low || value > high) {
    fail(i, "must be in [" + std::to_string(low) + ", " + std::to_string(high) + "], got " +
                std::string(t));
  }
  return value;
}

template <typename T>
T RowParser::real(int i) const {
  const std::string_view t = field(i);
  if (t.empty()) {
    fail(i, "empty (a value is required here)");
  }
  T value = 0;
  const auto [ptr, error] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (error != std::errc() || ptr != t.data() + t.size()) {
    fail(i, "not a number " + quote(t));
  }
  if (!std::isfinite(value)) {
    fail(i, "not finite " + quote(t));
  }
  return value;
}

template float RowParser::real<float>(int i) const;
template double RowParser::real<double>(int i) const;

}  // namespace vp::csv
