// Renderer::buildFurniture: the static geometry of the scene's street furniture (benches,
// bus shelters, kiosks, stair/underpass entrances, sign posts, street lamps) and of the road users
// that are not vehicles (rows of motorbikes, bicycle racks, groups of people) as boxes and quads
// standing on the DTM.
// They are static casters like buildings, so their shadows come from the same shadow map.
#include <algorithm>
#include <array>
#include <cmath>

#include "mesh_build.hpp"
#include "renderer.hpp"
#include "sim_random.hpp"

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
      case FurnitureKind::Motorbikes:
      case FurnitureKind::Bicycles: {
        // Machines side by side along the row (a), each pointing to +n (c); colours of the
        // machines after the first drawn from the item's seed.
        Rng rng(item.seed);
        const bool motor = item.kind == FurnitureKind::Motorbikes;
        const std::uint32_t tyre =
            surface(Material::Furniture, Eigen::Vector3f(0.035F, 0.035F, 0.035F), 0.1F, 10.0F);
        const std::uint32_t dark =
            surface(Material::Furniture, Eigen::Vector3f(0.07F, 0.07F, 0.075F), 0.3F, 30.0F);
        const std::uint32_t glass =
            surface(Material::Glass, Eigen::Vector3f(0.1F, 0.11F, 0.12F), 0.9F, 150.0F);
        const double len = item.width_m;  // one machine's length
        const double h = item.height_m;
        const double pitch = item.count > 1 ? (item.length_m - 0.8) / (item.count - 1) : 0.0;
        if (!motor) {  // the rack's rail, at the front wheels
          const std::uint32_t rail = surface(Material::Furniture, item.roofAlbedo, 0.4F, 40.0F);
          box(0.0, hw - 0.35, hl, 0.025, 0.55, 0.62, rail, rail);
        }
        for (int k = 0; k < item.count; ++k) {
          const Eigen::Vector3f colour =
              k == 0 ? item.albedo
                     : (rng.chance(0.3) ? item.albedo
                                        : item.albedo
                                              .cwiseProduct(Eigen::Vector3f(
                                                  static_cast<float>(rng.uniform(0.3, 1.8)),
                                                  static_cast<float>(rng.uniform(0.3, 1.8)),
                                                  static_cast<float>(rng.uniform(0.3, 1.8))))
                                              .cwiseMin(0.9F)
                                              .cwiseMax(0.02F));
          const std::uint32_t paint = surface(Material::Furniture, colour, 0.5F, 60.0F);
          const double a = -hl + 0.4 + k * pitch;
          // Racks hold bicycles alternately further in and out; motorbikes stand as parked.
          const double c = motor ? rng.uniform(-0.1, 0.1) : (k % 2 == 0 ? 0.0 : -0.2);
          if (motor) {
            const double r = 0.3;  // wheel radius
            for (const double s : {-1.0, 1.0}) {
              box(a, c + s * (0.5 * len - r), 0.06, r, 0.0, 2.0 * r, tyre, tyre);
            }
            box(a, c, 0.16, 0.25 * len, 0.3, 0.6, dark, dark);                      // engine
            box(a, c + 0.12 * len, 0.17, 0.16 * len, 0.6, 0.72 * h, paint, paint);  // tank
            box(a, c - 0.14 * len, 0.15, 0.18 * len, 0.6, 0.66 * h, dark, dark);    // seat
            box(a, c - 0.37 * len, 0.11, 0.1 * len, 0.55, 0.62 * h, paint, paint);  // tail
            box(a, c + 0.3 * len, 0.37, 0.025, h - 0.12, h - 0.07, dark, dark);     // handlebar
            box(a, c + 0.36 * len, 0.12, 0.05, 0.75 * h, h, paint, glass);          // fairing
          } else {
            const double r = 0.33;
            for (const double s : {-1.0, 1.0}) {
              box(a, c + s * (0.5 * len - r), 0.018, r, 0.0, 2.0 * r, tyre, tyre);
            }
            box(a, c, 0.02, 0.3 * len, 0.7, 0.76, paint, paint);                 // top tube
            box(a, c + 0.05 * len, 0.02, 0.2 * len, 0.35, 0.42, paint, paint);   // down tube
            box(a, c - 0.18 * len, 0.07, 0.12, h - 0.12, h - 0.06, dark, dark);  // saddle
            box(a, c + 0.3 * len, 0.28, 0.02, h - 0.04, h, dark, dark);          // handlebar
            if (rng.chance(0.3)) {  // a basket or a child seat
              box(a, c + (rng.chance(0.5) ? 0.45 : -0.4) * len, 0.17, 0.15, 0.7, 0.95, paint, dark);
            }
          }
        }
        break;
      }
      case FurnitureKind::Pedestrians: {
        // People walking along the item's axis (or standing), spread over the footprint.
        Rng rng(item.seed);
        static const std::array<Eigen::Vector3f, 8> kClothes = {
            Eigen::Vector3f(0.05F, 0.05F, 0.06F), Eigen::Vector3f(0.8F, 0.8F, 0.78F),
            Eigen::Vector3f(0.1F, 0.15F, 0.35F),  Eigen::Vector3f(0.5F, 0.08F, 0.08F),
            Eigen::Vector3f(0.35F, 0.33F, 0.3F),  Eigen::Vector3f(0.55F, 0.45F, 0.3F),
            Eigen::Vector3f(0.15F, 0.3F, 0.15F),  Eigen::Vector3f(0.75F, 0.6F, 0.1F)};
        static const std::array<Eigen::Vector3f, 4> kTrousers = {
            Eigen::Vector3f(0.04F, 0.04F, 0.05F), Eigen::Vector3f(0.08F, 0.12F, 0.25F),
            Eigen::Vector3f(0.45F, 0.4F, 0.32F), Eigen::Vector3f(0.25F, 0.25F, 0.26F)};
        static const std::array<Eigen::Vector3f, 4> kHair = {
            Eigen::Vector3f(0.04F, 0.03F, 0.025F), Eigen::Vector3f(0.2F, 0.12F, 0.06F),
            Eigen::Vector3f(0.55F, 0.45F, 0.25F), Eigen::Vector3f(0.5F, 0.5F, 0.5F)};
        for (int k = 0; k < item.count; ++k) {
          const double h = k == 0 ? item.height_m : item.height_m * rng.uniform(0.82, 1.0);
          const double a =
              item.count > 1 ? -hl + 0.3 + (item.length_m - 0.6) * k / (item.count - 1) : 0.0;
          const double c = rng.uniform(-1.0, 1.0) * std::max(0.0, hw - 0.25);
          const Eigen::Vector3f top =
              k == 0
                  ? item.albedo
                  : toneColour(rng, kClothes[static_cast<std::size_t>(rng.uniformInt(0, 7))], 0.2);
          const std::uint32_t shirt = surface(Material::Furniture, top, 0.1F, 15.0F);
          const std::uint32_t legs =
              surface(Material::Furniture,
                      kTrousers[static_cast<std::size_t>(rng.uniformInt(0, 3))], 0.1F, 15.0F);
          const std::uint32_t hair =
              surface(Material::Furniture, kHair[static_cast<std::size_t>(rng.uniformInt(0, 3))],
                      0.2F, 20.0F);
          const double stride = rng.uniform(0.0, 0.15);  // 0: standing
          box(a + stride, c - 0.09, 0.07, 0.07, 0.0, 0.47 * h, legs, legs);
          box(a - stride, c + 0.09, 0.07, 0.07, 0.0, 0.47 * h, legs, legs);
          box(a, c, 0.12, 0.23, 0.47 * h, 0.82 * h, shirt, shirt);  // torso and arms
          box(a, c, 0.1, 0.085, 0.85 * h, h, hair, hair);           // head
          if (rng.chance(0.2)) {  // a bag or an umbrella held beside
            box(a, c + 0.3, 0.15, 0.08, 0.35 * h, 0.55 * h, legs, legs);
          }
        }
        break;
      }
    }
  }
}

}  // namespace vp::sim
