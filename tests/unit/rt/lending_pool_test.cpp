// LendingPool: objects come back when the last handle is dropped, not before; a full pool grows; a
// handle outliving the pool stays valid; lending once warm does not allocate. The two-thread check
// (the reason the pool exists) is in tests/concurrency/channels_stress_test.cpp, run under TSan.
#include "aerotrack/rt/lending_pool.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "../malloc_counter.hpp"

namespace aerotrack::rt {
namespace {

TEST(LendingPool, GivenHeldHandlesThenEachAcquireLendsAnotherObject) {
  LendingPool<std::vector<int>> pool(2, std::vector<int>(4, 7));
  const std::shared_ptr<std::vector<int>> a = pool.acquire();
  const std::shared_ptr<std::vector<int>> b = pool.acquire();
  EXPECT_NE(a.get(), b.get());
  EXPECT_EQ(*a, std::vector<int>(4, 7));  // slots start as copies of the prototype
  EXPECT_EQ(pool.growths(), 0U);
  const std::shared_ptr<std::vector<int>> c = pool.acquire();  // both lent: the pool grows
  EXPECT_NE(c.get(), a.get());
  EXPECT_NE(c.get(), b.get());
  EXPECT_EQ(pool.growths(), 1U);
  EXPECT_EQ(pool.size(), 3U);
}

TEST(LendingPool, GivenADroppedHandleThenItsObjectIsLentAgainAsTheBorrowerLeftIt) {
  LendingPool<std::vector<int>> pool(1, std::vector<int>(3, 0));
  std::shared_ptr<std::vector<int>> a = pool.acquire();
  (*a)[1] = 42;
  const std::vector<int>* address = a.get();
  a.reset();
  const std::shared_ptr<std::vector<int>> again = pool.acquire();
  EXPECT_EQ(again.get(), address);
  EXPECT_EQ((*again)[1], 42);
  EXPECT_EQ(pool.growths(), 0U);
}

TEST(LendingPool, GivenACopiedHandleThenTheObjectStaysLentUntilTheLastCopyIsDropped) {
  LendingPool<int> pool(1, 0);
  std::shared_ptr<int> a = pool.acquire();
  std::shared_ptr<const int> reader = a;  // as a channel would hand it out
  const int* address = a.get();
  a.reset();
  const std::shared_ptr<int> b = pool.acquire();
  EXPECT_NE(b.get(), address);  // still held by reader
  EXPECT_EQ(pool.growths(), 1U);
  reader.reset();
  const std::shared_ptr<int> c = pool.acquire();
  EXPECT_EQ(c.get(), address);
  EXPECT_EQ(pool.growths(), 1U);
}

TEST(LendingPool, GivenAHandleThatOutlivesThePoolThenItsObjectStaysValid) {
  std::shared_ptr<std::vector<int>> survivor;
  {
    LendingPool<std::vector<int>> pool(2, std::vector<int>(1000, 5));
    survivor = pool.acquire();
  }
  // AddressSanitizer would report a use after free here if the slot had gone with the pool.
  long sum = 0;
  for (const int v : *survivor) sum += v;
  EXPECT_EQ(sum, 5000);
  survivor.reset();
}

TEST(LendingPool, GivenAWarmPoolThenLendingAndReturningNeverAllocate) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  EXPECT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);
  LendingPool<std::vector<double>> pool(3, std::vector<double>(10000, 0.0));
  std::shared_ptr<const std::vector<double>> held = pool.acquire();
  long mallocs = 0;
  {
    const aerotrack::test::MallocCount count;
    for (int i = 0; i < 100; ++i) {
      std::shared_ptr<std::vector<double>> lent = pool.acquire();
      (*lent)[0] = i;
      held = lent;  // the previous one goes back
    }
    mallocs = count.count();
  }
  EXPECT_EQ(mallocs, 0);
  EXPECT_EQ(pool.growths(), 0U);
}

}  // namespace
}  // namespace aerotrack::rt
