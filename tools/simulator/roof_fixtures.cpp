// Roof fixtures of a building: HVAC units on flat roofs, rows of skylights, dormers and solar
// panels on pitched ones (and skylights/panels on some flat ones). From the drone these are
// small bright or dark rectangles in rows: the detector boxes them on real footage, so the
// simulator draws them for training to see as background. Placed in the roof's own frame
// (along the length axis, across it), clear of the roof edges and of each other.
#include <algorithm>
#include <array>
#include <cmath>

#include "scene.hpp"

namespace vp::sim {

namespace {

constexpr double kEdgeMargin_m = 0.5;  // from the roof edge (parapet, eaves) to a fixture

bool fits(const Building& b, const RoofFixture& f) {
  const double hl = 0.5 * b.length_m - kEdgeMargin_m;
  const double hw = 0.5 * b.width_m - kEdgeMargin_m;
  if (std::fabs(f.along_m) + 0.5 * f.length_m > hl ||
      std::fabs(f.across_m) + 0.5 * f.width_m > hw) {
    return false;
  }
  if (b.roof == RoofKind::Gabled && std::fabs(f.across_m) - 0.5 * f.width_m < 0.4) {
    return false;  // not across the ridge
  }
  const Footprint mine{{f.along_m, f.across_m}, {1.0, 0.0}, 0.5 * f.length_m, 0.5 * f.width_m};
  for (const RoofFixture& o : b.fixtures) {
    const Footprint other{{o.along_m, o.across_m}, {1.0, 0.0}, 0.5 * o.length_m, 0.5 * o.width_m};
    if (footprintsOverlap(mine, other, 0.25)) {
      return false;
    }
  }
  return true;
}

void tryAdd(Building& b, const RoofFixture& f) {
  if (fits(b, f)) {
    b.fixtures.push_back(f);
  }
}

// A row of equal fixtures along the length axis at `across`, spaced by `pitch`.
void addRow(Building& b, RoofFixtureKind kind, double across, double length, double width,
            double height, double pitch, int count) {
  for (int i = 0; i < count; ++i) {
    RoofFixture f;
    f.kind = kind;
    f.along_m = (i - 0.5 * (count - 1)) * pitch;
    f.across_m = across;
    f.length_m = length;
    f.width_m = width;
    f.height_m = height;
    tryAdd(b, f);
  }
}

void addSkylightRow(Building& b, Rng& rng, double across) {
  const double length = rng.uniform(0.8, 1.3);
  const double pitch = length + rng.uniform(0.8, 3.0);
  const int count =
      std::max(1, static_cast<int>((b.length_m - 2.0) / pitch * rng.uniform(0.5, 1.0)));
  addRow(b, RoofFixtureKind::Skylight, across, length, rng.uniform(1.0, 1.5), 0.0, pitch, count);
}

void addSolarArray(Building& b, Rng& rng, double across, double maxWidth) {
  RoofFixture f;
  f.kind = RoofFixtureKind::SolarPanel;
  f.length_m = b.length_m * rng.uniform(0.35, 0.8);
  f.width_m = std::max(1.0, maxWidth * rng.uniform(0.6, 0.95));
  f.along_m = rng.uniform(-0.15, 0.15) * b.length_m;
  f.across_m = across;
  tryAdd(b, f);
}

}  // namespace

void addRoofFixtures(Building& b) {
  Rng rng((static_cast<std::uint64_t>(b.seed) << 32U) ^ 0x700f'0f1eULL);
  b.fixtures.clear();
  const double hw = 0.5 * b.width_m;
  if (b.roof == RoofKind::Flat) {
    // HVAC boxes 1-3 m (the drawn rooftopUnits plus 0-3 more), in a loose cluster or row.
    const int units = b.rooftopUnits + rng.uniformInt(0, 3);
    for (int u = 0, tries = 0; u < units && tries < units * 10; ++tries) {
      RoofFixture f;
      f.kind = RoofFixtureKind::Hvac;
      f.length_m = rng.uniform(1.0, 3.0);
      f.width_m = rng.uniform(1.0, std::min(2.5, f.length_m));
      f.height_m = rng.uniform(0.8, 2.0);
      f.along_m = rng.uniform(-0.5, 0.5) * (b.length_m - f.length_m - 1.0);
      f.across_m = rng.uniform(-0.5, 0.5) * (b.width_m - f.width_m - 1.0);
      const std::size_t before = b.fixtures.size();
      tryAdd(b, f);
      u += b.fixtures.size() > before ? 1 : 0;
    }
    if (rng.chance(0.25)) {  // skylights of a hall or a mall
      addSkylightRow(b, rng, rng.uniform(-0.5, 0.5) * hw);
    }
    if (rng.chance(0.2)) {
      addSolarArray(b, rng, rng.uniform(-0.3, 0.3) * hw, 0.6 * b.width_m);
    }
    return;
  }
  // Pitched roof: each slope gets skylights (45 %), dormers (30 %) or solar panels (30 %).
  for (const double side : {1.0, -1.0}) {
    if (rng.chance(0.45)) {
      addSkylightRow(b, rng, side * rng.uniform(0.35, 0.65) * hw);
    }
    if (rng.chance(0.3)) {
      const double width = rng.uniform(1.5, 2.5);  // horizontal depth into the slope
      const double front = rng.uniform(0.65, 0.8) * hw;
      const double length = rng.uniform(1.4, 2.4);
      addRow(b, RoofFixtureKind::Dormer, side * (front - 0.5 * width), length, width,
             rng.uniform(1.1, 1.6), length + rng.uniform(1.5, 4.0), rng.uniformInt(1, 4));
    }
    if (rng.chance(0.3)) {
      addSolarArray(b, rng, side * 0.5 * hw, 0.55 * hw);
    }
  }
}

}  // namespace vp::sim
