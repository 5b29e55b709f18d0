// input/subtitle_telemetry: the per-frame telemetry that consumer drones write beside their
// videos as a SubRip subtitle file (DJI's .SRT), read into the drone's position and camera
// attitude over the video's time (docs/field_data.md, "Importing a drone video").
//
// Contract: parseSubtitles() reads the text of a subtitle file: blocks of a subtitle number,
// a time range "HH:MM:SS,mmm --> HH:MM:SS,mmm" (the video's clock, from its first frame) and
// text lines, separated by empty lines. Two families of text are read:
//   - Bracketed (DJI Mini 3 / Mini 3 Pro / Mavic 3 / Air 2S and later): `key: value` pairs,
//     mostly in square brackets: latitude, longitude, rel_alt, abs_alt and, where the model
//     writes them, gb_yaw, gb_pitch, gb_roll (the camera head's attitude relative to north
//     and the horizon), plus FrameCnt / SrtCnt.
//   - Legacy (Phantom 3 / Phantom 4 / Mavic Pro firmware): `GPS(lon,lat,alt)` with
//     `HOME(lon,lat)`, `BAROMETER:h` or `H 80.0m` (height above the take-off point). No
//     attitude.
// Anything else in the text (exposure, colour, dates) is ignored. A block that cannot be read
// (no number or time range, a value that is not a number, a position missing, out of range or
// 0,0 (no GPS fix), gimbal angles given only in part, a start time not after the previous
// one) is a problem naming the file and its line; it is skipped and the next block is read.
// The caller counts and reports the problems; parsing never throws.
//
// toTelemetry() turns the samples into recorded-sequence telemetry rows (timestamp = the
// subtitle's start time): height from abs_alt + the geoid separation, or from rel_alt + the
// ellipsoidal height of the take-off point; gimbal earth-referenced from the gb_* angles.
// Where a sample has no attitude, the camera is assumed to look straight down (gimbal pitch
// -90 deg) with yaw along the drone's motion (0 before it first moves): those rows are counted
// (`nadirAssumed`) so that the importer states it. The body attitude is level with the gimbal's
// yaw (the SRT has none; an earth-referenced gimbal does not use it).
//
// Pure: readSubtitleFile() is the one file read; everything else works on memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geodesy/attitude.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::subtitle {

enum class SubtitleFormat : std::uint8_t { Bracketed, Legacy };
const char* toString(SubtitleFormat format);  // "bracketed", "legacy"

struct SubtitleSample {
  std::int64_t number = 0;    // the subtitle's number
  std::size_t line = 0;       // line of that number in the file (1-based)
  std::int64_t start_ns = 0;  // time range on the video's clock
  std::int64_t end_ns = 0;
  std::int64_t frameCount = -1;  // FrameCnt / SrtCnt when given
  SubtitleFormat format = SubtitleFormat::Bracketed;
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  std::optional<double> relativeAltitude_m;       // above the take-off point: rel_alt, H, BAROMETER
  std::optional<double> absoluteAltitude_m;       // above mean sea level: abs_alt, GPS(...)'s third
  std::optional<geodesy::EulerAnglesDeg> gimbal;  // gb_roll, gb_pitch, gb_yaw (earth), deg
};

struct SubtitleFile {
  std::vector<SubtitleSample> samples;
  std::vector<std::string> problems;  // "<file>:<line>: <what>; subtitle skipped"
  std::size_t blocks = 0;             // subtitles seen (read or skipped)
  std::size_t bracketed = 0;          // samples of each format
  std::size_t legacy = 0;
};

// name: the file's name in the messages.
SubtitleFile parseSubtitles(std::string_view text, const std::string& name);
// Reads and parses a file; false (and *why naming it) only when it cannot be read.
bool readSubtitleFile(const std::string& path, SubtitleFile& out, std::string* why);

enum class AltitudeSource : std::uint8_t { Absolute, Relative };
const char* toString(AltitudeSource source);  // "abs", "rel"
std::optional<AltitudeSource> altitudeSourceFromString(std::string_view text);

// How the subtitle's heights and the missing attitude become the telemetry's.
struct SubtitleTelemetryOptions {
  AltitudeSource altitude = AltitudeSource::Absolute;
  double geoidSeparation_m = 0.0;  // [-200, 200]: ellipsoidal height = abs_alt + this (N)
  double homeHeight_m = 0.0;       // [-500, 9000]: ellipsoidal height of the take-off point (rel)
  double yawMinSpeed_mps = 1.0;    // (0, 100]: slower, the nadir yaw keeps its last value
};

struct SubtitleTelemetry {
  std::vector<sequence::TelemetryRecord> records;
  std::vector<std::string> problems;  // samples without the chosen altitude ("<file>:<line>: ...")
  std::size_t nadirAssumed = 0;       // rows whose attitude is the nadir assumption
  std::size_t yawFromMotion = 0;      // of those, rows whose yaw came from the motion
};

SubtitleTelemetry toTelemetry(const SubtitleFile& file, const SubtitleTelemetryOptions& options,
                              const std::string& name);

}  // namespace vp::subtitle
