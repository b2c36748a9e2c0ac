// The input policy (issue 23): the largest file of each kind the program reads, the largest world
// it generates, the longest run it simulates or replays and the valid range of every time stamp.
// Every reader checks its limit before it allocates for the input, and fails with one line that
// names the file and the limit. One place, so that a reviewer can see all of them and a change is
// a one-line diff; docs/input-limits.md explains each figure.
#pragma once

#include <cstdint>

#include "aerotrack/rt/time.hpp"

namespace aerotrack::rt::limits {

inline constexpr std::uint64_t kKiB = 1024;
inline constexpr std::uint64_t kMiB = 1024 * kKiB;

/// YAML: configs, scenarios, suites, casts, calibrations, dataset manifests, localization
/// parameters. The largest shipped one is ~12 KiB; a scenario listing thousands of obstacles fits.
inline constexpr std::uint64_t kMaxYamlBytes = 4 * kMiB;
/// Small text files read whole: summary.json of a trial, a model's sidecar, a device serial.
inline constexpr std::uint64_t kMaxTextBytes = 16 * kMiB;
/// One line of a CSV (recordings, calibration data, candump logs). The widest row, detections.csv
/// with six persons, 17 keypoints and 80 appearance bins each, is ~40 KiB.
inline constexpr std::uint64_t kMaxCsvLineBytes = 256 * kKiB;
/// A localization calibration CSV read whole (~100 bytes a row: a million rows).
inline constexpr std::uint64_t kMaxCalibrationCsvBytes = 256 * kMiB;
/// An image file (photo, recorded frame, MJPG frame) before decoding, and the decoded size.
inline constexpr std::uint64_t kMaxImageFileBytes = 64 * kMiB;
inline constexpr int kMaxImageSidePx = 8192;
inline constexpr std::uint64_t kMaxImagePixels = 4096ULL * 4096ULL;

/// The generated world: every coordinate within +-kMaxWorldExtentM, at most kMaxObstacles boxes,
/// cylinders and trees together (the mapper and the renderer walk them every frame).
inline constexpr double kMaxWorldExtentM = 2000.0;
inline constexpr std::uint64_t kMaxObstacles = 200000;

/// The longest simulated run (max_duration_s), replay and recording span.
inline constexpr double kMaxRunS = 6.0 * 3600.0;
inline constexpr TimeNs kMaxRunNs = static_cast<TimeNs>(kMaxRunS) * 1'000'000'000;

/// A recorded stamp (CLOCK_MONOTONIC or the Unix epoch in ns) lies in [0, kMaxStampNs]: the year
/// 2116 on the Unix epoch, and far enough below INT64_MAX that a stamp plus a run, or the
/// difference of two stamps, cannot overflow.
inline constexpr TimeNs kMaxStampNs = TimeNs{1} << 62;

}  // namespace aerotrack::rt::limits
