#include "ground_texture.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace

float GroundTexture::roadTone(const Eigen::Vector2d& p, const Road* road, double along,
                              double lateral, bool inJunction) const {
  const GroundStyle& s = scene_->style;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  float tone = 1.0F + s.roadMacroVariation * (2.0F * fbm(x / 7.0F, y / 7.0F, 3, s.seed) - 1.0F);
  tone *= 1.0F + 0.5F * s.roadFineVariation *
                     (2.0F * valueNoise(x / 0.35F, y / 0.35F, s.seed + 1U) - 1.0F);
  // Aggregate grain: independent per 1.2 cm cell, averaged by the supersampling.
  tone *= 1.0F + s.roadFineVariation *
                     (2.0F * latticeValue(static_cast<int>(std::floor(x / 0.012F)),
                                          static_cast<int>(std::floor(y / 0.012F)), s.seed + 2U) -
                      1.0F);
  if (road != nullptr && !inJunction) {
    // Tyre tracks and the oil stripe follow the lanes.
    const float oilNoise = fbm(x / 2.0F, y / 2.0F, 2, s.seed + 3U);
    for (int dirSign = 0; dirSign < 2; ++dirSign) {
      const bool forward = dirSign == 0;
      const int lanes = forward ? road->lanesForward : road->lanesBackward;
      for (int k = 0; k < lanes; ++k) {
        const double dl = lateral - road->laneOffsetM(forward, k);
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
      const double slab = s.slabLengthM;
      const int slabIndex = static_cast<int>(std::floor(along / slab));
      const int laneIndex = static_cast<int>(std::floor(lateral / road->laneWidthM));
      tone *= 0.94F + 0.12F * latticeValue(slabIndex, laneIndex, s.seed + 4U);
      const double joint =
          std::min(periodicDistance(along, slab),
                   periodicDistance(lateral - road->medianHalfM, road->laneWidthM));
      if (joint < 0.015) {
        tone *= 0.6F;
      }
    }
  }
  if (s.crackDensity > 0.0F) {
    // Thin dark cracks along the zero set of a noise field, in patches of the road.
    const float mask = fbm(x / 25.0F, y / 25.0F, 2, s.seed + 5U);
    if (mask < 0.6F * s.crackDensity) {
      const float r = ridge(x / 6.0F, y / 6.0F, s.seed + 6U);
      const float w = 0.5F * s.crackWidth;
      if (r > 1.0F - w) {
        const float crack = smoothstep(1.0F - w, 1.0F - 0.2F * w, r);
        tone *= 1.0F - 0.4F * crack * smoothstep(0.0F, 0.15F, 0.6F * s.crackDensity - mask);
      }
    }
  }
  const float stain = fbm(x / 3.0F + 40.0F, y / 3.0F, 3, s.seed + 7U);
  tone *= 1.0F - 0.25F * smoothstep(0.68F, 0.8F, stain);
  for (const Patch& patch : scene_->patches) {
    const Eigen::Vector2d d = p - patch.centre;
    const double u = std::fabs(d.dot(patch.dir)) - patch.halfLengthM;
    const double v = std::fabs(d.x() * -patch.dir.y() + d.y() * patch.dir.x()) - patch.halfWidthM;
    const double edge = std::max(u, v);
    if (edge < 0.0) {
      tone *= patch.tone;
    }
    if (std::fabs(edge) < 0.04) {
      tone *= 0.65F;  // sealant along the seam
    }
  }
  for (const Manhole& m : scene_->manholes) {
    const double r = (p - m.position).norm();
    if (r < m.radiusM + 0.06) {
      if (r > m.radiusM) {
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
  const double m = road.medianHalfM;
  const double fwdEdge = -(m + road.lanesForward * road.laneWidthM);
  const double bwdEdge = m + road.lanesBackward * road.laneWidthM;
  const double lineHalf = 0.06;
  float cover = 0.0F;
  // Stop lines and crosswalks (intersection: on both approaches).
  if (intersection) {
    const double a = std::fabs(along);
    if (along < 0 && std::fabs(a - road.stopDistanceM) < 0.2 && lateral > fwdEdge && lateral < -m) {
      return 1.0F;
    }
    if (along > 0 && std::fabs(a - road.stopDistanceM) < 0.2 && lateral < bwdEdge && lateral > m) {
      return 1.0F;
    }
  }
  if (road.crosswalkCentreM < 1e8) {
    const double a = intersection ? std::fabs(along) : along;
    const double dc = std::fabs(a - road.crosswalkCentreM);
    if (dc < 0.5 * road.crosswalkWidthM && lateral > -road.rightHalfM() &&
        lateral < road.leftHalfM()) {
      if (road.zebra) {
        return periodicDistance(lateral + 0.25, 1.1) < 0.28 ? 1.0F : 0.0F;
      }
      if (dc > 0.5 * road.crosswalkWidthM - 0.3) {
        return 1.0F;
      }
      return 0.0F;
    }
  }
  if (intersection && std::fabs(along) < road.stopDistanceM) {
    return 0.0F;  // no lane lines inside the junction
  }
  // Centre line.
  switch (road.centreLine) {
    case CentreLine::DoubleYellow: {
      const double c = std::max(0.5 * m + 0.02, 0.085);
      if (band(lateral, c, 0.05) > 0 || band(lateral, -c, 0.05) > 0) {
        *yellow = true;
        return 1.0F;
      }
      break;
    }
    case CentreLine::YellowDashed:
    case CentreLine::WhiteDashed:
      if (std::fabs(lateral) < lineHalf && dashOn(along, road.dashLengthM, road.dashGapM)) {
        *yellow = road.centreLine == CentreLine::YellowDashed;
        return 1.0F;
      }
      break;
    case CentreLine::None:
      break;
  }
  // Lane lines between lanes of one direction.
  for (int k = 1; k < road.lanesForward; ++k) {
    if (band(lateral, -(m + k * road.laneWidthM), lineHalf) > 0 &&
        dashOn(along, road.dashLengthM, road.dashGapM)) {
      cover = 1.0F;
    }
  }
  for (int k = 1; k < road.lanesBackward; ++k) {
    if (band(lateral, m + k * road.laneWidthM, lineHalf) > 0 &&
        dashOn(-along, road.dashLengthM, road.dashGapM)) {
      cover = 1.0F;
    }
  }
  // Edge lines: at the parking lane, or just inside the kerb.
  if (road.edgeLines || road.parkingRightM > 0) {
    const double e = road.parkingRightM > 0 ? fwdEdge : -(road.rightHalfM() - 0.35);
    if (band(lateral, e, lineHalf) > 0) {
      cover = 1.0F;
    }
  }
  if (road.edgeLines || road.parkingLeftM > 0) {
    const double e = road.parkingLeftM > 0 ? bwdEdge : road.leftHalfM() - 0.35;
    if (band(lateral, e, lineHalf) > 0) {
      cover = 1.0F;
    }
  }
  // Parking lane: short ticks marking the stalls.
  if (road.parkingRightM > 0 && lateral < fwdEdge && periodicDistance(along, 6.5) < 0.05 &&
      lateral > fwdEdge - 0.6) {
    cover = 1.0F;
  }
  if (road.parkingLeftM > 0 && lateral > bwdEdge && periodicDistance(along, 6.5) < 0.05 &&
      lateral < bwdEdge + 0.6) {
    cover = 1.0F;
  }
  return cover;
}

float GroundTexture::lotMarkings(const ParkingLot& lot, const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - lot.centre;
  const double u = d.dot(lot.dir);
  const double v = d.dot(lot.leftNormal());
  const double halfRow = 0.5 * lot.baysPerRow * lot.bayWidthM;
  if (std::fabs(u) > halfRow + 0.06) {
    return 0.0F;
  }
  for (std::size_t r = 0; r < lot.rowOffsetsM.size(); ++r) {
    const double dv = v - lot.rowOffsetsM[r];
    if (std::fabs(dv) > 0.5 * lot.bayDepthM + 0.06) {
      continue;
    }
    const double back = -lot.rowFacing[r] * 0.5 * lot.bayDepthM;
    if (std::fabs(dv - back) < 0.06) {
      return 1.0F;
    }
    // Separators between bays, slightly shorter than the bay at the aisle end.
    if (periodicDistance(u + halfRow, lot.bayWidthM) < 0.055 &&
        lot.rowFacing[r] * dv < 0.5 * lot.bayDepthM - 0.3) {
      return 1.0F;
    }
  }
  return 0.0F;
}

Eigen::Vector3f GroundTexture::sidewalk(const Eigen::Vector2d& p, double kerbDistance) const {
  const GroundStyle& s = scene_->style;
  const Road* nearest = &scene_->roads[0];
  double best = 1e9;
  for (const Road& road : scene_->roads) {
    const double l = road.lateral(p);
    const double dd = std::max(l - road.leftHalfM(), -l - road.rightHalfM());
    if (dd < best) {
      best = dd;
      nearest = &road;
    }
  }
  const double a = nearest->along(p);
  const double q = kerbDistance - scene_->kerbWidthM;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  float tone = 1.0F + 0.12F * (2.0F * fbm(x / 3.0F, y / 3.0F, 2, s.seed + 20U) - 1.0F);
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
    const int i = static_cast<int>(std::floor(a / s.sidewalkSlabM));
    const int j = static_cast<int>(std::floor(q / s.sidewalkSlabM));
    tone *= 0.94F + 0.12F * latticeValue(i, j, s.seed + 23U);
    if (periodicDistance(a, s.sidewalkSlabM) < 0.01 ||
        (scene_->sidewalkWidthM > 2.5 && periodicDistance(q, s.sidewalkSlabM) < 0.01)) {
      tone *= 0.72F;
    }
  }
  return s.sidewalkAlbedo * tone;
}

Eigen::Vector3f GroundTexture::verge(const Eigen::Vector2d& p) const {
  const GroundStyle& s = scene_->style;
  const auto x = static_cast<float>(p.x());
  const auto y = static_cast<float>(p.y());
  // Concrete apron around buildings.
  for (const Building& b : scene_->buildings) {
    const Eigen::Vector2d d = p - b.centre;
    const Eigen::Vector2d f(std::cos(b.headingRad), std::sin(b.headingRad));
    const double u = std::fabs(d.dot(f)) - 0.5 * b.lengthM;
    const double v = std::fabs(d.x() * -f.y() + d.y() * f.x()) - 0.5 * b.widthM;
    if (std::max(u, v) < 1.5) {
      const float t =
          0.9F + 0.2F * latticeValue(static_cast<int>(std::floor(x / 0.02F)),
                                     static_cast<int>(std::floor(y / 0.02F)), s.seed + 30U);
      return s.sidewalkAlbedo * 0.9F * t;
    }
  }
  const float mix = fbm(x / 4.0F, y / 4.0F, 4, s.seed + 31U);
  Eigen::Vector3f c = s.grassA * (1.0F - mix) + s.grassB * mix;
  const float blades = latticeValue(static_cast<int>(std::floor(x / 0.025F)),
                                    static_cast<int>(std::floor(y / 0.025F)), s.seed + 32U);
  c *= 0.75F + 0.5F * blades;
  const float soil = fbm(x / 9.0F + 100.0F, y / 9.0F, 4, s.seed + 33U);
  const float soilWeight = smoothstep(s.soilShare + 0.05F, s.soilShare - 0.05F, soil);
  if (soilWeight > 0.0F) {
    const float grain = 0.85F + 0.3F * valueNoise(x / 0.08F, y / 0.08F, s.seed + 34U);
    c = c * (1.0F - soilWeight) + s.soilAlbedo * grain * soilWeight;
  }
  return c;
}

Eigen::Vector3f GroundTexture::albedo(double xEast, double yNorth, GroundClass* cls) const {
  const Eigen::Vector2d p(xEast, yNorth);
  const double d = scene_->roadDistance(p);
  const GroundStyle& s = scene_->style;
  if (d < 0.0) {
    // Inside the drivable area: road surface or parking lot.
    const ParkingLot* lot = nullptr;
    for (const ParkingLot& l : scene_->lots) {
      const Eigen::Vector2d q = p - l.centre;
      if (std::fabs(q.dot(l.dir)) < 0.5 * l.lengthM &&
          std::fabs(q.dot(l.leftNormal())) < 0.5 * l.widthM) {
        lot = &l;
      }
    }
    const Road* road = nullptr;
    double along = 0.0;
    double lateral = 0.0;
    for (const Road& r : scene_->roads) {
      const double l = r.lateral(p);
      if (l < r.leftHalfM() && l > -r.rightHalfM()) {
        road = &r;
        along = r.along(p);
        lateral = l;
        break;
      }
    }
    const bool inJunction = scene_->kind == SceneKind::Intersection && road != nullptr &&
                            std::fabs(along) < road->stopDistanceM - 0.5;
    const float tone = roadTone(p, lot != nullptr ? nullptr : road, along, lateral, inJunction);
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
        if (l < r.leftHalfM() && l > -r.rightHalfM()) {
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
  if (d < scene_->kerbWidthM) {
    if (cls != nullptr) {
      *cls = GroundClass::Kerb;
    }
    const auto x = static_cast<float>(p.x());
    const auto y = static_cast<float>(p.y());
    float t = 0.9F + 0.2F * latticeValue(static_cast<int>(std::floor(x / 0.02F)),
                                         static_cast<int>(std::floor(y / 0.02F)), s.seed + 50U);
    if (d < 0.025) {
      t *= 0.55F;  // the kerb face / gutter joint reads as a dark line from above
    }
    return s.kerbAlbedo * t;
  }
  if (d < scene_->kerbWidthM + scene_->sidewalkWidthM) {
    if (cls != nullptr) {
      *cls = GroundClass::Sidewalk;
    }
    return sidewalk(p, d);
  }
  if (cls != nullptr) {
    *cls = GroundClass::Verge;
  }
  Eigen::Vector3f c = verge(p);
  // A strip of bare soil / edging right behind the pavement.
  const double e = d - scene_->kerbWidthM - scene_->sidewalkWidthM;
  if (e < 0.15) {
    c = c * 0.6F + s.soilAlbedo * 0.4F;
  }
  return c;
}

}  // namespace vp::sim
