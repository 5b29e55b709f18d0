// Per-call costs of the geometry core at the camera's resolution (seed 000: 2592 x 2048).
#include <benchmark/benchmark.h>

#include <cmath>

#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"
#include "camera/undistorter.hpp"
#include "geometry/rotated_box.hpp"
#include "terrain/terrain_model.hpp"

namespace {

vp::camera::CameraModel seedCamera() {
  vp::camera::Distortion d;
  d.model = vp::camera::LensModel::BrownConrady;
  d.k1 = -0.12;
  d.k2 = 0.08;
  d.p1 = 1e-4;
  d.p2 = -2e-4;
  d.k3 = -0.01;
  vp::camera::CameraModel camera;
  camera.init({2592, 2048, 2900.0, 2900.0, 1295.5, 1023.5}, d);
  return camera;
}

void undistortFrame(benchmark::State& state) {
  const vp::camera::CameraModel camera = seedCamera();
  vp::camera::Undistorter undistorter;
  undistorter.init(camera);
  const int type = state.range(0) == 1 ? CV_8UC1 : CV_8UC3;
  const cv::Mat src(2048, 2592, type, cv::Scalar::all(80));
  cv::Mat dst(undistorter.outputSize(), type);
  for (auto _ : state) {
    undistorter.apply(src, dst);
    benchmark::DoNotOptimize(dst.data);
  }
}
BENCHMARK(undistortFrame)->Arg(1)->Arg(3)->Unit(benchmark::kMillisecond);

void pixelToRay(benchmark::State& state) {
  const vp::camera::CameraModel camera = seedCamera();
  double u = 0.0;
  for (auto _ : state) {
    u = u > 2590.0 ? 0.0 : u + 7.3;
    benchmark::DoNotOptimize(camera.pixelToRay({u, 0.4 * u}));
  }
}
BENCHMARK(pixelToRay);

void rotatedIou(benchmark::State& state) {
  const vp::geometry::RotatedBox a{100.0, 100.0, 130.0, 52.0, 0.3};
  vp::geometry::RotatedBox b{110.0, 95.0, 125.0, 50.0, 0.5};
  for (auto _ : state) {
    b.angle += 1e-3;
    benchmark::DoNotOptimize(vp::geometry::rotatedIou(a, b));
  }
}
BENCHMARK(rotatedIou);

// One viewing ray from 100 m onto a gently undulating 5 m DTM, 20 deg off nadir.
void terrainRay(benchmark::State& state) {
  const vp::geodesy::GeodeticPoint origin{43.0731, -89.4012, 260.0};
  const vp::geodesy::LocalFrame frame(origin);
  const vp::geodesy::UtmPoint centre = vp::geodesy::toUtm(origin);
  vp::terrain::TerrainGrid grid;
  grid.cols = grid.rows = 161;
  grid.crs = {vp::terrain::HorizontalCrs::Utm, centre.zone, centre.northp};
  grid.transform = {centre.easting_m - 400.0, 5.0, 0.0, centre.northing_m + 400.0, 0.0, -5.0};
  grid.heights_m.resize(161 * 161);
  for (int r = 0; r < 161; ++r) {
    for (int c = 0; c < 161; ++c) {
      grid.heights_m[static_cast<std::size_t>(r * 161 + c)] =
          static_cast<float>(260.0 + 3.0 * std::sin(c / 9.0) * std::cos(r / 7.0));
    }
  }
  vp::terrain::TerrainModel terrain;
  terrain.init(std::move(grid), frame);
  const Eigen::Vector3d camera(0.0, 0.0, 100.0);
  double azimuth = 0.0;
  for (auto _ : state) {
    azimuth += 0.37;
    const Eigen::Vector3d dir(0.34 * std::cos(azimuth), 0.34 * std::sin(azimuth), -0.94);
    benchmark::DoNotOptimize(terrain.intersectRay(camera, dir));
  }
}
BENCHMARK(terrainRay);

}  // namespace
