// simulator/renderer: turns the scene, the world and the vehicles of one frame into
// triangles and shades them: the linear-light image of an ideal pinhole camera on a canvas
// that covers the lens's whole ideal field, supersampled (S x S samples per pixel, box
// filtered), with the per-sample depth and triangle (object id) buffers kept for ground truth.
//
// Contract: init() builds the static geometry once per sequence (the ground mesh with its
// procedural texture, buildings with their roof fixtures, trees, street furniture), the static
// part of the sun's shadow map and the ground cache (texture and static shadow, filled as
// frames first see the ground); render() adds the vehicles of the frame (their shadows, the
// darkening of the ground under them) and shades every sample: Lambertian diffuse from the sun
// (shadow mapped, soft) and the sky (hemispherical, ambient occlusion under vehicles),
// Blinn-Phong highlights and Fresnel sky reflections on paint and glass. Output values are
// scene radiance in arbitrary linear units (a white surface in full sun is about 1).
// Deterministic for any thread count.
#pragma once

#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ground_cache.hpp"
#include "ground_texture.hpp"
#include "rasterizer.hpp"
#include "scene.hpp"
#include "traffic.hpp"
#include "world.hpp"

namespace vp::sim {

// Pose of a vehicle in the world: yaw only (heading), standing on the ground at its centre.
struct VehiclePose {
  Eigen::Vector3d originEnu{0, 0, 0};
  double heading_rad = 0.0;
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
  // gsd_m: ground sampling distance (of a pixel) at the view centre; sets the shadow-map,
  // sky-occlusion and ground-cache resolutions (finer than a pixel, no finer than needed);
  // supersampling: samples per pixel and side.
  void init(const SceneSpec& scene, const World& world, const Eigen::Vector2d& regionMin,
            const Eigen::Vector2d& regionMax, double gsd_m, int supersampling, int threads);

  // view: the ideal pinhole on the sample grid of `canvas`. linear: CV_32FC3 (RGB) canvas.
  void render(const std::vector<SimVehicle>& vehicles, const PinholeView& view,
              const Canvas& canvas, cv::Mat& linear);

  // Canvas pixels to shade (1; others are set to 0): see Sensor::neededCanvas. Empty: all.
  void setCanvasMask(std::vector<std::uint8_t> mask) { canvasMask_ = std::move(mask); }

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
  // A building's HVAC units, skylights, dormers and solar panels (roof_mesh.cpp); z1: eaves
  // (flat roof) height, roof/unit: the building's roof and rooftop-unit surfaces.
  void buildRoofFixtures(const Building& b, int objectId, double z1, std::uint32_t roof,
                         std::uint32_t unit);
  // Benches, shelters, kiosks, stair entrances (furniture_mesh.cpp): object ids -3000 - index.
  void buildFurniture();
  void buildOcclusion(const std::vector<SimVehicle>& vehicles);
  float occlusionAt(double x, double y) const;
  // Colour of the surface point seen at sample coordinates (x, y) on triangle ti (-1: none)
  // at inverse depth invDepth.
  Eigen::Vector3f shade(const PinholeView& view, double x, double y, std::int32_t ti,
                        float invDepth) const;
  // Surfaces without texture detail below a pixel (shaded once per pixel when a pixel lies
  // wholly on one).
  bool smoothSurface(std::uint32_t surface) const;
  // Colour of canvas pixel (x, y) whose samples all show the ground.
  // previous: the ground point of the last ground pixel of this row (for prefetching).
  Eigen::Vector3f shadeGroundPixel(const PinholeView& view, int x, int y, int ss,
                                   Eigen::Vector2d* previous) const;

  const SceneSpec* scene_ = nullptr;
  const World* world_ = nullptr;
  std::optional<GroundTexture> texture_;
  HeightGrid heights_;
  // Albedo and static sun visibility of the ground, filled on first sight, kept for the
  // sequence (the ground does not move; only vehicles do).
  GroundCache groundCache_;
  int threads_ = 1;
  std::vector<RenderTriangle> staticTriangles_;
  std::size_t groundTriangles_ = 0;             // the first ones of staticTriangles_
  std::vector<Eigen::Vector3f> groundNormals_;  // per ground triangle
  std::vector<std::uint8_t> canvasMask_;
  // This frame's viewing ray (z = 1) of sample (x, y): ray0_ + x rayDx_ + y rayDy_.
  Eigen::Vector3d ray0_{0, 0, 1};
  Eigen::Vector3d rayDx_{0, 0, 0};
  Eigen::Vector3d rayDy_{0, 0, 0};
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
