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

#include "../malloc_counter.hpp"

namespace aerotrack::planning {
namespace {

TEST(KinodynamicSearchAllocation, GivenACreatedSearchAndAWarmPathThenSearchNeverAllocates) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
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
  EXPECT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);  // the interposition works
  SearchPath path;
  for (const auto& [start, goal] : queries) (void)search->search(grid, start, goal, 0.0, person, path);  // warm
  long mallocs = 0;
  int reached = 0;
  {
    aerotrack::test::g_mallocs = 0;
    aerotrack::test::g_counting_mallocs = true;
    for (const auto& [start, goal] : queries) {
      reached += search->search(grid, start, goal, 0.0, person, path) == SearchStatus::kReachedGoal ? 1 : 0;
    }
    search->setOcclusionAware(false);
    reached +=
        search->search(grid, queries[0].first, queries[0].second, 0.0, person, path) == SearchStatus::kReachedGoal ? 1
                                                                                                                   : 0;
    aerotrack::test::g_counting_mallocs = false;
    mallocs = aerotrack::test::g_mallocs.load();
  }
  EXPECT_EQ(reached, 4);
  EXPECT_EQ(mallocs, 0);
}

}  // namespace
}  // namespace aerotrack::planning
