// Renderer::buildRoofFixtures: the geometry of a building's roof fixtures (roof_fixtures.cpp
// places them): HVAC boxes, skylights (glass, raised on flat roofs, flush on pitched ones),
// dormers (boxes out of the slope with a window) and solar panels. They belong to the
// building (its object id) and cast shadows through the static shadow map like it.
#include <algorithm>
#include <cmath>

#include "mesh_build.hpp"
#include "renderer.hpp"

namespace vp::sim {

void Renderer::buildRoofFixtures(const Building& b, int objectId, double z1, std::uint32_t roof,
                                 std::uint32_t unit) {
  if (b.fixtures.empty()) {
    return;
  }
  const Eigen::Vector2d f(std::cos(b.heading_rad), std::sin(b.heading_rad));
  const Eigen::Vector2d n(-f.y(), f.x());
  const double hw = 0.5 * b.width_m;
  const bool gabled = b.roof == RoofKind::Gabled;
  // Roof height at `across` m from the ridge line (flat: the eaves height).
  const auto roofZ = [&](double across) {
    return gabled ? z1 + b.ridgeHeight_m * (1.0 - std::fabs(across) / hw) : z1;
  };
  const auto surface = [&](Material m, const Eigen::Vector3f& albedo, float specular,
                           float shininess) {
    RenderSurface s;
    s.material = m;
    s.albedo = albedo;
    s.specular = specular;
    s.shininess = shininess;
    s.objectId = objectId;
    s.seed = b.seed + 7U;
    s.axis = Eigen::Vector3f(static_cast<float>(f.x()), static_cast<float>(f.y()), 0.0F);
    staticSurfaces_.push_back(s);
    return static_cast<std::uint32_t>(staticSurfaces_.size() - 1);
  };
  const std::uint32_t glass =
      surface(Material::Glass, Eigen::Vector3f(0.07F, 0.08F, 0.09F), 0.9F, 150.0F);
  const std::uint32_t solar =
      surface(Material::SolarPanel, Eigen::Vector3f(0.03F, 0.045F, 0.09F), 0.5F, 80.0F);
  const std::uint32_t dormerWall = surface(Material::RoofUnit, b.wallAlbedo, 0.05F, 20.0F);
  // Corner (a, c) of the roof frame, lifted by `lift` above the roof surface there.
  const auto onRoof = [&](double a, double c, double lift) {
    const Eigen::Vector2d p = b.centre + a * f + c * n;
    return Eigen::Vector3d(p.x(), p.y(), roofZ(c) + lift);
  };
  for (const RoofFixture& x : b.fixtures) {
    const double a0 = x.along_m - 0.5 * x.length_m;
    const double a1 = x.along_m + 0.5 * x.length_m;
    const double c0 = x.across_m - 0.5 * x.width_m;
    const double c1 = x.across_m + 0.5 * x.width_m;
    const Eigen::Vector2d centre = b.centre + x.along_m * f + x.across_m * n;
    switch (x.kind) {
      case RoofFixtureKind::Hvac:
        addBox(staticTriangles_, centre, f, 0.5 * x.length_m, 0.5 * x.width_m, z1 - 0.05,
               z1 + x.height_m, unit, unit);
        break;
      case RoofFixtureKind::Skylight:
      case RoofFixtureKind::SolarPanel: {
        const std::uint32_t top = x.kind == RoofFixtureKind::Skylight ? glass : solar;
        if (gabled) {  // flush with the slope
          const double lift = x.kind == RoofFixtureKind::Skylight ? 0.05 : 0.12;
          addQuad(staticTriangles_, onRoof(a0, c0, lift), onRoof(a1, c0, lift),
                  onRoof(a1, c1, lift), onRoof(a0, c1, lift), top);
        } else {  // on a curb (skylight) or a low rack (panels)
          const double h = x.kind == RoofFixtureKind::Skylight ? 0.3 : 0.25;
          addBox(staticTriangles_, centre, f, 0.5 * x.length_m, 0.5 * x.width_m, z1 - 0.05, z1 + h,
                 unit, top);
        }
        break;
      }
      case RoofFixtureKind::Dormer: {
        // Front (eaves side) at the outer edge; the flat top no higher than the slope at the
        // back edge, so the back is buried in the roof.
        const double side = x.across_m >= 0.0 ? 1.0 : -1.0;
        const double outer = std::max(std::fabs(c0), std::fabs(c1));
        const double base = roofZ(outer);
        const double top = std::min(base + x.height_m, roofZ(outer - x.width_m));
        addBox(staticTriangles_, centre, f, 0.5 * x.length_m, 0.5 * x.width_m, base - 0.1, top,
               dormerWall, roof);
        // Window on the front face, 2 cm proud of it.
        const double c = side * (outer + 0.02);
        const double wa = std::max(0.2, 0.5 * x.length_m - 0.3);
        const double w0 = base + 0.25;
        const double w1 = std::max(w0 + 0.2, top - 0.2);
        const Eigen::Vector2d p0 = b.centre + (x.along_m - wa) * f + c * n;
        const Eigen::Vector2d p1 = b.centre + (x.along_m + wa) * f + c * n;
        addQuad(staticTriangles_, {p0.x(), p0.y(), w0}, {p1.x(), p1.y(), w0}, {p1.x(), p1.y(), w1},
                {p0.x(), p0.y(), w1}, glass);
        break;
      }
    }
  }
}

}  // namespace vp::sim
