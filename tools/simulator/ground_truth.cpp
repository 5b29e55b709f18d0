#include "ground_truth.hpp"

#include <algorithm>
#include <cmath>

namespace vp::sim {

namespace {
constexpr double kKeypointDepthTolerance_m = 0.15;
}

bool imageBox(const SimVehicle& vehicle, const GroundTruthContext& ctx, geometry::RotatedBox* box) {
  const VehiclePose pose = vehiclePose(vehicle, *ctx.world);
  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(vehicle.model->vertices.size());
  for (const Eigen::Vector3d& v : vehicle.model->vertices) {
    vertices.push_back(pose.toWorld(v));
  }
  const auto enclosing = ctx.lifter->enclosingImageBox(ctx.pose, pose.originEnu,
                                                       pose.toWorld({1.0, 0.0, 0.0}), vertices);
  if (!enclosing) {
    return false;
  }
  *box = *enclosing;
  return true;
}

void computeGroundTruth(std::int64_t frameId, const std::vector<SimVehicle>& vehicles,
                        const GroundTruthContext& ctx, std::vector<sequence::ObjectTruth>& objects,
                        std::vector<sequence::KeypointTruth>& keypoints) {
  const Renderer& renderer = *ctx.renderer;
  const SampleBuffers& samples = renderer.samples();
  const Canvas& canvas = ctx.sensor->canvas();
  const int ss = canvas.supersampling;
  std::vector<std::uint8_t> scratch;
  for (std::size_t i = 0; i < vehicles.size(); ++i) {
    const SimVehicle& v = vehicles[i];
    const VehicleRange& range = renderer.vehicleRanges()[i];
    long total = 0;
    long inside = 0;
    long visible = 0;
    rasterizeSilhouette(renderer.triangles(), range.first, range.count, ctx.view, scratch,
                        [&](int sx, int sy) {
                          ++total;
                          // Canvas pixel holding this sample.
                          const int cx = static_cast<int>(std::floor(static_cast<double>(sx) / ss));
                          const int cy = static_cast<int>(std::floor(static_cast<double>(sy) / ss));
                          if (!ctx.sensor->canvasInImage(cx, cy)) {
                            return;
                          }
                          ++inside;
                          if (sx >= 0 && sy >= 0 && sx < samples.width && sy < samples.height &&
                              renderer.objectAt(static_cast<std::size_t>(sy) *
                                                    static_cast<std::size_t>(samples.width) +
                                                static_cast<std::size_t>(sx)) == v.trackId) {
                            ++visible;
                          }
                        });
    if (inside == 0) {
      continue;
    }
    sequence::ObjectTruth o;
    if (!imageBox(v, ctx, &o.imageBox)) {
      continue;
    }
    const VehiclePose pose = vehiclePose(v, *ctx.world);
    o.frameId = frameId;
    o.trackId = v.trackId;
    o.type = v.model->type;
    o.shape = v.model->hasKeypoints ? v.model->gamma : shape::ShapeParams{};
    o.dimensions_m = v.model->dimensions_m;
    o.positionEnu = pose.originEnu;
    o.headingEnu_rad = geometry::wrapTwoPi(v.rear.psi);
    o.speed_mps = v.speed_mps;
    o.yawRate_radps = v.yawRate_radps;
    o.truncation = 1.0 - static_cast<double>(inside) / static_cast<double>(total);
    o.occlusion = 1.0 - static_cast<double>(visible) / static_cast<double>(inside);
    o.parked = v.parked;
    objects.push_back(o);
    if (!v.model->hasKeypoints) {
      continue;
    }
    for (int k = 0; k < shape::kKeypointCount; ++k) {
      sequence::KeypointTruth kp;
      kp.frameId = frameId;
      kp.trackId = v.trackId;
      kp.keypoint = k;
      kp.worldEnu = pose.toWorld(v.model->vertices[static_cast<std::size_t>(k)]);
      const auto pixel = ctx.lifter->worldToPixel(ctx.pose, kp.worldEnu);
      if (!pixel) {
        continue;
      }
      kp.pixel = *pixel;
      if (ctx.camera->inImage(kp.pixel)) {
        const Eigen::Vector3d c = ctx.view.worldToCamera * (kp.worldEnu - ctx.view.centre);
        const double sx = ctx.view.fx * c.x() / c.z() + ctx.view.cx;
        const double sy = ctx.view.fy * c.y() / c.z() + ctx.view.cy;
        const int x0 = static_cast<int>(std::floor(sx));
        const int y0 = static_cast<int>(std::floor(sy));
        for (int dy = 0; dy <= 1 && !kp.visible; ++dy) {
          for (int dx = 0; dx <= 1 && !kp.visible; ++dx) {
            const int x = x0 + dx;
            const int y = y0 + dy;
            if (x < 0 || y < 0 || x >= samples.width || y >= samples.height) {
              continue;
            }
            const std::size_t idx =
                static_cast<std::size_t>(y) * static_cast<std::size_t>(samples.width) +
                static_cast<std::size_t>(x);
            if (renderer.objectAt(idx) == v.trackId &&
                std::fabs(1.0 / static_cast<double>(samples.invDepth[idx]) - c.z()) <
                    kKeypointDepthTolerance_m) {
              kp.visible = true;
            }
          }
        }
      }
      if (kp.visible && ctx.ids != nullptr) {
        bool onCar = false;
        const int u0 = static_cast<int>(std::floor(kp.pixel.x()));
        const int v0 = static_cast<int>(std::floor(kp.pixel.y()));
        for (int dv = 0; dv <= 1; ++dv) {
          for (int du = 0; du <= 1; ++du) {
            const int u = u0 + du;
            const int vv = v0 + dv;
            onCar = onCar || (u >= 0 && vv >= 0 && u < ctx.ids->cols && vv < ctx.ids->rows &&
                              ctx.ids->at<std::int32_t>(vv, u) == v.trackId);
          }
        }
        kp.visible = onCar;
      }
      keypoints.push_back(kp);
    }
  }
}

}  // namespace vp::sim
