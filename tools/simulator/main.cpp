// vp_simulate: renders drone-camera image sequences of roads with vehicles, with full ground
// truth, in the recorded-sequence format (docs/simulator.md, docs/recorded_sequence.md).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#include "simulator.hpp"

namespace {

void usage(std::ostream& out) {
  out << "usage: vp_simulate --scene intersection|straight|parking --seed N --frames N --out DIR\n"
         "                   [--width 2592 --height 2048] [--altitude-m 60..150] [--tilt-deg "
         "0..45]\n"
         "                   [--jpeg-quality Q | --png] [--threads N] [--supersampling 1..4]\n"
         "                   [--asm PATH] [--telemetry-noise] [--static-hover] [--instance-masks]\n"
         "                   [--two-tone-share 0..1] [--city-car-share 0..1] [--poles]\n"
         "                   [--pickup-share 0..1] [--large-share 0..1] [--bus-roof-share 0..1]\n"
         "                   [--islands] [--road-users]\n"
         "                   [--help]\n"
         "Renders N frames at 10 Hz of a scene drawn from the seed (same seed: byte-identical\n"
         "output) into DIR as a recorded sequence with ground truth. See docs/simulator.md.\n";
}

bool parseNumber(const char* text, double* out) {
  char* end = nullptr;
  *out = std::strtod(text, &end);
  return end != text && *end == '\0';
}

}  // namespace

int main(int argc, char** argv) {
  vp::sim::SimOptions options;
  bool haveScene = false, haveSeed = false, haveFrames = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&](const char* name) -> const char* {
      if (i + 1 >= argc) {
        std::cerr << "vp_simulate: " << name << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    const auto number = [&](const char* name, double lo, double hi) {
      double v = 0.0;
      const char* text = value(name);
      if (!parseNumber(text, &v) || v < lo || v > hi) {
        std::cerr << "vp_simulate: " << name << ": expected a number in [" << lo << ", " << hi
                  << "], got '" << text << "'\n";
        std::exit(2);
      }
      return v;
    };
    if (arg == "--help" || arg == "-h") {
      usage(std::cout);
      return 0;
    } else if (arg == "--scene") {
      const char* text = value("--scene");
      const auto kind = vp::sim::sceneKindFromString(text);
      if (!kind) {
        std::cerr << "vp_simulate: --scene: unknown scene '" << text << "'\n";
        return 2;
      }
      options.scene = *kind;
      haveScene = true;
    } else if (arg == "--seed") {
      const char* text = value("--seed");
      char* end = nullptr;
      options.seed = std::strtoull(text, &end, 10);
      if (end == text || *end != '\0') {
        std::cerr << "vp_simulate: --seed: not an integer '" << text << "'\n";
        return 2;
      }
      haveSeed = true;
    } else if (arg == "--frames") {
      options.frames = static_cast<int>(number("--frames", 1, 1e6));
      haveFrames = true;
    } else if (arg == "--out") {
      options.outDir = value("--out");
    } else if (arg == "--width") {
      options.width = static_cast<int>(number("--width", 16, 16384));
    } else if (arg == "--height") {
      options.height = static_cast<int>(number("--height", 16, 16384));
    } else if (arg == "--altitude-m") {
      options.altitude_m = number("--altitude-m", 60, 150);
    } else if (arg == "--tilt-deg") {
      options.tilt_deg = number("--tilt-deg", 0, 45);
    } else if (arg == "--jpeg-quality") {
      options.jpegQuality = static_cast<int>(number("--jpeg-quality", 1, 100));
      options.png = false;
    } else if (arg == "--png") {
      options.png = true;
    } else if (arg == "--threads") {
      options.threads = static_cast<int>(number("--threads", 1, 256));
    } else if (arg == "--supersampling") {
      options.supersampling = static_cast<int>(number("--supersampling", 1, 4));
    } else if (arg == "--asm") {
      options.asmPath = value("--asm");
    } else if (arg == "--telemetry-noise") {
      options.telemetryNoise = true;
    } else if (arg == "--static-hover") {
      options.staticHover = true;
    } else if (arg == "--instance-masks") {
      options.instanceMasks = true;
    } else if (arg == "--two-tone-share") {
      options.twoToneShare = number("--two-tone-share", 0, 1);
    } else if (arg == "--city-car-share") {
      options.cityCarShare = number("--city-car-share", 0, 1);
    } else if (arg == "--pickup-share") {
      options.pickupShare = number("--pickup-share", 0, 1);
    } else if (arg == "--bus-roof-share") {
      options.busRoofShare = number("--bus-roof-share", 0, 1);
    } else if (arg == "--large-share") {
      options.largeVehicleShare = number("--large-share", 0, 1);
    } else if (arg == "--poles") {
      options.poles = true;
    } else if (arg == "--islands") {
      options.islands = true;
    } else if (arg == "--road-users") {
      options.roadUsers = true;
    } else {
      std::cerr << "vp_simulate: unknown argument '" << arg << "'\n";
      usage(std::cerr);
      return 2;
    }
  }
  if (!haveScene || !haveSeed || !haveFrames || options.outDir.empty()) {
    std::cerr << "vp_simulate: --scene, --seed, --frames and --out are required\n";
    usage(std::cerr);
    return 2;
  }
  const auto start = std::chrono::steady_clock::now();
  vp::sim::Simulator simulator;
  std::string why;
  if (!simulator.init(options, &why)) {
    std::cerr << "vp_simulate: " << why << "\n";
    return 1;
  }
  std::cerr << "vp_simulate: " << simulator.summary() << "\n";
  const auto rendering = std::chrono::steady_clock::now();
  if (!simulator.write(&why)) {
    std::cerr << "vp_simulate: " << why << "\n";
    return 1;
  }
  const auto end = std::chrono::steady_clock::now();
  const double setup = std::chrono::duration<double>(rendering - start).count();
  const double render = std::chrono::duration<double>(end - rendering).count();
  std::cerr << "vp_simulate: wrote " << options.frames << " frames to " << options.outDir
            << " (setup " << setup << " s, " << options.frames / render << " frames/s)\n";
  return 0;
}
