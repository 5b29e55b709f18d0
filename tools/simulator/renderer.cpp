#include "renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <thread>

#include "mesh_build.hpp"
#include "noise.hpp"

namespace vp::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kOcclusionCell_m = 0.1;  // finest sky-occlusion cell

// Unit icosphere (two subdivisions): 162 vertices, 320 faces.
void icosphere(std::vector<Eigen::Vector3d>& v, std::vector<std::array<int, 3>>& f) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) {
    p.normalize();
  }
  f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
       {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
       {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < 2; ++level) {
    std::vector<std::array<int, 3>> next;
    std::vector<std::pair<std::pair<int, int>, int>> cache;
    const auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      for (const auto& [k, i] : cache) {
        if (k == key) {
          return i;
        }
      }
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      const int i = static_cast<int>(v.size()) - 1;
      cache.emplace_back(key, i);
      return i;
    };
    for (const auto& tri : f) {
      const int a = mid(tri[0], tri[1]);
      const int b = mid(tri[1], tri[2]);
      const int c = mid(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
}

float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0F, 1.0F);
  return t * t * (3.0F - 2.0F * t);
}

// Corner normals interpolated at p (barycentric weights of p's projection on the triangle).
Eigen::Vector3f smoothNormal(const RenderTriangle& tri, const Eigen::Vector3f& p) {
  const Eigen::Vector3f v0 = tri.p[1] - tri.p[0];
  const Eigen::Vector3f v1 = tri.p[2] - tri.p[0];
  const Eigen::Vector3f v2 = p - tri.p[0];
  const float d00 = v0.dot(v0);
  const float d01 = v0.dot(v1);
  const float d11 = v1.dot(v1);
  const float d20 = v2.dot(v0);
  const float d21 = v2.dot(v1);
  const float den = d00 * d11 - d01 * d01;
  float b1 = den != 0.0F ? (d11 * d20 - d01 * d21) / den : 0.0F;
  float b2 = den != 0.0F ? (d00 * d21 - d01 * d20) / den : 0.0F;
  b1 = std::clamp(b1, 0.0F, 1.0F);
  b2 = std::clamp(b2, 0.0F, 1.0F - b1);
  Eigen::Vector3f normal = (1.0F - b1 - b2) * tri.n[0] + b1 * tri.n[1] + b2 * tri.n[2];
  normal.normalize();
  return normal;
}

}  // namespace

Eigen::Vector3d VehiclePose::toWorld(const Eigen::Vector3d& local) const {
  const double c = std::cos(heading_rad);
  const double s = std::sin(heading_rad);
  return originEnu +
         Eigen::Vector3d(c * local.x() - s * local.y(), s * local.x() + c * local.y(), local.z());
}

VehiclePose vehiclePose(const SimVehicle& vehicle, const World& world) {
  VehiclePose pose;
  const Eigen::Vector2d c = vehicle.centre();
  pose.originEnu = world.ground(c.x(), c.y());
  pose.heading_rad = vehicle.rear.psi;
  return pose;
}

void Renderer::appendVehicle(const VehicleModel& model, const VehiclePose& pose, int objectId,
                             std::vector<RenderTriangle>& triangles,
                             std::vector<RenderSurface>& surfaces) {
  const auto base = static_cast<std::uint32_t>(surfaces.size());
  const auto surface = [&](Material m, Eigen::Vector3f albedo, float spec, float shininess) {
    RenderSurface s;
    s.material = m;
    s.albedo = albedo;
    s.specular = spec;
    s.shininess = shininess;
    s.objectId = objectId;
    surfaces.push_back(s);
  };
  // Slots follow the Material enum from Paint to RoofPaint.
  surface(Material::Paint, model.look.paint, 0.25F + 0.5F * model.look.metallic, 60.0F);
  surface(Material::Glass, model.look.glassTint, 0.9F, 150.0F);
  surface(Material::Tyre, {0.03F, 0.03F, 0.03F}, 0.05F, 10.0F);
  surface(Material::Rim, {0.35F, 0.35F, 0.36F}, 0.5F, 40.0F);
  surface(Material::HeadLight, {0.6F, 0.6F, 0.58F}, 0.8F, 80.0F);
  surface(Material::TailLight, {0.45F, 0.03F, 0.03F}, 0.5F, 60.0F);
  surface(Material::Underbody, {0.025F, 0.025F, 0.025F}, 0.0F, 10.0F);
  surface(Material::RoofPaint, model.look.twoTone ? model.look.roofPaint : model.look.paint,
          0.25F + 0.5F * model.look.metallic, 60.0F);
  const double c = std::cos(pose.heading_rad);
  const double s = std::sin(pose.heading_rad);
  const auto rotate = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector3d(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
  };
  for (std::size_t t = 0; t < model.triangles.size(); ++t) {
    const VehicleTriangle& vt = model.triangles[t];
    RenderTriangle rt;
    for (std::size_t k = 0; k < 3; ++k) {
      rt.p[k] = pose.toWorld(model.vertices[vt.v[k]]).cast<float>();
      rt.n[k] = rotate(model.normals[3 * t + k]).cast<float>();
    }
    rt.surface = base + static_cast<std::uint32_t>(static_cast<int>(vt.material) -
                                                   static_cast<int>(Material::Paint));
    triangles.push_back(rt);
  }
}

void Renderer::init(const SceneSpec& scene, const World& world, const Eigen::Vector2d& regionMin,
                    const Eigen::Vector2d& regionMax, double gsd_m, int supersampling,
                    int threads) {
  scene_ = &scene;
  world_ = &world;
  texture_.emplace(scene);
  threads_ = threads;
  staticTriangles_.clear();
  staticSurfaces_.clear();
  buildGround(regionMin, regionMax);
  groundTriangles_ = staticTriangles_.size();
  groundNormals_.clear();
  for (const RenderTriangle& t : staticTriangles_) {
    groundNormals_.push_back((t.n[0] + t.n[1] + t.n[2]).normalized());
  }
  buildBuildings();
  buildTrees();
  buildFurniture();
  double zMin = 1e9;
  double zMax = -1e9;
  for (const RenderTriangle& t : staticTriangles_) {
    for (const auto& p : t.p) {
      zMin = std::min(zMin, static_cast<double>(p.z()));
      zMax = std::max(zMax, static_cast<double>(p.z()));
    }
  }
  staticShadow_.init(scene.light.sunDirectionEnu, {regionMin.x(), regionMin.y(), zMin},
                     {regionMax.x(), regionMax.y(), zMax + 5.0}, std::max(0.03, 0.8 * gsd_m), 6000);
  for (const RenderTriangle& t : staticTriangles_) {
    const RenderSurface& s = staticSurfaces_[t.surface];
    if (s.material != Material::Ground) {
      staticShadow_.add(t, s);
    }
  }
  staticShadow_.finishStatic();
  shadow_ = staticShadow_;
  // Finest ground texel: a sample's footprint at the view centre (nadir views see about that
  // footprint everywhere), so the texture keeps the samples' detail.
  groundCache_.init(*texture_, staticShadow_, scene.light.shadowSoftnessTexels, heights_, regionMin,
                    regionMax, gsd_m / std::max(1, supersampling));
  occlusionOrigin_ = regionMin;
  occlusionCellM_ = std::max(kOcclusionCell_m, gsd_m);
  occlusionW_ = static_cast<int>(std::ceil((regionMax.x() - regionMin.x()) / occlusionCellM_)) + 1;
  occlusionH_ = static_cast<int>(std::ceil((regionMax.y() - regionMin.y()) / occlusionCellM_)) + 1;
  occlusion_.assign(static_cast<std::size_t>(occlusionW_) * static_cast<std::size_t>(occlusionH_),
                    1.0F);
}

void Renderer::buildGround(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  RenderSurface ground;
  ground.material = Material::Ground;
  staticSurfaces_.push_back(ground);
  const double extent = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  const double cell = extent > 320.0 ? 2.0 : 1.0;
  const int nx = static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)) + 1;
  const int ny = static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)) + 1;
  std::vector<Eigen::Vector3d> v(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  heights_.origin = lo;
  heights_.cell_m = cell;
  heights_.nx = nx;
  heights_.ny = ny;
  heights_.z.resize(v.size());
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const std::size_t k =
          static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
      v[k] = world_->ground(lo.x() + i * cell, lo.y() + j * cell);
      // As the triangles store it (float), so the cache sits on the rasterized surface.
      heights_.z[k] = static_cast<double>(static_cast<float>(v[k].z()));
    }
  }
  const auto at = [&](int i, int j) -> const Eigen::Vector3d& {
    return v[static_cast<std::size_t>(std::clamp(j, 0, ny - 1)) * static_cast<std::size_t>(nx) +
             static_cast<std::size_t>(std::clamp(i, 0, nx - 1))];
  };
  const auto normal = [&](int i, int j) {
    const double dzdx =
        (at(i + 1, j).z() - at(i - 1, j).z()) / (at(i + 1, j).x() - at(i - 1, j).x() + 1e-9);
    const double dzdy =
        (at(i, j + 1).z() - at(i, j - 1).z()) / (at(i, j + 1).y() - at(i, j - 1).y() + 1e-9);
    return Eigen::Vector3d(-dzdx, -dzdy, 1.0).normalized().cast<float>().eval();
  };
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      RenderTriangle a;
      a.p = {at(i, j).cast<float>(), at(i + 1, j).cast<float>(), at(i + 1, j + 1).cast<float>()};
      a.n = {normal(i, j), normal(i + 1, j), normal(i + 1, j + 1)};
      a.surface = 0;
      RenderTriangle b;
      b.p = {at(i, j).cast<float>(), at(i + 1, j + 1).cast<float>(), at(i, j + 1).cast<float>()};
      b.n = {normal(i, j), normal(i + 1, j + 1), normal(i, j + 1)};
      b.surface = 0;
      staticTriangles_.push_back(a);
      staticTriangles_.push_back(b);
    }
  }
}

void Renderer::buildBuildings() {
  for (std::size_t bi = 0; bi < scene_->buildings.size(); ++bi) {
    const Building& b = scene_->buildings[bi];
    const Eigen::Vector2d f(std::cos(b.heading_rad), std::sin(b.heading_rad));
    const Eigen::Vector2d n(-f.y(), f.x());
    double gMin = 1e9;
    double gMax = -1e9;
    for (int i = -1; i <= 1; ++i) {
      for (int j = -1; j <= 1; ++j) {
        const Eigen::Vector2d p = b.centre + 0.5 * i * b.length_m * f + 0.5 * j * b.width_m * n;
        const double z = world_->groundZ(p.x(), p.y());
        gMin = std::min(gMin, z);
        gMax = std::max(gMax, z);
      }
    }
    const int id = -1000 - static_cast<int>(bi);
    const auto base = static_cast<std::uint32_t>(staticSurfaces_.size());
    RenderSurface wall;
    wall.material = Material::Wall;
    wall.albedo = b.wallAlbedo;
    wall.objectId = id;
    wall.seed = b.seed;
    wall.param = static_cast<float>(gMax);
    RenderSurface roof;
    roof.material = Material::Roof;
    roof.albedo = b.roofAlbedo;
    roof.objectId = id;
    roof.seed = b.seed + 1U;
    roof.specular = 0.05F;
    RenderSurface unit;
    unit.material = Material::RoofUnit;
    unit.albedo = Eigen::Vector3f(0.45F, 0.46F, 0.47F) * (0.7F + 0.6F * hashToUnit(b.seed));
    unit.objectId = id;
    unit.specular = 0.2F;
    // Walls: one surface per facade so windows follow its direction.
    const double z0 = gMin - 0.3;
    const double z1 = gMax + b.height_m;
    const double hl = 0.5 * b.length_m;
    const double hw = 0.5 * b.width_m;
    std::array<Eigen::Vector2d, 4> k = {b.centre + hl * f + hw * n, b.centre - hl * f + hw * n,
                                        b.centre - hl * f - hw * n, b.centre + hl * f - hw * n};
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector2d& a = k[static_cast<std::size_t>(i)];
      const Eigen::Vector2d& c = k[static_cast<std::size_t>((i + 1) % 4)];
      RenderSurface facade = wall;
      facade.axis = Eigen::Vector3d((c - a).x(), (c - a).y(), 0.0).normalized().cast<float>();
      staticSurfaces_.push_back(facade);
      addQuad(staticTriangles_, {a.x(), a.y(), z0}, {c.x(), c.y(), z0}, {c.x(), c.y(), z1},
              {a.x(), a.y(), z1}, base + static_cast<std::uint32_t>(i));
    }
    staticSurfaces_.push_back(roof);
    staticSurfaces_.push_back(unit);
    const std::uint32_t roofIndex = base + 4;
    const std::uint32_t unitIndex = base + 5;
    if (b.roof == RoofKind::Flat) {
      addQuad(staticTriangles_, {k[0].x(), k[0].y(), z1}, {k[1].x(), k[1].y(), z1},
              {k[2].x(), k[2].y(), z1}, {k[3].x(), k[3].y(), z1}, roofIndex);
    } else {
      // Gabled: ridge along the length axis, eaves overhanging by 0.35 m.
      const double o = 0.35;
      const double zr = z1 + b.ridgeHeight_m;
      const Eigen::Vector2d r0 = b.centre + (hl + o) * f;
      const Eigen::Vector2d r1 = b.centre - (hl + o) * f;
      const double drop = b.ridgeHeight_m * o / hw;
      for (const double side : {1.0, -1.0}) {
        const Eigen::Vector2d e0 = r0 + side * (hw + o) * n;
        const Eigen::Vector2d e1 = r1 + side * (hw + o) * n;
        addQuad(staticTriangles_, {e0.x(), e0.y(), z1 - drop}, {r0.x(), r0.y(), zr},
                {r1.x(), r1.y(), zr}, {e1.x(), e1.y(), z1 - drop}, roofIndex);
      }
      for (const double end : {1.0, -1.0}) {
        const Eigen::Vector2d m = b.centre + end * hl * f;
        const Eigen::Vector2d l = m + hw * n;
        const Eigen::Vector2d r = m - hw * n;
        staticTriangles_.push_back(flatTriangle({l.x(), l.y(), z1}, {r.x(), r.y(), z1},
                                                {m.x(), m.y(), zr}, base + (end > 0 ? 3U : 1U)));
      }
    }
    buildRoofFixtures(b, id, z1, roofIndex, unitIndex);
  }
}

void Renderer::buildTrees() {
  std::vector<Eigen::Vector3d> sphere;
  std::vector<std::array<int, 3>> faces;
  icosphere(sphere, faces);
  for (std::size_t ti = 0; ti < scene_->trees.size(); ++ti) {
    const Tree& tree = scene_->trees[ti];
    const int id = -2000 - static_cast<int>(ti);
    const auto base = static_cast<std::uint32_t>(staticSurfaces_.size());
    RenderSurface canopy;
    canopy.material = Material::Canopy;
    canopy.albedo = tree.leafAlbedo;
    canopy.objectId = id;
    canopy.seed = tree.seed;
    canopy.param = tree.gapFraction;
    canopy.specular = 0.03F;
    RenderSurface trunk;
    trunk.material = Material::Trunk;
    trunk.albedo = Eigen::Vector3f(0.12F, 0.1F, 0.08F);
    trunk.objectId = id;
    staticSurfaces_.push_back(canopy);
    staticSurfaces_.push_back(trunk);
    const double gz = world_->groundZ(tree.position.x(), tree.position.y());
    const Eigen::Vector3d centre(tree.position.x(), tree.position.y(),
                                 gz + tree.canopyCentreHeight_m);
    std::vector<Eigen::Vector3d> pts(sphere.size());
    for (std::size_t i = 0; i < sphere.size(); ++i) {
      const Eigen::Vector3d& s = sphere[i];
      const float lump =
          valueNoise3(static_cast<float>(s.x() * 1.6 + 3.0), static_cast<float>(s.y() * 1.6),
                      static_cast<float>(s.z() * 1.6), tree.seed + 9U);
      const float lump2 =
          valueNoise3(static_cast<float>(s.x() * 4.0), static_cast<float>(s.y() * 4.0 + 7.0),
                      static_cast<float>(s.z() * 4.0), tree.seed + 10U);
      const double r =
          1.0 + 0.45 * (static_cast<double>(lump) - 0.5) + 0.2 * (static_cast<double>(lump2) - 0.5);
      pts[i] =
          centre + Eigen::Vector3d(s.x() * tree.canopyRadius_m * r, s.y() * tree.canopyRadius_m * r,
                                   s.z() * tree.canopyVerticalRadius_m * r);
    }
    // Upper faces first: seen from above, they fill the z-buffer before the lower ones, whose
    // samples then fail the depth test before the (costly) foliage alpha test.
    std::vector<std::array<int, 3>> ordered = faces;
    std::stable_sort(ordered.begin(), ordered.end(), [&](const auto& a, const auto& b) {
      const auto z = [&](const std::array<int, 3>& f) {
        return pts[static_cast<std::size_t>(f[0])].z() + pts[static_cast<std::size_t>(f[1])].z() +
               pts[static_cast<std::size_t>(f[2])].z();
      };
      return z(a) > z(b);
    });
    for (const auto& f : ordered) {
      RenderTriangle t;
      for (std::size_t k = 0; k < 3; ++k) {
        t.p[k] = pts[static_cast<std::size_t>(f[k])].cast<float>();
        t.n[k] = sphere[static_cast<std::size_t>(f[k])].cast<float>();
      }
      t.surface = base;
      staticTriangles_.push_back(t);
    }
    // Trunk: a hexagonal prism up into the crown.
    for (int i = 0; i < 6; ++i) {
      const double a0 = 2.0 * kPi * i / 6.0;
      const double a1 = 2.0 * kPi * (i + 1) / 6.0;
      const Eigen::Vector3d p0(tree.position.x() + tree.trunkRadius_m * std::cos(a0),
                               tree.position.y() + tree.trunkRadius_m * std::sin(a0), gz - 0.2);
      const Eigen::Vector3d p1(tree.position.x() + tree.trunkRadius_m * std::cos(a1),
                               tree.position.y() + tree.trunkRadius_m * std::sin(a1), gz - 0.2);
      const Eigen::Vector3d up(0, 0, tree.canopyCentreHeight_m + 0.2);
      addQuad(staticTriangles_, p0, p1, p1 + up, p0 + up, base + 1U);
    }
  }
}

void Renderer::buildOcclusion(const std::vector<SimVehicle>& vehicles) {
  for (const std::size_t i : occlusionTouched_) {
    occlusion_[i] = 1.0F;
  }
  occlusionTouched_.clear();
  for (const SimVehicle& v : vehicles) {
    const Eigen::Vector2d c = v.centre();
    const Eigen::Vector2d f(std::cos(v.rear.psi), std::sin(v.rear.psi));
    const double halfL = 0.5 * (v.model->frontXM - v.model->rearXM);
    const double mid = 0.5 * (v.model->frontXM + v.model->rearXM);
    const double halfW = v.model->halfWidth_m;
    const Eigen::Vector2d centre = c + mid * f;
    const double reach = halfL + 1.0;
    const int i0 =
        static_cast<int>(std::floor((centre.x() - reach - occlusionOrigin_.x()) / occlusionCellM_));
    const int i1 =
        static_cast<int>(std::ceil((centre.x() + reach - occlusionOrigin_.x()) / occlusionCellM_));
    const int j0 =
        static_cast<int>(std::floor((centre.y() - reach - occlusionOrigin_.y()) / occlusionCellM_));
    const int j1 =
        static_cast<int>(std::ceil((centre.y() + reach - occlusionOrigin_.y()) / occlusionCellM_));
    for (int j = std::max(0, j0); j <= std::min(occlusionH_ - 1, j1); ++j) {
      for (int i = std::max(0, i0); i <= std::min(occlusionW_ - 1, i1); ++i) {
        const Eigen::Vector2d p =
            occlusionOrigin_ + Eigen::Vector2d(i, j) * occlusionCellM_ - centre;
        const double qx = std::fabs(p.dot(f)) - halfL;
        const double qy = std::fabs(-p.x() * f.y() + p.y() * f.x()) - halfW;
        const double d =
            std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
        const float ao = d < 0.0 ? 0.5F - 0.35F * smoothstep(0.0F, 0.6F, static_cast<float>(-d))
                                 : 0.5F + 0.5F * smoothstep(0.0F, 0.9F, static_cast<float>(d));
        const std::size_t idx =
            static_cast<std::size_t>(j) * static_cast<std::size_t>(occlusionW_) +
            static_cast<std::size_t>(i);
        if (ao < occlusion_[idx]) {
          if (occlusion_[idx] == 1.0F) {
            occlusionTouched_.push_back(idx);
          }
          occlusion_[idx] = ao;
        }
      }
    }
  }
}

float Renderer::occlusionAt(double x, double y) const {
  // Nearest cell (floor of + 0.5: lround is a library call, and this runs per pixel).
  const int i = static_cast<int>(std::floor((x - occlusionOrigin_.x()) / occlusionCellM_ + 0.5));
  const int j = static_cast<int>(std::floor((y - occlusionOrigin_.y()) / occlusionCellM_ + 0.5));
  if (i < 0 || j < 0 || i >= occlusionW_ || j >= occlusionH_) {
    return 1.0F;
  }
  return occlusion_[static_cast<std::size_t>(j) * static_cast<std::size_t>(occlusionW_) +
                    static_cast<std::size_t>(i)];
}

Eigen::Vector3f Renderer::shade(const PinholeView& view, double x, double y, std::int32_t ti,
                                float invDepth) const {
  const Lighting& light = scene_->light;
  if (ti < 0) {
    return scene_->style.grassA;
  }
  const RenderTriangle& tri = triangles_[static_cast<std::size_t>(ti)];
  const RenderSurface& s = surfaces_[tri.surface];
  const Eigen::Vector3d pd = view.unproject(x, y, 1.0 / static_cast<double>(invDepth));
  const Eigen::Vector3f p = pd.cast<float>();
  Eigen::Vector3f normal = smoothNormal(tri, p);
  const Eigen::Vector3d toCameraD = view.centre - pd;
  const double distance = toCameraD.norm();
  const Eigen::Vector3f toCamera = (toCameraD / distance).cast<float>();
  if (normal.dot(toCamera) < 0.0F) {
    normal = -normal;
  }
  const Eigen::Vector3f sun = light.sunDirectionEnu.cast<float>();
  Eigen::Vector3f albedo = s.albedo;
  float specular = s.specular;
  float shininess = s.shininess;
  float skyOcclusion = 1.0F;
  float reflect = 0.0F;
  float staticSun = -1.0F;  // ground: the cached visibility past static casters
  switch (s.material) {
    case Material::Ground: {
      // Ground area the sample covers: (z / f)^2 on the image plane, stretched by the ray's
      // obliquity to the image plane (z / distance) and to the ground (cos incidence).
      const double z = 1.0 / static_cast<double>(invDepth);
      const double footprint = z * z / (view.fx * view.fy) * (z / distance) /
                               static_cast<double>(std::max(0.05F, normal.dot(toCamera)));
      const GroundSample g = groundCache_.sample(pd.x(), pd.y(), groundCache_.level(footprint));
      albedo = g.albedo;
      staticSun = g.sunVisibility;
      skyOcclusion = occlusionAt(pd.x(), pd.y());
      break;
    }
    case Material::Wall: {
      const double along = p.dot(s.axis);
      const double h = p.z() - s.param;
      const double floorH = 3.3;
      const double bay = 3.0 + 0.6 * static_cast<double>(hashToUnit(s.seed));
      const double fa = along / bay - std::floor(along / bay);
      const double fh = h / floorH - std::floor(h / floorH);
      if (h > 0.8 && fa > 0.25 && fa < 0.75 && fh > 0.3 && fh < 0.75) {
        albedo = Eigen::Vector3f(0.05F, 0.06F, 0.07F);
        specular = 0.6F;
        shininess = 100.0F;
        reflect = 0.3F;
      }
      albedo *= 0.9F + 0.2F * valueNoise(p.x() / 0.5F + p.y() / 0.5F, p.z() / 0.5F, s.seed);
      break;
    }
    case Material::Roof:
      albedo *= 0.8F + 0.25F * fbm(p.x() / 1.5F, p.y() / 1.5F, 3, s.seed) +
                0.15F * latticeValue(static_cast<int>(std::floor(p.x() / 0.04F)),
                                     static_cast<int>(std::floor(p.y() / 0.04F)), s.seed + 1U);
      break;
    case Material::Canopy: {
      // Clumps of foliage: a bumped normal gives sunlit tops and dark crevices.
      const float f = 1.3F;
      const Eigen::Vector3f bump(
          valueNoise3(p.x() * f, p.y() * f, p.z() * f, s.seed + 5U) - 0.5F,
          valueNoise3(p.x() * f + 9.1F, p.y() * f, p.z() * f, s.seed + 7U) - 0.5F,
          valueNoise3(p.x() * f, p.y() * f + 4.7F, p.z() * f, s.seed + 8U) - 0.5F);
      normal = (normal + 1.6F * bump).normalized();
      const float leaf = valueNoise3(p.x() * 9.0F, p.y() * 9.0F, p.z() * 9.0F, s.seed + 6U);
      albedo *= 0.7F + 0.6F * leaf;
      break;
    }
    case Material::Stairs: {
      // Steps going down along the axis from param: a light nosing per 0.3 m tread, darker
      // (less sky, no sun past the walls) the deeper they are.
      const float t = std::max(0.0F, p.x() * s.axis.x() + p.y() * s.axis.y() - s.param);
      const float tread = t / 0.3F - std::floor(t / 0.3F);
      const float depth = std::max(0.1F, std::exp(-t / 1.8F));
      albedo *= (tread < 0.12F ? 1.5F : 1.0F) * depth;
      skyOcclusion = std::max(0.2F, depth);
      break;
    }
    case Material::SolarPanel: {
      // Modules of 1.0 x 1.7 m with a light frame; cells of 0.16 m with faint gaps.
      const float u = p.x() * s.axis.x() + p.y() * s.axis.y();
      const float v = -p.x() * s.axis.y() + p.y() * s.axis.x();
      const float mu = u / 1.0F - std::floor(u / 1.0F);
      const float mv = v / 1.7F - std::floor(v / 1.7F);
      if (mu < 0.03F || mv < 0.02F) {
        albedo = Eigen::Vector3f(0.45F, 0.46F, 0.47F);
      } else {
        const float cu = u / 0.16F - std::floor(u / 0.16F);
        const float cv = v / 0.16F - std::floor(v / 0.16F);
        albedo *= (cu < 0.06F || cv < 0.06F) ? 1.6F : 1.0F;
        reflect = 0.5F;
      }
      break;
    }
    case Material::Paint:
    case Material::RoofPaint:
      reflect = 0.35F * specular;
      break;
    case Material::Glass:
      reflect = 1.0F;
      break;
    case Material::HeadLight:
    case Material::Rim:
      reflect = 0.4F;
      break;
    default:
      break;
  }
  const float nDotL = normal.dot(sun);
  float sunVisible = 0.0F;
  if (nDotL > 0.0F) {
    const Eigen::Vector3f lifted = p + normal * 0.03F;
    sunVisible = staticSun >= 0.0F && !shadow_.dynamicNear(lifted)
                     ? staticSun
                     : shadow_.visibility(lifted, light.shadowSoftnessTexels);
  }
  const float skyTerm = (0.6F + 0.4F * normal.z()) * skyOcclusion;
  Eigen::Vector3f colour = albedo.cwiseProduct(
      light.sunIrradiance * (std::max(nDotL, 0.0F) * sunVisible) + light.skyIrradiance * skyTerm);
  if (specular > 0.0F && sunVisible > 0.0F) {
    const Eigen::Vector3f half = (sun + toCamera).normalized();
    const float nh = std::max(0.0F, normal.dot(half));
    colour += light.sunIrradiance * (specular * sunVisible * std::pow(nh, shininess));
  }
  if (reflect > 0.0F) {
    const float c = 1.0F - std::max(0.0F, normal.dot(toCamera));
    const float fresnel = 0.04F + 0.96F * c * c * c * c * c;
    // Sky radiance seen in the reflection: brighter towards the horizon.
    const Eigen::Vector3f r = 2.0F * normal.dot(toCamera) * normal - toCamera;
    const float horizon = 1.0F - std::max(0.0F, r.z());
    const Eigen::Vector3f skyRadiance =
        light.skyIrradiance * (1.1F + 1.2F * horizon) * skyOcclusion;
    colour += skyRadiance * (reflect * fresnel * 1.5F);
  }
  return colour;
}

Eigen::Vector3f Renderer::shadeGroundPixel(const PinholeView& view, int x, int y, int ss,
                                           Eigen::Vector2d* previous) const {
  // The ground's light (sun, sky, sky occlusion, vehicle shadows) varies little within a
  // pixel, so it is computed once at the pixel's centre; the albedo and the static shadow
  // (the detail) are taken at every sample and averaged, as before.
  const Lighting& light = scene_->light;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double depth = 0.0;
  std::array<Eigen::Vector2d, 16> ground;
  int n = 0;
  // Sample rays are affine in the sample coordinates (view.unproject without its divisions).
  const Eigen::Vector3d rayRow = ray0_ + (x * ss) * rayDx_ + (y * ss) * rayDy_;
  for (int j = 0; j < ss; ++j) {
    const std::size_t row =
        static_cast<std::size_t>(y * ss + j) * static_cast<std::size_t>(samples_.width) +
        static_cast<std::size_t>(x * ss);
    for (int i = 0; i < ss; ++i) {
      const double z =
          1.0 / static_cast<double>(samples_.invDepth[row + static_cast<std::size_t>(i)]);
      const Eigen::Vector3d pd = view.centre + z * (rayRow + i * rayDx_ + j * rayDy_);
      ground[static_cast<std::size_t>(n++)] = pd.head<2>();
      centre += pd;
      depth += z;
    }
  }
  centre /= n;
  depth /= n;
  const std::int32_t first =
      samples_
          .triangle[static_cast<std::size_t>(y * ss) * static_cast<std::size_t>(samples_.width) +
                    static_cast<std::size_t>(x * ss)];
  const Eigen::Vector3f p = centre.cast<float>();
  // The ground is nearly flat: one normal per triangle (its corners' mean) is enough.
  Eigen::Vector3f normal = groundNormals_[static_cast<std::size_t>(first)];
  const Eigen::Vector3d toCameraD = view.centre - centre;
  const double distance = toCameraD.norm();
  const Eigen::Vector3f toCamera = (toCameraD / distance).cast<float>();
  if (normal.dot(toCamera) < 0.0F) {
    normal = -normal;
  }
  // Ground area one sample covers (see shade()).
  const double footprint = depth * depth / (view.fx * view.fy) * (depth / distance) /
                           static_cast<double>(std::max(0.05F, normal.dot(toCamera)));
  const int level = groundCache_.level(footprint);
  // The texels of a frame are read once each, in an order the hardware prefetcher cannot
  // guess: ask for those of the pixel a few steps ahead along the row (extrapolated).
  if (previous != nullptr) {
    const Eigen::Vector2d c = centre.head<2>();
    if (previous->allFinite()) {
      const Eigen::Vector2d ahead = c + 8.0 * (c - *previous);
      groundCache_.prefetch(ahead.x(), ahead.y(), level);
    }
    *previous = c;
  }
  Eigen::Vector3f albedo = Eigen::Vector3f::Zero();
  float staticSun = 0.0F;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d& g = ground[static_cast<std::size_t>(k)];
    const GroundSample s = groundCache_.sample(g.x(), g.y(), level);
    albedo += s.albedo;
    staticSun += s.sunVisibility;
  }
  albedo /= static_cast<float>(n);
  staticSun /= static_cast<float>(n);
  const Eigen::Vector3f sun = light.sunDirectionEnu.cast<float>();
  const float nDotL = normal.dot(sun);
  float sunVisible = 0.0F;
  if (nDotL > 0.0F) {
    const Eigen::Vector3f lifted = p + normal * 0.03F;
    sunVisible = shadow_.dynamicNear(lifted)
                     ? shadow_.visibility(lifted, light.shadowSoftnessTexels)
                     : staticSun;
  }
  const float skyTerm = (0.6F + 0.4F * normal.z()) * occlusionAt(centre.x(), centre.y());
  return albedo.cwiseProduct(light.sunIrradiance * (std::max(nDotL, 0.0F) * sunVisible) +
                             light.skyIrradiance * skyTerm);
}

bool Renderer::smoothSurface(std::uint32_t surface) const {
  switch (surfaces_[surface].material) {
    case Material::Canopy:
    case Material::Paint:
    case Material::RoofPaint:
    case Material::Glass:
    case Material::Tyre:
    case Material::Rim:
    case Material::HeadLight:
    case Material::TailLight:
    case Material::Underbody:
      return true;
    default:
      return false;
  }
}

void Renderer::render(const std::vector<SimVehicle>& vehicles, const PinholeView& view,
                      const Canvas& canvas, cv::Mat& linear) {
  triangles_ = staticTriangles_;
  surfaces_ = staticSurfaces_;
  ranges_.clear();
  shadow_.restoreFrom(staticShadow_);
  for (const SimVehicle& v : vehicles) {
    VehicleRange range;
    range.trackId = v.trackId;
    range.first = triangles_.size();
    appendVehicle(*v.model, vehiclePose(v, *world_), v.trackId, triangles_, surfaces_);
    range.count = triangles_.size() - range.first;
    ranges_.push_back(range);
    for (std::size_t t = range.first; t < triangles_.size(); ++t) {
      shadow_.addDynamic(triangles_[t], surfaces_[triangles_[t].surface]);
    }
  }
  shadow_.finishDynamic();
  buildOcclusion(vehicles);
  rasterize(triangles_, surfaces_, view, samples_, threads_);

  const int ss = canvas.supersampling;
  const Eigen::Matrix3d toWorld = view.worldToCamera.transpose();
  ray0_ = toWorld * Eigen::Vector3d(-view.cx / view.fx, -view.cy / view.fy, 1.0);
  rayDx_ = toWorld.col(0) / view.fx;
  rayDy_ = toWorld.col(1) / view.fy;
  linear.create(canvas.height, canvas.width, CV_32FC3);
  const auto shadeRows = [&](int r0, int r1) {
    for (int y = r0; y < r1; ++y) {
      auto* row = linear.ptr<cv::Vec3f>(y);
      const std::uint8_t* needed =
          canvasMask_.empty() ? nullptr
                              : canvasMask_.data() + static_cast<std::ptrdiff_t>(y) * canvas.width;
      Eigen::Vector2d previous = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
      for (int x = 0; x < canvas.width; ++x) {
        if (needed != nullptr && needed[x] == 0) {
          row[x] = cv::Vec3f(0.0F, 0.0F, 0.0F);  // never read by the sensor
          continue;
        }
        bool allGround = ss <= 4;
        for (int j = 0; j < ss && allGround; ++j) {
          const std::int32_t* t = samples_.triangle.data() +
                                  static_cast<std::ptrdiff_t>(y * ss + j) * samples_.width + x * ss;
          for (int i = 0; i < ss; ++i) {
            // Ground triangles come first in the list (buildGround runs first).
            allGround = allGround && t[i] >= 0 && static_cast<std::size_t>(t[i]) < groundTriangles_;
          }
        }
        if (allGround) {
          const Eigen::Vector3f c = shadeGroundPixel(view, x, y, ss, &previous);
          row[x] = cv::Vec3f(c.x(), c.y(), c.z());
          continue;
        }
        // Pixels wholly on one smooth surface (tree crown, vehicle paint, glass, ...) are
        // shaded once at their centre: these shadings (foliage noise, filtered shadows,
        // highlights) vary little within a pixel. Edges and textured surfaces keep S x S.
        std::int32_t t0 = samples_.triangle[static_cast<std::size_t>(y * ss) *
                                                static_cast<std::size_t>(samples_.width) +
                                            static_cast<std::size_t>(x * ss)];
        bool uniform = t0 >= 0 && smoothSurface(triangles_[static_cast<std::size_t>(t0)].surface);
        float invDepth = 0.0F;
        for (int j = 0; j < ss && uniform; ++j) {
          const std::size_t base =
              static_cast<std::size_t>(y * ss + j) * static_cast<std::size_t>(samples_.width) +
              static_cast<std::size_t>(x * ss);
          for (int i = 0; i < ss && uniform; ++i) {
            const std::int32_t t = samples_.triangle[base + static_cast<std::size_t>(i)];
            uniform = t >= 0 && triangles_[static_cast<std::size_t>(t)].surface ==
                                    triangles_[static_cast<std::size_t>(t0)].surface;
            invDepth += samples_.invDepth[base + static_cast<std::size_t>(i)];
          }
        }
        if (uniform) {
          const double c = 0.5 * (ss - 1);
          const Eigen::Vector3f v =
              shade(view, x * ss + c, y * ss + c, t0, invDepth / static_cast<float>(ss * ss));
          row[x] = cv::Vec3f(v.x(), v.y(), v.z());
          continue;
        }
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        for (int j = 0; j < ss; ++j) {
          for (int i = 0; i < ss; ++i) {
            const int sx = x * ss + i;
            const int sy = y * ss + j;
            const std::size_t idx =
                static_cast<std::size_t>(sy) * static_cast<std::size_t>(samples_.width) +
                static_cast<std::size_t>(sx);
            sum += shade(view, sx, sy, samples_.triangle[idx], samples_.invDepth[idx]);
          }
        }
        sum /= static_cast<float>(ss * ss);
        row[x] = cv::Vec3f(sum.x(), sum.y(), sum.z());
      }
    }
  };
  if (threads_ <= 1) {
    shadeRows(0, canvas.height);
  } else {
    std::vector<std::thread> pool;
    const int rows = (canvas.height + threads_ - 1) / threads_;
    for (int i = 0; i < threads_; ++i) {
      const int r0 = i * rows;
      const int r1 = std::min(canvas.height, r0 + rows);
      if (r0 < r1) {
        pool.emplace_back(shadeRows, r0, r1);
      }
    }
    for (auto& t : pool) {
      t.join();
    }
  }
}

}  // namespace vp::sim
