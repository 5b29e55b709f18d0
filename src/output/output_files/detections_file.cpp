#include "output_files/detections_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <utility>

namespace vp::output_files {
namespace {

using csv::Problem;
using csv::quote;
using csv::ReadError;
using csv::RowParser;

constexpr double kProbabilitySumTolerance = 1e-3;  // |sum p - 1| allowed (float rounding)
constexpr std::size_t kRowBufferBytes = 4096;      // > the longest row (~42 fields * 26 + stem)

constexpr std::array<const char*, kLiftStatusCount> kLiftStatusWords{
    "ok",           "not_lifted",    "no_pose",     "stale_pose", "invalid_pose",   "invalid_box",
    "outside_lens", "behind_camera", "outside_dtm", "no_data",    "no_intersection"};

// The columns after the key (frame_id or image) and before the probabilities; format 1 lacks
// at_frame_edge and vehicle_probability (kFormat2Columns of them, after direction_known).
constexpr std::array<const char*, 11> kHeadColumns{
    "det_id",       "score",         "box_cx_px",       "box_cy_px",     "box_length_px",
    "box_width_px", "box_angle_rad", "direction_known", "at_frame_edge", "vehicle_probability",
    "type"};
constexpr int kFormat2Columns = 2;
constexpr std::array<const char*, shape::kVehicleTypeCount> kProbabilityColumns{
    "p_estate", "p_compact", "p_sports", "p_sedan", "p_suv", "p_van", "p_large"};
constexpr std::array<const char*, 10> kWorldColumns{
    "east_m",   "north_m",         "up_m",     "lat_deg", "lon_deg",
    "height_m", "heading_enu_rad", "length_m", "width_m", "height_m_vehicle"};

// Column layout of one file: fixed head (format 2: with the frame-edge flag and the verifier's
// probability), 7 probabilities, n gamma, lift status, world tail.
struct Layout {
  int gammaColumns = 0;
  int formatVersion = kDetectionsFormatVersion;
  static constexpr int kKey = 0;
  static constexpr int kDetId = 1;
  static constexpr int kScore = 2;
  static constexpr int kBox = 3;  // cx, cy, length, width, angle
  static constexpr int kDirection = 8;
  static constexpr int kFrameEdge = 9;            // format 2
  static constexpr int kVehicleProbability = 10;  // format 2
  constexpr bool hasFormat2Columns() const { return formatVersion >= 2; }
  constexpr int type() const { return hasFormat2Columns() ? 11 : 9; }
  constexpr int probabilities() const { return type() + 1; }
  constexpr int gamma() const { return probabilities() + shape::kVehicleTypeCount; }
  constexpr int liftStatus() const { return gamma() + gammaColumns; }
  constexpr int world() const { return liftStatus() + 1; }
  constexpr int count() const { return world() + static_cast<int>(kWorldColumns.size()); }
  // The name of column c (for messages).
  constexpr const char* name(int c, DetectionsKey key) const {
    if (c == kKey) {
      return key == DetectionsKey::FrameId ? "frame_id" : "image";
    }
    if (c < probabilities()) {
      const int skipped = !hasFormat2Columns() && c > kDirection ? kFormat2Columns : 0;
      return kHeadColumns[static_cast<std::size_t>(c - kDetId + skipped)];
    }
    if (c < gamma()) {
      return kProbabilityColumns[static_cast<std::size_t>(c - probabilities())];
    }
    if (c < liftStatus()) {
      return "gamma";
    }
    if (c == liftStatus()) {
      return "lift_status";
    }
    return kWorldColumns[static_cast<std::size_t>(c - world())];
  }
};
static_assert(kHeadColumns.size() ==
              static_cast<std::size_t>(Layout{0, 2}.type() - Layout::kDetId + 1));

bool finite(double value) {
  return std::isfinite(value);
}

// Semantic checks shared by the writer (before formatting) and the reader (after parsing).
std::optional<Problem> checkRecord(const DetectionRecord& r, DetectionsKey key,
                                   const Layout& layout) {
  const int gammaColumns = layout.gammaColumns;
  if (key == DetectionsKey::FrameId && r.frameId < 0) {
    return Problem{Layout::kKey, "must be >= 0"};
  }
  if (key == DetectionsKey::Image) {
    const std::string_view stem = r.imageStem();
    if (stem.empty()) {
      return Problem{Layout::kKey, "empty image stem"};
    }
    if (stem.find_first_of(",\"\n\r") != std::string_view::npos) {
      return Problem{Layout::kKey, "image stem holds a comma, quote or line break"};
    }
  }
  if (r.detId < 0) {
    return Problem{Layout::kDetId, "must be >= 0"};
  }
  if (!(r.score >= 0.0F && r.score <= 1.0F)) {
    return Problem{Layout::kScore, "must be in [0, 1]"};
  }
  if (!finite(r.box.cx)) {
    return Problem{Layout::kBox, "not finite"};
  }
  if (!finite(r.box.cy)) {
    return Problem{Layout::kBox + 1, "not finite"};
  }
  if (!(r.box.length > 0.0 && finite(r.box.length))) {
    return Problem{Layout::kBox + 2, "must be > 0 and finite"};
  }
  if (!(r.box.width > 0.0 && finite(r.box.width))) {
    return Problem{Layout::kBox + 3, "must be > 0 and finite"};
  }
  if (!(r.box.angle >= 0.0 && r.box.angle < geometry::kTwoPi)) {
    return Problem{Layout::kBox + 4, "must be in [0, 2 pi)"};
  }
  if (!std::isnan(r.vehicleProbability) &&
      !(r.vehicleProbability >= 0.0F && r.vehicleProbability <= 1.0F)) {
    return Problem{Layout::kVehicleProbability, "must be in [0, 1] (or empty: no verifier)"};
  }
  double sum = 0.0;
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    const float p = r.typeProbabilities[static_cast<std::size_t>(t)];
    if (!(p >= 0.0F && p <= 1.0F)) {
      return Problem{layout.probabilities() + t, "must be in [0, 1]"};
    }
    sum += static_cast<double>(p);
  }
  if (std::abs(sum - 1.0) > kProbabilitySumTolerance) {
    return Problem{layout.probabilities(), "probabilities p_estate..p_large do not sum to 1"};
  }
  if (r.gamma.count < 0 || r.gamma.count > gammaColumns) {
    return Problem{layout.gamma(), "more gamma values than gamma columns"};
  }
  for (int s = 0; s < r.gamma.count; ++s) {
    if (!std::isfinite(r.gamma.gamma[static_cast<std::size_t>(s)])) {
      return Problem{layout.gamma() + s, "not finite"};
    }
  }
  if (static_cast<int>(r.liftStatus) >= kLiftStatusCount) {
    return Problem{layout.liftStatus(), "unknown lift status"};
  }
  if (r.liftStatus == LiftStatus::Ok) {
    const std::array<double, 10> world{r.positionEnu.x(), r.positionEnu.y(),  r.positionEnu.z(),
                                       r.latitude_deg,    r.longitude_deg,    r.height_m,
                                       r.headingEnu_rad,  r.dimensions_m.x(), r.dimensions_m.y(),
                                       r.dimensions_m.z()};
    for (std::size_t i = 0; i < world.size(); ++i) {
      if (!finite(world[i])) {
        return Problem{layout.world() + static_cast<int>(i), "not finite"};
      }
    }
    if (std::abs(r.latitude_deg) > 90.0) {
      return Problem{layout.world() + 3, "must be in [-90, 90]"};
    }
    if (std::abs(r.longitude_deg) > 180.0) {
      return Problem{layout.world() + 4, "must be in [-180, 180]"};
    }
    if (!(r.headingEnu_rad >= 0.0 && r.headingEnu_rad < geometry::kTwoPi)) {
      return Problem{layout.world() + 6, "must be in [0, 2 pi)"};
    }
    for (int i = 0; i < 3; ++i) {
      if (r.dimensions_m[i] < 0.0) {
        return Problem{layout.world() + 7 + i, "must be >= 0"};
      }
    }
  }
  return std::nullopt;
}

// ---- formatting (no allocation) ------------------------------------------------------------

class RowFormatter {
 public:
  RowFormatter(char* begin, std::size_t size) : pos_(begin), end_(begin + size) {}

  template <typename T>
  void number(T value) {
    if (!ok_) {
      return;
    }
    const auto result = std::to_chars(pos_, end_, value);
    if (result.ec != std::errc()) {
      ok_ = false;
      return;
    }
    pos_ = result.ptr;
  }
  void text(std::string_view value) {
    if (!ok_ || static_cast<std::size_t>(end_ - pos_) < value.size()) {
      ok_ = false;
      return;
    }
    std::memcpy(pos_, value.data(), value.size());
    pos_ += value.size();
  }
  void character(char c) {
    if (!ok_ || pos_ == end_) {
      ok_ = false;
      return;
    }
    *pos_++ = c;
  }
  bool ok() const { return ok_; }
  char* position() const { return pos_; }

 private:
  char* pos_;
  char* end_;
  bool ok_ = true;
};

void formatRow(const DetectionRecord& r, const DetectionsFileInfo& info, RowFormatter& out) {
  // The writer writes the current format only (kDetectionsFormatVersion, with the format 2
  // columns).
  if (info.key == DetectionsKey::FrameId) {
    out.number(r.frameId);
  } else {
    out.text(r.imageStem());
  }
  out.character(',');
  out.number(r.detId);
  out.character(',');
  out.number(r.score);
  for (const double v : {r.box.cx, r.box.cy, r.box.length, r.box.width, r.box.angle}) {
    out.character(',');
    out.number(v);
  }
  out.character(',');
  out.character(r.directionKnown ? '1' : '0');
  out.character(',');
  out.character(r.atFrameEdge ? '1' : '0');
  out.character(',');
  if (!std::isnan(r.vehicleProbability)) {
    out.number(r.vehicleProbability);
  }
  out.character(',');
  out.text(shape::toString(r.topType()));
  for (const float p : r.typeProbabilities) {
    out.character(',');
    out.number(p);
  }
  for (int s = 0; s < info.gammaColumns; ++s) {
    out.character(',');
    if (s < r.gamma.count) {
      out.number(r.gamma.gamma[static_cast<std::size_t>(s)]);
    }
  }
  out.character(',');
  out.text(toString(r.liftStatus));
  const bool lifted = r.liftStatus == LiftStatus::Ok;
  for (const double v :
       {r.positionEnu.x(), r.positionEnu.y(), r.positionEnu.z(), r.latitude_deg, r.longitude_deg,
        r.height_m, r.headingEnu_rad, r.dimensions_m.x(), r.dimensions_m.y(), r.dimensions_m.z()}) {
    out.character(',');
    if (lifted) {
      out.number(v);
    }
  }
  out.character('\n');
}

// ---- parsing -------------------------------------------------------------------------------

DetectionRecord parseRow(const RowParser& p, const DetectionsFileInfo& info, int formatVersion) {
  const Layout layout{info.gammaColumns, formatVersion};
  DetectionRecord r;
  if (info.key == DetectionsKey::FrameId) {
    r.frameId = p.integer(Layout::kKey, 0, std::numeric_limits<std::int64_t>::max());
  } else if (!r.setImageStem(p.field(Layout::kKey))) {
    p.fail(Layout::kKey,
           "image stem longer than " + std::to_string(kMaxImageStemChars) + " characters");
  }
  r.detId = static_cast<int>(p.integer(Layout::kDetId, 0, std::numeric_limits<int>::max()));
  r.score = p.real<float>(Layout::kScore);
  r.box.cx = p.real<double>(Layout::kBox);
  r.box.cy = p.real<double>(Layout::kBox + 1);
  r.box.length = p.real<double>(Layout::kBox + 2);
  r.box.width = p.real<double>(Layout::kBox + 3);
  r.box.angle = p.real<double>(Layout::kBox + 4);
  const std::string_view direction = p.field(Layout::kDirection);
  if (direction != "0" && direction != "1") {
    p.fail(Layout::kDirection, "expected 0 or 1, got " + quote(direction));
  }
  r.directionKnown = direction == "1";
  if (layout.hasFormat2Columns()) {
    const std::string_view edge = p.field(Layout::kFrameEdge);
    if (edge != "0" && edge != "1") {
      p.fail(Layout::kFrameEdge, "expected 0 or 1, got " + quote(edge));
    }
    r.atFrameEdge = edge == "1";
    if (!p.field(Layout::kVehicleProbability).empty()) {
      r.vehicleProbability = p.real<float>(Layout::kVehicleProbability);
    }
  }
  const std::string_view typeName = p.field(layout.type());
  const std::optional<shape::VehicleType> type = shape::vehicleTypeFromString(typeName);
  if (!type || typeName != shape::toString(*type)) {
    p.fail(layout.type(), "unknown vehicle type " + quote(typeName) +
                              " (estate, compact, sports, sedan, suv, van, large)");
  }
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    r.typeProbabilities[static_cast<std::size_t>(t)] = p.real<float>(layout.probabilities() + t);
  }
  bool gap = false;
  for (int s = 0; s < info.gammaColumns; ++s) {
    if (p.field(layout.gamma() + s).empty()) {
      gap = true;
      continue;
    }
    if (gap) {
      p.fail(layout.gamma() + s, "value after an empty gamma field");
    }
    r.gamma.gamma[static_cast<std::size_t>(s)] = p.real<float>(layout.gamma() + s);
    r.gamma.count = s + 1;
  }
  const std::string_view status = p.field(layout.liftStatus());
  const std::optional<LiftStatus> lift = liftStatusFromString(status);
  if (!lift) {
    p.fail(layout.liftStatus(),
           "unknown lift status " + quote(status) +
               " (ok, not_lifted, no_pose, stale_pose, invalid_pose, "
               "invalid_box, outside_lens, behind_camera, outside_dtm, no_data, "
               "no_intersection)");
  }
  r.liftStatus = *lift;
  const int w = layout.world();
  if (r.liftStatus == LiftStatus::Ok) {
    r.positionEnu = {p.real<double>(w), p.real<double>(w + 1), p.real<double>(w + 2)};
    r.latitude_deg = p.real<double>(w + 3);
    r.longitude_deg = p.real<double>(w + 4);
    r.height_m = p.real<double>(w + 5);
    r.headingEnu_rad = p.real<double>(w + 6);
    r.dimensions_m = {p.real<double>(w + 7), p.real<double>(w + 8), p.real<double>(w + 9)};
  } else {
    for (int i = 0; i < static_cast<int>(kWorldColumns.size()); ++i) {
      if (!p.field(w + i).empty()) {
        p.fail(w + i, "must be empty when lift_status is " + std::string(status) + ", got " +
                          quote(p.field(w + i)));
      }
    }
  }
  if (const std::optional<Problem> problem = checkRecord(r, info.key, layout)) {
    p.fail(problem->column,
           std::string(problem->what) + ", got " + quote(p.field(problem->column)));
  }
  // The type column must name a most probable type (any of them when several tie).
  const float top = r.typeProbabilities[static_cast<std::size_t>(r.topType())];
  if (r.typeProbabilities[static_cast<std::size_t>(*type)] != top) {
    p.fail(layout.type(),
           quote(typeName) + " is not the most probable type (" +
               kProbabilityColumns[static_cast<std::size_t>(r.topType())] + " " +
               std::string(p.field(layout.probabilities() + static_cast<int>(r.topType()))) + ")");
  }
  return r;
}

// Parses the "# key: value" metadata lines before the header.
void parseMetadata(const std::string& file, int line, std::string_view text, DetectionsFile* out,
                   std::set<std::string>& seen) {
  std::string_view body = text.substr(1);
  while (!body.empty() && body.front() == ' ') {
    body.remove_prefix(1);
  }
  const std::size_t colon = body.find(':');
  const std::string where = csv::location(file, line) + ": ";
  if (colon == std::string_view::npos) {
    throw ReadError{where + "metadata line must be '# key: value', got " + quote(text)};
  }
  const std::string key(body.substr(0, colon));
  std::string_view value = body.substr(colon + 1);
  while (!value.empty() && value.front() == ' ') {
    value.remove_prefix(1);
  }
  if (!seen.insert(key).second) {
    throw ReadError{where + key + ": duplicate metadata key"};
  }
  if (key == "format_version") {
    int version = 0;
    const auto [ptr, error] = std::from_chars(value.data(), value.data() + value.size(), version);
    if (error != std::errc() || ptr != value.data() + value.size()) {
      throw ReadError{where + "format_version: not an integer " + quote(value)};
    }
    if (version < kOldestDetectionsFormatVersion || version > kDetectionsFormatVersion) {
      throw ReadError{where + "format_version: " + std::string(value) +
                      " not supported (this reader reads " +
                      std::to_string(kOldestDetectionsFormatVersion) + " to " +
                      std::to_string(kDetectionsFormatVersion) + ")"};
    }
    out->formatVersion = version;
  } else if ((key == "model" || key == "source") && value.find('\r') != std::string_view::npos) {
    // The writer keeps metadata to one line of text; a carriage return inside it would not
    // survive writing the file again.
    throw ReadError{where + std::string(key) + ": carriage return inside the value"};
  } else if (key == "model") {
    out->info.model = std::string(value);
  } else if (key == "source") {
    out->info.source = std::string(value);
  } else {
    throw ReadError{where + "unknown metadata key " + quote(key) +
                    " (format_version, model, source)"};
  }
}

// Reads the header: the key column and the gamma count follow from it; without a
// format_version line, so does the format (the at_frame_edge column is format 2's).
void parseHeader(const std::string& file, int line, std::string_view text, DetectionsFile* out,
                 std::vector<std::string>* names, bool versionGiven) {
  DetectionsFileInfo& info = out->info;
  const std::string where = csv::location(file, line) + ": header: ";
  if (text.starts_with("frame_id,")) {
    info.key = DetectionsKey::FrameId;
  } else if (text.starts_with("image,")) {
    info.key = DetectionsKey::Image;
  } else {
    throw ReadError{where +
                    "must start with 'frame_id,' (sequences) or 'image,' (image "
                    "folders), got " +
                    (text.empty() ? std::string("an empty line") : quote(text))};
  }
  if (!versionGiven) {
    out->formatVersion = text.find(",at_frame_edge,") != std::string_view::npos ? 2 : 1;
  }
  const int version = out->formatVersion;
  const std::size_t fields =
      static_cast<std::size_t>(std::count(text.begin(), text.end(), ',')) + 1;
  const int gamma = static_cast<int>(fields) - Layout{0, version}.count();
  if (gamma < 0 || gamma > shape::kMaxShapeComponents) {
    throw ReadError{where + "expected " + std::to_string(Layout{0, version}.count()) + " to " +
                    std::to_string(Layout{shape::kMaxShapeComponents, version}.count()) +
                    " columns (0 to 8 gamma columns, format " + std::to_string(version) +
                    "), got " + std::to_string(fields)};
  }
  info.gammaColumns = gamma;
  *names = detectionsColumns(info.key, gamma, version);
  const std::string expected = csv::joinColumns(*names);
  if (text != expected) {
    throw ReadError{where + "expected " + quote(expected) + ", got " + quote(text)};
  }
}

}  // namespace

const char* toString(LiftStatus status) {
  const auto i = static_cast<std::size_t>(status);
  return i < kLiftStatusWords.size() ? kLiftStatusWords[i] : "unknown";
}

std::optional<LiftStatus> liftStatusFromString(std::string_view word) {
  for (std::size_t i = 0; i < kLiftStatusWords.size(); ++i) {
    if (word == kLiftStatusWords[i]) {
      return static_cast<LiftStatus>(i);
    }
  }
  return std::nullopt;
}

std::string_view DetectionRecord::imageStem() const {
  return std::string_view(image.data(), strnlen(image.data(), image.size()));
}

bool DetectionRecord::setImageStem(std::string_view stem) {
  if (stem.size() > kMaxImageStemChars) {
    return false;
  }
  image.fill('\0');
  std::memcpy(image.data(), stem.data(), stem.size());
  return true;
}

shape::VehicleType DetectionRecord::topType() const {
  std::size_t best = 0;
  for (std::size_t t = 1; t < typeProbabilities.size(); ++t) {
    if (typeProbabilities[t] > typeProbabilities[best]) {
      best = t;
    }
  }
  return static_cast<shape::VehicleType>(best);
}

std::vector<std::string> detectionsColumns(DetectionsKey key, int gammaColumns, int formatVersion) {
  // The key and head columns by the layout's own naming (which knows format 1's gap).
  const Layout layout{gammaColumns, formatVersion};
  std::vector<std::string> names;
  for (int c = Layout::kKey; c < layout.probabilities(); ++c) {
    names.emplace_back(layout.name(c, key));
  }
  names.insert(names.end(), kProbabilityColumns.begin(), kProbabilityColumns.end());
  for (int s = 0; s < gammaColumns; ++s) {
    names.push_back("gamma_" + std::to_string(s));
  }
  names.emplace_back("lift_status");
  names.insert(names.end(), kWorldColumns.begin(), kWorldColumns.end());
  return names;
}

// ---- writer --------------------------------------------------------------------------------

DetectionsFileWriter::DetectionsFileWriter() = default;

DetectionsFileWriter::~DetectionsFileWriter() = default;

bool DetectionsFileWriter::open(const std::string& path, const DetectionsFileInfo& info,
                                std::string* why) {
  if (!writer_.checkOpen(path, info.gammaColumns, shape::kMaxShapeComponents, why)) {
    return false;
  }
  for (const std::string* text : {&info.model, &info.source}) {
    if (text->find_first_of("\n\r") != std::string::npos) {
      return csv::failWith(why, path + ": model/source metadata must be one line");
    }
  }
  if (!writer_.open(path, kRowBufferBytes, why)) {
    return false;
  }
  info_ = info;
  std::string head = "# format_version: " + std::to_string(kDetectionsFormatVersion) + "\n";
  if (!info.model.empty()) {
    head += "# model: " + info.model + "\n";
  }
  if (!info.source.empty()) {
    head += "# source: " + info.source + "\n";
  }
  head += csv::joinColumns(detectionsColumns(info.key, info.gammaColumns)) + "\n";
  return writer_.writeHeader(head, why);
}

bool DetectionsFileWriter::writeRow(const DetectionRecord& record, std::string* why) {
  // Messages are built only on failure (they allocate; the success path does not).
  const auto failWith = [&](const char* column, const char* problem) {
    return csv::failWith(why, writer_.path() + ": row " +
                                  std::to_string(writer_.rowsWritten() + 1) + ": " + column + ": " +
                                  problem);
  };
  if (!writer_.isOpen()) {
    return failWith("-", "writer is not open");
  }
  const Layout layout{info_.gammaColumns};
  if (const std::optional<Problem> problem = checkRecord(record, info_.key, layout)) {
    return failWith(layout.name(problem->column, info_.key), problem->what);
  }
  const std::span<char> row = writer_.rowBuffer();
  RowFormatter out(row.data(), row.size());
  formatRow(record, info_, out);
  if (!out.ok()) {
    return failWith("-", "row longer than the row buffer");
  }
  if (!writer_.writeRow(static_cast<std::size_t>(out.position() - row.data()))) {
    return failWith("-", "write failed (disk full or I/O error; see lastErrno())");
  }
  return true;
}

bool DetectionsFileWriter::flush(std::string* why) {
  return writer_.flush(why);
}

bool DetectionsFileWriter::close(std::string* why) {
  return writer_.close("detections writer", why);
}

// ---- reader --------------------------------------------------------------------------------

bool readDetectionsFile(const std::string& path, DetectionsFile* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    const std::string text = csv::readWholeFile(path);
    std::vector<std::string> names;
    std::set<std::string> metadataKeys;
    std::set<std::pair<std::string, int>> keys;  // (frame or image, det_id)
    std::optional<std::int64_t> lastFrame;
    bool haveHeader = false;
    out->formatVersion = kDetectionsFormatVersion;
    const int lines = csv::forEachLine(text, [&](int line, std::string_view row) {
      if (!haveHeader) {
        if (row.starts_with("#")) {
          parseMetadata(path, line, row, out, metadataKeys);
          return;
        }
        parseHeader(path, line, row, out, &names, metadataKeys.contains("format_version"));
        haveHeader = true;
        return;
      }
      const RowParser parser(path, line, row, names);
      const DetectionRecord record = parseRow(parser, out->info, out->formatVersion);
      std::string key;
      if (out->info.key == DetectionsKey::FrameId) {
        if (lastFrame && record.frameId < *lastFrame) {
          parser.fail(0, "not in non-decreasing order (" + std::to_string(record.frameId) +
                             " after " + std::to_string(*lastFrame) + ")");
        }
        lastFrame = record.frameId;
        key = std::to_string(record.frameId);
      } else {
        key = std::string(record.imageStem());
      }
      if (!keys.emplace(key, record.detId).second) {
        parser.fail(1, "det_id " + std::to_string(record.detId) + " appears twice in " +
                           (out->info.key == DetectionsKey::FrameId ? "frame " : "image ") + key);
      }
      out->rows.push_back(record);
      out->lines.push_back(line);
    });
    if (!haveHeader) {
      throw ReadError{csv::location(path, lines + 1) +
                      ": header: missing (empty file or only metadata lines)"};
    }
  });
}

}  // namespace vp::output_files
