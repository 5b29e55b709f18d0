// simulator/renderer: turns the scene, the world and the vehicles of one frame into
// triangles and shades them: the linear-light image of an ideal pinhole camera on a canvas
// that covers the lens's whole ideal field, supersampled (S x S samples per pixel, box
// filtered), with the per-sample depth and triangle (object id) buffers kept for ground truth.
//
// Contract: init() builds the static geometry once per sequence (the ground mesh with its
// procedural texture, buildings, trees) and the static part of the sun's shadow map; render()
// adds the vehicles of the frame (their shadows, the darkening of the ground under them) and
// shades every sample: Lambertian diffuse from the sun (shadow mapped, soft) and the sky
// (hemispherical, ambient occlusion under vehicles), Blinn-Phong highlights and Fresnel sky
// reflections on paint and glass. Output values are scene radiance in arbitrary linear
// units (a white surface in full sun is about 1). Deterministic for any thread count.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ground_texture.hpp"
#include "rasterizer.hpp"
#include "scene.hpp"
#include "traffic.hpp"
#include "world.hpp"

namespace vp::sim {

// Pose of a vehicle in the world: yaw only (heading), standing on the ground at its centre.
struct VehiclePose {
  Eigen::Vector3d originEnu{0, 0, 0};
  double headingRad = 0.0;
  Eigen::Vector3d toWorld(const Eigen::Vector3d& local) const;
};
VehiclePose vehiclePose(const SimVehicle& vehicle, const World& world);

// Canvas geometry: ideal image coordinates (u, v) of the camera (pixel centres at integers)
// map to canvas pixel (u + offsetX, v + offsetY); samples sit at canvas (x + (i + 0.5) / S - 0.5).
struct Canvas {
  int width = 0;
  int height = 0;
  int offsetX = 0;
  int offsetY = 0;
  int supersampling = 2;
};

struct VehicleRange {
  int trackId = 0;
  std::size_t first = 0;  // into Renderer::triangles()
  std::size_t count = 0;
};

class Renderer {
 public:
  // gsdM: ground sampling distance at the view centre; sets the shadow-map and sky-occlusion
  // resolutions (finer than a pixel, no finer than needed).
  void init(const SceneSpec& scene, const World& world, const Eigen::Vector2d& regionMin,
            const Eigen::Vector2d& regionMax, double gsdM, int threads);

  // view: the ideal pinhole on the sample grid of `canvas`. linear: CV_32FC3 (RGB) canvas.
  void render(const std::vector<SimVehicle>& vehicles, const PinholeView& view,
              const Canvas& canvas, cv::Mat& linear);

  const std::vector<RenderTriangle>& triangles() const { return triangles_; }
  const std::vector<RenderSurface>& surfaces() const { return surfaces_; }
  const std::vector<VehicleRange>& vehicleRanges() const { return ranges_; }
  const SampleBuffers& samples() const { return samples_; }
  // Object id of a sample (0: ground or nothing).
  int objectAt(std::size_t sampleIndex) const {
    const std::int32_t t = samples_.triangle[sampleIndex];
    return t < 0 ? 0 : surfaces_[triangles_[static_cast<std::size_t>(t)].surface].objectId;
  }

  // Appends a vehicle's triangles (and its surfaces) to the given lists.
  static void appendVehicle(const VehicleModel& model, const VehiclePose& pose, int objectId,
                            std::vector<RenderTriangle>& triangles,
                            std::vector<RenderSurface>& surfaces);

 private:
  void buildGround(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);
  void buildBuildings();
  void buildTrees();
  void buildOcclusion(const std::vector<SimVehicle>& vehicles);
  float occlusionAt(double x, double y) const;
  Eigen::Vector3f shade(const PinholeView& view, double x, double y, std::size_t index) const;

  const SceneSpec* scene_ = nullptr;
  const World* world_ = nullptr;
  std::optional<GroundTexture> texture_;
  int threads_ = 1;
  std::vector<RenderTriangle> staticTriangles_;
  std::vector<RenderSurface> staticSurfaces_;
  std::vector<RenderTriangle> triangles_;  // this frame: static + vehicles
  std::vector<RenderSurface> surfaces_;
  std::vector<VehicleRange> ranges_;
  ShadowMap staticShadow_;
  ShadowMap shadow_;
  SampleBuffers samples_;
  // Sky occlusion of the ground (1 open, lower under and beside vehicles), 0.1 m cells.
  std::vector<float> occlusion_;
  Eigen::Vector2d occlusionOrigin_{0, 0};
  int occlusionW_ = 0;
  int occlusionH_ = 0;
  double occlusionCellM_ = 0.1;
  std::vector<std::size_t> occlusionTouched_;
};

}  // namespace vp::sim
