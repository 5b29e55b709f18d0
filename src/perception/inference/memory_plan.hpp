// inference/memory_plan: places a network's activation tensors in one arena by liveness.
//
// Contract: a MemoryBlock is a byte range that must stay intact from the step that first
// writes it to the last step that reads it (both inclusive, steps = node indices in
// execution order). planMemory() gives every block an offset in one arena such that two
// blocks whose step ranges intersect never share a byte: a node's output and its inputs are
// all alive during that node's step, so no operator ever works in place. Each block is
// reserved with `slack_bytes` of its own behind it (XNNPACK reads up to XNN_EXTRA_BYTES past
// a tensor) and starts on an `alignment_bytes` boundary. Placement is greedy: largest block
// first, into the smallest gap left by the already placed blocks it overlaps in time (best
// fit), else on top of them. tensorLifetimes() derives the blocks of a QdqGraph's tensors:
// the image input is alive from the first step, graph outputs to the end (they are read
// after run() and must stay valid until the next one), every other tensor from its producer
// to its last consumer, so a skip connection keeps its tensor until the Add that reads it.
// A tensor no node produces (other than the input) is kept for the whole run. Pure
// functions of their arguments; used at load only.
#pragma once

#include <cstddef>
#include <vector>

#include "inference/onnx_graph.hpp"

namespace vp::inference {

struct MemoryBlock {
  std::size_t bytes = 0;  // the data itself, without slack
  int firstStep = 0;      // first step that writes it (or 0: alive from the start)
  int lastStep = 0;       // last step that reads it (inclusive)
};

struct MemoryPlanOptions {
  std::size_t alignment_bytes = 64;  // every offset is a multiple (a power of two)
  std::size_t slack_bytes = 0;       // reserved behind each block, readable, never shared
};

struct MemoryPlan {
  std::vector<std::size_t> offsets;  // per block, in the order given
  std::size_t arena_bytes = 0;       // the arena that holds every block with its slack
  std::size_t separate_bytes = 0;    // sum of bytes + slack: one buffer per block
};

bool lifetimesOverlap(const MemoryBlock& a, const MemoryBlock& b);

// The size reserved for a block: bytes + slack, rounded up to the alignment.
std::size_t reservedBytes(const MemoryBlock& block, const MemoryPlanOptions& options);

MemoryPlan planMemory(const std::vector<MemoryBlock>& blocks, const MemoryPlanOptions& options);

// No arena can be smaller: the largest sum of reserved bytes alive at one step.
std::size_t liveBytesLowerBound(const std::vector<MemoryBlock>& blocks,
                                const MemoryPlanOptions& options);

// One block per graph tensor (index = tensor id), elementBytes per tensor element.
std::vector<MemoryBlock> tensorLifetimes(const QdqGraph& graph, std::size_t elementBytes);

}  // namespace vp::inference
