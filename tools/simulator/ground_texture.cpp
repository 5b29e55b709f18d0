#include "ground_texture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "noise.hpp"
#include "sim_random.hpp"

namespace vp::sim {

namespace {

float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0F, 1.0F);
  return t * t * (3.0F - 2.0F * t);
}

// Distance to the nearest line of a periodic family (period, offset), metres.
double periodicDistance(double x, double period) {
  const double m = x - period * std::floor(x / period);
  return std::min(m, period - m);
}

bool dashOn(double along, double dash, double gap) {
  const double period = dash + gap;
  return along - period * std::floor(along / period) < dash;
}

float band(double x, double centre, double halfWidth) {
  return std::fabs(x - centre) <= halfWidth ? 1.0F : 0.0F;
}

// Smooth fields evaluated exactly at one point.
class DirectFields {
 public:
  DirectFields(const GroundTexture& texture, const Eigen::Vector2d& p)
      : texture_(texture), x_(static_cast<float>(p.x())), y_(static_cast<float>(p.y())) {}
  float operator()(GroundField f) const { return texture_.field(f, x_, y_); }

 private:
  const GroundTexture& texture_;
  float x_;
  float y_;
};

// Smooth fields of one cache tile: each evaluated (on first use) on a lattice of nodes and
// interpolated bilinearly at the texels in between. Node spacings are about a sixth of the
// field's finest wavelength, which reproduces it closely while sparing most noise calls.
class TileFields {
 public:
  TileFields(const GroundTexture& texture, double x0, double y0, double texel_m, int texels)
      : texture_(texture), x0_(x0), y0_(y0), texelM_(texel_m), texels_(texels) {}

  void moveTo(int i, int j) {
    i_ = i;
    j_ = j;
  }

  float operator()(GroundField f) {
    Grid& g = grids_[static_cast<std::size_t>(f)];
    if (g.values.empty()) {
      build(f, g);
    }
    const int ci = i_ / g.step;
    const int cj = j_ / g.step;
    const float wx = static_cast<float>(i_ - ci * g.step) * g.invStep;
    const float wy = static_cast<float>(j_ - cj * g.step) * g.invStep;
    const float* r0 = g.values.data() + static_cast<std::ptrdiff_t>(cj * g.nodes + ci);
    const float* r1 = r0 + g.nodes;
    const float a = r0[0] + wx * (r0[1] - r0[0]);
    const float b = r1[0] + wx * (r1[1] - r1[0]);
    return a + wy * (b - a);
  }

 private:
  struct Grid {
    int step = 1;  // texels between nodes
    float invStep = 1.0F;
    int nodes = 0;  // per side
    std::vector<float> values;
  };

  static double spacing_m(GroundField f) {
    switch (f) {
      case GroundField::Fine:  // 0.35 m lattice
        return 0.06;
      case GroundField::Mix:  // finest octave 0.48 m
        return 0.08;
      case GroundField::Stain:  // 0.73 m
        return 0.12;
      case GroundField::Oil:         // 1 m
      case GroundField::CrackRidge:  // 2.9 m, but the cracks sit on its zero set
      case GroundField::Soil:        // 1.1 m
        return 0.16;
      case GroundField::Macro:  // 1.7 m
      case GroundField::Walk:   // 1.5 m
        return 0.25;
      case GroundField::CrackMask:  // 12 m
        return 2.0;
      case GroundField::Count:
        break;
    }
    return 0.06;
  }

  void build(GroundField f, Grid& g) const {
    g.step = std::max(1, static_cast<int>(std::lround(spacing_m(f) / texelM_)));
    g.invStep = 1.0F / static_cast<float>(g.step);
    g.nodes = (texels_ - 1 + g.step - 1) / g.step + 2;
    const double node_m = texelM_ * g.step;
    g.values.resize(static_cast<std::size_t>(g.nodes) * static_cast<std::size_t>(g.nodes));
    for (int j = 0; j < g.nodes; ++j) {
      for (int i = 0; i < g.nodes; ++i) {
        g.values[static_cast<std::size_t>(j * g.nodes + i)] = texture_.field(
            f, static_cast<float>(x0_ + i * node_m), static_cast<float>(y0_ + j * node_m));
      }
    }
  }

  const GroundTexture& texture_;
  double x0_;
  double y0_;
  double texelM_;
  int texels_;
  int i_ = 0;
  int j_ = 0;
  std::array<Grid, static_cast<std::size_t>(GroundField::Count)> grids_;
};

}  // namespace

template <typename Fields>
float GroundTexture::roadTone(const Eigen::Vector2d& p, const Road* road, double along,
                              double lateral, bool inJunction, Fields& fields,
                              const Nearby& nearby) const {
  const GroundStyle& s = scene_->style;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  float tone = 1.0F + s.roadMacroVariation * (2.0F * fields(GroundField::Macro) - 1.0F);
  tone *= 1.0F + 0.5F * s.roadFineVariation * (2.0F * fields(GroundField::Fine) - 1.0F);
  // Aggregate grain: independent per 1.2 cm cell, averaged by the supersampling.
  tone *= 1.0F + s.roadFineVariation *
                     (2.0F * latticeValue(static_cast<int>(std::floor(x / 0.012F)),
                                          static_cast<int>(std::floor(y / 0.012F)), s.seed + 2U) -
                      1.0F);
  if (road != nullptr && !inJunction) {
    // Tyre tracks and the oil stripe follow the lanes.
    const float oilNoise = fields(GroundField::Oil);
    for (int dirSign = 0; dirSign < 2; ++dirSign) {
      const bool forward = dirSign == 0;
      const int lanes = forward ? road->lanesForward : road->lanesBackward;
      for (int k = 0; k < lanes; ++k) {
        const double dl = lateral - road->laneOffset_m(forward, k);
        if (std::fabs(dl) > 1.6) {
          continue;
        }
        const double dt = std::fabs(dl) - 0.8;
        tone *= 1.0F -
                s.wheelTrackDarkening * static_cast<float>(std::exp(-dt * dt / (2 * 0.28 * 0.28)));
        tone *= 1.0F - s.oilStripe * (0.4F + oilNoise) *
                           static_cast<float>(std::exp(-dl * dl / (2 * 0.22 * 0.22)));
      }
    }
    if (s.concreteRoad) {
      const double slab = s.slabLength_m;
      const int slabIndex = static_cast<int>(std::floor(along / slab));
      const int laneIndex = static_cast<int>(std::floor(lateral / road->laneWidth_m));
      tone *= 0.94F + 0.12F * latticeValue(slabIndex, laneIndex, s.seed + 4U);
      const double joint =
          std::min(periodicDistance(along, slab),
                   periodicDistance(lateral - road->medianHalf_m, road->laneWidth_m));
      if (joint < 0.015) {
        tone *= 0.6F;
      }
    }
  }
  if (s.crackDensity > 0.0F) {
    // Thin dark cracks along the zero set of a noise field, in patches of the road.
    const float mask = fields(GroundField::CrackMask);
    if (mask < 0.6F * s.crackDensity) {
      // The ridge's fold is taken here, after interpolation, so cracks stay sharp.
      const float r = 1.0F - std::fabs(2.0F * fields(GroundField::CrackRidge) - 1.0F);
      const float w = 0.5F * s.crackWidth;
      if (r > 1.0F - w) {
        const float crack = smoothstep(1.0F - w, 1.0F - 0.2F * w, r);
        tone *= 1.0F - 0.4F * crack * smoothstep(0.0F, 0.15F, 0.6F * s.crackDensity - mask);
      }
    }
  }
  const float stain = fields(GroundField::Stain);
  tone *= 1.0F - 0.25F * smoothstep(0.68F, 0.8F, stain);
  for (const Patch* pp : nearby.patches) {
    const Patch& patch = *pp;
    const Eigen::Vector2d d = p - patch.centre;
    const double u = std::fabs(d.dot(patch.dir)) - patch.halfLength_m;
    const double v = std::fabs(d.x() * -patch.dir.y() + d.y() * patch.dir.x()) - patch.halfWidth_m;
    const double edge = std::max(u, v);
    if (edge < 0.0) {
      tone *= patch.tone;
    }
    if (std::fabs(edge) < 0.04) {
      tone *= 0.65F;  // sealant along the seam
    }
  }
  for (const Manhole* mp : nearby.manholes) {
    const Manhole& m = *mp;
    const double r = (p - m.position).norm();
    if (r < m.radius_m + 0.06) {
      if (r > m.radius_m) {
        tone *= 0.75F;
      } else {
        const float grid =
            (periodicDistance(p.x(), 0.06) < 0.01 || periodicDistance(p.y(), 0.06) < 0.01) ? 0.8F
                                                                                           : 1.0F;
        tone = 0.55F * grid * tone / std::max(0.3F, tone);
      }
    }
  }
  return tone;
}

float GroundTexture::roadMarkings(const Road& road, double along, double lateral,
                                  bool* yellow) const {
  const bool intersection = scene_->kind == SceneKind::Intersection;
  const double m = road.medianHalf_m;
  const double fwdEdge = -(m + road.lanesForward * road.laneWidth_m);
  const double bwdEdge = m + road.lanesBackward * road.laneWidth_m;
  const double lineHalf = 0.06;
  float cover = 0.0F;
  // Stop lines and crosswalks (intersection: on both approaches).
  if (intersection) {
    const double a = std::fabs(along);
    if (along < 0 && std::fabs(a - road.stopDistance_m) < 0.2 && lateral > fwdEdge &&
        lateral < -m) {
      return 1.0F;
    }
    if (along > 0 && std::fabs(a - road.stopDistance_m) < 0.2 && lateral < bwdEdge && lateral > m) {
      return 1.0F;
    }
  }
  if (road.crosswalkCentre_m < 1e8) {
    const double a = intersection ? std::fabs(along) : along;
    const double dc = std::fabs(a - road.crosswalkCentre_m);
    if (dc < 0.5 * road.crosswalkWidth_m && lateral > -road.rightHalf_m() &&
        lateral < road.leftHalf_m()) {
      if (road.zebra) {
        return periodicDistance(lateral + 0.25, 1.1) < 0.28 ? 1.0F : 0.0F;
      }
      if (dc > 0.5 * road.crosswalkWidth_m - 0.3) {
        return 1.0F;
      }
      return 0.0F;
    }
  }
  if (intersection && std::fabs(along) < road.stopDistance_m) {
    return 0.0F;  // no lane lines inside the junction
  }
  // Centre line.
  switch (road.centreLine) {
    case CentreLine::DoubleYellow: {
      // A median widened for islands keeps its lines beside the lanes (and may be hatched).
      const double c = m > 0.3 ? m - 0.12 : std::max(0.5 * m + 0.02, 0.085);
      if (m > 0.3 && road.medianHatch && std::fabs(lateral) < c - 0.1 &&
          periodicDistance(along + lateral, 2.0) < 0.18) {
        *yellow = true;
        return 1.0F;
      }
      if (band(lateral, c, 0.05) > 0 || band(lateral, -c, 0.05) > 0) {
        *yellow = true;
        return 1.0F;
      }
      break;
    }
    case CentreLine::YellowDashed:
    case CentreLine::WhiteDashed:
      if (std::fabs(lateral) < lineHalf && dashOn(along, road.dashLength_m, road.dashGap_m)) {
        *yellow = road.centreLine == CentreLine::YellowDashed;
        return 1.0F;
      }
      break;
    case CentreLine::None:
      break;
  }
  // Lane lines between lanes of one direction.
  for (int k = 1; k < road.lanesForward; ++k) {
    if (band(lateral, -(m + k * road.laneWidth_m), lineHalf) > 0 &&
        dashOn(along, road.dashLength_m, road.dashGap_m)) {
      cover = 1.0F;
    }
  }
  for (int k = 1; k < road.lanesBackward; ++k) {
    if (band(lateral, m + k * road.laneWidth_m, lineHalf) > 0 &&
        dashOn(-along, road.dashLength_m, road.dashGap_m)) {
      cover = 1.0F;
    }
  }
  // Edge lines: at the parking lane, or just inside the kerb.
  if (road.edgeLines || road.parkingRight_m > 0) {
    const double e = road.parkingRight_m > 0 ? fwdEdge : -(road.rightHalf_m() - 0.35);
    if (band(lateral, e, lineHalf) > 0) {
      cover = 1.0F;
    }
  }
  if (road.edgeLines || road.parkingLeft_m > 0) {
    const double e = road.parkingLeft_m > 0 ? bwdEdge : road.leftHalf_m() - 0.35;
    if (band(lateral, e, lineHalf) > 0) {
      cover = 1.0F;
    }
  }
  // Parking lane: short ticks marking the stalls.
  if (road.parkingRight_m > 0 && lateral < fwdEdge && periodicDistance(along, 6.5) < 0.05 &&
      lateral > fwdEdge - 0.6) {
    cover = 1.0F;
  }
  if (road.parkingLeft_m > 0 && lateral > bwdEdge && periodicDistance(along, 6.5) < 0.05 &&
      lateral < bwdEdge + 0.6) {
    cover = 1.0F;
  }
  return cover;
}

float GroundTexture::lotMarkings(const ParkingLot& lot, const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - lot.centre;
  const double u = d.dot(lot.dir);
  const double v = d.dot(lot.leftNormal());
  const double halfRow = 0.5 * lot.baysPerRow * lot.bayWidth_m;
  if (std::fabs(u) > halfRow + 0.06) {
    return 0.0F;
  }
  for (std::size_t r = 0; r < lot.rowOffsets_m.size(); ++r) {
    const double dv = v - lot.rowOffsets_m[r];
    if (std::fabs(dv) > 0.5 * lot.bayDepth_m + 0.06) {
      continue;
    }
    const double back = -lot.rowFacing[r] * 0.5 * lot.bayDepth_m;
    if (std::fabs(dv - back) < 0.06) {
      return 1.0F;
    }
    // Separators between bays, slightly shorter than the bay at the aisle end.
    if (periodicDistance(u + halfRow, lot.bayWidth_m) < 0.055 &&
        lot.rowFacing[r] * dv < 0.5 * lot.bayDepth_m - 0.3) {
      return 1.0F;
    }
  }
  return 0.0F;
}

template <typename Fields>
Eigen::Vector3f GroundTexture::sidewalk(const Eigen::Vector2d& p, double kerbDistance,
                                        Fields& fields) const {
  const GroundStyle& s = scene_->style;
  const Road* nearest = &scene_->roads[0];
  double best = 1e9;
  for (const Road& road : scene_->roads) {
    const double l = road.lateral(p);
    const double dd = std::max(l - road.leftHalf_m(), -l - road.rightHalf_m());
    if (dd < best) {
      best = dd;
      nearest = &road;
    }
  }
  const double a = nearest->along(p);
  const double q = kerbDistance - scene_->kerbWidth_m;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  float tone = 1.0F + 0.12F * (2.0F * fields(GroundField::Walk) - 1.0F);
  tone *=
      1.0F + 0.08F * (2.0F * latticeValue(static_cast<int>(std::floor(x / 0.015F)),
                                          static_cast<int>(std::floor(y / 0.015F)), s.seed + 21U) -
                      1.0F);
  if (s.pavers) {
    const int row = static_cast<int>(std::floor(q / 0.1));
    const double shifted = a + ((row & 1) != 0 ? 0.1 : 0.0);
    const int col = static_cast<int>(std::floor(shifted / 0.2));
    tone *= 0.88F + 0.24F * latticeValue(col, row, s.seed + 22U);
    if (periodicDistance(q, 0.1) < 0.006 || periodicDistance(shifted, 0.2) < 0.006) {
      tone *= 0.7F;
    }
  } else {
    const int i = static_cast<int>(std::floor(a / s.sidewalkSlab_m));
    const int j = static_cast<int>(std::floor(q / s.sidewalkSlab_m));
    tone *= 0.94F + 0.12F * latticeValue(i, j, s.seed + 23U);
    if (periodicDistance(a, s.sidewalkSlab_m) < 0.01 ||
        (scene_->sidewalkWidth_m > 2.5 && periodicDistance(q, s.sidewalkSlab_m) < 0.01)) {
      tone *= 0.72F;
    }
  }
  return s.sidewalkAlbedo * tone;
}

template <typename Fields>
Eigen::Vector3f GroundTexture::verge(const Eigen::Vector2d& p, Fields& fields,
                                     const Nearby& nearby) const {
  const GroundStyle& s = scene_->style;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  // Concrete apron around buildings.
  for (const std::size_t i : nearby.buildings) {
    const Building& b = scene_->buildings[i];
    const Eigen::Vector2d d = p - b.centre;
    const Eigen::Vector2d& f = buildingAxes_[i];
    const double u = std::fabs(d.dot(f)) - 0.5 * b.length_m;
    const double v = std::fabs(d.x() * -f.y() + d.y() * f.x()) - 0.5 * b.width_m;
    if (std::max(u, v) < 1.5) {
      const float t =
          0.9F + 0.2F * latticeValue(static_cast<int>(std::floor(x / 0.02F)),
                                     static_cast<int>(std::floor(y / 0.02F)), s.seed + 30U);
      return s.sidewalkAlbedo * 0.9F * t;
    }
  }
  const float mix = fields(GroundField::Mix);
  Eigen::Vector3f c = s.grassA * (1.0F - mix) + s.grassB * mix;
  const float blades = latticeValue(static_cast<int>(std::floor(x / 0.025F)),
                                    static_cast<int>(std::floor(y / 0.025F)), s.seed + 32U);
  c *= 0.75F + 0.5F * blades;
  const float soil = fields(GroundField::Soil);
  const float soilWeight = smoothstep(s.soilShare + 0.05F, s.soilShare - 0.05F, soil);
  if (soilWeight > 0.0F) {
    const float grain = 0.85F + 0.3F * valueNoise(x / 0.08F, y / 0.08F, s.seed + 34U);
    c = c * (1.0F - soilWeight) + s.soilAlbedo * grain * soilWeight;
  }
  return c;
}

template <typename Fields>
Eigen::Vector3f GroundTexture::albedoAt(const Eigen::Vector2d& p, Fields& fields,
                                        const Nearby& nearby, GroundClass* cls) const {
  double d = scene_->roadDistance(p);
  const GroundStyle& s = scene_->style;
  if (d < 0.0) {
    for (const Island& island : scene_->islands) {
      const double e = island.distance(p);
      if (e < 0.0) {
        return islandAlbedo(island, p, -e, fields, nearby, cls);
      }
      d = std::max(d, -e);  // the island's kerb gathers dirt like the road's
    }
    // Inside the drivable area: road surface or parking lot.
    const ParkingLot* lot = nullptr;
    for (const ParkingLot& l : scene_->lots) {
      const Eigen::Vector2d q = p - l.centre;
      if (std::fabs(q.dot(l.dir)) < 0.5 * l.length_m &&
          std::fabs(q.dot(l.leftNormal())) < 0.5 * l.width_m) {
        lot = &l;
      }
    }
    const Road* road = nullptr;
    double along = 0.0;
    double lateral = 0.0;
    for (const Road& r : scene_->roads) {
      const double l = r.lateral(p);
      if (l < r.leftHalf_m() && l > -r.rightHalf_m()) {
        road = &r;
        along = r.along(p);
        lateral = l;
        break;
      }
    }
    const bool inJunction = scene_->kind == SceneKind::Intersection && road != nullptr &&
                            std::fabs(along) < road->stopDistance_m - 0.5;
    const float tone =
        roadTone(p, lot != nullptr ? nullptr : road, along, lateral, inJunction, fields, nearby);
    Eigen::Vector3f c = (lot != nullptr ? s.lotAlbedo : s.roadAlbedo) * tone;
    // Dirt collects along the kerb.
    if (d > -0.35) {
      c *= static_cast<float>(0.85 + 0.15 * (-d / 0.35));
    }
    float cover = 0.0F;
    bool yellow = false;
    if (lot != nullptr) {
      cover = lotMarkings(*lot, p);
      yellow = lot->yellowLines;
    } else {
      for (const Road& r : scene_->roads) {
        const double l = r.lateral(p);
        if (l < r.leftHalf_m() && l > -r.rightHalf_m()) {
          cover = std::max(cover, roadMarkings(r, r.along(p), l, &yellow));
        }
      }
    }
    if (cover > 0.0F) {
      const auto x = static_cast<float>(p.x());
      const auto y = static_cast<float>(p.y());
      const float wear =
          s.markingWear * smoothstep(0.3F, 0.75F, fbm(x * 1.3F, y * 1.3F, 3, s.seed + 40U));
      const float chips = latticeValue(static_cast<int>(std::floor(x / 0.02F)),
                                       static_cast<int>(std::floor(y / 0.02F)), s.seed + 41U);
      cover *= std::clamp(1.0F - wear - 0.25F * chips * s.markingWear, 0.0F, 1.0F);
      const Eigen::Vector3f paint =
          (yellow ? s.yellowMarking : s.whiteMarking) * (0.9F + 0.1F * tone);
      c = c * (1.0F - cover) + paint * cover;
    }
    if (cls != nullptr) {
      *cls = lot != nullptr ? GroundClass::Lot : GroundClass::Road;
    }
    return c;
  }
  if (d < scene_->kerbWidth_m) {
    if (cls != nullptr) {
      *cls = GroundClass::Kerb;
    }
    return kerb(p, d);
  }
  if (d < scene_->kerbWidth_m + scene_->sidewalkWidth_m) {
    if (cls != nullptr) {
      *cls = GroundClass::Sidewalk;
    }
    return sidewalk(p, d, fields);
  }
  if (cls != nullptr) {
    *cls = GroundClass::Verge;
  }
  Eigen::Vector3f c = verge(p, fields, nearby);
  // A strip of bare soil / edging right behind the pavement.
  const double e = d - scene_->kerbWidth_m - scene_->sidewalkWidth_m;
  if (e < 0.15) {
    c = c * 0.6F + s.soilAlbedo * 0.4F;
  }
  return c;
}

Eigen::Vector3f GroundTexture::kerb(const Eigen::Vector2d& p, double kerbDistance) const {
  const GroundStyle& s = scene_->style;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  float t = 0.9F + 0.2F * latticeValue(static_cast<int>(std::floor(x / 0.02F)),
                                       static_cast<int>(std::floor(y / 0.02F)), s.seed + 50U);
  if (kerbDistance < 0.025) {
    t *= 0.55F;  // the kerb face / gutter joint reads as a dark line from above
  }
  return s.kerbAlbedo * t;
}

template <typename Fields>
Eigen::Vector3f GroundTexture::islandAlbedo(const Island& island, const Eigen::Vector2d& p,
                                            double depth_m, Fields& fields, const Nearby& nearby,
                                            GroundClass* cls) const {
  const GroundStyle& s = scene_->style;
  if (depth_m < scene_->kerbWidth_m) {
    if (cls != nullptr) {
      *cls = GroundClass::Kerb;
    }
    return kerb(p, depth_m);
  }
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  if (!island.planted) {
    // Setts: small stones with dark joints.
    if (cls != nullptr) {
      *cls = GroundClass::Sidewalk;
    }
    const auto ix = static_cast<int>(std::floor(x / 0.14F));
    const auto iy = static_cast<int>(std::floor(y / 0.14F));
    float t = 0.8F + 0.35F * latticeValue(ix, iy, s.seed + 60U);
    if (periodicDistance(p.x(), 0.14) < 0.015 || periodicDistance(p.y(), 0.14) < 0.015) {
      t *= 0.6F;
    }
    return s.sidewalkAlbedo * t;
  }
  if (cls != nullptr) {
    *cls = GroundClass::Verge;
  }
  // Weeds left to grow: clumps of lush green on bare soil and dry, straw-coloured patches,
  // far rougher than the mown verges.
  Eigen::Vector3f c = verge(p, fields, nearby);
  const float clumps = 0.6F * valueNoise(x / 0.35F, y / 0.35F, s.seed + 61U) +
                       0.4F * valueNoise(x / 0.12F, y / 0.12F, s.seed + 63U);
  const float dry = valueNoise(x / 0.9F, y / 0.9F, s.seed + 62U);
  const float grain =
      0.8F + 0.4F * latticeValue(static_cast<int>(std::floor(x / 0.03F)),
                                 static_cast<int>(std::floor(y / 0.03F)), s.seed + 64U);
  const float green = smoothstep(0.45F, 0.62F, clumps);
  const Eigen::Vector3f lush = c * 1.4F + Eigen::Vector3f(0.0F, 0.03F, 0.0F);
  c = s.soilAlbedo * (1.0F - green) + lush * green;
  if (dry > 0.62F) {
    const Eigen::Vector3f straw(0.3F, 0.27F, 0.16F);
    const float w = std::min(1.0F, (dry - 0.62F) * 3.0F) * (1.0F - 0.5F * green);
    c = c * (1.0F - w) + straw * w;
  }
  return c * grain;
}

GroundTexture::GroundTexture(const SceneSpec& scene) : scene_(&scene) {
  for (const Building& b : scene.buildings) {
    buildingAxes_.emplace_back(std::cos(b.heading_rad), std::sin(b.heading_rad));
  }
  all_ = nearby(Eigen::Vector2d::Constant(-1e18), Eigen::Vector2d::Constant(1e18));
}

GroundTexture::Nearby GroundTexture::nearby(const Eigen::Vector2d& lo,
                                            const Eigen::Vector2d& hi) const {
  // Features whose bounding circle (with the margin of their effect) meets [lo, hi].
  const auto meets = [&](const Eigen::Vector2d& c, double r) {
    const Eigen::Vector2d q = c.cwiseMax(lo).cwiseMin(hi);
    return (q - c).squaredNorm() <= r * r;
  };
  Nearby n;
  for (const Patch& patch : scene_->patches) {
    if (meets(patch.centre, std::hypot(patch.halfLength_m, patch.halfWidth_m) + 0.1)) {
      n.patches.push_back(&patch);
    }
  }
  for (const Manhole& m : scene_->manholes) {
    if (meets(m.position, m.radius_m + 0.1)) {
      n.manholes.push_back(&m);
    }
  }
  for (std::size_t i = 0; i < scene_->buildings.size(); ++i) {
    const Building& b = scene_->buildings[i];
    if (meets(b.centre, 0.5 * std::hypot(b.length_m, b.width_m) + 1.6)) {
      n.buildings.push_back(i);
    }
  }
  return n;
}

float GroundTexture::field(GroundField f, float x, float y) const {
  const std::uint32_t seed = scene_->style.seed;
  switch (f) {
    case GroundField::Macro:
      return fbm(x / 7.0F, y / 7.0F, 3, seed);
    case GroundField::Fine:
      return valueNoise(x / 0.35F, y / 0.35F, seed + 1U);
    case GroundField::Oil:
      return fbm(x / 2.0F, y / 2.0F, 2, seed + 3U);
    case GroundField::CrackMask:
      return fbm(x / 25.0F, y / 25.0F, 2, seed + 5U);
    case GroundField::CrackRidge: {
      // ridge() before its fold: 0.65 n(p) + 0.35 n(2.1 p), p in 6 m units.
      const float u = x / 6.0F;
      const float v = y / 6.0F;
      return 0.65F * valueNoise(u, v, seed + 6U) +
             0.35F * valueNoise(2.1F * u, 2.1F * v, seed + 13U);
    }
    case GroundField::Stain:
      return fbm(x / 3.0F + 40.0F, y / 3.0F, 3, seed + 7U);
    case GroundField::Walk:
      return fbm(x / 3.0F, y / 3.0F, 2, seed + 20U);
    case GroundField::Mix:
      return fbm(x / 4.0F, y / 4.0F, 4, seed + 31U);
    case GroundField::Soil:
      return fbm(x / 9.0F + 100.0F, y / 9.0F, 4, seed + 33U);
    case GroundField::Count:
      break;
  }
  return 0.5F;
}

Eigen::Vector3f GroundTexture::albedo(double xEast, double yNorth, GroundClass* cls) const {
  const Eigen::Vector2d p(xEast, yNorth);
  DirectFields fields(*this, p);
  return albedoAt(p, fields, all_, cls);
}

void GroundTexture::fillTile(double x0, double y0, double texel_m, int texels,
                             Eigen::Vector3f* out) const {
  TileFields fields(*this, x0, y0, texel_m, texels);
  // Patches, manholes and building aprons are few per scene but were tested at every texel.
  const double extent = (texels - 1) * texel_m;
  const Nearby near = nearby({x0, y0}, {x0 + extent, y0 + extent});
  for (int j = 0; j < texels; ++j) {
    for (int i = 0; i < texels; ++i) {
      fields.moveTo(i, j);
      out[static_cast<std::ptrdiff_t>(j) * texels + i] =
          albedoAt(Eigen::Vector2d(x0 + i * texel_m, y0 + j * texel_m), fields, near, nullptr);
    }
  }
}

}  // namespace vp::sim
