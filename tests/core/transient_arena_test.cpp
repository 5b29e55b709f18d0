// core/transient_arena: operator new inside a scope is served by the arena (no heap allocation),
// blocks come back on delete from any thread, the arena rewinds only when every block is back,
// a block that does not fit goes to the heap and is counted, and nothing changes outside a scope.
#include "core/transient_arena.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <new>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace vp::core {
namespace {

bool inside(const TransientArena& arena, const void* p, const void* first) {
  const auto a = reinterpret_cast<std::uintptr_t>(p);
  const auto b = reinterpret_cast<std::uintptr_t>(first);
  return a >= b && a < b + arena.capacity();
}

#define SKIP_WITHOUT_REDIRECTION()                                                      \
  if (!TransientArena::redirects())                                                     \
  GTEST_SKIP() << "AddressSanitizer build: operator new is the sanitizer's, the arena " \
                  "redirects nothing"

TEST(TransientArena, ALibraryStyleCallInsideAScopeAllocatesNothingFromTheHeap) {
  SKIP_WITHOUT_REDIRECTION();
  TransientArena arena(64 * 1024);
  std::size_t heapAllocations = 0;
  {
    test::AllocationCounter counter;
    const TransientArena::Scope scope(arena);
    ASSERT_TRUE(scope.isOpen());
    // What a library call does: a map and a vector built, used and destroyed.
    std::unordered_map<int, std::string> args;
    for (int i = 0; i < 8; ++i)
      args.emplace(i, std::string(40, static_cast<char>('a' + i)));
    std::vector<double> scratch(100, 1.0);
    EXPECT_EQ(args.at(3).front(), 'd');
    EXPECT_DOUBLE_EQ(scratch[99], 1.0);
    counter.stop();
    heapAllocations = counter.count();
  }
  EXPECT_EQ(heapAllocations, 0U);
  EXPECT_GT(arena.blocksServed(), 9U);
  EXPECT_EQ(arena.blocksOut(), 0U);
  EXPECT_EQ(arena.overflows(), 0U);
  EXPECT_GT(arena.highWaterBytes(), 100 * sizeof(double));
  EXPECT_LE(arena.highWaterBytes(), arena.capacity());
}

TEST(TransientArena, OutsideAScopeOperatorNewIsTheHeaps) {
  TransientArena arena(4096);
  test::AllocationCounter counter;
  auto block = std::make_unique<int[]>(16);
  counter.stop();
  EXPECT_EQ(arena.blocksServed(), 0U);
  EXPECT_EQ(counter.count(), 1U);  // malloc's count, or operator new's under AddressSanitizer
  block[15] = 7;
  EXPECT_EQ(block[15], 7);
}

TEST(TransientArena, RewindsWhenEveryBlockIsBackAndNotBefore) {
  SKIP_WITHOUT_REDIRECTION();
  TransientArena arena(4096);
  void* first = nullptr;
  std::unique_ptr<int> kept;
  {
    const TransientArena::Scope scope(arena);
    auto a = std::make_unique<int>(1);
    first = a.get();
    kept = std::make_unique<int>(2);  // outlives the scope, like a block a library keeps
    EXPECT_TRUE(inside(arena, kept.get(), first));
  }
  EXPECT_EQ(arena.blocksOut(), 1U);
  {
    const TransientArena::Scope scope(arena);
    auto b = std::make_unique<int>(3);
    EXPECT_NE(static_cast<void*>(b.get()), first);  // not rewound: the kept block is still out
    EXPECT_NE(b.get(), kept.get());
    EXPECT_EQ(*kept, 2);  // the kept block is intact
  }
  kept.reset();
  EXPECT_EQ(arena.blocksOut(), 0U);
  {
    const TransientArena::Scope scope(arena);  // closes with nothing out: rewinds
  }
  {
    const TransientArena::Scope scope(arena);
    auto c = std::make_unique<int>(4);
    EXPECT_EQ(static_cast<void*>(c.get()), first);
  }
}

TEST(TransientArena, ABlockThatDoesNotFitComesFromTheHeapAndIsCounted) {
  SKIP_WITHOUT_REDIRECTION();
  TransientArena arena(1024);
  const TransientArena::Scope scope(arena);
  auto small = std::make_unique<char[]>(100);
  auto large = std::make_unique<char[]>(4096);
  large[4095] = 'x';
  EXPECT_EQ(large[4095], 'x');
  EXPECT_EQ(arena.overflows(), 1U);
  EXPECT_EQ(arena.blocksServed(), 1U);
  const auto a = reinterpret_cast<std::uintptr_t>(large.get());
  const auto s = reinterpret_cast<std::uintptr_t>(small.get());
  EXPECT_TRUE(a + 4096 <= s || a >= s + 1024);  // the large block is not in the arena
}

TEST(TransientArena, AlignedBlocksKeepTheirAlignment) {
  SKIP_WITHOUT_REDIRECTION();
  TransientArena arena(8192);
  const TransientArena::Scope scope(arena);
  auto byte = std::make_unique<char>('a');
  struct alignas(64) Line {
    std::uint8_t bytes[64];
  };
  auto line = std::make_unique<Line>();
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(line.get()) % 64, 0U);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(byte.get()) % 16, 0U);
  EXPECT_EQ(arena.blocksServed(), 2U);
  auto* raw = static_cast<int*>(::operator new(sizeof(int), std::nothrow));
  ASSERT_NE(raw, nullptr);
  EXPECT_EQ(arena.blocksServed(), 3U);
  ::operator delete(raw, std::nothrow);
}

TEST(TransientArena, ABlockReturnedOnAnotherThreadIsCountedBack) {
  SKIP_WITHOUT_REDIRECTION();
  TransientArena arena(4096);
  std::unique_ptr<std::map<int, int> > handed;
  {
    const TransientArena::Scope scope(arena);
    handed = std::make_unique<std::map<int, int> >();
    (*handed)[1] = 2;
  }
  EXPECT_EQ(arena.blocksOut(), 2U);  // the map and its node
  std::thread other([&handed] { handed.reset(); });
  other.join();
  EXPECT_EQ(arena.blocksOut(), 0U);
}

TEST(TransientArena, ScopesDoNotNest) {
  TransientArena a(1024);
  TransientArena b(1024);
  const TransientArena::Scope outer(a);
  EXPECT_TRUE(outer.isOpen());
  const TransientArena::Scope inner(b);
  EXPECT_FALSE(inner.isOpen());
  EXPECT_EQ(TransientArena::current(), &a);
}

TEST(TransientArena, AnArenaBeyondTheRegistryHasNoBlockAndOverflows) {
  SKIP_WITHOUT_REDIRECTION();
  std::vector<std::unique_ptr<TransientArena> > arenas;
  for (std::size_t i = 0; i <= TransientArena::kMaxArenas; ++i)
    arenas.push_back(std::make_unique<TransientArena>(256));
  TransientArena& last = *arenas.back();  // the registry is full (this process has no other)
  EXPECT_EQ(last.capacity(), 0U);
  {
    const TransientArena::Scope scope(last);
    auto block = std::make_unique<int>(5);
    EXPECT_EQ(*block, 5);
  }
  EXPECT_EQ(last.overflows(), 1U);
  EXPECT_EQ(last.blocksServed(), 0U);
}

}  // namespace
}  // namespace vp::core
