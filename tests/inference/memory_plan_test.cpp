// The activation memory plan (inference/memory_plan.hpp): the planner on tiny graphs and on
// random ones (every pair of blocks alive at the same step checked for overlap), then the
// engine with and without the plan on the shipped models and the fixtures: the outputs must
// be bit-identical, also when the arena still holds the previous frame's values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "inference/dnnl_int8.hpp"
#include "inference/engine.hpp"
#include "inference/memory_plan.hpp"
#include "synthetic_frame.hpp"

namespace vp::inference {
namespace {

namespace fs = std::filesystem;

// --- tiny graphs ---------------------------------------------------------------------------

// A graph of `sizes.size()` tensors (tensor 0 the input, one channel of `sizes[t]` pixels)
// and nodes given as (inputs, output); outputs lists the graph outputs.
QdqGraph tinyGraph(const std::vector<int>& sizes,
                   const std::vector<std::pair<std::vector<int>, int>>& nodes,
                   const std::vector<int>& outputs) {
  QdqGraph g;
  g.file = "tiny.onnx";
  for (std::size_t t = 0; t < sizes.size(); ++t) {
    GraphTensor tensor;
    tensor.name = "t" + std::to_string(t);
    tensor.shape = TensorShape{1, 1, 1, sizes[t]};
    g.tensors.push_back(tensor);
  }
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    GraphNode node;
    node.kind = nodes[n].first.size() > 1 ? OpKind::Add : OpKind::Conv;
    node.name = "n" + std::to_string(n);
    node.inputs = nodes[n].first;
    node.output = nodes[n].second;
    g.nodes.push_back(node);
  }
  for (const int out : outputs)
    g.outputs.push_back(GraphOutput{"out" + std::to_string(out), out});
  return g;
}

// Every pair of blocks alive at a common step must own disjoint byte ranges (slack
// included); every offset is aligned and every block lies inside the arena.
void expectValidPlan(const std::vector<MemoryBlock>& blocks, const MemoryPlan& plan,
                     const MemoryPlanOptions& options) {
  ASSERT_EQ(plan.offsets.size(), blocks.size());
  for (std::size_t a = 0; a < blocks.size(); ++a) {
    const std::size_t aEnd = plan.offsets[a] + blocks[a].bytes + options.slack_bytes;
    EXPECT_EQ(plan.offsets[a] % options.alignment_bytes, 0U) << "block " << a;
    EXPECT_LE(aEnd, plan.arena_bytes) << "block " << a;
    for (std::size_t b = a + 1; b < blocks.size(); ++b) {
      if (!lifetimesOverlap(blocks[a], blocks[b]))
        continue;
      const std::size_t bEnd = plan.offsets[b] + blocks[b].bytes + options.slack_bytes;
      const bool disjoint = aEnd <= plan.offsets[b] || bEnd <= plan.offsets[a];
      EXPECT_TRUE(disjoint) << "blocks " << a << " [" << plan.offsets[a] << ", " << aEnd << ") and "
                            << b << " [" << plan.offsets[b] << ", " << bEnd
                            << ") are alive together (steps " << blocks[a].firstStep << ".."
                            << blocks[a].lastStep << " and " << blocks[b].firstStep << ".."
                            << blocks[b].lastStep << ")";
    }
  }
  EXPECT_GE(plan.arena_bytes, liveBytesLowerBound(blocks, options));
  EXPECT_LE(plan.arena_bytes, [&] {
    std::size_t sum = 0;
    for (const auto& b : blocks)
      sum += reservedBytes(b, options);
    return sum;
  }()) << "the arena must never exceed separate aligned buffers";
}

MemoryPlanOptions xnnLikeOptions() {
  MemoryPlanOptions options;
  options.alignment_bytes = 64;
  options.slack_bytes = 16;
  return options;
}

TEST(MemoryPlan, ChainPingPongsBetweenTwoSlots) {
  // in -> a -> b -> c -> out, all 1000 bytes: each step needs its input and its output.
  const QdqGraph g =
      tinyGraph({1000, 1000, 1000, 1000, 1000}, {{{0}, 1}, {{1}, 2}, {{2}, 3}, {{3}, 4}}, {4});
  const auto blocks = tensorLifetimes(g, 1);
  ASSERT_EQ(blocks.size(), 5U);
  EXPECT_EQ(blocks[0].firstStep, 0);
  EXPECT_EQ(blocks[0].lastStep, 0);
  EXPECT_EQ(blocks[2].firstStep, 1);
  EXPECT_EQ(blocks[2].lastStep, 2);
  EXPECT_EQ(blocks[4].lastStep, 3);
  const auto options = xnnLikeOptions();
  const auto plan = planMemory(blocks, options);
  expectValidPlan(blocks, plan, options);
  const std::size_t slot = reservedBytes(blocks[0], options);
  EXPECT_EQ(plan.arena_bytes, 2 * slot);
  EXPECT_EQ(plan.separate_bytes, 5 * (1000U + 16U));
  // Consecutive tensors never share, tensors two steps apart do.
  EXPECT_NE(plan.offsets[1], plan.offsets[2]);
  EXPECT_EQ(plan.offsets[1], plan.offsets[3]);
}

TEST(MemoryPlan, SkipConnectionKeepsItsTensorUntilTheAdd) {
  // in -> a; a -> b -> c; add(a, c) -> out: `a` is read again three steps after its birth.
  const QdqGraph g =
      tinyGraph({500, 800, 800, 800, 800}, {{{0}, 1}, {{1}, 2}, {{2}, 3}, {{1, 3}, 4}}, {4});
  const auto blocks = tensorLifetimes(g, 1);
  EXPECT_EQ(blocks[1].firstStep, 0);
  EXPECT_EQ(blocks[1].lastStep, 3);
  const auto options = xnnLikeOptions();
  const auto plan = planMemory(blocks, options);
  expectValidPlan(blocks, plan, options);
  for (const int t : {2, 3, 4})
    EXPECT_NE(plan.offsets[1], plan.offsets[static_cast<std::size_t>(t)]) << "tensor " << t;
  EXPECT_LT(plan.arena_bytes, plan.separate_bytes);
}

TEST(MemoryPlan, ConcatBranchesAreAliveTogether) {
  // in -> a, in -> b (two branches), concat(a, b) -> c, c -> out.
  const QdqGraph g =
      tinyGraph({300, 200, 200, 400, 400}, {{{0}, 1}, {{0}, 2}, {{1, 2}, 3}, {{3}, 4}}, {4});
  const auto blocks = tensorLifetimes(g, 4);
  EXPECT_EQ(blocks[0].lastStep, 1);
  EXPECT_EQ(blocks[1].lastStep, 2);
  EXPECT_EQ(blocks[3].bytes, 1600U);
  const auto options = xnnLikeOptions();
  const auto plan = planMemory(blocks, options);
  expectValidPlan(blocks, plan, options);
  // After the concat only c and the output are alive: the output reuses the branches' bytes.
  EXPECT_LT(plan.arena_bytes, plan.separate_bytes);
}

TEST(MemoryPlan, OutputsLiveToTheEndAndTheInputFromTheStart) {
  // An early output (a head) must survive every later step; the input is born before step 0.
  const QdqGraph g = tinyGraph({100, 100, 100, 100}, {{{0}, 1}, {{1}, 2}, {{2}, 3}}, {1, 3});
  const auto blocks = tensorLifetimes(g, 1);
  EXPECT_EQ(blocks[0].firstStep, 0);
  EXPECT_EQ(blocks[1].lastStep, 2);
  EXPECT_EQ(blocks[3].lastStep, 2);
  const auto options = xnnLikeOptions();
  const auto plan = planMemory(blocks, options);
  expectValidPlan(blocks, plan, options);
  EXPECT_NE(plan.offsets[1], plan.offsets[3]);
}

TEST(MemoryPlan, BestFitTakesTheSmallestGapThatFits) {
  // Largest first: pillars (alive throughout) and short-lived blocks (dead after step 0)
  // alternate in the arena, so after step 0 the short ones leave a 512-byte and a 256-byte
  // gap between the pillars. A 100-byte block born later goes into the 256-byte gap (first
  // fit would have taken the 512-byte one).
  const std::vector<MemoryBlock> blocks = {
      {1024, 0, 10},  // pillar at 0
      {512, 0, 0},    // short, above it
      {448, 0, 10},   // pillar
      {256, 0, 0},    // short
      {192, 0, 10},   // pillar
      {100, 5, 6},    // alive with the pillars only
  };
  MemoryPlanOptions options;
  options.alignment_bytes = 64;
  const auto plan = planMemory(blocks, options);
  expectValidPlan(blocks, plan, options);
  EXPECT_LT(plan.offsets[1], plan.offsets[3]);
  EXPECT_EQ(plan.offsets[5], plan.offsets[3]) << "not in the smallest gap that fits";
  EXPECT_EQ(plan.arena_bytes, 1024U + 512U + 448U + 256U + 192U);
}

TEST(MemoryPlan, RandomGraphsNeverOverlapLiveTensors) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 200; ++trial) {
    const int tensors = 2 + static_cast<int>(rng() % 40);
    std::vector<int> sizes;
    for (int t = 0; t < tensors; ++t)
      sizes.push_back(1 + static_cast<int>(rng() % 5000));
    // Node k produces tensor k + 1 from one or two earlier tensors (skips, branches).
    std::vector<std::pair<std::vector<int>, int>> nodes;
    for (int t = 1; t < tensors; ++t) {
      std::vector<int> inputs{static_cast<int>(rng() % static_cast<unsigned>(t))};
      if (rng() % 3 == 0)
        inputs.push_back(static_cast<int>(rng() % static_cast<unsigned>(t)));
      nodes.emplace_back(inputs, t);
    }
    std::vector<int> outputs{tensors - 1};
    if (tensors > 3 && rng() % 2 == 0)
      outputs.push_back(1 + static_cast<int>(rng() % static_cast<unsigned>(tensors - 2)));
    const QdqGraph g = tinyGraph(sizes, nodes, outputs);
    const std::size_t elementBytes = rng() % 2 == 0 ? 1 : 4;
    const auto blocks = tensorLifetimes(g, elementBytes);
    // The lifetimes themselves: born at the producer, alive through every consumer.
    for (std::size_t n = 0; n < g.nodes.size(); ++n) {
      const int step = static_cast<int>(n);
      for (const int in : g.nodes[n].inputs) {
        EXPECT_LE(blocks[static_cast<std::size_t>(in)].firstStep, step);
        EXPECT_GE(blocks[static_cast<std::size_t>(in)].lastStep, step);
      }
      EXPECT_EQ(blocks[static_cast<std::size_t>(g.nodes[n].output)].firstStep, step);
    }
    for (const int out : outputs)
      EXPECT_EQ(blocks[static_cast<std::size_t>(out)].lastStep, tensors - 2);
    MemoryPlanOptions options;
    options.alignment_bytes = rng() % 2 == 0 ? 64 : 16;
    options.slack_bytes = rng() % 64;
    const auto plan = planMemory(blocks, options);
    expectValidPlan(blocks, plan, options);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "trial " << trial;
      return;
    }
  }
}

// --- the engine with and without the plan --------------------------------------------------

const std::string kDetectorModel =
    std::string(VP_SOURCE_DIR) + "/models/detector/detector_int8.onnx";
const std::string kCropModel = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";

std::vector<std::string> shippedAndFixtureModels() {
  std::vector<std::string> paths{kDetectorModel, kCropModel};
  const fs::path fixtures = fs::path(VP_FIXTURE_DIR) / "models";
  std::vector<std::string> more;
  for (const auto& entry : fs::directory_iterator(fixtures)) {
    if (entry.path().extension() == ".onnx")
      more.push_back(entry.path().string());
  }
  std::sort(more.begin(), more.end());
  paths.insert(paths.end(), more.begin(), more.end());
  return paths;
}

bool loadEngine(Engine* engine, const std::string& path, Backend backend, bool planMemory) {
  EngineOptions options;
  options.backend = backend;
  options.planMemory = planMemory;
  std::string why;
  const bool ok = engine->load(path, options, &why);
  EXPECT_TRUE(ok) << why;
  return ok;
}

cv::Mat frameFor(const Engine& engine, std::uint64_t seed) {
  const TensorShape s = engine.inputShape();
  const cv::Mat big = test::syntheticCarFrame(2 * s.w, 2 * s.h, seed, 12);
  cv::Mat small;
  cv::resize(big, small, cv::Size(s.w, s.h), 0, 0, cv::INTER_AREA);
  return small;
}

ImageView viewOf(const cv::Mat& image) {
  return ImageView{image.data, image.cols, image.rows, image.step[0]};
}

// Every output as bytes: the raw int8 tensor when there is one, and the float values.
std::vector<std::vector<std::uint8_t>> outputBytes(const Engine& engine) {
  std::vector<std::vector<std::uint8_t>> all;
  for (std::size_t o = 0; o < engine.outputCount(); ++o) {
    const auto& out = engine.output(o);
    const std::size_t n = out.shape.elements();
    const auto* f = reinterpret_cast<const std::uint8_t*>(out.data);
    all.emplace_back(f, f + n * sizeof(float));
    if (out.quantized != nullptr) {
      const auto* q = reinterpret_cast<const std::uint8_t*>(out.quantized);
      all.emplace_back(q, q + n);
    }
  }
  return all;
}

// Planned and unplanned engines of one backend on two different frames; the planned engine's
// arena holds the first frame's values when the second runs, so a tensor read before it is
// written (or a plan that lets two live tensors share bytes) shows up as a difference.
void expectPlanChangesNothing(Backend backend, const std::vector<std::string>& paths) {
  for (const auto& path : paths) {
    const std::string name = fs::path(path).filename().string();
    Engine planned;
    Engine separate;
    if (!loadEngine(&planned, path, backend, true) || !loadEngine(&separate, path, backend, false))
      continue;
    const ActivationMemory withPlan = planned.activationMemory();
    const ActivationMemory without = separate.activationMemory();
    EXPECT_TRUE(withPlan.planned);
    EXPECT_FALSE(without.planned);
    EXPECT_EQ(withPlan.separate_bytes, without.separate_bytes) << name;
    EXPECT_EQ(without.allocated_bytes, without.separate_bytes) << name;
    EXPECT_LT(withPlan.allocated_bytes, without.allocated_bytes) << name;
    std::printf(
        "  %-22s %-9s activations: planned arena %9zu bytes, separate buffers %9zu bytes "
        "(%.1f %%)\n",
        name.c_str(), toString(backend), withPlan.allocated_bytes, without.allocated_bytes,
        100.0 * static_cast<double>(withPlan.allocated_bytes) /
            static_cast<double>(without.allocated_bytes));
    for (const std::uint64_t seed : {3U, 4U}) {
      const cv::Mat frame = frameFor(planned, seed);
      ASSERT_EQ(planned.run(viewOf(frame)), RunStatus::Ok) << name;
      ASSERT_EQ(separate.run(viewOf(frame)), RunStatus::Ok) << name;
      const auto a = outputBytes(planned);
      const auto b = outputBytes(separate);
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t o = 0; o < a.size(); ++o)
        EXPECT_TRUE(a[o] == b[o]) << name << " " << toString(backend) << " output part " << o
                                  << " differs with the memory plan (frame seed " << seed << ")";
    }
  }
}

// The planner on the shipped models' real lifetimes: a valid plan, and how far the greedy
// arena is above the bound no plan can beat.
TEST(MemoryPlanEngine, ShippedModelsPlanNearTheLiveBytesBound) {
  for (const std::string& path : {kDetectorModel, kCropModel}) {
    std::string bytes;
    std::string why;
    ASSERT_TRUE(readFileBytes(path, &bytes, &why)) << why;
    QdqGraph graph;
    ASSERT_TRUE(parseQdqModel(bytes, path, &graph, &why)) << why;
    const auto blocks = tensorLifetimes(graph, 1);
    MemoryPlanOptions options;
    options.alignment_bytes = 64;
    options.slack_bytes = 16;
    const auto plan = planMemory(blocks, options);
    expectValidPlan(blocks, plan, options);
    const std::size_t bound = liveBytesLowerBound(blocks, options);
    std::printf(
        "  %-18s %zu tensors: arena %zu bytes, live-bytes bound %zu (+%.1f %%), "
        "separate %zu\n",
        fs::path(path).filename().c_str(), blocks.size(), plan.arena_bytes, bound,
        100.0 * (static_cast<double>(plan.arena_bytes) / static_cast<double>(bound) - 1.0),
        plan.separate_bytes);
    EXPECT_LE(plan.arena_bytes, bound + bound / 4) << "greedy best fit far from the bound";
    Engine engine;
    ASSERT_TRUE(loadEngine(&engine, path, Backend::XnnpackInt8, true));
    EXPECT_GE(engine.activationMemory().allocated_bytes, bound);
  }
}

TEST(MemoryPlanEngine, XnnpackInt8OutputsBitIdenticalWithAndWithoutPlan) {
  expectPlanChangesNothing(Backend::XnnpackInt8, shippedAndFixtureModels());
}

TEST(MemoryPlanEngine, XnnpackFp32OutputsBitIdenticalWithAndWithoutPlan) {
  expectPlanChangesNothing(Backend::XnnpackFp32, shippedAndFixtureModels());
}

TEST(MemoryPlanEngine, DnnlInt8OutputsBitIdenticalWithAndWithoutPlan) {
  if (!dnnlInt8Available())
    GTEST_SKIP() << "this build has no oneDNN (libdnnl-dev absent at configure time)";
  // oneDNN runs on any x86-64 CPU (without VNNI on slower kernels): the plan is checked here
  // even where Auto would not pick it.
  expectPlanChangesNothing(Backend::DnnlInt8, {kDetectorModel, kCropModel});
}

TEST(MemoryPlanEngine, OpenCvReportsNoActivationMemory) {
  Engine engine;
  ASSERT_TRUE(loadEngine(&engine, kCropModel, Backend::OpenCvFp32, true));
  const ActivationMemory m = engine.activationMemory();
  EXPECT_EQ(m.allocated_bytes, 0U);
  EXPECT_EQ(m.separate_bytes, 0U);
  EXPECT_EQ(Engine().activationMemory().allocated_bytes, 0U);
}

}  // namespace
}  // namespace vp::inference
