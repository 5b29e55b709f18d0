// vp_asm_learn: learns the Active Shape Model of seed 000 (Eq. 1) from generated cars.
//
// Draws --models-per-type keypoint models of each of the six car types with the parametric
// generator (tools/simulator/car_generator.hpp, seeded with --seed), keeps the last --holdout share
// of each type aside, computes the mean and the principal components of the training models (the 3
// x 36 keypoints as one 108-vector), keeps --components of them, fits every training model to get
// the per-type gamma priors, and writes the versioned ASM file (docs/asm.md). It prints the
// explained variance share and the held-out reconstruction errors for n_s = 1..8 so that the choice
// of n_s can be judged.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "car_generator.hpp"
#include "shape/vehicle_model.hpp"

namespace {

using vp::shape::kCarTypeCount;
using vp::shape::KeypointModel;
using vp::shape::kKeypointCount;
using vp::shape::kMaxShapeComponents;
using vp::shape::VehicleType;

constexpr int kVectorSize = 3 * kKeypointCount;

struct Options {
  std::string out;
  int components = 3;
  int modelsPerType = 200;
  std::uint64_t seed = 1;
  double holdout = 0.2;
};

void printHelp() {
  std::puts(
      "Usage: vp_asm_learn --out PATH [options]\n"
      "\n"
      "Learns the Active Shape Model (seed 000, Eq. 1: M(g) = m + sum_s g_s sigma_s e_s) from\n"
      "cars drawn by the parametric generator and writes the ASM file (docs/asm.md).\n"
      "\n"
      "Options:\n"
      "  --out PATH              ASM file to write (required)\n"
      "  --components N          shape components n_s to keep, 1..8 (default 3)\n"
      "  --models-per-type N     cars drawn per type (six types; default 200)\n"
      "  --seed N                generator seed (default 1)\n"
      "  --holdout F             share of each type kept aside for the error report,\n"
      "                          0 <= F < 1 (default 0.2)\n"
      "  -h, --help              this text\n"
      "\n"
      "The shipped models/asm/default_asm.yaml is made by:\n"
      "  vp_asm_learn --out models/asm/default_asm.yaml --components 3 --models-per-type 200 "
      "--seed 1 --holdout 0.2\n");
}

bool parseInt(const std::string& text, long long lo, long long hi, long long* out) {
  errno = 0;
  char* end = nullptr;
  const long long value = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || value < lo || value > hi) {
    return false;
  }
  *out = value;
  return true;
}

// Returns 0 to go on, otherwise the exit code.
int parseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      printHelp();
      return -1;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "vp_asm_learn: %s needs a value (see --help)\n", arg.c_str());
      return 2;
    }
    const std::string value = argv[++i];
    long long number = 0;
    if (arg == "--out") {
      o->out = value;
    } else if (arg == "--components") {
      if (!parseInt(value, 1, kMaxShapeComponents, &number)) {
        std::fprintf(stderr, "vp_asm_learn: --components must be 1..%d, got '%s'\n",
                     kMaxShapeComponents, value.c_str());
        return 2;
      }
      o->components = static_cast<int>(number);
    } else if (arg == "--models-per-type") {
      if (!parseInt(value, 2, 1000000, &number)) {
        std::fprintf(stderr, "vp_asm_learn: --models-per-type must be 2..1000000, got '%s'\n",
                     value.c_str());
        return 2;
      }
      o->modelsPerType = static_cast<int>(number);
    } else if (arg == "--seed") {
      if (!parseInt(value, 0, INT64_MAX, &number)) {
        std::fprintf(stderr, "vp_asm_learn: --seed must be a non-negative integer, got '%s'\n",
                     value.c_str());
        return 2;
      }
      o->seed = static_cast<std::uint64_t>(number);
    } else if (arg == "--holdout") {
      char* end = nullptr;
      o->holdout = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || !(o->holdout >= 0.0 && o->holdout < 1.0)) {
        std::fprintf(stderr, "vp_asm_learn: --holdout must be in [0, 1), got '%s'\n",
                     value.c_str());
        return 2;
      }
    } else {
      std::fprintf(stderr, "vp_asm_learn: unknown option '%s' (see --help)\n", arg.c_str());
      return 2;
    }
  }
  if (o->out.empty()) {
    std::fprintf(stderr, "vp_asm_learn: --out PATH is required (see --help)\n");
    return 2;
  }
  return 0;
}

struct Sample {
  VehicleType type = VehicleType::Sedan;
  KeypointModel keypoints;
};

Eigen::Matrix<double, 1, kVectorSize> asRow(const KeypointModel& k) {
  return Eigen::Map<const Eigen::Matrix<double, 1, kVectorSize>>(k.data());
}

KeypointModel asModel(const Eigen::VectorXd& v) {
  return Eigen::Map<const KeypointModel>(v.data());
}

struct ErrorSums {
  double sum3d = 0.0;
  double sumXy = 0.0;
  double sumZ = 0.0;
  double sumAll = 0.0;
  double max3d = 0.0;
  long evaluated = 0;
  long all = 0;
  int models = 0;
  double rms() const { return std::sqrt(sum3d / static_cast<double>(std::max(evaluated, 1L))); }
};

// Fits every model (all keypoints, no prior: the projection onto the components) and sums the
// keypoint errors: 3D, planimetric, height over the evaluation keypoints, 3D over all.
ErrorSums reconstructionErrors(const vp::shape::ActiveShapeModel& asm_,
                               const std::vector<Sample>& samples) {
  ErrorSums e;
  std::array<bool, kKeypointCount> all{};
  all.fill(true);
  std::array<bool, kKeypointCount> evaluation{};
  for (int k : vp::shape::evaluationKeypoints()) {
    evaluation[static_cast<std::size_t>(k)] = true;
  }
  for (const Sample& s : samples) {
    const auto gamma = asm_.fit(s.keypoints, all, 0.0);
    if (!gamma) {
      continue;
    }
    const KeypointModel diff = asm_.shape(*gamma) - s.keypoints;
    for (int k = 0; k < kKeypointCount; ++k) {
      const double d2 = diff.col(k).squaredNorm();
      e.sumAll += d2;
      ++e.all;
      if (evaluation[static_cast<std::size_t>(k)]) {
        e.sum3d += d2;
        e.sumXy += diff.col(k).head<2>().squaredNorm();
        e.sumZ += diff(2, k) * diff(2, k);
        e.max3d = std::max(e.max3d, std::sqrt(d2));
        ++e.evaluated;
      }
    }
    ++e.models;
  }
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  const int parsed = parseOptions(argc, argv, &o);
  if (parsed != 0) {
    return parsed < 0 ? 0 : parsed;
  }

  std::mt19937_64 rng(o.seed);
  const int heldPerType = static_cast<int>(std::lround(o.holdout * o.modelsPerType));
  const int trainPerType = o.modelsPerType - heldPerType;
  if (trainPerType < 2) {
    std::fprintf(stderr, "vp_asm_learn: fewer than 2 training models per type\n");
    return 2;
  }
  std::vector<Sample> train;
  std::vector<Sample> held;
  for (int t = 0; t < kCarTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    for (int i = 0; i < o.modelsPerType; ++i) {
      Sample s{type, vp::shape::generateCar(type, rng).keypoints};
      // The draws are independent, so the last ones of each type are a random hold-out set.
      (i < trainPerType ? train : held).push_back(s);
    }
  }
  if (static_cast<int>(train.size()) <= kMaxShapeComponents) {
    std::fprintf(stderr, "vp_asm_learn: too few training models\n");
    return 2;
  }

  // Mean and covariance of the 108-vectors; principal components, largest first.
  Eigen::MatrixXd x(static_cast<Eigen::Index>(train.size()), kVectorSize);
  for (std::size_t i = 0; i < train.size(); ++i) {
    x.row(static_cast<Eigen::Index>(i)) = asRow(train[i].keypoints);
  }
  const Eigen::RowVectorXd mean = x.colwise().mean();
  x.rowwise() -= mean;
  const Eigen::MatrixXd covariance = (x.transpose() * x) / static_cast<double>(x.rows() - 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
  if (solver.info() != Eigen::Success) {
    std::fprintf(stderr, "vp_asm_learn: the eigen decomposition failed\n");
    return 1;
  }
  const double total = covariance.trace();
  std::vector<double> eigenvalues;
  std::vector<KeypointModel> vectors;
  const KeypointModel meanModel = asModel(mean.transpose());
  for (int s = 0; s < kMaxShapeComponents; ++s) {
    const Eigen::Index column = kVectorSize - 1 - s;
    eigenvalues.push_back(std::max(solver.eigenvalues()(column), 0.0));
    KeypointModel e = asModel(solver.eigenvectors().col(column));
    // Fixed sign: a positive gamma moves the keypoints away from the origin (a bigger car).
    if (e.cwiseProduct(meanModel).sum() < 0.0) {
      e = -e;
    }
    vectors.push_back(e);
  }
  std::vector<double> share(kMaxShapeComponents);
  double cumulative = 0.0;
  for (int s = 0; s < kMaxShapeComponents; ++s) {
    cumulative += eigenvalues[static_cast<std::size_t>(s)];
    share[static_cast<std::size_t>(s)] = cumulative / total;
  }

  // Held-out reconstruction errors for every n_s; the chosen one goes into the file.
  std::printf("vp_asm_learn: %zu training and %zu held-out cars (seed %llu, %d per type)\n\n",
              train.size(), held.size(), static_cast<unsigned long long>(o.seed), o.modelsPerType);
  std::printf(
      "n_s  explained  held-out error over the 24 evaluation keypoints (m)       all 36\n"
      "     variance   RMS 3D   max 3D   E_D2D (xy RMS)  E_dH (z RMS)          RMS 3D\n");
  vp::shape::ActiveShapeModel chosen;
  std::string why;
  for (int n = 1; n <= kMaxShapeComponents; ++n) {
    vp::shape::ActiveShapeModel model;
    const auto count = static_cast<std::size_t>(n);
    if (!model.init(meanModel, std::span<const double>(eigenvalues.data(), count),
                    std::span<const KeypointModel>(vectors.data(), count), share[count - 1],
                    &why)) {
      std::fprintf(stderr, "vp_asm_learn: %s\n", why.c_str());
      return 1;
    }
    const ErrorSums e = reconstructionErrors(model, held);
    const double evaluated = static_cast<double>(std::max(e.evaluated, 1L));
    if (held.empty()) {
      std::printf("%3d  %8.4f   (no held-out cars)\n", n, share[count - 1]);
    } else {
      std::printf("%3d  %8.4f   %6.4f   %6.4f   %6.4f          %6.4f                %6.4f\n", n,
                  share[count - 1], e.rms(), e.max3d, std::sqrt(e.sumXy / evaluated),
                  std::sqrt(e.sumZ / evaluated),
                  std::sqrt(e.sumAll / static_cast<double>(std::max(e.all, 1L))));
    }
    if (n == o.components) {
      chosen = model;
      chosen.setHeldOutError({e.rms(), e.max3d, std::sqrt(e.sumXy / evaluated),
                              std::sqrt(e.sumZ / evaluated), e.models});
    }
  }

  // Per-type gamma priors from the training cars.
  const int n = o.components;
  std::array<bool, kKeypointCount> all{};
  all.fill(true);
  std::printf("\ngamma priors (mean per component) from the training cars:\n");
  for (int t = 0; t < kCarTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    std::vector<Eigen::VectorXd> gammas;
    for (const Sample& s : train) {
      if (s.type != type) {
        continue;
      }
      const auto gamma = chosen.fit(s.keypoints, all, 0.0);
      if (gamma) {
        Eigen::VectorXd g(n);
        for (int i = 0; i < n; ++i) {
          g(i) = gamma->gamma[static_cast<std::size_t>(i)];
        }
        gammas.push_back(g);
      }
    }
    vp::shape::TypePrior prior;
    prior.sampleCount = static_cast<int>(gammas.size());
    Eigen::VectorXd m = Eigen::VectorXd::Zero(n);
    for (const auto& g : gammas) {
      m += g;
    }
    m /= static_cast<double>(std::max<std::size_t>(gammas.size(), 1));
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
    for (const auto& g : gammas) {
      c += (g - m) * (g - m).transpose();
    }
    c /= static_cast<double>(std::max<std::size_t>(gammas.size(), 2) - 1);
    std::printf("  %-8s (%3d cars):", vp::shape::toString(type), prior.sampleCount);
    for (int i = 0; i < n; ++i) {
      prior.mean[static_cast<std::size_t>(i)] = m(i);
      std::printf(" %+7.3f", m(i));
    }
    std::printf("   sd:");
    for (int i = 0; i < n; ++i) {
      std::printf(" %5.3f", std::sqrt(c(i, i)));
    }
    std::printf("\n");
    prior.covariance.topLeftCorner(n, n) = c;
    chosen.setTypePrior(type, prior);
  }

  if (!chosen.save(o.out, &why)) {
    std::fprintf(stderr, "vp_asm_learn: %s\n", why.c_str());
    return 1;
  }
  // A comment header records how the file was made (YAML ignores it).
  std::stringstream body;
  {
    std::ifstream in(o.out);
    body << in.rdbuf();
  }
  std::ofstream outFile(o.out, std::ios::trunc);
  outFile << "# Active Shape Model of seed 000 (Eq. 1), format: docs/asm.md. Made by:\n#";
  outFile << " vp_asm_learn --out " << o.out << " --components " << o.components
          << " --models-per-type " << o.modelsPerType << " --seed " << o.seed << " --holdout "
          << o.holdout << "\n"
          << body.str();
  outFile.close();
  if (!outFile) {
    std::fprintf(stderr, "vp_asm_learn: %s: cannot write the file\n", o.out.c_str());
    return 1;
  }
  std::printf("\nwrote %s: n_s = %d, explained variance share %.4f, held-out RMS %.4f m\n",
              o.out.c_str(), n, chosen.explainedVarianceShare(), chosen.heldOutError().rms_m);
  return 0;
}
