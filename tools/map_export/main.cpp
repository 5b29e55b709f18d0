// vp_map_export: the outputs of a run as one GeoJSON map for people (QGIS, geojson.io, a web
// map): tracks, the site, gate counts, zone occupancy, lane speeds, turning movements and
// traffic events. docs/site_map.md, section "Map export".
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "map_export.hpp"
#include "rig_config/rig_config.hpp"

namespace {

namespace fs = std::filesystem;
using vp::map_export::MapExportOptions;

constexpr const char* kUsage = R"(usage: vp_map_export [INPUTS] --out FILE [OPTIONS]

Writes one GeoJSON FeatureCollection (RFC 7946, WGS84) of what the app wrote about a run.

Inputs (each optional, at least one):
  --trajectory FILE       the app's trajectory.csv: each track as a line
  --site FILE             the site file (site.geojson): its features
  --traffic DIR           the traffic files found in DIR (traffic_counts.csv,
                          traffic_movements.csv, traffic_zones.csv, traffic_lanes.csv,
                          traffic_events.csv); a file option below overrides its file
  --counts FILE           traffic_counts.csv: totals by direction and type on each gate
  --movements FILE        traffic_movements.csv: a line from gate to gate per movement
  --zones FILE            traffic_zones.csv: mean occupancy and longest queue of each zone
  --lanes FILE            traffic_lanes.csv: vehicles and speeds of each lane
  --events FILE           traffic_events.csv: each event as a point
  (the statistics files need --site: they are drawn on its gates, zones and lanes)

World frame (only for rows without latitude/longitude, placed by their ENU position):
  --rig FILE              the rig's origin: a recording's rig.yaml or the app's configuration
  --origin LAT,LON[,H]    the origin in degrees (and metres)

Output and options:
  --out FILE              the GeoJSON file ('-': standard output)
  --min-track-points N    leave out tracks with fewer trajectory rows (default 2)
  --simplify-m M          drop track vertices closer than M metres along the line to the
                          last kept one (default 0: keep all)
  --help                  this text

Exit status: 0 written, 1 an input could not be read or is inconsistent, 2 usage.
)";

int usageError(const std::string& message) {
  std::fprintf(stderr, "vp_map_export: %s\n(vp_map_export --help for the usage)\n",
               message.c_str());
  return 2;
}

bool parseNumber(std::string_view text, double* value) {
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), *value);
  return error == std::errc() && end == text.data() + text.size();
}

bool parseOrigin(const std::string& text, vp::geodesy::GeodeticPoint* origin) {
  std::vector<double> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    double value = 0.0;
    if (!parseNumber(std::string_view(text).substr(start, comma - start), &value)) {
      return false;
    }
    values.push_back(value);
    start = comma + 1;
  }
  if (values.size() < 2 || values.size() > 3 || std::abs(values[0]) > 90.0 ||
      std::abs(values[1]) > 180.0 || !std::isfinite(values.back())) {
    return false;
  }
  *origin = {values[0], values[1], values.size() == 3 ? values[2] : 0.0};
  return true;
}

bool writeOutput(const std::string& path, const std::string& text, std::string* why) {
  if (path == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return std::fflush(stdout) == 0;
  }
  // Written beside the target and renamed into place: a reader never sees half a map.
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      *why = temporary + ": cannot write (" + std::strerror(errno) + ")";
      std::error_code ignored;
      fs::remove(temporary, ignored);
      return false;
    }
  }
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) {
    *why = path + ": cannot rename " + temporary + " into place (" + error.message() + ")";
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  MapExportOptions options;
  std::string out;
  std::string trafficDir;
  std::string rigPath;
  std::string originText;
  // The file options given explicitly: --traffic does not override them.
  std::string counts, movements, zones, lanes, events;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    const auto value = [&](std::string* target) {
      if (i + 1 >= argc) {
        return false;
      }
      *target = argv[++i];
      return true;
    };
    bool ok = true;
    std::string number;
    if (arg == "--trajectory") {
      ok = value(&options.trajectoryPath);
    } else if (arg == "--site") {
      ok = value(&options.sitePath);
    } else if (arg == "--traffic") {
      ok = value(&trafficDir);
    } else if (arg == "--counts") {
      ok = value(&counts);
    } else if (arg == "--movements") {
      ok = value(&movements);
    } else if (arg == "--zones") {
      ok = value(&zones);
    } else if (arg == "--lanes") {
      ok = value(&lanes);
    } else if (arg == "--events") {
      ok = value(&events);
    } else if (arg == "--rig") {
      ok = value(&rigPath);
    } else if (arg == "--origin") {
      ok = value(&originText);
    } else if (arg == "--out") {
      ok = value(&out);
    } else if (arg == "--min-track-points") {
      ok = value(&number);
      int n = 0;
      const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), n);
      if (ok && (error != std::errc() || end != number.data() + number.size())) {
        return usageError("--min-track-points: not an integer '" + number + "'");
      }
      options.minTrackPoints = n;
    } else if (arg == "--simplify-m") {
      ok = value(&number);
      if (ok && !parseNumber(number, &options.simplify_m)) {
        return usageError("--simplify-m: not a number '" + number + "'");
      }
    } else {
      return usageError("unknown argument '" + arg + "'");
    }
    if (!ok) {
      return usageError(arg + ": needs a value");
    }
  }
  if (out.empty()) {
    return usageError("--out: where to write the map is required");
  }
  if (!rigPath.empty() && !originText.empty()) {
    return usageError("--rig and --origin both give the origin: give one");
  }
  if (!originText.empty()) {
    vp::geodesy::GeodeticPoint origin;
    if (!parseOrigin(originText, &origin)) {
      return usageError(
          "--origin: expected LAT,LON or LAT,LON,HEIGHT in degrees and metres, got '" + originText +
          "'");
    }
    options.origin = origin;
  }
  if (!rigPath.empty()) {
    try {
      options.origin = vp::config::loadRigConfig(rigPath).origin;
    } catch (const vp::config::ConfigError& error) {
      std::fprintf(stderr, "vp_map_export: --rig: %s\n", error.what());
      return 1;
    }
  }
  if (!trafficDir.empty()) {
    if (!fs::is_directory(trafficDir)) {
      std::fprintf(stderr, "vp_map_export: --traffic %s: not a directory\n", trafficDir.c_str());
      return 1;
    }
    const auto found = [&](const char* name) {
      const fs::path path = fs::path(trafficDir) / name;
      return fs::is_regular_file(path) ? path.string() : std::string();
    };
    options.countsPath = found("traffic_counts.csv");
    options.movementsPath = found("traffic_movements.csv");
    options.zonesPath = found("traffic_zones.csv");
    options.lanesPath = found("traffic_lanes.csv");
    options.eventsPath = found("traffic_events.csv");
  }
  for (const auto& [given, target] :
       {std::pair{&counts, &options.countsPath}, std::pair{&movements, &options.movementsPath},
        std::pair{&zones, &options.zonesPath}, std::pair{&lanes, &options.lanesPath},
        std::pair{&events, &options.eventsPath}}) {
    if (!given->empty()) {
      *target = *given;
    }
  }
  std::string why;
  if (!vp::map_export::checkOptions(options, &why)) {
    return usageError(why);
  }
  std::string geojson;
  vp::map_export::MapExportSummary s;
  if (!vp::map_export::exportMap(options, &geojson, &s, &why)) {
    std::fprintf(stderr, "vp_map_export: %s\n", why.c_str());
    return 1;
  }
  if (!writeOutput(out, geojson, &why)) {
    std::fprintf(stderr, "vp_map_export: %s\n", why.c_str());
    return 1;
  }
  std::fprintf(out == "-" ? stderr : stdout,
               "vp_map_export: wrote %s: %zu tracks (%zu with fewer than %d rows left out; %zu "
               "rows, %zu vertices), %zu site features (%zu gates with counts, %zu zones and "
               "%zu lanes with statistics), %zu movements, %zu events\n",
               out == "-" ? "standard output" : out.c_str(), s.tracks, s.tracksTooShort,
               options.minTrackPoints, s.trackRows, s.trackVertices, s.siteFeatures,
               s.gatesWithCounts, s.zonesWithStatistics, s.lanesWithStatistics, s.movements,
               s.events);
  return 0;
}
