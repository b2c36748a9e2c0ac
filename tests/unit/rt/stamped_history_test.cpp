// Unit tests of rt::StampedHistory, the one timestamped history behind the pose and gimbal-angle
// histories: seeded random pushes (in order, out of order, duplicates, refused samples) and lookups
// checked against a slow obvious reference (a plain vector of the samples kept, linear search and the
// interpolation written out); parameter validation; eviction; the hold tolerance; the traits'
// admit/none hooks; and no allocation in push or lookup after create().
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "../malloc_counter.hpp"
#include "aerotrack/rt/stamped_history.hpp"

namespace aerotrack::rt {
namespace {

struct ScalarSample {
  TimeNs stamp_ns = 0;
  double x = 0.0;
};

/// A scalar, linearly interpolated; non-finite values refused.
struct ScalarTraits {
  using Sample = ScalarSample;
  using Value = double;
  static constexpr std::string_view kName = "scalar history";
  static bool admit(const ScalarSample& s) { return std::isfinite(s.x); }
  static double value(const ScalarSample& s) { return s.x; }
  static double interpolate(const ScalarSample& a, const ScalarSample& b, double alpha) {
    return a.x + alpha * (b.x - a.x);
  }
};
using ScalarHistory = StampedHistory<ScalarTraits>;

/// Admission that normalises (clamps to [-1, 1]) and a sentinel for failed lookups.
struct ClampedTraits {
  using Sample = ScalarSample;
  using Value = double;
  static constexpr std::string_view kName = "clamped history";
  static bool admit(ScalarSample& s) {
    if (std::isnan(s.x)) return false;
    s.x = std::clamp(s.x, -1.0, 1.0);
    return true;
  }
  static double value(const ScalarSample& s) { return s.x; }
  static double interpolate(const ScalarSample& a, const ScalarSample& b, double alpha) {
    return a.x + alpha * (b.x - a.x);
  }
  static double none() { return -99.0; }
};

/// The slow obvious reference: every accepted sample in a vector, the newest `capacity` of them kept.
struct ReferenceHistory {
  StampedHistoryParams params;
  std::vector<ScalarSample> kept;
  std::uint64_t accepted = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t invalid = 0;

  HistoryPush push(const ScalarSample& s) {
    if (!std::isfinite(s.x)) {
      ++invalid;
      return HistoryPush::kRejectedInvalid;
    }
    if (!kept.empty() && s.stamp_ns <= kept.back().stamp_ns) {
      ++out_of_order;
      return HistoryPush::kRejectedOutOfOrder;
    }
    kept.push_back(s);
    if (kept.size() > params.capacity) kept.erase(kept.begin());
    ++accepted;
    return HistoryPush::kAccepted;
  }

  HistoryLookup<double> lookup(TimeNs t_ns) const {
    if (kept.empty()) return {HistoryStatus::kEmpty, 0.0};
    if (t_ns < kept.front().stamp_ns) return {HistoryStatus::kBeforeOldest, 0.0};
    for (const ScalarSample& s : kept) {
      if (s.stamp_ns == t_ns) return {HistoryStatus::kOk, s.x};
    }
    if (t_ns > kept.back().stamp_ns) {
      if (t_ns - kept.back().stamp_ns > params.future_tolerance_ns) return {HistoryStatus::kAfterNewest, 0.0};
      return {HistoryStatus::kOk, kept.back().x};  // held, not extrapolated
    }
    for (std::size_t i = 0; i + 1 < kept.size(); ++i) {
      const ScalarSample& a = kept[i];
      const ScalarSample& b = kept[i + 1];
      if (a.stamp_ns < t_ns && t_ns < b.stamp_ns) {
        if (b.stamp_ns - a.stamp_ns > params.max_gap_ns) return {HistoryStatus::kGapTooLarge, 0.0};
        const double alpha = static_cast<double>(t_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
        return {HistoryStatus::kOk, a.x + alpha * (b.x - a.x)};
      }
    }
    ADD_FAILURE() << "reference: no bracket for t = " << t_ns;
    return {HistoryStatus::kEmpty, 0.0};
  }
};

TEST(StampedHistory, GivenSeededRandomPushesWhenLookedUpEverywhereThenTheLinearScanReferenceAgrees) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    StampedHistoryParams params;
    params.capacity = std::uniform_int_distribution<std::size_t>(2, 12)(rng);
    params.max_gap_ns = std::uniform_int_distribution<DurationNs>(5, 40)(rng);
    params.future_tolerance_ns = std::uniform_int_distribution<DurationNs>(0, 1)(rng) * 7;
    auto history = ScalarHistory::create(params);
    ASSERT_TRUE(history.has_value()) << history.error().message;
    ReferenceHistory reference{params, {}, 0, 0, 0};

    std::uniform_int_distribution<int> step(-6, 30);  // <= 0: out of order or a duplicate
    std::uniform_real_distribution<double> value(-5.0, 5.0);
    std::bernoulli_distribution refuse(0.05);
    TimeNs stamp_ns = 0;
    for (int k = 0; k < 200; ++k) {
      stamp_ns += step(rng);
      const ScalarSample s{stamp_ns, refuse(rng) ? std::numeric_limits<double>::quiet_NaN() : value(rng)};
      ASSERT_EQ(history->push(s), reference.push(s)) << "seed " << seed << ", push " << k;
      ASSERT_EQ(history->size(), reference.kept.size());
      if (k % 10 != 9) continue;
      // Every time from before the oldest kept to past the newest, each stamp included.
      const TimeNs from_ns = reference.kept.empty() ? -5 : reference.kept.front().stamp_ns - 5;
      const TimeNs to_ns = reference.kept.empty() ? 5 : reference.kept.back().stamp_ns + 10;
      for (TimeNs t = from_ns; t <= to_ns; ++t) {
        const HistoryLookup<double> got = history->lookup(t);
        const HistoryLookup<double> want = reference.lookup(t);
        ASSERT_EQ(got.status, want.status) << "seed " << seed << ", t " << t;
        if (want.status == HistoryStatus::kOk) {
          EXPECT_EQ(got.value, want.value) << "seed " << seed << ", t " << t;
          const std::optional<double> at = history->valueAt(t);
          ASSERT_TRUE(at.has_value());
          EXPECT_EQ(*at, want.value);
        } else {
          EXPECT_FALSE(history->valueAt(t).has_value()) << "seed " << seed << ", t " << t;
        }
      }
    }
    EXPECT_EQ(history->acceptedCount(), reference.accepted);
    EXPECT_EQ(history->rejectedOutOfOrderCount(), reference.out_of_order);
    EXPECT_EQ(history->rejectedInvalidCount(), reference.invalid);
    EXPECT_EQ(history->rejectedCount(), reference.out_of_order + reference.invalid);
    for (std::size_t i = 0; i < reference.kept.size(); ++i) {
      EXPECT_EQ(history->at(i).stamp_ns, reference.kept[i].stamp_ns);
      EXPECT_EQ(history->at(i).x, reference.kept[i].x);
    }
  }
}

TEST(StampedHistory, GivenInvalidParamsWhenCreatedThenAnErrorNamingTheHistoryAndTheField) {
  StampedHistoryParams params;
  params.capacity = 1;
  auto bad = ScalarHistory::create(params);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().message, "scalar history: capacity must be >= 2, got 1");
  params = {};
  params.max_gap_ns = 0;
  bad = ScalarHistory::create(params);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().message, "scalar history: max_gap_ns must be > 0, got 0");
  params = {};
  params.future_tolerance_ns = -1;
  bad = ScalarHistory::create(params);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().message, "scalar history: future_tolerance_ns must be >= 0, got -1");
  params = {};
  params.capacity = 2;
  params.max_gap_ns = 1;
  EXPECT_TRUE(ScalarHistory::create(params).has_value());  // the smallest valid ones
  const auto defaults = ScalarHistory::create({});
  ASSERT_TRUE(defaults.has_value());
  EXPECT_EQ(defaults->capacity(), 512U);
  EXPECT_EQ(defaults->params().max_gap_ns, 50 * kNsPerMillisecond);
  EXPECT_EQ(defaults->params().future_tolerance_ns, 0);
}

TEST(StampedHistory, GivenAFullRingWhenPushedThenTheOldestIsEvictedAndOlderTimesAreBeforeTheOldest) {
  auto history = ScalarHistory::create({.capacity = 3, .max_gap_ns = 100});
  ASSERT_TRUE(history.has_value());
  for (int i = 1; i <= 5; ++i) ASSERT_EQ(history->push({i * 10, static_cast<double>(i)}), HistoryPush::kAccepted);
  ASSERT_EQ(history->size(), 3U);
  EXPECT_EQ(history->oldest().stamp_ns, 30);
  EXPECT_EQ(history->newest().stamp_ns, 50);
  EXPECT_EQ(history->lookup(29).status, HistoryStatus::kBeforeOldest);  // 20..29 were evicted
  EXPECT_EQ(history->lookup(30).value, 3.0);
  EXPECT_EQ(history->lookup(45).value, 4.5);
}

TEST(StampedHistory, GivenOlderOrDuplicateStampsWhenPushedThenRejectedCountedAndTheRingUnchanged) {
  auto history = ScalarHistory::create({.capacity = 4, .max_gap_ns = 100});
  ASSERT_TRUE(history.has_value());
  ASSERT_EQ(history->push({10, 1.0}), HistoryPush::kAccepted);
  ASSERT_EQ(history->push({20, 2.0}), HistoryPush::kAccepted);
  EXPECT_EQ(history->push({15, 9.0}), HistoryPush::kRejectedOutOfOrder);  // never reordered in
  EXPECT_EQ(history->push({20, 9.0}), HistoryPush::kRejectedOutOfOrder);  // a duplicate
  EXPECT_EQ(history->push({30, std::numeric_limits<double>::infinity()}), HistoryPush::kRejectedInvalid);
  EXPECT_EQ(history->size(), 2U);
  EXPECT_EQ(history->lookup(15).value, 1.5);
  EXPECT_EQ(history->lookup(20).value, 2.0);
  EXPECT_EQ(history->rejectedOutOfOrderCount(), 2U);
  EXPECT_EQ(history->rejectedInvalidCount(), 1U);
  EXPECT_EQ(history->acceptedCount(), 2U);
  EXPECT_EQ(history->push({30, 3.0}), HistoryPush::kAccepted);  // a refused stamp is still free
}

TEST(StampedHistory, GivenAToleranceWhenLookedUpJustAfterTheNewestThenTheNewestIsHeldNotExtrapolated) {
  auto history = ScalarHistory::create({.capacity = 4, .max_gap_ns = 100, .future_tolerance_ns = 5});
  ASSERT_TRUE(history.has_value());
  ASSERT_EQ(history->push({0, 0.0}), HistoryPush::kAccepted);
  ASSERT_EQ(history->push({10, 1.0}), HistoryPush::kAccepted);
  EXPECT_EQ(history->lookup(15).status, HistoryStatus::kOk);
  EXPECT_EQ(history->lookup(15).value, 1.0);  // not 1.5
  EXPECT_EQ(history->lookup(16).status, HistoryStatus::kAfterNewest);
}

TEST(StampedHistory, GivenTraitsThatNormaliseAndASentinelThenTheAdmittedSampleIsKeptAndFailuresGiveTheSentinel) {
  auto history = StampedHistory<ClampedTraits>::create({.capacity = 4, .max_gap_ns = 100});
  ASSERT_TRUE(history.has_value());
  EXPECT_EQ(history->lookup(0).value, -99.0);  // empty
  ASSERT_EQ(history->push({0, 7.0}), HistoryPush::kAccepted);
  ASSERT_EQ(history->push({10, -3.0}), HistoryPush::kAccepted);
  EXPECT_EQ(history->push({20, std::nan("")}), HistoryPush::kRejectedInvalid);
  EXPECT_EQ(history->oldest().x, 1.0);  // stored as admitted
  EXPECT_EQ(history->lookup(5).value, 0.0);
  EXPECT_EQ(history->lookup(-1).value, -99.0);
  EXPECT_EQ(history->lookup(11).value, -99.0);
}

TEST(StampedHistory, GivenEveryStatusThenEachHasItsOwnPhrase) {
  const HistoryStatus all[] = {HistoryStatus::kOk, HistoryStatus::kEmpty, HistoryStatus::kBeforeOldest,
                               HistoryStatus::kAfterNewest, HistoryStatus::kGapTooLarge};
  std::vector<std::string> phrases;
  for (HistoryStatus s : all) phrases.emplace_back(toString(s));
  std::sort(phrases.begin(), phrases.end());
  EXPECT_EQ(std::unique(phrases.begin(), phrases.end()), phrases.end());
  EXPECT_EQ(std::string(toString(HistoryStatus::kAfterNewest)), "newer than the newest sample");
}

TEST(StampedHistory, GivenACreatedHistoryThenPushAndLookupNeverAllocate) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc belongs to the sanitizer";
  auto history = ScalarHistory::create({.capacity = 64, .max_gap_ns = 100});
  ASSERT_TRUE(history.has_value());
  EXPECT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);  // the interposer works
  long mallocs = 0;
  double sum = 0.0;
  {
    const aerotrack::test::MallocCount count;
    for (TimeNs t = 0; t < 1000; t += 7) (void)history->push({t, static_cast<double>(t)});  // wraps the ring
    (void)history->push({0, 1.0});                                                          // refused
    for (TimeNs t = 400; t < 1100; t += 3) {
      sum += history->lookup(t).value;
      sum += history->valueAt(t).value_or(0.0);
    }
    mallocs = count.count();
  }
  EXPECT_EQ(mallocs, 0);
  EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace aerotrack::rt
