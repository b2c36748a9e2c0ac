// Log-bucket latency histogram and per-task timing statistics (see timing_stats.hpp).
#include "aerotrack/rt/timing_stats.hpp"

#include <algorithm>
#include <cmath>

namespace aerotrack::rt {
namespace {

std::size_t bucketOf(double sample_ns) {
  if (sample_ns <= LatencyHistogram::kMinNs) return 0;
  const double index = std::ceil(std::log(sample_ns / LatencyHistogram::kMinNs) / std::log(LatencyHistogram::kGrowth));
  return std::min(static_cast<std::size_t>(index), LatencyHistogram::kBuckets - 1);
}

double upperEdgeNs(std::size_t bucket) {
  return LatencyHistogram::kMinNs * std::pow(LatencyHistogram::kGrowth, static_cast<double>(bucket));
}

}  // namespace

void LatencyHistogram::record(DurationNs sample_ns) {
  const DurationNs clamped = std::max<DurationNs>(sample_ns, 0);
  // Single writer: load + store is enough and avoids read-modify-write instructions.
  auto& bucket = buckets_[bucketOf(static_cast<double>(clamped))];
  bucket.store(bucket.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  count_.store(count_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  sum_ns_.store(sum_ns_.load(std::memory_order_relaxed) + clamped, std::memory_order_relaxed);
  if (clamped > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(clamped, std::memory_order_relaxed);
}

double LatencyHistogram::quantileNs(double q) const {
  const std::uint64_t total = count();
  if (total == 0) return 0.0;
  // Rank of the q-quantile among the sorted samples (1-based, nearest-rank definition).
  const auto rank = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(total))));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += buckets_[i].load(std::memory_order_relaxed);
    if (seen >= rank) return std::min(upperEdgeNs(i), maxNs());
  }
  return maxNs();
}

double LatencyHistogram::meanNs() const {
  const std::uint64_t total = count();
  return total == 0 ? 0.0 : static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) / static_cast<double>(total);
}

void TimingStats::recordRun(DurationNs exec_ns) {
  execution_.record(exec_ns);
  if (budget_ns_ > 0 && exec_ns > budget_ns_) overruns_.fetch_add(1, std::memory_order_relaxed);
}

TimingSnapshot TimingStats::snapshot() const {
  TimingSnapshot s;
  s.runs = execution_.count();
  s.overruns = overruns_.load(std::memory_order_relaxed);
  s.missed_deadlines = missed_deadlines_.load(std::memory_order_relaxed);
  s.p50_ms = execution_.quantileNs(0.50) * 1e-6;
  s.p99_ms = execution_.quantileNs(0.99) * 1e-6;
  s.max_ms = execution_.maxNs() * 1e-6;
  s.mean_ms = execution_.meanNs() * 1e-6;
  return s;
}

}  // namespace aerotrack::rt
