// evaluation/seed_reference: the figures seed 000 reports for its best variant (V_L1) on its
// own UAV data set (3 cm GSD), so that every report can print them beside ours.
//
// Contract: a fixed table, transcribed from the seed's Tables 1-5 and the text on its
// Figure 2 (section 5.2). Each figure names the measure key used by the evaluation reports,
// its value in the report's unit (shares as fractions in [0, 1], metres, degrees) and where in
// the seed it comes from. The seed's data are not ours: the figures are a yardstick, not a
// test expectation. Approximate figures (read from the text, not a table) say so.
#pragma once

#include <optional>
#include <span>
#include <string_view>

namespace vp::evaluation {

struct SeedFigure {
  std::string_view measure;  // report key, e.g. "precision", "e_d2d_m"
  double value = 0.0;        // fraction, m or deg
  std::string_view source;   // "Table 1, UAV V_L1" ...
  bool approximate = false;  // read from the text ("about 85 %"), not from a table
};

std::span<const SeedFigure> seedFigures();
std::optional<SeedFigure> seedFigure(std::string_view measure);

}  // namespace vp::evaluation
