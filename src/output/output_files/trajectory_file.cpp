#include "output_files/trajectory_file.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "geometry/rotated_box.hpp"

namespace vp::output_files {
namespace {

using csv::Problem;
using csv::quote;
using csv::ReadError;
using csv::RowParser;

constexpr double kProbabilitySumTolerance = 1e-3;  // |sum p - 1| allowed (4-decimal rounding)
// class_id must name the most probable type; written probabilities are rounded to 1e-4, so a
// close runner-up may print up to 1e-4 above it.
constexpr float kTypeTieTolerance = 1.5e-4F;
constexpr double kDegPerRad = 180.0 / geometry::kPi;
constexpr int kMaxUtmZone = 60;
constexpr double kMaxUtmEasting_m = 1'000'000.0;
constexpr double kMaxUtmNorthing_m = 10'000'000.0;

// Column indices (trajectory_csv's order).
enum Column : int {
  kFrameId = 0,
  kClassId,
  kTrackId,
  kVelocity,
  kRearX,
  kRearY,
  kCentreX,
  kCentreY,
  kTime,
  kStatus,
  kLatitude,
  kLongitude,
  kHeight,
  kHeading,
  kSpeedSigma,
  kAcceleration,
  kAccelerationSigma,
  kYawRate,
  kLength,
  kWidth,
  kWheelbase,
  kClassName,
  kLengthVariance,
  kWidthVariance,
  kUtmZone,
  kUtmHemisphere,
  kUtmEasting,
  kUtmNorthing,
  kRearLatitude,
  kRearLongitude,
  kRearHeight,
  kProbabilities,
  kGamma = kProbabilities + shape::kVehicleTypeCount,
};
static_assert(kGamma == kTrajectoryFixedColumns);

std::optional<tracking::TrackStatus> statusFromString(std::string_view word) {
  for (const tracking::TrackStatus s :
       {tracking::TrackStatus::Tentative, tracking::TrackStatus::Confirmed,
        tracking::TrackStatus::Lost}) {
    if (word == tracking::toString(s)) {
      return s;
    }
  }
  return std::nullopt;
}

// The row the writer would produce for this track, before rounding (no allocation).
TrajectoryRecord recordOf(std::int64_t frameId, const tracking::TrackState& t,
                          const tracking::Wgs84Position* wgs84,
                          const tracking::TrajectoryPlace* place) {
  TrajectoryRecord r;
  r.frameId = frameId;
  r.type = t.type;
  r.trackId = t.id;
  r.speed_mps = t.speed_mps;
  r.rearAxleEnu = t.rearAxleEnu;
  r.centreEnu = t.centreEnu;
  r.timeS = static_cast<double>(t.timestamp_ns) * 1e-9;
  r.status = t.status;
  if (wgs84 != nullptr) {
    r.centreWgs84 = *wgs84;
  }
  r.headingEnu_deg = t.headingEnu_rad * kDegPerRad;
  r.speedSigma_mps = t.speedSigma_mps;
  r.acceleration_mps2 = t.acceleration_mps2;
  r.accelerationSigma_mps2 = t.accelerationSigma_mps2;
  r.yawRateDps = t.yawRate_radps * kDegPerRad;
  r.length_m = t.length_m;
  r.width_m = t.width_m;
  r.wheelbase_m = t.wheelbase_m;
  r.lengthVariance_m2 = t.lengthVariance_m2;
  r.widthVariance_m2 = t.widthVariance_m2;
  if (place != nullptr) {
    r.place = *place;
  }
  r.typeProbabilities = t.typeProbabilities;
  r.gamma = t.shape;
  return r;
}

// Latitude, longitude, height columns (first = latitude's) of one WGS84 point.
std::optional<Problem> checkWgs84(const tracking::Wgs84Position& p, int first) {
  if (!(std::abs(p.latitude_deg) <= 90.0)) {
    return Problem{first, "must be in [-90, 90]"};
  }
  if (!(std::abs(p.longitude_deg) <= 180.0)) {
    return Problem{first + 1, "must be in [-180, 180]"};
  }
  if (!std::isfinite(p.height_m)) {
    return Problem{first + 2, "not finite"};
  }
  return std::nullopt;
}

// Semantic checks shared by the writer (before formatting) and the reader (after parsing).
std::optional<Problem> checkRecord(const TrajectoryRecord& r, int gammaColumns) {
  if (r.frameId < 0) {
    return Problem{kFrameId, "must be >= 0"};
  }
  const int type = static_cast<int>(r.type);
  if (type < 0 || type >= shape::kVehicleTypeCount) {
    return Problem{kClassId, "must be in [0, 6] (shape::VehicleType)"};
  }
  const std::array<std::pair<int, double>, 6> finiteColumns{{{kVelocity, r.speed_mps},
                                                             {kRearX, r.rearAxleEnu.x()},
                                                             {kRearY, r.rearAxleEnu.y()},
                                                             {kCentreX, r.centreEnu.x()},
                                                             {kCentreY, r.centreEnu.y()},
                                                             {kTime, r.timeS}}};
  for (const auto& [column, value] : finiteColumns) {
    if (!std::isfinite(value)) {
      return Problem{column, "not finite"};
    }
  }
  if (statusFromString(tracking::toString(r.status)) != r.status) {
    return Problem{kStatus, "unknown track status"};
  }
  if (r.centreWgs84) {
    if (const std::optional<Problem> problem = checkWgs84(*r.centreWgs84, kLatitude)) {
      return problem;
    }
  }
  // 360 is allowed: a heading just below 2 pi prints as 360.00.
  if (!(r.headingEnu_deg >= 0.0 && r.headingEnu_deg <= 360.0)) {
    return Problem{kHeading, "must be in [0, 360]"};
  }
  const std::array<std::pair<int, double>, 2> finiteMotion{
      {{kAcceleration, r.acceleration_mps2}, {kYawRate, r.yawRateDps}}};
  for (const auto& [column, value] : finiteMotion) {
    if (!std::isfinite(value)) {
      return Problem{column, "not finite"};
    }
  }
  const std::array<std::pair<int, double>, 7> nonNegative{
      {{kSpeedSigma, r.speedSigma_mps},
       {kAccelerationSigma, r.accelerationSigma_mps2},
       {kLength, r.length_m},
       {kWidth, r.width_m},
       {kWheelbase, r.wheelbase_m},
       {kLengthVariance, r.lengthVariance_m2},
       {kWidthVariance, r.widthVariance_m2}}};
  for (const auto& [column, value] : nonNegative) {
    if (!(value >= 0.0 && std::isfinite(value))) {
      return Problem{column, "must be >= 0 and finite"};
    }
  }
  const tracking::TrajectoryPlace& place = r.place;
  if (place.utmZone < 0 || place.utmZone > kMaxUtmZone) {
    return Problem{kUtmZone, "must be in [1, 60] (or empty)"};
  }
  if (place.utmZone > 0) {
    // UTM's easting stays within ~170..830 km in its band, northing within 0..10 000 km.
    if (!(place.utmEasting_m >= 0.0 && place.utmEasting_m <= kMaxUtmEasting_m)) {
      return Problem{kUtmEasting, "must be in [0, 1 000 000] m"};
    }
    if (!(place.utmNorthing_m >= 0.0 && place.utmNorthing_m <= kMaxUtmNorthing_m)) {
      return Problem{kUtmNorthing, "must be in [0, 10 000 000] m"};
    }
  }
  if (place.hasRearAxle) {
    if (const std::optional<Problem> problem = checkWgs84(place.rearAxle, kRearLatitude)) {
      return problem;
    }
  }
  double sum = 0.0;
  float top = 0.0F;
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    const float p = r.typeProbabilities[static_cast<std::size_t>(t)];
    if (!(p >= 0.0F && p <= 1.0F)) {
      return Problem{kProbabilities + t, "must be in [0, 1]"};
    }
    sum += static_cast<double>(p);
    top = std::max(top, p);
  }
  if (std::abs(sum - 1.0) > kProbabilitySumTolerance) {
    return Problem{kProbabilities, "probabilities p_estate..p_large do not sum to 1"};
  }
  if (r.typeProbabilities[static_cast<std::size_t>(type)] < top - kTypeTieTolerance) {
    return Problem{kClassId, "is not the most probable type of p_estate..p_large"};
  }
  if (r.gamma.count < 0 || r.gamma.count > gammaColumns) {
    return Problem{kGamma, "more gamma values than gamma columns"};
  }
  for (int s = 0; s < r.gamma.count; ++s) {
    if (!std::isfinite(r.gamma.gamma[static_cast<std::size_t>(s)])) {
      return Problem{kGamma + s, "not finite"};
    }
  }
  return std::nullopt;
}

// ---- parsing -------------------------------------------------------------------------------

TrajectoryRecord parseRow(const RowParser& p, int gammaColumns) {
  TrajectoryRecord r;
  r.frameId = p.integer(kFrameId, 0, std::numeric_limits<std::int64_t>::max());
  r.type = static_cast<shape::VehicleType>(p.integer(kClassId, 0, shape::kVehicleTypeCount - 1));
  r.trackId =
      static_cast<std::uint32_t>(p.integer(kTrackId, 0, std::numeric_limits<std::uint32_t>::max()));
  r.speed_mps = p.real<double>(kVelocity);
  r.rearAxleEnu = {p.real<double>(kRearX), p.real<double>(kRearY)};
  r.centreEnu = {p.real<double>(kCentreX), p.real<double>(kCentreY)};
  r.timeS = p.real<double>(kTime);
  const std::string_view status = p.field(kStatus);
  const std::optional<tracking::TrackStatus> parsed = statusFromString(status);
  if (!parsed) {
    p.fail(kStatus, "unknown track status " + quote(status) + " (tentative, confirmed, lost)");
  }
  r.status = *parsed;
  const int given = (p.field(kLatitude).empty() ? 0 : 1) + (p.field(kLongitude).empty() ? 0 : 1) +
                    (p.field(kHeight).empty() ? 0 : 1);
  if (given == 3) {
    r.centreWgs84 = tracking::Wgs84Position{p.real<double>(kLatitude), p.real<double>(kLongitude),
                                            p.real<double>(kHeight)};
  } else if (given != 0) {
    const int column = p.field(kLatitude).empty()
                           ? kLatitude
                           : (p.field(kLongitude).empty() ? kLongitude : kHeight);
    p.fail(column, "latitude_deg, longitude_deg, height_m must be all set or all empty");
  }
  r.headingEnu_deg = p.real<double>(kHeading);
  r.speedSigma_mps = p.real<double>(kSpeedSigma);
  r.acceleration_mps2 = p.real<double>(kAcceleration);
  r.accelerationSigma_mps2 = p.real<double>(kAccelerationSigma);
  r.yawRateDps = p.real<double>(kYawRate);
  r.length_m = p.real<double>(kLength);
  r.width_m = p.real<double>(kWidth);
  r.wheelbase_m = p.real<double>(kWheelbase);
  if (p.field(kClassName) != shape::toString(r.type)) {
    p.fail(kClassName, "must name class_id's type (" + quote(shape::toString(r.type)) + "), got " +
                           quote(p.field(kClassName)));
  }
  r.lengthVariance_m2 = p.real<double>(kLengthVariance);
  r.widthVariance_m2 = p.real<double>(kWidthVariance);
  const int utmGiven =
      (p.field(kUtmZone).empty() ? 0 : 1) + (p.field(kUtmHemisphere).empty() ? 0 : 1) +
      (p.field(kUtmEasting).empty() ? 0 : 1) + (p.field(kUtmNorthing).empty() ? 0 : 1);
  if (utmGiven == 4) {
    r.place.utmZone = static_cast<int>(p.integer(kUtmZone, 1, kMaxUtmZone));
    const std::string_view hemisphere = p.field(kUtmHemisphere);
    if (hemisphere != "N" && hemisphere != "S") {
      p.fail(kUtmHemisphere, "must be N or S, got " + quote(hemisphere));
    }
    r.place.utmNorth = hemisphere == "N";
    r.place.utmEasting_m = p.real<double>(kUtmEasting);
    r.place.utmNorthing_m = p.real<double>(kUtmNorthing);
  } else if (utmGiven != 0) {
    p.fail(kUtmZone,
           "utm_zone, utm_hemisphere, utm_easting_m, utm_northing_m must be all set or "
           "all empty");
  }
  const int rearGiven = (p.field(kRearLatitude).empty() ? 0 : 1) +
                        (p.field(kRearLongitude).empty() ? 0 : 1) +
                        (p.field(kRearHeight).empty() ? 0 : 1);
  if (rearGiven == 3) {
    r.place.hasRearAxle = true;
    r.place.rearAxle = tracking::Wgs84Position{
        p.real<double>(kRearLatitude), p.real<double>(kRearLongitude), p.real<double>(kRearHeight)};
  } else if (rearGiven != 0) {
    p.fail(kRearLatitude,
           "rear_axle_latitude_deg, rear_axle_longitude_deg, rear_axle_height_m must be all set "
           "or all empty");
  }
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    r.typeProbabilities[static_cast<std::size_t>(t)] = p.real<float>(kProbabilities + t);
  }
  bool gap = false;
  for (int s = 0; s < gammaColumns; ++s) {
    if (p.field(kGamma + s).empty()) {
      gap = true;
      continue;
    }
    if (gap) {
      p.fail(kGamma + s, "value after an empty gamma field");
    }
    r.gamma.gamma[static_cast<std::size_t>(s)] = p.real<float>(kGamma + s);
    r.gamma.count = s + 1;
  }
  if (const std::optional<Problem> problem = checkRecord(r, gammaColumns)) {
    p.fail(problem->column,
           std::string(problem->what) + ", got " + quote(p.field(problem->column)));
  }
  return r;
}

// Reads the header: the gamma count follows from the column count.
std::vector<std::string> parseHeader(const std::string& file, int line, std::string_view text,
                                     TrajectoryFileInfo* info) {
  const std::string where = csv::location(file, line) + ": header: ";
  const auto fields = static_cast<int>(std::count(text.begin(), text.end(), ',')) + 1;
  const int gamma = fields - kTrajectoryFixedColumns;
  if (gamma < 0 || gamma > shape::kMaxShapeComponents) {
    throw ReadError{where + "expected " + std::to_string(kTrajectoryFixedColumns) + " to " +
                    std::to_string(kTrajectoryFixedColumns + shape::kMaxShapeComponents) +
                    " columns (0 to 8 gamma columns), got " + std::to_string(fields) +
                    (text.empty() ? std::string(" (an empty line)") : std::string())};
  }
  info->gammaColumns = gamma;
  std::vector<std::string> names = trajectoryColumns(gamma);
  const std::string expected = csv::joinColumns(names);
  if (text != expected) {
    throw ReadError{where + "expected " + quote(expected) + ", got " + quote(text)};
  }
  return names;
}

}  // namespace

double TrajectoryRecord::headingEnu_rad() const {
  return headingEnu_deg / kDegPerRad;
}

tracking::TrackState toTrackState(const TrajectoryRecord& r) {
  tracking::TrackState t;
  t.id = r.trackId;
  t.status = r.status;
  t.timestamp_ns = std::llround(r.timeS * 1e9);
  t.centreEnu = r.centreEnu;
  t.rearAxleEnu = r.rearAxleEnu;
  t.headingEnu_rad = r.headingEnu_rad();
  t.speed_mps = r.speed_mps;
  t.speedSigma_mps = r.speedSigma_mps;
  t.acceleration_mps2 = r.acceleration_mps2;
  t.accelerationSigma_mps2 = r.accelerationSigma_mps2;
  t.yawRate_radps = r.yawRateDps / kDegPerRad;
  t.length_m = r.length_m;
  t.width_m = r.width_m;
  t.wheelbase_m = r.wheelbase_m;
  t.lengthVariance_m2 = r.lengthVariance_m2;
  t.widthVariance_m2 = r.widthVariance_m2;
  t.typeProbabilities = r.typeProbabilities;
  t.type = r.type;
  t.shape = r.gamma;
  return t;
}

std::vector<std::string> trajectoryColumns(int gammaColumns) {
  std::array<char, tracking::kTrajectoryCsvMaxLine> header{};
  const int n = tracking::trajectoryCsvHeader(header, gammaColumns);
  std::vector<std::string> names;
  std::string_view text(header.data(), n > 0 ? static_cast<std::size_t>(n) : 0);
  if (!text.empty() && text.back() == '\n') {
    text.remove_suffix(1);
  }
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    names.emplace_back(text.substr(start, comma - start));
    start = comma + 1;
  }
  return names;
}

// ---- writer --------------------------------------------------------------------------------

TrajectoryFileWriter::TrajectoryFileWriter() = default;

TrajectoryFileWriter::~TrajectoryFileWriter() = default;

bool TrajectoryFileWriter::open(const std::string& path, const TrajectoryFileInfo& info,
                                std::string* why) {
  if (!writer_.checkOpen(path, info.gammaColumns, shape::kMaxShapeComponents, why) ||
      !writer_.open(path, tracking::kTrajectoryCsvMaxLine, why)) {
    return false;
  }
  info_ = info;
  const std::span<char> row = writer_.rowBuffer();
  const int n = tracking::trajectoryCsvHeader(row, info.gammaColumns);
  return writer_.writeHeader(std::string_view(row.data(), n > 0 ? static_cast<std::size_t>(n) : 0),
                             why);
}

bool TrajectoryFileWriter::writeRow(std::int64_t frameId, const tracking::TrackState& track,
                                    const tracking::Wgs84Position* centreWgs84, std::string* why,
                                    const tracking::TrajectoryPlace* place) {
  // Messages are built only on failure (they allocate; the success path does not).
  const auto failWith = [&](int column, const char* problem) {
    if (why != nullptr) {
      const std::vector<std::string> names = trajectoryColumns(info_.gammaColumns);
      const std::string name = column >= 0 && static_cast<std::size_t>(column) < names.size()
                                   ? names[static_cast<std::size_t>(column)]
                                   : std::string("-");
      *why = writer_.path() + ": row " + std::to_string(writer_.rowsWritten() + 1) + " (track " +
             std::to_string(track.id) + ", frame " + std::to_string(frameId) + "): " + name + ": " +
             problem;
    }
    return false;
  };
  if (!writer_.isOpen()) {
    return failWith(-1, "writer is not open");
  }
  if (const std::optional<Problem> problem =
          checkRecord(recordOf(frameId, track, centreWgs84, place), info_.gammaColumns)) {
    return failWith(problem->column, problem->what);
  }
  const int n = tracking::trajectoryCsvRow(writer_.rowBuffer(), frameId, track, centreWgs84,
                                           info_.gammaColumns, place);
  if (n <= 0) {
    return failWith(-1, "row longer than the row buffer");
  }
  if (!writer_.writeRow(static_cast<std::size_t>(n))) {
    return failWith(-1, "write failed (disk full or I/O error; see lastErrno())");
  }
  return true;
}

bool TrajectoryFileWriter::flush(std::string* why) {
  return writer_.flush(why);
}

bool TrajectoryFileWriter::close(std::string* why) {
  return writer_.close("trajectory writer", why);
}

// ---- reader --------------------------------------------------------------------------------

bool readTrajectoryFile(const std::string& path, TrajectoryFile* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    const std::string text = csv::readWholeFile(path);
    std::vector<std::string> names;
    std::set<std::pair<std::int64_t, std::uint32_t>> keys;  // (frame_id, track_id)
    std::optional<std::int64_t> lastFrame;
    bool haveHeader = false;
    csv::forEachLine(text, [&](int line, std::string_view row) {
      if (!haveHeader) {
        names = parseHeader(path, line, row, &out->info);
        haveHeader = true;
        return;
      }
      const RowParser parser(path, line, row, names);
      const TrajectoryRecord record = parseRow(parser, out->info.gammaColumns);
      if (lastFrame && record.frameId < *lastFrame) {
        parser.fail(kFrameId, "not in non-decreasing order (" + std::to_string(record.frameId) +
                                  " after " + std::to_string(*lastFrame) + ")");
      }
      lastFrame = record.frameId;
      if (!keys.emplace(record.frameId, record.trackId).second) {
        parser.fail(kTrackId, "track " + std::to_string(record.trackId) +
                                  " appears twice in frame " + std::to_string(record.frameId));
      }
      out->rows.push_back(record);
      out->lines.push_back(line);
    });
    if (!haveHeader) {
      throw ReadError{path + ":1: header: missing (empty file)"};
    }
  });
}

}  // namespace vp::output_files
