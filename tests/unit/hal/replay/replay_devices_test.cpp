// The replay backend's numeric devices (hal/replay/replay_devices.hpp) on a small hand-made recording:
// samples served by executor time in timestamp order and restamped onto the executor's clock; the
// offset and the loop; actuator commands kept, not obeyed; bad rows skipped and reported in the
// device's health, or (strict) a start-up error naming the file and line; a recording cut by a
// kill -9 replays to its last complete record.
#include "aerotrack/hal/replay/replay_devices.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "aerotrack/hal/replay/stream_codecs.hpp"
#include "support/temp_dir.hpp"

namespace aerotrack::hal::replay {
namespace {

constexpr rt::TimeNs kStart = 1'000'000'000'000;  // the recording's clock
constexpr rt::TimeNs kMs = 1'000'000;

class Recording {
 public:
  Recording() : dir_(tmp_.path()) {
    DatasetManifest m;
    m.software_version = "test";
    m.start_ns = kStart;
    m.source = "sim";
    m.streams = {{"odometry", "odometry.csv"}, {"gimbal", "gimbal.csv"}};
    EXPECT_TRUE(writeManifest(m, (dir_ / "manifest.yaml").string()));
    // Odometry at 100 Hz for 1 s, x = t; the gimbal at 50 Hz, angle = t.
    auto odometry = CsvStreamWriter::create((dir_ / "odometry.csv").string(), DeliveredOdometryCodec::columns());
    auto gimbal = CsvStreamWriter::create((dir_ / "gimbal.csv").string(), DeliveredGimbalStateCodec::columns());
    EXPECT_TRUE(odometry && gimbal);
    for (int k = 0; k <= 100; ++k) {
      OdometrySample s;
      s.stamp_ns = kStart + k * 10 * kMs;
      s.p_WB_m.x() = 0.01 * k;
      EXPECT_TRUE(odometry->write(s.stamp_ns, DeliveredOdometryCodec::encode({s, 0})));
      if (k % 2 == 0) {
        // The encoder's readings arrive 3 ms after they were taken.
        EXPECT_TRUE(
            gimbal->write(s.stamp_ns, DeliveredGimbalStateCodec::encode({{s.stamp_ns, 0.01 * k, 1.0}, 3 * kMs})));
      }
    }
  }
  std::string dir() const { return dir_.string(); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

 private:
  test::TempDir tmp_;
  std::filesystem::path dir_;
};

TEST(ReplayDevices, ServesSamplesByExecutorTimeRestampedOntoItsClock) {
  const Recording rec;
  ReplayOptions options;
  options.dir = rec.dir();
  auto dataset = ReplayDataset::open(options, /*replay_start_ns=*/0);  // lockstep: the clock starts at 0
  ASSERT_TRUE(dataset) << dataset.error().message;
  ReplayOdometry odometry(*dataset);
  ReplayGimbal gimbal(*dataset);
  auto first = odometry.read(0);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->stamp_ns, 0);
  EXPECT_EQ(first->p_WB_m.x(), 0.0);
  auto later = odometry.read(255 * kMs);  // the newest at or before 255 ms: the 250 ms sample
  ASSERT_TRUE(later.has_value());
  EXPECT_EQ(later->stamp_ns, 250 * kMs);
  EXPECT_DOUBLE_EQ(later->p_WB_m.x(), 0.25);
  auto g = gimbal.read(255 * kMs);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->stamp_ns, 240 * kMs);
  // Each record is shown from the instant it was delivered: the 260 ms reading at 263 ms, not before.
  EXPECT_EQ(gimbal.read(262 * kMs)->stamp_ns, 240 * kMs);
  EXPECT_EQ(gimbal.read(263 * kMs)->stamp_ns, 260 * kMs);
  EXPECT_EQ(odometry.health(255 * kMs).state, DeviceHealth::State::kOk);
  // After the end: the last sample stays, and the health says the recording has ended.
  EXPECT_EQ(odometry.read(2000 * kMs)->stamp_ns, 1000 * kMs);
  EXPECT_EQ(odometry.health(2000 * kMs).state, DeviceHealth::State::kFailed);
}

TEST(ReplayDevices, OffsetAndLoop) {
  const Recording rec;
  ReplayOptions options;
  options.dir = rec.dir();
  options.offset_s = 0.5;
  options.loop = true;
  auto dataset = ReplayDataset::open(options, 7 * kMs);  // real-time: some monotonic instant
  ASSERT_TRUE(dataset);
  ReplayOdometry odometry(*dataset);
  auto s = odometry.read(7 * kMs);  // the first instant shows the recording at 0.5 s
  ASSERT_TRUE(s.has_value());
  EXPECT_DOUBLE_EQ(s->p_WB_m.x(), 0.5);
  EXPECT_EQ(s->stamp_ns, 7 * kMs);
  // A lap runs from 0.5 s to the recording's last delivery (the gimbal's 1 s reading, at 1.003 s), plus
  // the 1 ns closing it: lap 2 shows the recording's 0.5 s again.
  rt::TimeNs previous = s->stamp_ns;
  for (rt::TimeNs t = 7 * kMs; t < 7 * kMs + 1200 * kMs; t += 5 * kMs) {
    auto r = odometry.read(t);
    ASSERT_TRUE(r.has_value());
    EXPECT_GE(r->stamp_ns, previous) << t;  // stamps never go back across a lap
    EXPECT_LE(r->stamp_ns, t);
    previous = r->stamp_ns;
  }
  ReplayOdometry fresh(*dataset);  // executor time only moves forward: a new reader for an earlier instant
  auto lap2 = fresh.read(7 * kMs + 2 * (503 * kMs + 1));
  ASSERT_TRUE(lap2.has_value());
  EXPECT_DOUBLE_EQ(lap2->p_WB_m.x(), 0.5);
  EXPECT_EQ(odometry.health(7 * kMs + 5000 * kMs).state, DeviceHealth::State::kOk);  // looping never ends
}

TEST(ReplayDevices, OnTheRealTimeExecutorTheReplayStartsWhenTheTasksFirstAsk) {
  const Recording rec;
  ReplayOptions options;
  options.dir = rec.dir();
  options.start_at_first_use = true;
  auto dataset = ReplayDataset::open(options, 0);  // built at 0; the tasks start 700 ms later
  ASSERT_TRUE(dataset);
  ReplayOdometry odometry(*dataset);
  ReplayGimbal gimbal(*dataset);
  auto first = odometry.read(700 * kMs);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->p_WB_m.x(), 0.0);  // the recording's first sample, not the one at 0.7 s
  EXPECT_EQ(first->stamp_ns, 700 * kMs);
  EXPECT_EQ(gimbal.read(710 * kMs)->stamp_ns, 700 * kMs);  // the other devices share the start
  EXPECT_DOUBLE_EQ(odometry.read(950 * kMs)->p_WB_m.x(), 0.25);
}

TEST(ReplayDevices, ActuatorCommandsAreKeptNotObeyed) {
  const Recording rec;
  ReplayOptions options;
  options.dir = rec.dir();
  auto dataset = ReplayDataset::open(options, 0);
  ASSERT_TRUE(dataset);
  ReplayGimbal gimbal(*dataset);
  ReplayVehicleLink link(*dataset);
  GimbalCommand c;
  c.stamp_ns = 100 * kMs;
  c.rate_radps = 3.0;
  gimbal.command(c);
  Setpoint sp;
  sp.stamp_ns = 100 * kMs;
  sp.p_W_m = {9, 9, 9};
  link.send(sp);
  ASSERT_EQ(gimbal.commands().size(), 1U);
  EXPECT_EQ(gimbal.commands()[0].rate_radps, 3.0);
  ASSERT_EQ(link.sent().size(), 1U);
  EXPECT_DOUBLE_EQ(gimbal.read(103 * kMs)->angle_rad, 0.1);  // what was recorded, whatever was commanded
  EXPECT_EQ(link.status(100 * kMs).mode, FlightMode::kOffboard);
}

TEST(ReplayDevices, BadRowsAreSkippedAndReportedOrStopTheStartWhenStrict) {
  const Recording rec;
  {
    std::ofstream out(rec.file("gimbal.csv"), std::ios::app);
    out << "1000000000000000,0,abc,0\n";  // a bad field, at the end of the recording
    out << "1000500000000,0,0.5,1\n";     // back in time
    out << "1001200000000,0,1.2,1\n";     // fine
  }
  ReplayOptions options;
  options.dir = rec.dir();
  auto lenient = ReplayDataset::open(options, 0);
  ASSERT_TRUE(lenient) << lenient.error().message;
  ReplayGimbal gimbal(*lenient);
  const DeviceHealth h = gimbal.health(0);
  EXPECT_EQ(h.state, DeviceHealth::State::kDegraded);
  EXPECT_EQ(h.error_count, 2U);
  EXPECT_NE(h.detail.find("gimbal.csv:53: angle_rad: expected a number, got 'abc'"), std::string::npos) << h.detail;
  EXPECT_DOUBLE_EQ(gimbal.read(1200 * kMs)->angle_rad, 1.2);

  options.bad_rows = BadRowPolicy::kStrict;
  auto strict = ReplayDataset::open(options, 0);
  ASSERT_FALSE(strict);
  EXPECT_NE(strict.error().message.find("gimbal.csv:53: angle_rad: expected a number"), std::string::npos);
}

TEST(ReplayDevices, MissingStreamFileOrManifestIsAOneLineError) {
  const Recording rec;
  std::filesystem::remove(rec.file("odometry.csv"));
  ReplayOptions options;
  options.dir = rec.dir();
  auto missing = ReplayDataset::open(options, 0);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("odometry.csv: cannot open"), std::string::npos);
  options.dir = rec.dir() + "/nowhere";
  auto no_manifest = ReplayDataset::open(options, 0);
  ASSERT_FALSE(no_manifest);
  EXPECT_NE(no_manifest.error().message.find("manifest.yaml"), std::string::npos);
}

TEST(ReplayDevices, ARecordingCutMidRecordReplaysToItsLastCompleteRecord) {
  const Recording rec;
  {
    std::ofstream out(rec.file("odometry.csv"), std::ios::app);
    out << "1001010000000,0,1.01,0,0,1,0";  // the record a killed recorder was writing
  }
  ReplayOptions options;
  options.dir = rec.dir();
  options.bad_rows = BadRowPolicy::kStrict;
  auto dataset = ReplayDataset::open(options, 0);
  ASSERT_TRUE(dataset) << dataset.error().message;
  const LoadedStream<Delivered<OdometrySample>>* stream = (*dataset)->odometry();
  ASSERT_NE(stream, nullptr);
  const bool truncated = stream != nullptr && stream->truncated_tail;
  const std::size_t count = stream != nullptr ? stream->samples.size() : 0;
  EXPECT_TRUE(truncated);
  EXPECT_EQ(count, 101U);
  ReplayOdometry odometry(*dataset);
  EXPECT_DOUBLE_EQ(odometry.read(5000 * kMs)->p_WB_m.x(), 1.0);
}

}  // namespace
}  // namespace aerotrack::hal::replay
