// Checks the allocation claim of the kinodynamic search (issue 7, item 2): after create(), search() with a
// reused SearchPath never allocates once the path's vector has grown to its size. malloc is interposed in
// this test binary (Eigen allocates through malloc, not operator new) and counts calls while a flag is set.
// Under AddressSanitizer or ThreadSanitizer (which own malloc) the test is skipped.
#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <vector>

#include "aerotrack/planning/kinodynamic_search.hpp"
#include "search_test_util.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_mallocs{0};
}  // namespace

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kInterposed = false;
#else
constexpr bool kInterposed = true;
extern "C" void* __libc_malloc(std::size_t size);  // NOLINT: glibc's own allocator

extern "C" void* malloc(std::size_t size) {  // NOLINT: interposes the C library's malloc
  if (g_counting.load(std::memory_order_relaxed)) g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
#endif

namespace aerotrack::planning {
namespace {

TEST(KinodynamicSearchAllocation, GivenACreatedSearchAndAWarmPathThenSearchNeverAllocates) {
  if (!kInterposed) GTEST_SKIP() << "malloc belongs to the sanitizer";
  const mapping::LocalGrid grid =
      test::makeBoxGrid(Eigen::Vector3d(10.0, 9.0, 3.0), Eigen::Vector3d(3.0, 1.25, 1.5),
                        {{Eigen::Vector3d(2.5, -1.0, -1.0), Eigen::Vector3d(3.5, 2.0, 4.0)}});
  KinodynamicSearchParams params;
  params.max_expansions = 5000;
  auto search = KinodynamicSearch::create(params);
  ASSERT_TRUE(search.has_value());
  const PersonPositionFn person = [](double /*t_s*/) { return Eigen::Vector3d(4.5, 4.0, 1.5); };
  std::vector<std::pair<KinematicState, KinematicState>> queries(3);
  queries[0].first.p_W_m = Eigen::Vector3d(0.0, 0.0, 1.5);
  queries[0].second.p_W_m = Eigen::Vector3d(6.0, 0.0, 1.5);
  queries[1].first.p_W_m = Eigen::Vector3d(5.0, -2.0, 1.0);
  queries[1].second.p_W_m = Eigen::Vector3d(1.0, 3.0, 2.0);
  queries[2].first.p_W_m = Eigen::Vector3d(0.0, 0.0, 1.5);
  queries[2].second.p_W_m = Eigen::Vector3d(0.0, 0.0, 1.5);
  {  // the interposition works: a dynamic Eigen vector is counted
    g_mallocs = 0;
    g_counting = true;
    const Eigen::VectorXd v = Eigen::VectorXd::Ones(100);
    g_counting = false;
    EXPECT_EQ(v.sum(), 100.0);
    EXPECT_GE(g_mallocs.load(), 1);
  }
  SearchPath path;
  for (const auto& [start, goal] : queries) (void)search->search(grid, start, goal, 0.0, person, path);  // warm
  long mallocs = 0;
  int reached = 0;
  {
    g_mallocs = 0;
    g_counting = true;
    for (const auto& [start, goal] : queries) {
      reached += search->search(grid, start, goal, 0.0, person, path) == SearchStatus::kReachedGoal ? 1 : 0;
    }
    search->setOcclusionAware(false);
    reached +=
        search->search(grid, queries[0].first, queries[0].second, 0.0, person, path) == SearchStatus::kReachedGoal ? 1
                                                                                                                   : 0;
    g_counting = false;
    mallocs = g_mallocs.load();
  }
  EXPECT_EQ(reached, 4);
  EXPECT_EQ(mallocs, 0);
}

}  // namespace
}  // namespace aerotrack::planning
