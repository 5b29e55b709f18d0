// vp_gcp: ground control points of a fixed view (docs/field_data.md, "Ground control points").
//
//   check: reads the rig (camera, origin, DTM) and a GCP file, estimates the image -> ground
//          homography as the app does, prints it with each point's residuals and, given a
//          frame, writes it annotated with the points and their reprojections.
//   pick:  shows a frame in a window; each click prints a CSV row (id, u_px, v_px) whose
//          latitude and longitude are then filled in from a map.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#ifdef VP_HAVE_HIGHGUI
#include <opencv2/highgui.hpp>
#endif

#include "georef/georeference.hpp"
#include "io/dtm_file.hpp"
#include "rig_config/rig_config.hpp"

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;

void printHelp() {
  std::puts(
      "Usage: vp_gcp check --rig FILE --gcp FILE [--image FRAME] [--out IMAGE]\n"
      "                    [--max-residual-m M]\n"
      "       vp_gcp pick --image FRAME [--out FILE]\n"
      "\n"
      "Ground control points (GCPs) place the fixed view of a hovering drone in the world when\n"
      "there is no telemetry (georef.gcp_file, docs/field_data.md). The GCP file is CSV:\n"
      "  id,u_px,v_px,latitude_deg,longitude_deg[,height_m]\n"
      "with the pixel in the raw camera frame and WGS84 degrees (height: ellipsoidal, m;\n"
      "optional, else the DTM's height there).\n"
      "\n"
      "check   Estimates the image -> ground homography as the app does (lens distortion\n"
      "        removed with the rig's camera model; normalised DLT + Levenberg-Marquardt) and\n"
      "        prints it, the ground plane, the camera it implies and, per point, the ground\n"
      "        residual (m) and the image residual (px). Exit status 1 when a residual exceeds\n"
      "        --max-residual-m or the set is degenerate (the message names the points).\n"
      "  --rig FILE           YAML with origin, camera and terrain: the app's configuration or\n"
      "                       a recording's rig.yaml\n"
      "  --gcp FILE           the GCP file\n"
      "  --image FRAME        a frame of the view (the camera's size): written annotated, each\n"
      "                       point as a green circle at its pixel and a red cross where its\n"
      "                       surveyed position maps back, joined by a line\n"
      "  --out IMAGE          the annotated frame (default: FRAME's name + _gcp.png)\n"
      "  --max-residual-m M   largest accepted ground residual (default 1, as "
      "georef.max_residual_m)\n"
      "\n"
      "pick    Opens FRAME in a window (needs a display): left click adds a point, u removes\n"
      "        the last, Enter, q or Esc ends. Prints the CSV rows (header included) with the\n"
      "        latitude and longitude left empty, to be filled in from a map or a survey.\n"
      "  --image FRAME        the frame\n"
      "  --out FILE           also write the rows there\n"
      "\n"
      "  -h, --help           this text\n");
}

struct Arguments {
  std::string mode;
  std::string rig;
  std::string gcp;
  std::string image;
  std::string out;
  double maxResidual_m = 1.0;
};

[[noreturn]] void usageError(const std::string& message) {
  std::fprintf(stderr, "vp_gcp: %s (vp_gcp --help)\n", message.c_str());
  std::exit(kUsage);
}

Arguments parse(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        usageError(arg + " needs a value");
      }
      return argv[++i];
    };
    if (arg == "-h" || arg == "--help") {
      printHelp();
      std::exit(0);
    } else if (i == 1 && (arg == "check" || arg == "pick")) {
      a.mode = arg;
    } else if (arg == "--rig") {
      a.rig = value();
    } else if (arg == "--gcp") {
      a.gcp = value();
    } else if (arg == "--image") {
      a.image = value();
    } else if (arg == "--out") {
      a.out = value();
    } else if (arg == "--max-residual-m") {
      const std::string text = value();
      char* end = nullptr;
      a.maxResidual_m = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !(a.maxResidual_m > 0.0)) {
        usageError("--max-residual-m: expected a number > 0, got '" + text + "'");
      }
    } else {
      usageError("unknown argument '" + arg + "'");
    }
  }
  if (a.mode.empty()) {
    usageError("the first argument is the mode: check or pick");
  }
  if (a.mode == "check" && (a.rig.empty() || a.gcp.empty())) {
    usageError("check needs --rig and --gcp");
  }
  if (a.mode == "pick" && a.image.empty()) {
    usageError("pick needs --image");
  }
  return a;
}

cv::Mat readFrame(const std::string& path) {
  cv::Mat frame = cv::imread(path, cv::IMREAD_COLOR);
  if (frame.empty()) {
    std::fprintf(stderr, "vp_gcp: %s: cannot read the image\n", path.c_str());
    std::exit(kFailure);
  }
  return frame;
}

void annotate(const vp::georef::GroundView& view, const vp::camera::CameraModel& camera,
              cv::Mat& frame) {
  const vp::georef::GroundHomography& h = view.homography;
  for (std::size_t i = 0; i < view.file.points.size(); ++i) {
    const vp::georef::GcpRecord& record = view.file.points[i];
    const cv::Point2d given(record.pixel.x(), record.pixel.y());
    const Eigen::Vector2d back = camera.distortPixel(h.residuals[i].reprojectedPixel);
    const cv::Point2d reprojected(back.x(), back.y());
    cv::line(frame, given, reprojected, cv::Scalar(0, 255, 255), 1, cv::LINE_AA);
    cv::circle(frame, given, 8, cv::Scalar(0, 200, 0), 2, cv::LINE_AA);
    cv::drawMarker(frame, reprojected, cv::Scalar(0, 0, 255), cv::MARKER_CROSS, 14, 2, cv::LINE_AA);
    char label[96];
    std::snprintf(label, sizeof label, "%s %.2f m", record.id.c_str(), h.residuals[i].ground_m);
    cv::putText(frame, label, given + cv::Point2d(10, -10), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
    cv::putText(frame, label, given + cv::Point2d(10, -10), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
}

int check(const Arguments& a) {
  const vp::config::RigConfig rig = vp::config::loadRigConfig(a.rig);
  for (const std::string& warning : rig.warnings) {
    std::fprintf(stderr, "vp_gcp: warning: %s\n", warning.c_str());
  }
  std::string why;
  vp::camera::CameraModel camera;
  if (!camera.init(rig.camera.intrinsics, rig.camera.distortion, &why)) {
    std::fprintf(stderr, "vp_gcp: %s: camera: %s\n", a.rig.c_str(), why.c_str());
    return kFailure;
  }
  const vp::geodesy::LocalFrame frame(rig.origin);
  // The DTM gives the heights the file leaves out; without it they are the origin's.
  vp::terrain::TerrainModel terrain;
  vp::terrain::TerrainGrid grid;
  const bool haveDtm =
      vp::io::loadDtm(rig.terrain.dtmPath, rig.terrain.crs, grid, &why, rig.terrain.load) &&
      terrain.init(std::move(grid), frame, &why);
  if (!haveDtm) {
    std::fprintf(stderr,
                 "vp_gcp: warning: terrain.dtm_path: %s (points without a height take "
                 "the origin's)\n",
                 why.c_str());
  }
  vp::georef::GeorefOptions options;
  options.gcpFile = a.gcp;
  vp::georef::GroundView view;
  if (!vp::georef::loadGroundView(options, camera, frame, haveDtm ? &terrain : nullptr, &view,
                                  &why)) {
    std::fprintf(stderr, "vp_gcp: %s\n", why.c_str());
    return kFailure;
  }
  const vp::georef::GroundHomography& h = view.homography;
  std::printf("%zu ground control points from %s (origin %.7f, %.7f, %.2f m)\n", view.points.size(),
              a.gcp.c_str(), rig.origin.latitude_deg, rig.origin.longitude_deg,
              rig.origin.height_m);
  std::printf("image -> ground homography (ideal pixel (u, v, 1) -> world ENU (E, N, w)):\n");
  for (int r = 0; r < 3; ++r) {
    std::printf("  [% .9e  % .9e  % .9e]\n", h.imageToGround(r, 0), h.imageToGround(r, 1),
                h.imageToGround(r, 2));
  }
  std::printf(
      "ground plane: z = %.3f %+.5f * E %+.5f * N m (ENU); Levenberg-Marquardt: %d "
      "steps, RMS %.4f m -> %.4f m\n",
      h.plane.a, h.plane.b, h.plane.c, h.iterations, h.initialRms_m, h.rms_m);
  if (view.camera) {
    const Eigen::Vector3d forward = view.camera->cameraToEnu.col(2);
    std::printf(
        "camera: centre E %.2f N %.2f U %.2f m, %.2f m above the ground, optical axis "
        "%.1f deg from nadir\n",
        view.camera->centreEnu.x(), view.camera->centreEnu.y(), view.camera->centreEnu.z(),
        view.camera->heightAboveGround_m,
        std::acos(std::clamp(-forward.z(), -1.0, 1.0)) * 180.0 / 3.14159265358979);
  } else {
    std::printf(
        "camera: the homography does not decompose into a camera above the ground "
        "(check the intrinsics and the points)\n");
  }
  std::printf("%-12s %5s %10s %10s %10s %10s %9s\n", "id", "line", "u_px", "v_px", "dE_m", "dN_m",
              "|d|_m");
  for (std::size_t i = 0; i < h.residuals.size(); ++i) {
    const vp::georef::PointResidual& r = h.residuals[i];
    const vp::georef::GcpRecord& record = view.file.points[i];
    std::printf("%-12s %5d %10.2f %10.2f %+10.3f %+10.3f %9.3f   (%.2f px in the image)\n",
                r.id.c_str(), record.line, record.pixel.x(), record.pixel.y(), r.groundError_m.x(),
                r.groundError_m.y(), r.ground_m, r.image_px);
  }
  std::printf("RMS %.3f m, largest %.3f m (point '%s')\n", h.rms_m, h.max_m,
              h.residuals[h.maxIndex].id.c_str());
  if (!a.image.empty()) {
    cv::Mat image = readFrame(a.image);
    if (image.cols != rig.camera.intrinsics.width_px ||
        image.rows != rig.camera.intrinsics.height_px) {
      std::fprintf(stderr, "vp_gcp: %s: %dx%d, but the camera is %dx%d\n", a.image.c_str(),
                   image.cols, image.rows, rig.camera.intrinsics.width_px,
                   rig.camera.intrinsics.height_px);
      return kFailure;
    }
    annotate(view, camera, image);
    const std::string out = !a.out.empty()
                                ? a.out
                                : (std::filesystem::path(a.image).parent_path() /
                                   (std::filesystem::path(a.image).stem().string() + "_gcp.png"))
                                      .string();
    if (!cv::imwrite(out, image)) {
      std::fprintf(stderr, "vp_gcp: %s: cannot write the annotated frame\n", out.c_str());
      return kFailure;
    }
    std::printf("annotated frame: %s\n", out.c_str());
  }
  if (!vp::georef::checkResiduals(view, a.maxResidual_m, &why)) {
    std::fprintf(stderr, "vp_gcp: %s\n", why.c_str());
    return kFailure;
  }
  return 0;
}

int pick(const Arguments& a) {
#ifndef VP_HAVE_HIGHGUI
  (void)a;
  std::fprintf(stderr,
               "vp_gcp: pick: this build has no OpenCV window support (highgui); read the "
               "pixels in an image viewer and write the rows by hand\n");
  return kUsage;
#else
  if (std::getenv("DISPLAY") == nullptr && std::getenv("WAYLAND_DISPLAY") == nullptr) {
    std::fprintf(stderr,
                 "vp_gcp: pick: no display (DISPLAY and WAYLAND_DISPLAY are unset); run it on a "
                 "desktop, or read the pixels in an image viewer\n");
    return kUsage;
  }
  const cv::Mat image = readFrame(a.image);
  struct State {
    std::vector<cv::Point2d> points;
  } state;
  const char* window = "vp_gcp pick: click points, u = undo, Enter/q/Esc = done";
  cv::namedWindow(window, cv::WINDOW_NORMAL);
  cv::setMouseCallback(
      window,
      [](int event, int x, int y, int, void* data) {
        if (event == cv::EVENT_LBUTTONDOWN) {
          auto* s = static_cast<State*>(data);
          s->points.emplace_back(x, y);
          std::fprintf(stderr, "P%zu,%d,%d,,\n", s->points.size(), x, y);
        }
      },
      &state);
  for (;;) {
    cv::Mat shown = image.clone();
    for (std::size_t i = 0; i < state.points.size(); ++i) {
      cv::circle(shown, state.points[i], 8, cv::Scalar(0, 200, 0), 2, cv::LINE_AA);
      cv::putText(shown, "P" + std::to_string(i + 1), state.points[i] + cv::Point2d(10, -10),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 255, 255), 2, cv::LINE_AA);
    }
    cv::imshow(window, shown);
    const int key = cv::waitKey(50);
    if (key == 13 || key == 10 || key == 'q' || key == 27) {
      break;
    }
    if (key == 'u' && !state.points.empty()) {
      state.points.pop_back();
    }
  }
  cv::destroyAllWindows();
  std::string rows = vp::georef::gcpHeader(true) + "\n";
  for (std::size_t i = 0; i < state.points.size(); ++i) {
    char row[96];
    std::snprintf(row, sizeof row, "P%zu,%.0f,%.0f,,,\n", i + 1, state.points[i].x,
                  state.points[i].y);
    rows += row;
  }
  std::fputs(rows.c_str(), stdout);
  if (!a.out.empty()) {
    std::ofstream file(a.out);
    file << rows;
    if (!file) {
      std::fprintf(stderr, "vp_gcp: %s: cannot write\n", a.out.c_str());
      return kFailure;
    }
  }
  std::fprintf(stderr, "%zu point(s); fill in latitude_deg and longitude_deg (WGS84) before use\n",
               state.points.size());
  return 0;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  const Arguments arguments = parse(argc, argv);
  try {
    return arguments.mode == "check" ? check(arguments) : pick(arguments);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "vp_gcp: %s\n", error.what());
    return kFailure;
  }
}
