// vp_import_video: a drone video and its telemetry subtitles into a recorded sequence
// (docs/field_data.md, "Importing a drone video").
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <string>

#include "video_import.hpp"

namespace {

void usage(std::ostream& out) {
  out << "usage: vp_import_video VIDEO [SRT] --out DIR\n"
         "         (--camera NAME | --calibration FILE) (--flat-dtm-height-m H | --dtm FILE)\n"
         "         [--every N] [--max-frames N] [--altitude abs|rel] [--geoid-separation-m N]\n"
         "         [--home-height-m H] [--dtm-crs auto|wgs84|utm:<zone><N|S>]\n"
         "         [--catalogue FILE] [--jpeg-quality Q] [--help]\n"
         "  SRT defaults to VIDEO with the extension .SRT or .srt.\n"
         "  --camera: a camera of the catalogue (default " VP_CAMERA_CATALOGUE
         ")\n"
         "  --altitude abs: height = abs_alt + --geoid-separation-m (default 0);\n"
         "             rel: height = rel_alt + --home-height-m (ellipsoidal, of the take-off "
         "point)\n";
}

}  // namespace

int main(int argc, char** argv) {
  vp::importer::ImportOptions options;
  options.cataloguePath = VP_CAMERA_CATALOGUE;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "vp_import_video: " << name << ": missing value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    const auto number = [&](const char* name, double lo, double hi) {
      const std::string text = value(name);
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
      if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v) || v < lo ||
          v > hi) {
        std::cerr << "vp_import_video: " << name << ": expected a number in [" << lo << ", " << hi
                  << "], got '" << text << "'\n";
        std::exit(2);
      }
      return v;
    };
    if (arg == "--help" || arg == "-h") {
      usage(std::cout);
      return 0;
    } else if (arg == "--out") {
      options.outDir = value("--out");
    } else if (arg == "--every") {
      options.every = static_cast<int>(number("--every", 1, 1e6));
    } else if (arg == "--max-frames") {
      options.maxFrames = static_cast<std::int64_t>(number("--max-frames", 0, 1e12));
    } else if (arg == "--camera") {
      options.cameraName = value("--camera");
    } else if (arg == "--calibration") {
      options.calibrationPath = value("--calibration");
    } else if (arg == "--catalogue") {
      options.cataloguePath = value("--catalogue");
    } else if (arg == "--flat-dtm-height-m") {
      options.flatDtmHeight_m = number("--flat-dtm-height-m", -500, 9000);
    } else if (arg == "--dtm") {
      options.dtmPath = value("--dtm");
    } else if (arg == "--dtm-crs") {
      options.dtmCrs = value("--dtm-crs");
    } else if (arg == "--altitude") {
      const std::string text = value("--altitude");
      const auto source = vp::subtitle::altitudeSourceFromString(text);
      if (!source) {
        std::cerr << "vp_import_video: --altitude: expected abs or rel, got '" << text << "'\n";
        return 2;
      }
      options.telemetry.altitude = *source;
    } else if (arg == "--geoid-separation-m") {
      options.telemetry.geoidSeparation_m = number("--geoid-separation-m", -200, 200);
    } else if (arg == "--home-height-m") {
      options.telemetry.homeHeight_m = number("--home-height-m", -500, 9000);
    } else if (arg == "--jpeg-quality") {
      options.jpegQuality = static_cast<int>(number("--jpeg-quality", 1, 100));
    } else if (!arg.empty() && arg[0] == '-') {
      std::cerr << "vp_import_video: unknown option " << arg << "\n";
      usage(std::cerr);
      return 2;
    } else if (positional == 0) {
      options.videoPath = arg;
      ++positional;
    } else if (positional == 1) {
      options.srtPath = arg;
      ++positional;
    } else {
      std::cerr << "vp_import_video: unexpected argument " << arg << "\n";
      return 2;
    }
  }
  if (options.videoPath.empty() || options.outDir.empty()) {
    usage(std::cerr);
    return 2;
  }

  vp::importer::ImportSummary summary;
  std::string why;
  const bool ok = vp::importer::importVideo(options, summary, &why);
  for (const std::string& error : summary.errors) {
    std::cerr << "vp_import_video: error: " << error << "\n";
  }
  for (const std::string& warning : summary.warnings) {
    std::cerr << "vp_import_video: warning: " << warning << "\n";
  }
  if (!ok) {
    std::cerr << "vp_import_video: " << why << "\n";
    return 1;
  }
  std::cout << "vp_import_video: " << options.outDir << ": " << summary.framesWritten
            << " frames written of " << summary.framesRead << " read, " << summary.telemetryRows
            << " telemetry rows from " << summary.subtitleBlocks << " subtitles, "
            << summary.errors.size() << " skipped (errors above), " << summary.nadirAssumed
            << " rows with the nadir assumption, " << summary.framesOutsideTelemetry
            << " frames outside the telemetry, " << summary.indexTimestamps
            << " frames timed by index\n";
  return 0;
}
