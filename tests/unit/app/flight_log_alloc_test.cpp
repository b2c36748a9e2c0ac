// The flight log task's hot path (issue 24 item 5): once warm, a step that logs the odometry, the
// setpoint, a detection, an estimate and a planning cycle -- filled, serialized, written to the MCAP
// file -- allocates nothing (the messages live in the task's arena; the JSON values in fixed buffers).
// The 1 Hz status topics (task timings, device health) are not part of it: none are configured here.
#include <gtest/gtest.h>

#include <filesystem>

#include "flight_log.hpp"
#include "system.hpp"
#include "unit/malloc_counter.hpp"

namespace aerotrack::app {
namespace {

TEST(FlightLogAllocation, OnceWarmAStepOfTheLogAllocatesNothing) {
  if (!aerotrack::test::kMallocCounted) GTEST_SKIP() << "malloc is the sanitizer's";
  ASSERT_GE(aerotrack::test::mallocsOfAHeapBuffer(), 1);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("aerotrack-flight-log-alloc-" + std::to_string(::getpid()) + ".mcap"))
          .string();
  auto channels = std::make_unique<Channels>();
  estimation::GimbalCameraExtrinsics extrinsics;
  FlightLogOptions options;
  options.targets.mcap_path = path;
  options.targets.mcap.chunk_bytes = 64 * 1024;  // chunks closed and compressed inside the counted steps
  auto task = FlightLogTask::create(options, FlightLogSources{*channels, &extrinsics, nullptr, nullptr});
  ASSERT_TRUE(task) << task.error().message;

  hal::OdometrySample odometry;
  hal::Setpoint setpoint;
  hal::DetectionFrame detection;
  detection.person_count = 2;
  detection.target_index = 1;
  for (auto& person : detection.persons)
    for (std::size_t i = 0; i < hal::kNumKeypoints; ++i) person.keypoints[i] = {100.0 + 4.0 * i, 80.0 + 9.0 * i, 0.9};
  estimation::TargetEstimate estimate;
  estimate.initialised = true;
  estimate.lost = false;
  estimate.v_WT_mps = {1.0, 0.5, 0.0};
  estimate.covariance *= 0.02;
  planning::PlanSnapshot plan;
  plan.box_count = 5;
  plan.search_count = planning::kSnapshotPathSamples;
  plan.prediction_count = planning::kSnapshotPredictionSamples;
  auto step = [&](int k) {
    const rt::TimeNs t = 10'000'000LL * k;
    odometry.stamp_ns = setpoint.stamp_ns = t;
    odometry.p_WB_m = {0.01 * k, 0.0, 1.5};
    channels->odometry.write(odometry);
    channels->setpoints.write(setpoint);
    if (k % 3 == 0) {
      detection.stamp_ns = estimate.stamp_ns = plan.stamp_ns = t;
      detection.sequence = static_cast<std::uint64_t>(k);
      channels->newest_detection.write(detection);
      channels->target.write(estimate);
      channels->plan_snapshots.write(plan);
    }
    (*task)->step(t);
  };
  for (int k = 0; k < 300; ++k) step(k);  // warm: every buffer at its size, several chunks written
  const std::uint64_t chunks_before = (*task)->stats().chunks;
  long mallocs = 0;
  {
    const aerotrack::test::MallocCount count;
    for (int k = 300; k < 1500; ++k) step(k);
    mallocs = count.count();
  }
  EXPECT_GE((*task)->stats().chunks - chunks_before, 2U);
  EXPECT_GE((*task)->stats().messages, 1500U);
  EXPECT_EQ(mallocs, 0);
  ASSERT_TRUE((*task)->finish());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace aerotrack::app
