#include "evaluation/seed_reference.hpp"

#include <array>

namespace vp::evaluation {
namespace {

// Seed 000, section 5.2, UAV data set, variant V_L1 (its best on every measure).
constexpr std::array<SeedFigure, 23> kSeedFigures{{
    {"precision", 0.816, "Table 1, UAV V_L1", false},
    {"recall", 0.765, "Table 1, UAV V_L1", false},
    {"f1", 0.789, "Table 1, UAV V_L1", false},
    {"position_median_m", 0.05, "Table 2, UAV V_L1 (eps_mae^t)", false},
    {"position_mad_m", 0.07, "Table 2, UAV V_L1 (sigma_MAD^t)", false},
    {"orientation_median_deg", 2.8, "Table 2, UAV V_L1 (eps_mae^theta)", false},
    {"orientation_mad_deg", 2.7, "Table 2, UAV V_L1 (sigma_MAD^theta)", false},
    {"orientation_share_below_10deg", 0.85, "Sec. 5.2.2 on Figure 2 ('about 85 %')", true},
    {"orientation_flip_share", 0.05, "Sec. 5.2.2 on Figure 2 ('about 5 %' near 180 deg)", true},
    {"type_f1_estate", 0.722, "Table 3, UAV V_L1 (EC)", false},
    {"type_f1_compact", 0.641, "Table 3, UAV V_L1 (CC)", false},
    {"type_f1_sports", 0.415, "Table 3, UAV V_L1 (SC)", false},
    {"type_f1_sedan", 0.702, "Table 3, UAV V_L1 (Sed.)", false},
    {"type_f1_suv", 0.314, "Table 3, UAV V_L1 (SUV)", false},
    {"type_f1_van", 0.369, "Table 3, UAV V_L1 (Van)", false},
    {"type_oa1", 0.658, "Table 4, UAV V_L1", false},
    {"type_oa2", 0.781, "Table 4, UAV V_L1", false},
    {"rms_length_m", 0.11, "Table 5, UAV V_L1 (E_l)", false},
    {"rms_width_m", 0.08, "Table 5, UAV V_L1 (E_w)", false},
    {"rms_height_m", 0.21, "Table 5, UAV V_L1 (E_h)", false},
    {"e_d2d_m", 0.07, "Table 5, UAV V_L1 (E_D2D)", false},
    {"e_dh_m", 0.24, "Table 5, UAV V_L1 (E_dH)", false},
    {"gsd_m", 0.03, "Sec. 4.1 (UAV data set: about 3 cm)", true},
}};

}  // namespace

std::span<const SeedFigure> seedFigures() {
  return kSeedFigures;
}

std::optional<SeedFigure> seedFigure(std::string_view measure) {
  for (const SeedFigure& figure : kSeedFigures) {
    if (figure.measure == measure) {
      return figure;
    }
  }
  return std::nullopt;
}

}  // namespace vp::evaluation
