// config/tracking_section: `tracking:` into the tracker's own options (tracking::TrackerConfig,
// its MotionNoise and AssociationParams). The file gives the heading noise in degrees, the
// motion model keeps radians.
#include "config/sections.hpp"
#include "geometry/rotated_box.hpp"  // kPi
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

// The publisher's table of published tracks holds 1024 (VehicleStatePublisher::kMaxTracks).
const Range kMaxTracksRange = Range::closed(1.0, 1024.0);
const Range kConfirmHitsRange = Range::closed(1.0, 100.0);
const Range kConfirmWholeHitsRange = Range::closed(0.0, 100.0);
const Range kTrackTimeRangeS = Range::closed(0.0, 60.0);
const Range kSpeedRange_mps = Range::closed(0.0, 50.0);
const Range kFlipVotesRange = Range::closed(1.0, 100.0);
const Range kEvidenceWeightRange = Range{0.0, 1.0, true};
const Range kShapeWeightRange = Range{0.0, 1e6, true};
const Range kGateDistanceRange_m = Range{0.0, 100.0, true};
const Range kMeasurementPositionRange_m = Range{0.0, 10.0, true};   // (0, 10] m
const Range kMeasurementHeadingRange_deg = Range{0.0, 90.0, true};  // (0, 90] deg
const Range kNoiseFactorRange = Range::closed(1.0, 1000.0);
const Range kLongVehicleLengthRange_m = Range::closed(0.0, 100.0);

}  // namespace

tracking::TrackerConfig readTracking(MapReader section) {
  const tracking::TrackerConfig d;
  tracking::TrackerConfig t;
  t.maxTracks = section.integer("max_tracks", kMaxTracksRange, d.maxTracks);
  t.confirmHits = section.integer("confirm_hits", kConfirmHitsRange, d.confirmHits);
  t.maxTentativeGap_s =
      section.number("max_tentative_gap_s", kTrackTimeRangeS, d.maxTentativeGap_s);
  t.maxLost_s = section.number("max_lost_s", kTrackTimeRangeS, d.maxLost_s);
  t.maxLostAtFrameEdge_s =
      section.number("max_lost_at_edge_s", kTrackTimeRangeS, d.maxLostAtFrameEdge_s);
  t.maxCoast_s = section.number("coast_s", kTrackTimeRangeS, d.maxCoast_s);
  t.movingSpeed_mps = section.number("moving_speed_mps", kSpeedRange_mps, d.movingSpeed_mps);
  t.flipVotes = section.integer("flip_votes", kFlipVotesRange, d.flipVotes);
  t.typeEvidenceWeight =
      section.number("type_evidence_weight", kEvidenceWeightRange, d.typeEvidenceWeight);
  t.shapeMaxWeight = section.number("shape_max_weight", kShapeWeightRange, d.shapeMaxWeight);
  t.association.maxDistance_m =
      section.number("max_distance_m", kGateDistanceRange_m, d.association.maxDistance_m);
  // The scores are floats in the tracker; low_score's bound is the high score as written.
  const double highScore =
      section.number("high_score", kProbabilityRange, floatAsDecimal(d.association.highScore));
  t.association.highScore = static_cast<float>(highScore);
  t.association.lowScore = static_cast<float>(section.number(
      "low_score", Range::closed(0.0, highScore), floatAsDecimal(d.association.lowScore)));
  t.noise.measurementPosition_m = section.number(
      "measurement_position_m", kMeasurementPositionRange_m, d.noise.measurementPosition_m);
  // Converted only when given: the default stays the motion model's own radians.
  if (section.has("measurement_heading_deg")) {
    t.noise.measurementHeading_rad =
        section.number("measurement_heading_deg", kMeasurementHeadingRange_deg, kRequired) *
        (geometry::kPi / 180.0);
  }
  t.noise.steeringDecay_s =
      section.number("steering_decay_s", kTrackTimeRangeS, d.noise.steeringDecay_s);
  t.confirmWholeHits =
      section.integer("confirm_whole_hits", kConfirmWholeHitsRange, d.confirmWholeHits);
  t.confirmHitsAnyway =
      section.integer("confirm_hits_anyway", kConfirmHitsRange, d.confirmHitsAnyway);
  t.confirmHitsStanding =
      section.integer("confirm_hits_standing", kConfirmHitsRange, d.confirmHitsStanding);
  t.confirmHitsLarge = section.integer("confirm_hits_large", kConfirmHitsRange, d.confirmHitsLarge);
  t.confirmMinScore = section.number("confirm_min_score", kProbabilityRange, d.confirmMinScore);
  t.partialInsideShare =
      section.number("partial_inside_share", kProbabilityRange, d.partialInsideShare);
  t.partialAlongNoiseFactor =
      section.number("partial_along_noise_factor", kNoiseFactorRange, d.partialAlongNoiseFactor);
  t.longVehicleLength_m =
      section.number("long_vehicle_length_m", kLongVehicleLengthRange_m, d.longVehicleLength_m);
  t.maxOverlap = section.number("max_overlap", kProbabilityRange, d.maxOverlap);
  section.warnUnknownKeys();
  return t;
}

}  // namespace vp::config::detail
