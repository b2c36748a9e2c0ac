// Channel benchmarks: our SpscQueue against moodycamel::ReaderWriterQueue (Debian's
// libreaderwriterqueue-dev, the library the design prefers), single-thread push+pop latency and
// two-thread throughput; the latest-value slot's write and read.
#include <benchmark/benchmark.h>
#include <readerwriterqueue/readerwriterqueue.h>

#include <thread>

#include "aerotrack/rt/latest_slot.hpp"
#include "aerotrack/rt/spsc_queue.hpp"

namespace {

using aerotrack::rt::LatestSlot;
using aerotrack::rt::OverflowPolicy;
using aerotrack::rt::SpscQueue;

constexpr std::size_t kCapacity = 1024;
constexpr std::int64_t kBatch = 1 << 20;

void BM_SpscQueue_PushPop(benchmark::State& state) {
  SpscQueue<std::uint64_t> q(kCapacity, static_cast<OverflowPolicy>(state.range(0)));
  std::uint64_t v = 0;
  for (auto _ : state) {
    q.try_push(v);
    q.try_pop(v);
    benchmark::DoNotOptimize(v);
  }
}
BENCHMARK(BM_SpscQueue_PushPop)->ArgName("drop_oldest")->Arg(0)->Arg(1);

void BM_ReaderWriterQueue_PushPop(benchmark::State& state) {
  moodycamel::ReaderWriterQueue<std::uint64_t> q(kCapacity);
  std::uint64_t v = 0;
  for (auto _ : state) {
    q.try_enqueue(v);
    q.try_dequeue(v);
    benchmark::DoNotOptimize(v);
  }
}
BENCHMARK(BM_ReaderWriterQueue_PushPop);

// Two threads: a producer pushes kBatch items, the consumer (this thread) pops them all.
template <class Push, class Pop>
void twoThreads(benchmark::State& state, Push push, Pop pop) {
  for (auto _ : state) {
    std::thread producer([&] {
      for (std::uint64_t i = 0; i < kBatch; ++i)
        while (!push(i)) {
        }
    });
    std::uint64_t v = 0, n = 0;
    while (n < kBatch)
      if (pop(v)) ++n;
    producer.join();
    benchmark::DoNotOptimize(v);
  }
  state.SetItemsProcessed(state.iterations() * kBatch);
}

void BM_SpscQueue_TwoThreads(benchmark::State& state) {
  SpscQueue<std::uint64_t> q(kCapacity, static_cast<OverflowPolicy>(state.range(0)));
  twoThreads(
      state, [&](std::uint64_t i) { return q.try_push(i); }, [&](std::uint64_t& v) { return q.try_pop(v); });
}
BENCHMARK(BM_SpscQueue_TwoThreads)->ArgName("drop_oldest")->Arg(0)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_ReaderWriterQueue_TwoThreads(benchmark::State& state) {
  moodycamel::ReaderWriterQueue<std::uint64_t> q(kCapacity);
  twoThreads(
      state, [&](std::uint64_t i) { return q.try_enqueue(i); }, [&](std::uint64_t& v) { return q.try_dequeue(v); });
}
BENCHMARK(BM_ReaderWriterQueue_TwoThreads)->UseRealTime()->Unit(benchmark::kMillisecond);

struct Odometry {
  double p[3], q[4], v[3], w[3];
  std::int64_t stamp;
};

void BM_LatestSlot_Write(benchmark::State& state) {
  LatestSlot<Odometry> slot;
  Odometry o{};
  for (auto _ : state) {
    ++o.stamp;
    slot.write(o);
  }
}
BENCHMARK(BM_LatestSlot_Write);

void BM_LatestSlot_Read(benchmark::State& state) {
  LatestSlot<Odometry> slot;
  slot.write(Odometry{});
  for (auto _ : state) benchmark::DoNotOptimize(slot.read());
}
BENCHMARK(BM_LatestSlot_Read);

}  // namespace
