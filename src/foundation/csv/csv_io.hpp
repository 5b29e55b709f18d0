// csv/csv_io: the CSV mechanics that the recorded-sequence reader (input) and the output files
// (detections file, trajectory file) share; the formats themselves live with their modules
// (sequence/recorded_sequence, output_files/detections_file, output_files/trajectory_file).
//
// Contract: CsvFileWriter is a small RAII writer for the real-time loop: open() allocates once
// (a row buffer of the size asked for and the buffer of pending rows) and creates the file; the
// owner formats a row into rowBuffer(), writeRow() appends it to the pending rows and commit()
// hands them to the kernel with one write(2) (no stdio buffering: rows committed survive a
// kill, and the file always ends with a complete row, a kill inside the write call aside). No
// allocation after open(); every failure is returned as a value (never thrown) when it
// happens, and the destructor commits and closes an open file, dropping errors. The reader helpers
// are for offline (start-up) readers: they throw ReadError with a complete message,
// "<file>:<line>:<column>: <field>: <problem>" for a field (column = 1-based character position of
// the field in the line), which readChecked() catches and returns. Fields are plain comma-separated
// text: quoted fields are rejected.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace vp::csv {

// ---- writing -------------------------------------------------------------------------------

// Stores message in *why (when given) and returns false, for `return failWith(why, ...)`.
bool failWith(std::string* why, const std::string& message);

class CsvFileWriter {
 public:
  CsvFileWriter() = default;
  ~CsvFileWriter();  // commits the pending rows and closes an open file, dropping errors
  CsvFileWriter(const CsvFileWriter&) = delete;
  CsvFileWriter& operator=(const CsvFileWriter&) = delete;

  // Both output files' writers take a gamma column count in [0, maxGammaColumns] (the ASM's
  // largest shape count, which this layer does not know) and refuse a second open(): the
  // checks they make before anything else.
  bool checkOpen(const std::string& path, int gammaColumns, int maxGammaColumns,
                 std::string* why) const;
  // Allocates the buffers and creates (truncates) path. Start-up.
  bool open(const std::string& path, std::size_t rowBytes, std::string* why);
  // Writes the lines before the rows, at once; an empty text (a formatter that failed) fails.
  bool writeHeader(std::string_view text, std::string* why);
  // The preallocated buffer a row is formatted into.
  std::span<char> rowBuffer() { return {row_.get(), rowBytes_}; }
  // Appends the first `size` bytes of rowBuffer() (one complete row) to the pending rows. When
  // they are full, commit() runs first; false when that commit failed (the row is kept for the
  // next one). No allocation.
  bool writeRow(std::size_t size);
  // Hands every pending row to the kernel in one write(2) (continued only after a partial
  // write): from then on they survive the process being killed. The app commits once per
  // frame. On failure (disk full, I/O error) the pending rows are dropped (rowsLost()), the
  // file is cut back to its last complete row where the file system allows it, the errno is
  // kept (lastErrno(), the first one in firstErrno()) and false returned; a later commit tries
  // again. No allocation, never throws.
  bool commit();
  // commit() with a message naming the file.
  bool flush(std::string* why);
  // Commits and closes; false (naming the file and the first error) when any write failed
  // since open(). `writerName` names the writer in the message of a close() without open().
  bool close(const char* writerName, std::string* why);

  bool isOpen() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  std::int64_t rowsWritten() const { return rowsWritten_; }  // rows taken by writeRow()
  std::int64_t rowsLost() const { return rowsLost_; }        // of those, dropped by a failed commit
  int lastErrno() const { return lastErrno_; }
  int firstErrno() const { return firstErrno_; }

 private:
  bool writeAll(const char* data, std::size_t size);

  int fd_ = -1;
  std::unique_ptr<char[]> pending_;  // rows not yet committed, complete rows only
  std::size_t pendingBytes_ = 0;     // capacity
  std::size_t pendingSize_ = 0;
  std::int64_t pendingRows_ = 0;
  std::unique_ptr<char[]> row_;  // one formatted row
  std::size_t rowBytes_ = 0;
  std::string path_;
  std::int64_t fileBytes_ = 0;  // bytes committed: the file ends with a complete line there
  std::int64_t rowsWritten_ = 0;
  std::int64_t rowsLost_ = 0;
  int lastErrno_ = 0;
  int firstErrno_ = 0;
};

// The header line of these column names (without the line break).
std::string joinColumns(const std::vector<std::string>& names);

// ---- reading -------------------------------------------------------------------------------

// A complete message; thrown inside the readers only (start-up code) and returned.
struct ReadError {
  std::string message;
};

// A problem found in a record, without allocating: the column and a static description. The
// semantic checks return it so that the writer and the reader share them.
struct Problem {
  int column = -1;
  const char* what = "";
};

// User text in a message is capped, so that a 10 MB file name or field neither floods the log
// nor pushes the rest of the line (frame, line number) out of it: longer text keeps its start
// and its end around "..." (the end of a path names the file).
constexpr std::size_t kMaxMessagePathChars = 200;  // a path in a message
constexpr std::size_t kMaxQuotedChars = 1024;      // a quoted field or header in a message
std::string shortened(std::string_view text, std::size_t maxChars = kMaxMessagePathChars);

// 'text' in quotes, shortened() to kMaxQuotedChars.
std::string quote(std::string_view text);
// "<file>:<line>" (the file shortened()), the start of every message about a line.
std::string location(const std::string& file, int line);

// Splits `line` at commas into `fields` (views into `line`; quotes are not special).
void splitFields(std::string_view line, std::vector<std::string_view>& fields);

// The whole file; throws ReadError "<file>: cannot open (missing or unreadable)".
std::string readWholeFile(const std::string& path);

// Calls onLine(line, text) for each line of text (line counted from 1, the '\n' and a '\r'
// before it removed); returns the number of lines.
template <typename OnLine>
int forEachLine(std::string_view text, OnLine&& onLine) {
  std::size_t position = 0;
  int line = 0;
  while (position < text.size()) {
    const std::size_t end = std::min(text.find('\n', position), text.size());
    std::string_view row = text.substr(position, end - position);
    position = end + 1;
    ++line;
    if (!row.empty() && row.back() == '\r') {
      row.remove_suffix(1);
    }
    onLine(line, row);
  }
  return line;
}

// Runs read() (which fills *out and throws ReadError on a problem) on a fresh File whose path
// is set; on a problem leaves *out empty but for its path and puts the message in *why.
template <typename File, typename Read>
bool readChecked(const std::string& path, File* out, std::string* why, Read&& read) {
  *out = File{};
  out->path = path;
  try {
    read();
  } catch (const ReadError& error) {
    *out = File{};
    out->path = path;
    return failWith(why, error.message);
  }
  return true;
}

// One data row split into its fields and checked against the column names on construction
// (an empty line is an error: "<file>:<line>: empty line").
// The accessors throw ReadError naming file:line:column and the field's column name.
class RowParser {
 public:
  RowParser(const std::string& file, int line, std::string_view text,
            const std::vector<std::string>& names);

  std::string_view field(int i) const { return fields_[static_cast<std::size_t>(i)]; }
  [[noreturn]] void fail(int column, const std::string& problem) const;
  // An integer in [low, high].
  std::int64_t integer(int i, std::int64_t low, std::int64_t high) const;
  // A finite number (a value is required).
  template <typename T>
  T real(int i) const;

 private:
  const std::string& file_;
  int line_;
  const std::vector<std::string>& names_;
  std::vector<std::string_view> fields_;
  std::vector<std::size_t> starts_;
};

extern template float RowParser::real<float>(int i) const;
extern template double RowParser::real<double>(int i) const;

}  // namespace vp::csv
