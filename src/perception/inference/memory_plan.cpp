// The liveness-based arena planner (contract in memory_plan.hpp).
#include "inference/memory_plan.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <utility>

namespace vp::inference {
namespace {

std::size_t alignUp(std::size_t value, std::size_t alignment) {
  return (value + alignment - 1) / alignment * alignment;
}

}  // namespace

bool lifetimesOverlap(const MemoryBlock& a, const MemoryBlock& b) {
  return a.firstStep <= b.lastStep && b.firstStep <= a.lastStep;
}

std::size_t reservedBytes(const MemoryBlock& block, const MemoryPlanOptions& options) {
  return alignUp(block.bytes + options.slack_bytes,
                 std::max<std::size_t>(options.alignment_bytes, 1));
}

MemoryPlan planMemory(const std::vector<MemoryBlock>& blocks, const MemoryPlanOptions& options) {
  const std::size_t alignment = std::max<std::size_t>(options.alignment_bytes, 1);
  MemoryPlan plan;
  plan.offsets.assign(blocks.size(), 0);
  for (const auto& b : blocks)
    plan.separate_bytes += b.bytes + options.slack_bytes;

  // Largest first; among equal sizes the earlier-born first, then the lower index, so that
  // the plan does not depend on the sort's stability.
  std::vector<std::size_t> order(blocks.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const std::size_t ra = reservedBytes(blocks[a], options);
    const std::size_t rb = reservedBytes(blocks[b], options);
    if (ra != rb)
      return ra > rb;
    if (blocks[a].firstStep != blocks[b].firstStep)
      return blocks[a].firstStep < blocks[b].firstStep;
    return a < b;
  });

  std::vector<std::size_t> placed;
  std::vector<std::pair<std::size_t, std::size_t>> busy;  // [begin, end) of overlapping blocks
  for (const std::size_t i : order) {
    const std::size_t need = reservedBytes(blocks[i], options);
    busy.clear();
    for (const std::size_t j : placed) {
      if (lifetimesOverlap(blocks[i], blocks[j]))
        busy.emplace_back(plan.offsets[j], plan.offsets[j] + reservedBytes(blocks[j], options));
    }
    std::sort(busy.begin(), busy.end());
    // Walk the gaps between the busy ranges; keep the smallest one that fits.
    std::size_t cursor = 0;
    std::size_t best = std::numeric_limits<std::size_t>::max();
    std::size_t bestGap = std::numeric_limits<std::size_t>::max();
    for (const auto& [begin, end] : busy) {
      if (begin > cursor && begin - cursor >= need && begin - cursor < bestGap) {
        best = cursor;
        bestGap = begin - cursor;
      }
      cursor = std::max(cursor, alignUp(end, alignment));
    }
    if (best == std::numeric_limits<std::size_t>::max())
      best = cursor;  // on top of everything alive at the same time
    plan.offsets[i] = best;
    plan.arena_bytes = std::max(plan.arena_bytes, best + need);
    placed.push_back(i);
  }
  return plan;
}

std::size_t liveBytesLowerBound(const std::vector<MemoryBlock>& blocks,
                                const MemoryPlanOptions& options) {
  int last = 0;
  for (const auto& b : blocks)
    last = std::max(last, b.lastStep);
  std::vector<std::size_t> live(static_cast<std::size_t>(last) + 1, 0);
  for (const auto& b : blocks) {
    for (int s = std::max(b.firstStep, 0); s <= b.lastStep; ++s)
      live[static_cast<std::size_t>(s)] += reservedBytes(b, options);
  }
  return live.empty() ? 0 : *std::max_element(live.begin(), live.end());
}

std::vector<MemoryBlock> tensorLifetimes(const QdqGraph& graph, std::size_t elementBytes) {
  const int end = std::max(static_cast<int>(graph.nodes.size()) - 1, 0);
  constexpr int kUnset = -1;
  std::vector<MemoryBlock> blocks(graph.tensors.size());
  std::vector<int> producer(graph.tensors.size(), kUnset);
  std::vector<int> lastUse(graph.tensors.size(), kUnset);
  for (std::size_t t = 0; t < graph.tensors.size(); ++t)
    blocks[t].bytes = graph.tensors[t].shape.elements() * elementBytes;
  for (std::size_t s = 0; s < graph.nodes.size(); ++s) {
    const int step = static_cast<int>(s);
    const auto& node = graph.nodes[s];
    for (const int in : node.inputs)
      lastUse[static_cast<std::size_t>(in)] = std::max(lastUse[static_cast<std::size_t>(in)], step);
    auto& p = producer[static_cast<std::size_t>(node.output)];
    if (p == kUnset)
      p = step;
    // Written again later (not in this IR today): alive until that write too.
    lastUse[static_cast<std::size_t>(node.output)] =
        std::max(lastUse[static_cast<std::size_t>(node.output)], step);
  }
  for (std::size_t t = 0; t < graph.tensors.size(); ++t) {
    const bool input = static_cast<int>(t) == graph.inputTensor;
    if (input || producer[t] == kUnset) {
      blocks[t].firstStep = 0;
      blocks[t].lastStep = input && producer[t] == kUnset ? std::max(lastUse[t], 0) : end;
    } else {
      blocks[t].firstStep = producer[t];
      blocks[t].lastStep = lastUse[t];
    }
  }
  for (const auto& out : graph.outputs)
    blocks[static_cast<std::size_t>(out.tensor)].lastStep = end;
  return blocks;
}

}  // namespace vp::inference
