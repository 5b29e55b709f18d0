// Tests of shape/vehicle_model: the keypoint topology, the closed car mesh and the ASM
// (Eq. 1, fit, the versioned file, no allocation), and the shipped default model.
#include "shape/vehicle_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "alloc_counter.hpp"
#include "car_generator.hpp"

namespace vp::shape {
namespace {

const std::string kDefaultAsm = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";

std::array<bool, kKeypointCount> allKeypoints() {
  std::array<bool, kKeypointCount> mask{};
  mask.fill(true);
  return mask;
}

// The 12 keypoints on the upper outline, the ones a near-nadir camera sees best.
std::array<bool, kKeypointCount> upperKeypoints() {
  std::array<bool, kKeypointCount> mask{};
  for (const char* name :
       {"bonnet_front_corner_left", "bonnet_front_corner_right", "windscreen_base_left",
        "windscreen_base_right", "roof_front_left", "roof_front_right", "roof_rear_left",
        "roof_rear_right", "rear_window_base_left", "rear_window_base_right",
        "tail_top_corner_left", "tail_top_corner_right"}) {
    mask[static_cast<std::size_t>(*keypointIndex(name))] = true;
  }
  return mask;
}

// A model learned in the test (like vp_asm_learn, smaller) so that the ASM tests do not
// depend on the shipped file.
ActiveShapeModel learnModel(int components, std::uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  constexpr int kPerType = 20;
  Eigen::MatrixXd x(kPerType * kCarTypeCount, 3 * kKeypointCount);
  for (int t = 0; t < kCarTypeCount; ++t) {
    for (int i = 0; i < kPerType; ++i) {
      const KeypointModel k = generateCar(static_cast<VehicleType>(t), rng).keypoints;
      x.row(t * kPerType + i) = Eigen::Map<const Eigen::RowVectorXd>(k.data(), k.size());
    }
  }
  const Eigen::RowVectorXd mean = x.colwise().mean();
  x.rowwise() -= mean;
  const Eigen::MatrixXd cov = x.transpose() * x / static_cast<double>(x.rows() - 1);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(cov);
  std::vector<double> values;
  std::vector<KeypointModel> vectors;
  for (int s = 0; s < components; ++s) {
    const Eigen::Index c = cov.rows() - 1 - s;
    values.push_back(solver.eigenvalues()(c));
    vectors.push_back(Eigen::Map<const KeypointModel>(solver.eigenvectors().col(c).data()));
  }
  ActiveShapeModel model;
  std::string why;
  EXPECT_TRUE(model.init(Eigen::Map<const KeypointModel>(mean.data()), values, vectors, 0.9, &why))
      << why;
  return model;
}

ShapeParams params(std::initializer_list<float> gamma) {
  ShapeParams p;
  for (float g : gamma) {
    p.gamma[static_cast<std::size_t>(p.count++)] = g;
  }
  return p;
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "vp_shape_" + name;
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

std::string readText(const std::string& path) {
  std::stringstream ss;
  ss << std::ifstream(path).rdbuf();
  return ss.str();
}

std::string replaceOnce(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) {
    text.replace(at, from.size(), to);
  }
  return text;
}

// --- Topology ---------------------------------------------------------------------------

TEST(Topology, KeypointNamesAreUniqueAndIndexed) {
  std::set<std::string> names;
  for (int k = 0; k < kKeypointCount; ++k) {
    const std::string name = keypointNames()[static_cast<std::size_t>(k)];
    EXPECT_TRUE(names.insert(name).second) << name;
    EXPECT_EQ(keypointIndex(name), k);
  }
  EXPECT_EQ(names.size(), static_cast<std::size_t>(kKeypointCount));
  EXPECT_FALSE(keypointIndex("no_such_keypoint").has_value());
}

TEST(Topology, EvaluationKeypointsAreDistinctAndValid) {
  std::set<int> seen;
  for (int k : evaluationKeypoints()) {
    EXPECT_GE(k, 0);
    EXPECT_LT(k, kKeypointCount);
    EXPECT_TRUE(seen.insert(k).second) << k;
  }
  EXPECT_EQ(seen.size(), static_cast<std::size_t>(kEvaluationKeypointCount));
  for (int w : wheelCentreKeypoints()) {
    EXPECT_TRUE(seen.count(w)) << "wheel centres are evaluated";
  }
}

TEST(Topology, KeypointsComeInLeftRightPairs) {
  for (int k = 0; k < kKeypointCount; k += 2) {
    std::string left = keypointNames()[static_cast<std::size_t>(k)];
    const std::string right = keypointNames()[static_cast<std::size_t>(k + 1)];
    ASSERT_EQ(left.substr(left.size() - 5), "_left");
    EXPECT_EQ(left.substr(0, left.size() - 5) + "_right", right);
  }
}

TEST(Topology, MeshTrianglesUseValidDistinctVertices) {
  ASSERT_EQ(mesh().size(), 60u);
  std::set<int> used;
  for (const Triangle& t : mesh()) {
    for (int i = 0; i < 3; ++i) {
      ASSERT_LT(t.v[static_cast<std::size_t>(i)], kKeypointCount);
      used.insert(t.v[static_cast<std::size_t>(i)]);
    }
    EXPECT_NE(t.v[0], t.v[1]);
    EXPECT_NE(t.v[1], t.v[2]);
    EXPECT_NE(t.v[0], t.v[2]);
  }
  // Every keypoint but the four wheel centres (drawn as cylinders) is a mesh vertex.
  EXPECT_EQ(used.size(), static_cast<std::size_t>(kKeypointCount - kWheelCount));
  for (int w : wheelCentreKeypoints()) {
    EXPECT_FALSE(used.count(w));
  }
}

// Closed and consistently wound: every directed edge a->b occurs once and b->a once.
template <class TriangleRange>
void expectClosed(const TriangleRange& triangles) {
  std::map<std::pair<int, int>, int> directed;
  for (const Triangle& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      ++directed[{t.v[static_cast<std::size_t>(i)], t.v[static_cast<std::size_t>((i + 1) % 3)]}];
    }
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge " << edge.first << "->" << edge.second << " used twice";
    const auto reverse = directed.find({edge.second, edge.first});
    EXPECT_TRUE(reverse != directed.end() && reverse->second == 1)
        << "edge " << edge.first << "-" << edge.second << " is a boundary edge";
  }
}

TEST(Topology, MeshIsClosedWithConsistentWinding) {
  expectClosed(mesh());
}

TEST(Topology, MeshLabelsEveryPartWithLightsAtTheRightEnd) {
  std::mt19937_64 rng(3);
  const KeypointModel car = generateCar(VehicleType::Sedan, rng).keypoints;
  std::map<SurfacePart, int> counts;
  for (const Triangle& t : mesh()) {
    ++counts[t.part];
    const double x = (car.col(t.v[0]) + car.col(t.v[1]) + car.col(t.v[2])).x() / 3.0;
    if (t.part == SurfacePart::HeadLight) {
      EXPECT_GT(x, 2.0);
    }
    if (t.part == SurfacePart::TailLight) {
      EXPECT_LT(x, -2.0);
    }
  }
  for (int p = 0; p <= static_cast<int>(SurfacePart::Underbody); ++p) {
    EXPECT_GT(counts[static_cast<SurfacePart>(p)], 0) << toString(static_cast<SurfacePart>(p));
  }
  EXPECT_EQ(counts[SurfacePart::HeadLight], 2);
  EXPECT_EQ(counts[SurfacePart::TailLight], 2);
}

TEST(Topology, VehicleTypeNamesRoundTrip) {
  for (int t = 0; t < kVehicleTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    EXPECT_EQ(vehicleTypeFromString(toString(type)), type);
  }
  EXPECT_EQ(vehicleTypeFromString("SUV"), VehicleType::Suv);
  EXPECT_FALSE(vehicleTypeFromString("tractor").has_value());
}

TEST(Topology, LargeVehiclesAreTheTransportersOfSeed002) {
  for (int t = 0; t < kCarTypeCount; ++t) {
    EXPECT_EQ(categoryOf(static_cast<VehicleType>(t)), VehicleCategory::Car);
  }
  EXPECT_EQ(categoryOf(VehicleType::Large), VehicleCategory::Transporter);
  EXPECT_STREQ(toString(VehicleCategory::Car), "car");
  EXPECT_STREQ(toString(VehicleCategory::Transporter), "transporter");
}

TEST(Topology, WheelRadiusIsTheWheelCentreHeight) {
  std::mt19937_64 rng(5);
  const GeneratedCar car = generateCar(VehicleType::Suv, rng);
  for (int w = 0; w < kWheelCount; ++w) {
    EXPECT_DOUBLE_EQ(wheelRadius(car.keypoints, w), car.dimensions.wheelRadius_m);
  }
}

// --- Active Shape Model ------------------------------------------------------------------

TEST(Asm, ShapeAtZeroGammaIsTheMean) {
  const ActiveShapeModel model = learnModel(3);
  EXPECT_EQ(model.shape(ShapeParams{}), model.mean());
  EXPECT_EQ(model.shape(params({0.0F, 0.0F, 0.0F})), model.mean());
}

TEST(Asm, ShapeIsEquationOne) {
  const ActiveShapeModel model = learnModel(3);
  const ShapeParams p = params({0.5F, -1.25F, 2.0F});
  KeypointModel expected = model.mean();
  for (int s = 0; s < 3; ++s) {
    expected += static_cast<double>(p.gamma[static_cast<std::size_t>(s)]) * model.sigma(s) *
                model.eigenvector(s);
  }
  EXPECT_LT((model.shape(p) - expected).cwiseAbs().maxCoeff(), 1e-12);
  // Linear: M(a + b) - m = (M(a) - m) + (M(b) - m); extra gamma entries are ignored.
  const ShapeParams a = params({1.0F, 0.0F, -0.5F});
  const ShapeParams b = params({-0.25F, 0.75F, 0.5F});
  const ShapeParams sum = params({0.75F, 0.75F, 0.0F, 9.0F});
  const KeypointModel lhs = model.shape(sum) - model.mean();
  const KeypointModel rhs = (model.shape(a) - model.mean()) + (model.shape(b) - model.mean());
  EXPECT_LT((lhs - rhs).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Asm, FitRecoversGammaFromAllKeypoints) {
  const ActiveShapeModel model = learnModel(3);
  const ShapeParams truth = params({0.8F, -1.3F, 0.45F});
  const auto fitted = model.fit(model.shape(truth), allKeypoints(), 0.0);
  ASSERT_TRUE(fitted.has_value());
  ASSERT_EQ(fitted->count, 3);
  for (int s = 0; s < 3; ++s) {
    EXPECT_NEAR(fitted->gamma[static_cast<std::size_t>(s)],
                truth.gamma[static_cast<std::size_t>(s)], 1e-6);
  }
}

TEST(Asm, FitRecoversGammaFromTheUpperKeypoints) {
  const ActiveShapeModel model = learnModel(3);
  const ShapeParams truth = params({-1.1F, 0.6F, 1.4F});
  const KeypointModel observed = model.shape(truth);
  const auto exact = model.fit(observed, upperKeypoints(), 0.0);
  const auto regularised = model.fit(observed, upperKeypoints());  // default prior
  ASSERT_TRUE(exact.has_value());
  ASSERT_TRUE(regularised.has_value());
  for (std::size_t s = 0; s < 3; ++s) {
    EXPECT_NEAR(exact->gamma[s], truth.gamma[s], 1e-5);
    EXPECT_NEAR(regularised->gamma[s], truth.gamma[s], 0.05);
  }
}

TEST(Asm, FitRejectsTooFewOrNonFiniteKeypoints) {
  const ActiveShapeModel model = learnModel(3);
  std::array<bool, kKeypointCount> one{};
  one[4] = true;
  EXPECT_FALSE(model.fit(model.mean(), one).has_value());
  std::array<bool, kKeypointCount> none{};
  EXPECT_FALSE(model.fit(model.mean(), none).has_value());
  KeypointModel bad = model.mean();
  bad(1, 7) = std::nan("");
  EXPECT_FALSE(model.fit(bad, allKeypoints()).has_value());
  bad(1, 7) = 0.0;
  EXPECT_TRUE(model.fit(bad, allKeypoints()).has_value());
  // Two keypoints are the minimum; with the prior they always give an answer.
  std::array<bool, kKeypointCount> pair{};
  pair[10] = pair[11] = true;
  const auto withPrior = model.fit(model.mean(), pair, 1e-3);
  EXPECT_TRUE(withPrior.has_value());
}

TEST(Asm, ShapeAndFitDoNotAllocate) {
  const ActiveShapeModel model = learnModel(3);
  const ShapeParams p = params({0.3F, -0.2F, 0.9F});
  const auto all = allKeypoints();
  const auto upper = upperKeypoints();
  double sink = 0.0;
  vp::test::AllocationCounter counter;
  for (int i = 0; i < 10; ++i) {
    const KeypointModel k = model.shape(p);
    const auto a = model.fit(k, all);
    const auto b = model.fit(k, upper, 0.0);
    sink += k(0, 0) + static_cast<double>(a ? a->gamma[0] : 0.0F) +
            static_cast<double>(b ? b->gamma[1] : 0.0F);
  }
  counter.stop();
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(Asm, InitValidatesItsInput) {
  KeypointModel e = KeypointModel::Zero();
  e(0, 0) = 1.0;
  const std::vector<KeypointModel> twice = {e, e};  // not orthogonal
  const std::vector<double> values = {1.0, 0.5};
  ActiveShapeModel model;
  std::string why;
  EXPECT_FALSE(model.init(KeypointModel::Zero(), values, twice, 0.9, &why));
  EXPECT_NE(why.find("orthonormal"), std::string::npos) << why;
  const std::vector<double> negative = {-1.0};
  EXPECT_FALSE(model.init(KeypointModel::Zero(), negative, std::span(twice).first(1), 0.9, &why));
  EXPECT_TRUE(model.init(KeypointModel::Zero(), std::span(values).first(1),
                         std::span(twice).first(1), 0.9, &why))
      << why;
  EXPECT_EQ(model.componentCount(), 1);
  EXPECT_DOUBLE_EQ(model.sigma(0), 1.0);
}

TEST(Asm, SaveLoadRoundTripIsIdentical) {
  ActiveShapeModel model = learnModel(3);
  TypePrior prior;
  prior.sampleCount = 17;
  prior.mean = {0.1, -0.2, 0.3};
  prior.covariance.topLeftCorner<3, 3>() << 1.0 / 3.0, 0.1, 0.0, 0.1, 0.5, 0.02, 0.0, 0.02, 0.7;
  model.setTypePrior(VehicleType::Van, prior);
  model.setHeldOutError({0.081, 0.46, 0.064, 0.051, 240});
  const std::string path = tempPath("roundtrip.yaml");
  std::string why;
  ASSERT_TRUE(model.save(path, &why)) << why;
  ActiveShapeModel loaded;
  ASSERT_TRUE(loaded.load(path, &why)) << why;
  EXPECT_EQ(loaded.componentCount(), 3);
  EXPECT_EQ(loaded.mean(), model.mean());
  EXPECT_EQ(loaded.explainedVarianceShare(), model.explainedVarianceShare());
  for (int s = 0; s < 3; ++s) {
    EXPECT_EQ(loaded.sigma(s), model.sigma(s));
    EXPECT_EQ(loaded.eigenvector(s), model.eigenvector(s));
  }
  const TypePrior& back = loaded.typePrior(VehicleType::Van);
  EXPECT_EQ(back.sampleCount, 17);
  EXPECT_EQ(back.mean, prior.mean);
  EXPECT_EQ(back.covariance, prior.covariance);
  EXPECT_EQ(loaded.typePrior(VehicleType::Sedan).sampleCount, 0);
  EXPECT_EQ(loaded.heldOutError().max_m, 0.46);
  EXPECT_EQ(loaded.heldOutError().modelCount, 240);
  const ShapeParams p = params({0.5F, 0.5F, -0.5F});
  EXPECT_EQ(loaded.shape(p), model.shape(p));
  // Saving the loaded model gives the same file.
  const std::string again = tempPath("roundtrip2.yaml");
  ASSERT_TRUE(loaded.save(again, &why)) << why;
  EXPECT_EQ(readText(again), readText(path));
}

// Each broken file must be rejected with a message naming the file and the field.
TEST(Asm, LoadErrorsNameTheFileAndTheField) {
  const ActiveShapeModel model = learnModel(2);
  const std::string good = tempPath("good.yaml");
  std::string why;
  ASSERT_TRUE(model.save(good, &why)) << why;
  const std::string text = readText(good);
  ActiveShapeModel target = learnModel(3);
  const KeypointModel before = target.mean();

  const std::string missing = tempPath("does_not_exist.yaml");
  EXPECT_FALSE(target.load(missing, &why));
  EXPECT_NE(why.find(missing), std::string::npos) << why;

  const struct {
    std::string name;
    std::string text;
    std::string field;
  } cases[] = {
      {"version", replaceOnce(text, "format_version: 1", "format_version: 2"), "format_version"},
      {"no_version", replaceOnce(text, "format_version: 1", "format_verzion: 1"), "format_version"},
      {"names", replaceOnce(text, "roof_rear_left", "roof_back_left"), "keypoint_names"},
      {"count", replaceOnce(text, "component_count: 2", "component_count: 9"), "component_count"},
      {"sigma_size", replaceOnce(text, "component_count: 2", "component_count: 3"), "sigma"},
      {"mean_size", replaceOnce(text, "mean:\n  - [", "mean:\n  - ["), "mean"},
      {"share", replaceOnce(text, "explained_variance_share: 0.9", "explained_variance_share: x"),
       "explained_variance_share"},
      {"syntax", text + "\n  : [unbalanced\n", ""},
  };
  for (const auto& c : cases) {
    std::string broken = c.text;
    if (c.name == "mean_size") {
      // Drop the first row of the mean: 35 rows instead of 36.
      const std::size_t at = broken.find("mean:\n") + 6;
      broken.erase(at, broken.find('\n', at) + 1 - at);
    }
    const std::string path = tempPath("broken_" + c.name + ".yaml");
    writeText(path, broken);
    EXPECT_FALSE(target.load(path, &why)) << c.name;
    EXPECT_NE(why.find(path), std::string::npos) << c.name << ": " << why;
    EXPECT_NE(why.find(c.field), std::string::npos) << c.name << ": " << why;
  }
  EXPECT_EQ(target.componentCount(), 3) << "a failed load leaves the model unchanged";
  EXPECT_EQ(target.mean(), before);
}

// --- The shipped default model ------------------------------------------------------------

// The crop network's mirror averaging averages gamma of a crop and its mirror image as they are
// (detection/vehicle_cropper.hpp): right only if every component maps onto itself when left and
// right swap (keypoint pairs exchanged, the lateral coordinate negated) — cars are symmetric.
TEST(DefaultAsm, ComponentsAreLeftRightSymmetric) {
  ActiveShapeModel model;
  std::string why;
  ASSERT_TRUE(model.load(kDefaultAsm, &why)) << why;
  for (int s = 0; s < model.componentCount(); ++s) {
    const KeypointModel& e = model.eigenvector(s);
    KeypointModel mirrored = e;
    for (int k = 0; k < kKeypointCount; k += 2) {
      mirrored.col(k) = e.col(k + 1);
      mirrored.col(k + 1) = e.col(k);
    }
    mirrored.row(1) *= -1.0;  // lateral (vehicle frame: x forward, y left, z up)
    EXPECT_LT((mirrored - e).cwiseAbs().maxCoeff(), 1e-6) << "component " << s;
    EXPECT_GT(e.cwiseAbs().maxCoeff(), 0.1) << "component " << s;
  }
}

TEST(DefaultAsm, LoadsWithThreeComponentsAndTypePriors) {
  ActiveShapeModel model;
  std::string why;
  ASSERT_TRUE(model.load(kDefaultAsm, &why)) << why;
  EXPECT_EQ(model.componentCount(), 3);
  EXPECT_GT(model.explainedVarianceShare(), 0.8);
  std::printf("default ASM: n_s = %d, explained variance share %.4f, held-out RMS %.4f m\n",
              model.componentCount(), model.explainedVarianceShare(), model.heldOutError().rms_m);
  for (int t = 0; t < kCarTypeCount; ++t) {
    const TypePrior& prior = model.typePrior(static_cast<VehicleType>(t));
    EXPECT_GT(prior.sampleCount, 100) << t;
    EXPECT_GT(prior.covariance(0, 0), 0.0) << t;
  }
  EXPECT_EQ(model.typePrior(VehicleType::Large).sampleCount, 0);
  EXPECT_GT(model.heldOutError().modelCount, 0);
  // The mean is a plausible car: about 4.6 m x 1.8 m x 1.5 m, a valid mesh.
  const Eigen::Vector3d size = boundingBoxSize(model.mean());
  EXPECT_NEAR(size.x(), 4.6, 0.3);
  EXPECT_NEAR(size.y(), 1.85, 0.1);
  EXPECT_NEAR(size.z(), 1.55, 0.15);
  EXPECT_TRUE(carProfileValid(model.mean()));
  // Type-typical shapes (within 2 sigma along each component) keep a valid mesh.
  for (int s = 0; s < 3; ++s) {
    for (float g : {-2.0F, 2.0F}) {
      ShapeParams p;
      p.count = 3;
      p.gamma[static_cast<std::size_t>(s)] = g;
      EXPECT_TRUE(carProfileValid(model.shape(p))) << "component " << s << " gamma " << g;
    }
  }
  for (int t = 0; t < kCarTypeCount; ++t) {
    const TypePrior& prior = model.typePrior(static_cast<VehicleType>(t));
    ShapeParams p;
    p.count = 3;
    for (std::size_t s = 0; s < 3; ++s) {
      p.gamma[s] = static_cast<float>(prior.mean[s]);
    }
    EXPECT_TRUE(carProfileValid(model.shape(p))) << toString(static_cast<VehicleType>(t));
  }
}

TEST(DefaultAsm, FitsNewGeneratedCarsWithinTheHeldOutError) {
  ActiveShapeModel model;
  std::string why;
  ASSERT_TRUE(model.load(kDefaultAsm, &why)) << why;
  const ReconstructionError& bound = model.heldOutError();
  std::mt19937_64 rng(20240601);  // not the learning seed: cars the model has not seen
  double sum = 0.0;
  double sumXy = 0.0;
  double sumZ = 0.0;
  int n = 0;
  for (int t = 0; t < kCarTypeCount; ++t) {
    for (int i = 0; i < 20; ++i) {
      const KeypointModel car = generateCar(static_cast<VehicleType>(t), rng).keypoints;
      const auto gamma = model.fit(car, allKeypoints(), 0.0);
      ASSERT_TRUE(gamma.has_value());
      const KeypointModel diff = model.shape(*gamma) - car;
      for (int k : evaluationKeypoints()) {
        const double d = diff.col(k).norm();
        EXPECT_LE(d, bound.max_m * 1.1) << "type " << t << " keypoint " << k;
        sum += d * d;
        sumXy += diff.col(k).head<2>().squaredNorm();
        sumZ += diff(2, k) * diff(2, k);
        ++n;
      }
    }
  }
  EXPECT_LE(std::sqrt(sum / n), bound.rms_m * 1.1);
  EXPECT_LE(std::sqrt(sumXy / n), bound.planimetricRms_m * 1.1);
  EXPECT_LE(std::sqrt(sumZ / n), bound.heightRms_m * 1.1);
}

}  // namespace
}  // namespace vp::shape
