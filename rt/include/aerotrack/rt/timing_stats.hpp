// Per-task timing statistics (runs, overruns, execution time p50/p99/max), printed at exit and
// written into the sim's summary.json. Recording is O(1), allocation-free and wait-free for the
// single thread that records; other threads may take a snapshot() at any time (values are
// relaxed atomics: a snapshot taken while the task runs may be off by the sample in flight).
//
// Percentiles come from a logarithmic histogram with 1 % bucket width from 10 ns to 100 s, so a
// reported p50/p99 is within 1 % of the true order statistic; max is exact.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt {

/// A copy of a TimingStats at one moment, in milliseconds.
struct TimingSnapshot {
  std::uint64_t runs = 0;
  std::uint64_t overruns = 0;          ///< Runs whose execution time exceeded the budget.
  std::uint64_t missed_deadlines = 0;  ///< Periods skipped because a run ended after the next release.
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  double max_ms = 0.0;
  double mean_ms = 0.0;
};

/// A latency histogram: log buckets of 1 % width. Single recording thread.
class LatencyHistogram {
 public:
  static constexpr double kMinNs = 10.0;
  static constexpr double kGrowth = 1.01;
  static constexpr std::size_t kBuckets = 2316;  // 10 ns * 1.01^2315 ~ 100 s

  void record(DurationNs sample_ns);
  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }
  /// The q-quantile (0 <= q <= 1) in nanoseconds: the upper edge of the bucket holding it,
  /// clamped to the exact maximum. 0 if empty.
  double quantileNs(double q) const;
  double maxNs() const { return static_cast<double>(max_ns_.load(std::memory_order_relaxed)); }
  double meanNs() const;

 private:
  std::array<std::atomic<std::uint64_t>, kBuckets> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> max_ns_{0};
  std::atomic<std::int64_t> sum_ns_{0};
};

class TimingStats {
 public:
  explicit TimingStats(DurationNs budget_ns = 0) : budget_ns_(budget_ns) {}

  /// Records one run that took exec_ns of execution time. Counts an overrun if over budget.
  void recordRun(DurationNs exec_ns);
  /// Records how late a periodic task woke relative to its release time (real-time executor).
  void recordWakeLatency(DurationNs late_ns) { wake_latency_.record(late_ns); }
  void addMissedDeadlines(std::uint64_t n) { missed_deadlines_.fetch_add(n, std::memory_order_relaxed); }

  TimingSnapshot snapshot() const;
  const LatencyHistogram& execution() const { return execution_; }
  const LatencyHistogram& wakeLatency() const { return wake_latency_; }
  DurationNs budgetNs() const { return budget_ns_; }

 private:
  DurationNs budget_ns_;
  LatencyHistogram execution_;
  LatencyHistogram wake_latency_;
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> missed_deadlines_{0};
};

}  // namespace aerotrack::rt
