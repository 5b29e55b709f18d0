#include "csv/csv_io.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace vp::csv {
namespace {

// Pending rows: one frame's rows in one write (hundreds of detections or tracks), more only
// when a frame has more; a writer that never commits (offline tools) writes in blocks of it.
constexpr std::size_t kPendingBytes = 256 * 1024;

}  // namespace

bool failWith(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

// ---- writer --------------------------------------------------------------------------------

CsvFileWriter::~CsvFileWriter() {
  if (fd_ >= 0) {
    commit();
    ::close(fd_);
  }
}

bool CsvFileWriter::checkOpen(const std::string& path, int gammaColumns, int maxGammaColumns,
                              std::string* why) const {
  if (fd_ >= 0) {
    return failWith(why, shortened(path) + ": writer already open on " + shortened(path_));
  }
  if (gammaColumns < 0 || gammaColumns > maxGammaColumns) {
    return failWith(why, shortened(path) + ": gammaColumns must be in [0, " +
                             std::to_string(maxGammaColumns) + "], got " +
                             std::to_string(gammaColumns));
  }
  return true;
}

bool CsvFileWriter::open(const std::string& path, std::size_t rowBytes, std::string* why) {
  if (fd_ >= 0) {
    return failWith(why, shortened(path) + ": writer already open on " + shortened(path_));
  }
  row_ = std::make_unique<char[]>(rowBytes);
  rowBytes_ = rowBytes;
  pendingBytes_ = std::max(kPendingBytes, rowBytes);
  pending_ = std::make_unique<char[]>(pendingBytes_);
  pendingSize_ = 0;
  pendingRows_ = 0;
  // 0666 less the umask: the permissions fopen() gives a new file.
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    return failWith(why, shortened(path) + ": cannot create file: " + std::strerror(errno));
  }
  path_ = path;
  fileBytes_ = 0;
  rowsWritten_ = 0;
  rowsLost_ = 0;
  lastErrno_ = 0;
  firstErrno_ = 0;
  return true;
}

bool CsvFileWriter::writeAll(const char* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, data + done, size - done);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      lastErrno_ = n < 0 ? errno : EIO;
      if (firstErrno_ == 0) {
        firstErrno_ = lastErrno_;
      }
      // Cut a partly written block back to the last complete line, so that the file stays
      // readable and the next commit does not continue a broken row (not possible on every
      // file: /dev/full, pipes).
      if (done > 0 && ::ftruncate(fd_, static_cast<off_t>(fileBytes_)) == 0) {
        ::lseek(fd_, static_cast<off_t>(fileBytes_), SEEK_SET);
      }
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  fileBytes_ += static_cast<std::int64_t>(size);
  return true;
}

bool CsvFileWriter::writeHeader(std::string_view text, std::string* why) {
  if (fd_ < 0) {
    return failWith(why, "writeHeader() without open()");
  }
  if (text.empty() || !writeAll(text.data(), text.size())) {
    return failWith(why, shortened(path_) + ": write failed: " +
                             (text.empty() ? std::string("empty header")
                                           : std::string(std::strerror(lastErrno_))));
  }
  return true;
}

bool CsvFileWriter::writeRow(std::size_t size) {
  if (fd_ < 0 || size > rowBytes_) {
    return false;
  }
  bool ok = true;
  if (pendingBytes_ - pendingSize_ < size) {
    ok = commit();
  }
  std::memcpy(pending_.get() + pendingSize_, row_.get(), size);
  pendingSize_ += size;
  ++pendingRows_;
  ++rowsWritten_;
  return ok;
}

bool CsvFileWriter::commit() {
  if (fd_ < 0) {
    return false;
  }
  if (pendingSize_ == 0) {
    return true;
  }
  const bool ok = writeAll(pending_.get(), pendingSize_);
  if (!ok) {
    rowsLost_ += pendingRows_;
  }
  pendingSize_ = 0;
  pendingRows_ = 0;
  return ok;
}

bool CsvFileWriter::flush(std::string* why) {
  if (fd_ < 0) {
    return failWith(why, shortened(path_) + ": flush failed (writer is not open)");
  }
  if (!commit()) {
    return failWith(why, shortened(path_) + ": write failed: " + std::strerror(lastErrno_));
  }
  return true;
}

bool CsvFileWriter::close(const char* writerName, std::string* why) {
  if (fd_ < 0) {
    return failWith(why, std::string(writerName) + ": close() without open()");
  }
  commit();
  if (::close(fd_) != 0 && firstErrno_ == 0) {
    firstErrno_ = errno;
  }
  fd_ = -1;
  if (firstErrno_ != 0) {
    return failWith(why, shortened(path_) + ": write failed: " + std::strerror(firstErrno_) + " (" +
                             std::to_string(rowsLost_) + " rows lost)");
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

std::string shortened(std::string_view text, std::size_t maxChars) {
  constexpr std::string_view kEllipsis = "...";
  if (text.size() <= maxChars) {
    return std::string(text);
  }
  if (maxChars <= kEllipsis.size()) {
    return std::string(text.substr(0, maxChars));
  }
  const std::size_t kept = maxChars - kEllipsis.size();
  const std::size_t head = kept / 2;
  const std::size_t tail = kept - head;
  std::string out;
  out.reserve(maxChars);
  out.append(text.substr(0, head));
  out.append(kEllipsis);
  out.append(text.substr(text.size() - tail));
  return out;
}

std::string quote(std::string_view text) {
  // Built by appending: GCC 12 at -O3 reports a false -Wrestrict on "'" + std::string(...).
  const std::string body = shortened(text, kMaxQuotedChars);
  std::string out;
  out.reserve(body.size() + 2);
  out.push_back('\'');
  out.append(body);
  out.push_back('\'');
  return out;
}

std::string location(const std::string& file, int line) {
  return shortened(file) + ":" + std::to_string(line);
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
