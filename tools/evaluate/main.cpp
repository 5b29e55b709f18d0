// vp_evaluate: the evaluation report of seed 000's measures (docs/evaluation.md). Thin: the
// work is in evaluate_app.cpp.
#include <iostream>
#include <string>
#include <vector>

#include "evaluate_app.hpp"

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string commandLine = "vp_evaluate";
  for (const std::string& arg : args) {
    const bool plain = !arg.empty() && arg.find_first_of(" \t'\"$`\\()") == std::string::npos;
    commandLine += " " + (plain ? arg : "'" + arg + "'");
  }
  vp::evaluate::EvaluateOptions options;
  std::string why;
  if (!vp::evaluate::parseArguments(args, &options, &why)) {
    std::cerr << "vp_evaluate: " << why << "\n";
    return 2;
  }
  options.commandLine = commandLine;
  return vp::evaluate::runEvaluate(options, std::cout, std::cerr);
}
