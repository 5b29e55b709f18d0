// input/subtitle_telemetry: the subtitle file's blocks into samples (see the header).
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "subtitle_telemetry/subtitle_telemetry.hpp"

namespace vp::subtitle {

namespace {

constexpr std::int64_t kNsPerMs = 1'000'000;
constexpr std::size_t kMaxQuoted = 80;  // characters of a bad line quoted in a message

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front())) != 0) {
    s.remove_prefix(1);
  }
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back())) != 0) {
    s.remove_suffix(1);
  }
  return s;
}

std::string quoted(std::string_view s) {
  if (s.size() > kMaxQuoted) {
    return "'" + std::string(s.substr(0, kMaxQuoted)) + "...'";
  }
  return "'" + std::string(s) + "'";
}

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

// A finite number, optionally followed by a metre unit ("80.0m", "0.3M") when allowed.
std::optional<double> number(std::string_view text, bool metreSuffix) {
  text = trim(text);
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || !std::isfinite(value)) {
    return std::nullopt;
  }
  const std::string_view rest(ptr, static_cast<std::size_t>(end - ptr));
  if (rest.empty() || (metreSuffix && (rest == "m" || rest == "M"))) {
    return value;
  }
  return std::nullopt;
}

std::optional<std::int64_t> integer(std::string_view text) {
  text = trim(text);
  std::int64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end) {
    return std::nullopt;
  }
  return value;
}

// "HH:MM:SS,mmm" (or '.' before the milliseconds) as ns; some recorders count seconds to 60.
std::optional<std::int64_t> clockTime_ns(std::string_view text) {
  text = trim(text);
  const std::size_t c1 = text.find(':');
  const std::size_t c2 = c1 == std::string_view::npos ? c1 : text.find(':', c1 + 1);
  const std::size_t dot = c2 == std::string_view::npos ? c2 : text.find_first_of(",.", c2 + 1);
  if (dot == std::string_view::npos) {
    return std::nullopt;
  }
  const auto h = integer(text.substr(0, c1));
  const auto m = integer(text.substr(c1 + 1, c2 - c1 - 1));
  const auto s = integer(text.substr(c2 + 1, dot - c2 - 1));
  const std::string_view fraction = text.substr(dot + 1);
  const auto ms = integer(fraction);
  if (!h || !m || !s || !ms || *h < 0 || *m < 0 || *m > 59 || *s < 0 || *s > 60 || *ms < 0 ||
      fraction.size() != 3) {
    return std::nullopt;
  }
  return ((*h * 3600 + *m * 60 + *s) * 1000 + *ms) * kNsPerMs;
}

// Removes the HTML tags some recorders wrap the text in (<font size="28">...</font>).
std::string withoutTags(std::string_view line) {
  std::string out;
  out.reserve(line.size());
  bool inTag = false;
  for (const char c : line) {
    if (c == '<') {
      inTag = true;
    } else if (c == '>' && inTag) {
      inTag = false;
      out.push_back(' ');
    } else if (!inTag) {
      out.push_back(c);
    }
  }
  return out;
}

bool identifierChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
}

struct KeyValue {
  std::string_view key;
  std::string_view value;
};

// Every `key: value` (or `key : value`) of a line: a key is a word that starts with a letter;
// the value runs to the next blank, bracket or comma.
std::vector<KeyValue> keyValues(std::string_view line) {
  std::vector<KeyValue> out;
  std::size_t p = 0;
  while (p < line.size()) {
    const char c = line[p];
    const bool startsWord = (std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_') &&
                            (p == 0 || !identifierChar(line[p - 1]));
    if (!startsWord) {
      ++p;
      continue;
    }
    std::size_t q = p;
    while (q < line.size() && identifierChar(line[q])) {
      ++q;
    }
    const std::string_view key = line.substr(p, q - p);
    std::size_t r = q;
    while (r < line.size() && line[r] == ' ') {
      ++r;
    }
    if (r >= line.size() || line[r] != ':') {
      p = q;
      continue;
    }
    ++r;
    while (r < line.size() && line[r] == ' ') {
      ++r;
    }
    std::size_t v = r;
    while (v < line.size() && line[v] != ' ' && line[v] != ']' && line[v] != '[' &&
           line[v] != ',' && line[v] != '\t') {
      ++v;
    }
    out.push_back({key, line.substr(r, v - r)});
    p = v;
  }
  return out;
}

// What the text lines of one block said, with the line of each problem.
struct BlockFields {
  std::optional<double> latitude;
  std::optional<double> longitude;
  std::optional<double> gpsLatitude;  // GPS(lon,lat,alt)
  std::optional<double> gpsLongitude;
  std::optional<double> relative;
  std::optional<double> absolute;
  std::optional<double> gimbalRoll;
  std::optional<double> gimbalPitch;
  std::optional<double> gimbalYaw;
  std::optional<std::int64_t> frameCount;
};

// Reads one text line into fields; an unreadable value of a field we use is a problem.
std::optional<std::string> readTextLine(std::string_view raw, BlockFields& f) {
  const std::string cleaned = withoutTags(raw);
  const std::string_view line(cleaned);

  // Legacy: GPS(lon,lat[,alt]) (also "GPS (lon, lat, alt)").
  for (std::size_t at = line.find("GPS"); at != std::string_view::npos;
       at = line.find("GPS", at + 3)) {
    std::size_t open = at + 3;
    while (open < line.size() && line[open] == ' ') {
      ++open;
    }
    if (open >= line.size() || line[open] != '(') {
      continue;
    }
    const std::size_t close = line.find(')', open);
    if (close == std::string_view::npos) {
      return "GPS(: no closing parenthesis in " + quoted(trim(line));
    }
    std::vector<std::string_view> parts;
    std::string_view inside = line.substr(open + 1, close - open - 1);
    for (std::size_t comma; (comma = inside.find(',')) != std::string_view::npos;) {
      parts.push_back(inside.substr(0, comma));
      inside.remove_prefix(comma + 1);
    }
    parts.push_back(inside);
    if (parts.size() < 2 || parts.size() > 3) {
      return "GPS(...): expected (longitude, latitude, altitude), got " +
             quoted(line.substr(at, close - at + 1));
    }
    const auto lon = number(parts[0], false);
    const auto lat = number(parts[1], false);
    if (!lon || !lat) {
      return "GPS(...): longitude or latitude is not a number in " +
             quoted(line.substr(at, close - at + 1));
    }
    f.gpsLongitude = lon;
    f.gpsLatitude = lat;
    if (parts.size() == 3) {
      const auto alt = number(parts[2], true);
      if (!alt) {
        return "GPS(...): altitude is not a number: " + quoted(trim(parts[2]));
      }
      f.absolute = alt;
    }
  }

  // Legacy: "H 80.00m" among comma-separated fields (height above the take-off point).
  std::string_view rest = line;
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    const std::string_view field = trim(rest.substr(0, comma));
    if (field.size() > 2 && field[0] == 'H' && field[1] == ' ') {
      const auto h = number(field.substr(2), true);
      if (!h) {
        return "H: not a number " + quoted(field.substr(2));
      }
      f.relative = h;
    }
    if (comma == std::string_view::npos) {
      break;
    }
    rest.remove_prefix(comma + 1);
  }

  for (const KeyValue& kv : keyValues(line)) {
    struct Target {
      std::string_view key;
      std::optional<double>* field;
      bool metres;
    };
    const Target targets[] = {
        {"latitude", &f.latitude, false},    {"longitude", &f.longitude, false},
        {"rel_alt", &f.relative, true},      {"abs_alt", &f.absolute, true},
        {"barometer", &f.relative, true},    {"gb_roll", &f.gimbalRoll, false},
        {"gb_pitch", &f.gimbalPitch, false}, {"gb_yaw", &f.gimbalYaw, false},
    };
    for (const Target& t : targets) {
      if (!equalsIgnoreCase(kv.key, t.key)) {
        continue;
      }
      const auto value = number(kv.value, t.metres);
      if (!value) {
        return std::string(kv.key) + ": not a number " + quoted(kv.value);
      }
      *t.field = value;
    }
    if (equalsIgnoreCase(kv.key, "FrameCnt") || equalsIgnoreCase(kv.key, "SrtCnt")) {
      const auto count = integer(kv.value);
      if (!count) {
        return std::string(kv.key) + ": not an integer " + quoted(kv.value);
      }
      f.frameCount = count;
    }
  }
  return std::nullopt;
}

std::string seconds(std::int64_t ns) {
  std::ostringstream s;
  s.precision(3);
  s << std::fixed << static_cast<double>(ns) * 1e-9 << " s";
  return s.str();
}

}  // namespace

const char* toString(SubtitleFormat format) {
  return format == SubtitleFormat::Bracketed ? "bracketed" : "legacy";
}

SubtitleFile parseSubtitles(std::string_view text, const std::string& name) {
  SubtitleFile out;
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") {
    text.remove_prefix(3);  // UTF-8 byte order mark
  }
  std::vector<std::string_view> lines;
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    if (!line.empty() && line.back() == '\r') {
      line.remove_suffix(1);
    }
    lines.push_back(line);
    if (end == std::string_view::npos) {
      break;
    }
    text.remove_prefix(end + 1);
  }

  std::optional<std::int64_t> previousStart_ns;
  std::size_t i = 0;
  while (i < lines.size()) {
    if (trim(lines[i]).empty()) {
      ++i;
      continue;
    }
    const std::size_t first = i;
    while (i < lines.size() && !trim(lines[i]).empty()) {
      ++i;
    }
    ++out.blocks;
    const auto problem = [&](std::size_t lineIndex, const std::string& what,
                             std::optional<std::int64_t> number) {
      out.problems.push_back(name + ":" + std::to_string(lineIndex + 1) + ": " + what +
                             "; subtitle" +
                             (number ? " " + std::to_string(*number) : std::string()) + " skipped");
    };

    const auto number = integer(lines[first]);
    if (!number) {
      problem(first, "expected a subtitle number, got " + quoted(trim(lines[first])), std::nullopt);
      continue;
    }
    if (first + 1 >= i) {
      problem(first, "no time range after the subtitle number", number);
      continue;
    }
    const std::string_view range = lines[first + 1];
    const std::size_t arrow = range.find("-->");
    const auto start =
        arrow == std::string_view::npos ? std::nullopt : clockTime_ns(range.substr(0, arrow));
    const auto end =
        arrow == std::string_view::npos ? std::nullopt : clockTime_ns(range.substr(arrow + 3));
    if (!start || !end) {
      problem(first + 1,
              "expected a time range 'HH:MM:SS,mmm --> HH:MM:SS,mmm', got " + quoted(trim(range)),
              number);
      continue;
    }
    if (*end < *start) {
      problem(first + 1, "time range ends before it starts " + quoted(trim(range)), number);
      continue;
    }

    BlockFields fields;
    bool bad = false;
    for (std::size_t k = first + 2; k < i && !bad; ++k) {
      if (const auto what = readTextLine(lines[k], fields)) {
        problem(k, *what, number);
        bad = true;
      }
    }
    if (bad) {
      continue;
    }

    SubtitleSample sample;
    sample.number = *number;
    sample.line = first + 1;
    sample.start_ns = *start;
    sample.end_ns = *end;
    sample.frameCount = fields.frameCount.value_or(-1);
    if (fields.latitude || fields.longitude) {
      if (!fields.latitude || !fields.longitude) {
        problem(first,
                fields.latitude ? "latitude without longitude" : "longitude without latitude",
                number);
        continue;
      }
      sample.format = SubtitleFormat::Bracketed;
      sample.latitude_deg = *fields.latitude;
      sample.longitude_deg = *fields.longitude;
    } else if (fields.gpsLatitude) {
      sample.format = SubtitleFormat::Legacy;
      sample.latitude_deg = *fields.gpsLatitude;
      sample.longitude_deg = *fields.gpsLongitude;
    } else {
      problem(first, "no position (expected [latitude: ...] [longitude: ...] or GPS(lon,lat,alt))",
              number);
      continue;
    }
    if (std::abs(sample.latitude_deg) > 90.0 || std::abs(sample.longitude_deg) > 180.0) {
      problem(first,
              "position out of range: latitude " + std::to_string(sample.latitude_deg) +
                  ", longitude " + std::to_string(sample.longitude_deg),
              number);
      continue;
    }
    if (sample.latitude_deg == 0.0 && sample.longitude_deg == 0.0) {
      problem(first, "no GPS fix (latitude and longitude 0)", number);
      continue;
    }
    const int gimbalFields = static_cast<int>(fields.gimbalRoll.has_value()) +
                             static_cast<int>(fields.gimbalPitch.has_value()) +
                             static_cast<int>(fields.gimbalYaw.has_value());
    if (gimbalFields != 0 && gimbalFields != 3) {
      problem(first, "gimbal angles given in part (gb_yaw, gb_pitch, gb_roll go together)", number);
      continue;
    }
    if (gimbalFields == 3) {
      sample.gimbal =
          geodesy::EulerAnglesDeg{*fields.gimbalRoll, *fields.gimbalPitch, *fields.gimbalYaw};
    }
    sample.relativeAltitude_m = fields.relative;
    sample.absoluteAltitude_m = fields.absolute;
    if (previousStart_ns && *start <= *previousStart_ns) {
      problem(first + 1,
              "starts at " + seconds(*start) + ", not after the previous subtitle (" +
                  seconds(*previousStart_ns) + ")",
              number);
      continue;
    }
    previousStart_ns = *start;
    ++(sample.format == SubtitleFormat::Bracketed ? out.bracketed : out.legacy);
    out.samples.push_back(sample);
  }
  return out;
}

bool readSubtitleFile(const std::string& path, SubtitleFile& out, std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (why != nullptr) {
      *why = path + ": cannot open subtitle file";
    }
    return false;
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    if (why != nullptr) {
      *why = path + ": read error";
    }
    return false;
  }
  out = parseSubtitles(text.str(), path);
  return true;
}

}  // namespace vp::subtitle
