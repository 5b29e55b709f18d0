// vp_traffic_eval: the traffic analysis measured against ground truth (docs/traffic.md,
// "Evaluation"). Thin: the work is in traffic_eval.cpp.
#include <iostream>
#include <string>
#include <vector>

#include "traffic_eval.hpp"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return vp::traffic_eval::runTrafficEval(args, std::cout, std::cerr);
}
