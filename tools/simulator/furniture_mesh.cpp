// Renderer::buildFurniture: the static geometry of the scene's street furniture (benches,
// bus shelters, kiosks, stair/underpass entrances, sign posts, street lamps) as boxes and quads
// standing on the DTM.
// They are static casters like buildings, so their shadows come from the same shadow map.
#include <algorithm>
#include <array>
#include <cmath>

#include "mesh_build.hpp"
#include "renderer.hpp"

namespace vp::sim {

void Renderer::buildFurniture() {
  for (std::size_t fi = 0; fi < scene_->furniture.size(); ++fi) {
    const StreetFurniture& item = scene_->furniture[fi];
    const int id = -3000 - static_cast<int>(fi);
    const Eigen::Vector2d f = item.axis();
    const Eigen::Vector2d n(-f.y(), f.x());  // the front
    const double hl = 0.5 * item.length_m;
    const double hw = 0.5 * item.width_m;
    double gMin = 1e9;
    double gMax = -1e9;
    for (int i = -1; i <= 1; i += 2) {
      for (int j = -1; j <= 1; j += 2) {
        const Eigen::Vector2d p = item.centre + i * hl * f + j * hw * n;
        const double z = world_->groundZ(p.x(), p.y());
        gMin = std::min(gMin, z);
        gMax = std::max(gMax, z);
      }
    }
    const auto surface = [&](Material m, const Eigen::Vector3f& albedo, float specular,
                             float shininess) {
      RenderSurface s;
      s.material = m;
      s.albedo = albedo;
      s.specular = specular;
      s.shininess = shininess;
      s.objectId = id;
      s.seed = item.seed;
      staticSurfaces_.push_back(s);
      return static_cast<std::uint32_t>(staticSurfaces_.size() - 1);
    };
    // A box in the item's frame: centre (a along, c towards the front), half sizes, heights
    // above the highest ground corner (a bottom at 0 reaches below the lowest one).
    const auto box = [&](double a, double c, double halfA, double halfC, double h0, double h1,
                         std::uint32_t side, std::uint32_t top) {
      addBox(staticTriangles_, item.centre + a * f + c * n, f, halfA, halfC,
             h0 <= 0.0 ? gMin - 0.1 : gMax + h0, gMax + h1, side, top);
    };
    switch (item.kind) {
      case FurnitureKind::Bench: {
        const std::uint32_t slats = surface(Material::Furniture, item.albedo, 0.1F, 20.0F);
        const std::uint32_t legs =
            surface(Material::Furniture, Eigen::Vector3f(0.1F, 0.1F, 0.1F), 0.2F, 30.0F);
        const double seat = item.backrest ? 0.8 * item.width_m : item.width_m;
        const double seatC = hw - 0.5 * seat;
        box(0.0, seatC, hl, 0.5 * seat, 0.4, 0.45, slats, slats);
        for (const double a : {-1.0, 1.0}) {
          box(a * (hl - 0.15), seatC, 0.04, 0.5 * seat - 0.04, 0.0, 0.4, legs, legs);
        }
        if (item.backrest) {
          box(0.0, -hw + 0.04, hl, 0.04, 0.45, item.height_m, slats, slats);
        }
        break;
      }
      case FurnitureKind::Shelter: {
        const std::uint32_t frame = surface(Material::Furniture, item.albedo, 0.3F, 40.0F);
        const std::uint32_t glass = surface(Material::Glass, item.roofAlbedo, 0.9F, 150.0F);
        const double h = item.height_m;
        box(0.0, 0.0, hl, hw, h - 0.06, h, glass, glass);  // glass roof
        for (const double s : {-1.0, 1.0}) {               // roof frame
          box(0.0, s * (hw - 0.05), hl, 0.05, h - 0.12, h + 0.02, frame, frame);
          box(s * (hl - 0.05), 0.0, 0.05, hw, h - 0.12, h + 0.02, frame, frame);
        }
        for (const double a : {-1.0, 1.0}) {  // posts
          for (const double c : {-1.0, 1.0}) {
            box(a * (hl - 0.1), c * (hw - 0.1), 0.05, 0.05, 0.0, h - 0.06, frame, frame);
          }
        }
        box(0.0, -hw + 0.1, hl - 0.15, 0.015, 0.1, h - 0.25, glass, frame);         // back panel
        box(hl - 0.1, -0.15 * hw, 0.015, 0.7 * hw, 0.1, h - 0.25, glass, frame);    // side
        box(0.0, -hw + 0.45, 0.35 * item.length_m, 0.2, 0.42, 0.46, frame, frame);  // seat
        break;
      }
      case FurnitureKind::Kiosk: {
        const std::uint32_t walls = surface(Material::Furniture, item.albedo, 0.1F, 20.0F);
        const std::uint32_t roof = surface(Material::Furniture, item.roofAlbedo, 0.15F, 30.0F);
        const std::uint32_t window =
            surface(Material::Glass, Eigen::Vector3f(0.05F, 0.06F, 0.07F), 0.9F, 150.0F);
        box(0.0, 0.0, hl, hw, 0.0, item.height_m, walls, roof);
        box(0.0, 0.0, hl + 0.25, hw + 0.25, item.height_m, item.height_m + 0.15, roof, roof);
        box(0.0, hw, hl - 0.3, 0.01, 1.0, 2.0, window, window);  // serving window
        break;
      }
      case FurnitureKind::StairEntrance: {
        // The stairs go down along +f from the open end at -hl; low concrete walls on both
        // sides and the far end carry a railing.
        const std::uint32_t wall = surface(Material::Furniture, item.albedo, 0.05F, 10.0F);
        const std::uint32_t rail = surface(Material::Furniture, item.roofAlbedo, 0.4F, 40.0F);
        RenderSurface steps;
        steps.material = Material::Stairs;
        steps.albedo = item.albedo * 0.8F;
        steps.objectId = id;
        steps.axis = Eigen::Vector3f(static_cast<float>(f.x()), static_cast<float>(f.y()), 0.0F);
        steps.param = static_cast<float>((item.centre - hl * f).dot(f));
        staticSurfaces_.push_back(steps);
        const auto stepsIndex = static_cast<std::uint32_t>(staticSurfaces_.size() - 1);
        const double wallH = 0.35;
        const double railH = item.height_m;
        for (const double s : {-1.0, 1.0}) {
          box(0.0, s * (hw - 0.1), hl, 0.1, 0.0, wallH, wall, wall);
          box(0.0, s * (hw - 0.1), hl, 0.025, railH - 0.05, railH, rail, rail);
        }
        box(hl - 0.1, 0.0, 0.1, hw - 0.2, 0.0, wallH, wall, wall);
        box(hl - 0.1, 0.0, 0.025, hw - 0.2, railH - 0.05, railH, rail, rail);
        const int posts = std::max(2, static_cast<int>(item.length_m / 1.5) + 1);
        for (int k = 0; k < posts; ++k) {
          const double a = -hl + 0.05 + (item.length_m - 0.1) * k / (posts - 1);
          for (const double s : {-1.0, 1.0}) {
            box(a, s * (hw - 0.1), 0.025, 0.025, wallH, railH - 0.05, rail, rail);
          }
        }
        // The opening: quads just above the ground inside the walls, in cells of <= 1 m so
        // they follow the relief's curvature.
        const double a0 = -hl;
        const double a1 = hl - 0.2;
        const double c0 = -hw + 0.2;
        const double c1 = hw - 0.2;
        const int na = std::max(1, static_cast<int>(std::ceil(a1 - a0)));
        const int nc = std::max(1, static_cast<int>(std::ceil(c1 - c0)));
        const auto at = [&](int i, int j) {
          const Eigen::Vector2d p =
              item.centre + (a0 + (a1 - a0) * i / na) * f + (c0 + (c1 - c0) * j / nc) * n;
          return Eigen::Vector3d(p.x(), p.y(), world_->groundZ(p.x(), p.y()) + 0.06);
        };
        for (int i = 0; i < na; ++i) {
          for (int j = 0; j < nc; ++j) {
            addQuad(staticTriangles_, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1),
                    stepsIndex);
          }
        }
        break;
      }
      case FurnitureKind::SignPost: {
        const std::uint32_t pole = surface(Material::Furniture, item.albedo, 0.4F, 40.0F);
        const std::uint32_t plate = surface(Material::Furniture, item.roofAlbedo, 0.3F, 30.0F);
        const double plateBottom = item.height_m - item.length_m;
        box(0.0, 0.0, 0.035, 0.035, 0.0, item.height_m - 0.05, pole, pole);
        box(0.0, 0.045, hl, 0.012, plateBottom, item.height_m, plate, pole);
        break;
      }
      case FurnitureKind::StreetLamp: {
        const std::uint32_t pole = surface(Material::Furniture, item.albedo, 0.4F, 40.0F);
        const std::uint32_t head = surface(Material::Furniture, item.roofAlbedo, 0.5F, 60.0F);
        const double h = item.height_m;
        const double r = item.reach_m;
        box(0.0, 0.0, 0.08, 0.08, 0.0, h, pole, pole);
        box(0.0, 0.5 * r, 0.04, 0.5 * r, h - 0.08, h, pole, pole);       // the arm
        box(0.0, r + 0.25, 0.18, 0.35, h - 0.22, h - 0.04, head, head);  // the lamp head
        break;
      }
    }
  }
}

}  // namespace vp::sim
