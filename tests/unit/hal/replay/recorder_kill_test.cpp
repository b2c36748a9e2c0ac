// A recorder killed with SIGKILL (hal/replay/recorder.hpp) leaves a dataset that the replay backend
// opens strictly: the manifest is written first and every record in one write(2).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "aerotrack/hal/replay/recorder.hpp"
#include "aerotrack/hal/replay/replay_devices.hpp"

namespace aerotrack::hal::replay {
namespace {

TEST(Recorder, AKilledRecorderLeavesADatasetThatReplaysStrictly) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("aerotrack-recorder-killed-" + std::to_string(::getpid()))).string();
  std::filesystem::remove_all(dir);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RecorderOptions options;
    options.dir = dir;
    auto recorder = DatasetRecorder::start(options, 0);
    if (!recorder) ::_exit(2);
    for (rt::TimeNs t = 0;; t += rt::kNsPerMillisecond) {
      OdometrySample s;
      s.stamp_ns = t;
      (*recorder)->record(Delivered<OdometrySample>{s, 0});
      if (t % (100 * rt::kNsPerMillisecond) == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  // Killed once its writer has written a few hundred rows (a fixed 300 ms was not enough under ASan on a busy
  // 2-core CI machine: nothing was written yet), or after 30 s whatever it wrote.
  const std::filesystem::path odometry_csv = std::filesystem::path(dir) / "odometry.csv";
  for (int waited_ms = 0; waited_ms < 30000; waited_ms += 10) {
    std::error_code error;
    if (std::filesystem::file_size(odometry_csv, error) > 8192 && !error) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(::kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  ReplayOptions replay;
  replay.dir = dir;
  replay.bad_rows = BadRowPolicy::kStrict;
  auto dataset = ReplayDataset::open(replay, 0);
  ASSERT_TRUE(dataset) << dataset.error().message;
  ASSERT_NE((*dataset)->odometry(), nullptr);
  const std::size_t samples = (*dataset)->odometry() != nullptr ? (*dataset)->odometry()->samples.size() : 0;
  EXPECT_GT(samples, 10U);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace aerotrack::hal::replay
