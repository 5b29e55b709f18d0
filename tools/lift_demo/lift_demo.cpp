// vp_lift_demo: places image points and a rotated box on the terrain with a given pose.
//
// The main job of the project until the firmware app exists: it loads the YAML
// configuration (camera, mount, DTM, origin), the DTM, takes a drone pose from the command
// line, and prints where pixels and an image rotated box land in the world (ENU, WGS84,
// UTM), then checks each point by projecting it back into the image.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "config/config.hpp"
#include "io/dtm_file.hpp"
#include "lifting/lifting.hpp"

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

struct Options {
  std::string configPath = "config/default.yaml";
  double altitudeAboveOrigin_m = 100.0;  // drone height above the origin's height, m
  double north_m = 0.0;                  // drone offset from the origin, m
  double east_m = 0.0;
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  double yaw_deg = 0.0;
  double gimbalPitch_deg = -90.0;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<vp::geometry::RotatedBox> boxes;
};

void printHelp() {
  std::puts(
      "Usage: vp_lift_demo [options]\n"
      "\n"
      "Lifts image points and rotated boxes to the terrain (DTM) with a drone pose, and\n"
      "projects them back to check the round trip.\n"
      "\n"
      "Options:\n"
      "  --config PATH        YAML configuration (default: config/default.yaml)\n"
      "  --altitude M         drone height above the origin's height, m (default 100)\n"
      "  --east M, --north M  drone offset from the origin, m (default 0, 0)\n"
      "  --roll DEG, --pitch DEG, --yaw DEG\n"
      "                       autopilot attitude, aerospace ZYX (default 0, 0, 0)\n"
      "  --gimbal-pitch DEG   gimbal pitch, -90 = nadir (default -90)\n"
      "  --pixel U,V          a pixel to lift (repeatable; default: centre and corners)\n"
      "  --box CX,CY,L,W,DEG  an image rotated box: centre px, length px, width px,\n"
      "                       driving direction deg from +u towards +v (repeatable)\n"
      "  -h, --help           this text\n");
}

bool parseNumbers(const char* text, std::size_t count, double* out) {
  std::stringstream ss(text);
  for (std::size_t i = 0; i < count; ++i) {
    if (!(ss >> out[i]) || !std::isfinite(out[i])) {
      return false;
    }
    if (i + 1 < count && ss.get() != ',') {
      return false;
    }
  }
  ss >> std::ws;
  return ss.eof();
}

// Returns false (after printing why) on a bad command line.
bool parseArgs(int argc, char** argv, Options& opt, bool& help) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      help = true;
      return true;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "vp_lift_demo: option %s needs a value (see --help)\n", arg.c_str());
      return false;
    }
    const char* value = argv[++i];
    double v[5] = {};
    bool ok = true;
    if (arg == "--config") {
      opt.configPath = value;
    } else if (arg == "--pixel") {
      ok = parseNumbers(value, 2, v);
      opt.pixels.emplace_back(v[0], v[1]);
    } else if (arg == "--box") {
      ok = parseNumbers(value, 5, v) && v[2] > 0.0 && v[3] > 0.0;
      opt.boxes.push_back({v[0], v[1], v[2], v[3], vp::geometry::wrapTwoPi(v[4] * kDegToRad)});
    } else {
      const std::pair<const char*, double*> numeric[] = {{"--altitude", &opt.altitudeAboveOrigin_m},
                                                         {"--east", &opt.east_m},
                                                         {"--north", &opt.north_m},
                                                         {"--roll", &opt.roll_deg},
                                                         {"--pitch", &opt.pitch_deg},
                                                         {"--yaw", &opt.yaw_deg},
                                                         {"--gimbal-pitch", &opt.gimbalPitch_deg}};
      double* target = nullptr;
      for (const auto& [name, field] : numeric) {
        target = arg == name ? field : target;
      }
      if (target == nullptr) {
        std::fprintf(stderr, "vp_lift_demo: unknown option %s (see --help)\n", arg.c_str());
        return false;
      }
      ok = parseNumbers(value, 1, target);
    }
    if (!ok) {
      std::fprintf(stderr, "vp_lift_demo: bad value '%s' for %s (see --help)\n", value,
                   arg.c_str());
      return false;
    }
  }
  return true;
}

void printPoint(const char* label, const vp::geodesy::LocalFrame& frame,
                const Eigen::Vector3d& enu) {
  const vp::geodesy::GeodeticPoint g = frame.toGeodetic(enu);
  const vp::geodesy::UtmPoint u = vp::geodesy::toUtm(g);
  std::printf(
      "%s ENU (%9.3f, %9.3f, %7.3f) m | WGS84 %.8f, %.8f, h %.3f m | UTM %d%c %.3f E %.3f N\n",
      label, enu.x(), enu.y(), enu.z(), g.latitude_deg, g.longitude_deg, g.height_m, u.zone,
      u.northp ? 'N' : 'S', u.easting_m, u.northing_m);
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  bool help = false;
  if (!parseArgs(argc, argv, opt, help)) {
    return 2;
  }
  if (help) {
    printHelp();
    return 0;
  }

  vp::config::AppConfig config;
  try {
    config = vp::config::loadConfig(opt.configPath);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vp_lift_demo: %s\n", e.what());
    return 1;
  }
  for (const std::string& w : config.warnings) {
    std::fprintf(stderr, "vp_lift_demo: warning: %s\n", w.c_str());
  }

  std::string why;
  vp::camera::CameraModel camera;
  if (!camera.init(config.camera.intrinsics, config.camera.distortion, &why)) {
    std::fprintf(stderr, "vp_lift_demo: %s: camera: %s\n", opt.configPath.c_str(), why.c_str());
    return 1;
  }
  vp::terrain::TerrainGrid grid;
  if (!vp::io::loadDtm(config.terrain.dtmPath, config.terrain.crs, grid, &why,
                       config.terrain.load)) {
    std::fprintf(stderr, "vp_lift_demo: %s\n", why.c_str());
    return 1;
  }
  const vp::geodesy::LocalFrame frame(config.origin);
  vp::terrain::TerrainModel terrain;
  if (!terrain.init(std::move(grid), frame, &why)) {
    std::fprintf(stderr, "vp_lift_demo: %s: %s\n", config.terrain.dtmPath.c_str(), why.c_str());
    return 1;
  }
  vp::lifting::Lifter lifter;
  if (!lifter.init(camera, config.mount.mount, terrain, frame, &why)) {
    std::fprintf(stderr, "vp_lift_demo: %s\n", why.c_str());
    return 1;
  }

  vp::lifting::DronePose pose;
  pose.position = frame.toGeodetic({opt.east_m, opt.north_m, opt.altitudeAboveOrigin_m});
  pose.bodyToNed = Eigen::Quaterniond(
      vp::geodesy::rotationFromEuler({opt.roll_deg, opt.pitch_deg, opt.yaw_deg}));
  pose.gimbal = config.mount.gimbal;
  pose.gimbal.angles.pitch_deg = opt.gimbalPitch_deg;
  const auto camPose = lifter.cameraPose(pose);
  if (!camPose) {
    std::fprintf(stderr, "vp_lift_demo: pose: %s\n", vp::lifting::toString(camPose.error()));
    return 1;
  }

  const auto& in = config.camera.intrinsics;
  std::printf(
      "DTM %s: %d x %d samples, %s, heights %.2f .. %.2f m\n", config.terrain.dtmPath.c_str(),
      terrain.grid().cols, terrain.grid().rows, vp::terrain::toString(terrain.grid().crs).c_str(),
      static_cast<double>(terrain.minHeight_m()), static_cast<double>(terrain.maxHeight_m()));
  printPoint("camera centre         ", frame, camPose->centreEnu);

  if (opt.pixels.empty() && opt.boxes.empty()) {
    const double w = in.width_px - 1.0;
    const double h = in.height_px - 1.0;
    opt.pixels = {{in.cx_px, in.cy_px}, {0.0, 0.0}, {w, 0.0}, {w, h}, {0.0, h}};
    opt.boxes.push_back({in.cx_px, in.cy_px, 130.0, 52.0, 30.0 * kDegToRad});
  }
  int failures = 0;
  for (const Eigen::Vector2d& p : opt.pixels) {
    char label[64];
    std::snprintf(label, sizeof label, "pixel (%7.1f, %7.1f)", p.x(), p.y());
    const auto world = lifter.pixelToWorld(*camPose, p);
    if (!world) {
      std::printf("%s -> no world position: %s\n", label, vp::lifting::toString(world.error()));
      continue;
    }
    printPoint(label, frame, *world);
    const auto back = lifter.worldToPixel(*camPose, *world);
    const double err_px = back ? (*back - p).norm() : std::numeric_limits<double>::infinity();
    std::printf("    back to the image: error %.2e px\n", err_px);
    failures += err_px > 1e-3 ? 1 : 0;
  }
  for (const vp::geometry::RotatedBox& b : opt.boxes) {
    const auto g = lifter.boxToGround(*camPose, b);
    std::printf("box centre (%.1f, %.1f) px, %.1f x %.1f px, %.1f deg: ", b.cx, b.cy, b.length,
                b.width, b.angle / kDegToRad);
    if (!g) {
      std::printf("no world position: %s\n", vp::lifting::toString(g.error()));
      continue;
    }
    std::printf("length %.3f m, width %.3f m, heading %.2f deg from true north\n", g->length_m,
                g->width_m, g->headingTrueNorth_deg);
    printPoint("    centre            ", frame, g->centreEnu);
  }
  return failures == 0 ? 0 : 1;
}
