// Dataset comparison: see dataset_compare.hpp.
#include "dataset_compare.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>

#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"
#include "output_recorder.hpp"

namespace aerotrack::app {
namespace {

using hal::replay::CsvRecord;
using hal::replay::CsvStreamReader;

struct ComparedStream {
  const char* file;
  const std::vector<std::string>& columns;
  bool input;  ///< What a device delivered (not what the system produced).
};

std::vector<ComparedStream> comparedStreams() {
  using namespace hal::replay;  // NOLINT(google-build-using-namespace): the codecs, in this function only
  return {                      // What the devices delivered: the replay must have fed all of it.
          {"odometry.csv", DeliveredOdometryCodec::columns(), true},
          {"gimbal.csv", DeliveredGimbalStateCodec::columns(), true},
          {"depth_camera/frames.csv", DeliveredFrameIndexCodec::columns(), true},
          {"gimbal_camera/frames.csv", DeliveredFrameIndexCodec::columns(), true},
          {"gimbal_camera/detections.csv", DeliveredDetectionCodec::columns(), true},
          // What the modules decided and the actuators were told.
          {"setpoints.csv", SetpointCodec::columns(), false},
          {"gimbal_commands.csv", GimbalCommandCodec::columns(), false},
          {"outputs/detections.csv", DetectionCodec::columns(), false},
          {"outputs/estimates.csv", EstimateCodec::columns(), false},
          {"outputs/trajectories.csv", TrajectoryCodec::columns(), false}};
}

bool sameBits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);  // -0.0 differs from 0.0, NaN == NaN
}

std::string number(double x) {
  std::ostringstream out;
  out.precision(17);
  out << x;
  return out.str();
}

rt::Expected<std::vector<CsvRecord>> readAll(const std::string& path, const std::vector<std::string>& columns) {
  auto reader = CsvStreamReader::open(path, columns, hal::replay::BadRowPolicy::kStrict);
  if (!reader) return reader.error();
  std::vector<CsvRecord> out;
  for (;;) {
    auto record = reader->next();
    if (!record) return record.error();
    if (!record->has_value()) return out;
    out.push_back(std::move(**record));
  }
}

}  // namespace

rt::Expected<std::vector<StreamComparison>> compareDatasets(const std::string& recorded_dir,
                                                            const std::string& replayed_dir, bool inputs,
                                                            bool recording_cut_short) {
  namespace fs = std::filesystem;
  // Stamps are compared from each recording's start: a replay on another clock (real time) lines up.
  const auto a_manifest = hal::replay::readManifest((fs::path(recorded_dir) / "manifest.yaml").string());
  if (!a_manifest) return a_manifest.error();
  const auto b_manifest = hal::replay::readManifest((fs::path(replayed_dir) / "manifest.yaml").string());
  if (!b_manifest) return b_manifest.error();
  const rt::TimeNs a_start_ns = a_manifest->start_ns;
  const rt::TimeNs b_start_ns = b_manifest->start_ns;
  struct Loaded {
    const ComparedStream* stream;
    std::string a_path;
    std::vector<CsvRecord> a, b;
  };
  const std::vector<ComparedStream> streams = comparedStreams();
  std::vector<Loaded> loaded;
  for (const ComparedStream& stream : streams) {
    if (stream.input && !inputs) continue;
    const std::string a_path = (fs::path(recorded_dir) / stream.file).string();
    const std::string b_path = (fs::path(replayed_dir) / stream.file).string();
    std::error_code ec;
    if (!fs::exists(a_path, ec) || !fs::exists(b_path, ec)) continue;
    auto a = readAll(a_path, stream.columns);
    if (!a) return a.error();
    auto b = readAll(b_path, stream.columns);
    if (!b) return b.error();
    if (a->empty() && b->empty()) continue;
    loaded.push_back({&stream, a_path, std::move(a.value()), std::move(b.value())});
  }
  // A recorder killed mid-run flushed each stream up to a different record: past the earliest
  // stream's last record the recording is incomplete (an output on disk whose input is not, a
  // replay's records the recorder never saw). Both sides are compared up to that time only.
  rt::TimeNs complete_until_ns = std::numeric_limits<rt::TimeNs>::max();
  if (recording_cut_short) {
    for (const Loaded& l : loaded)
      if (!l.a.empty()) complete_until_ns = std::min(complete_until_ns, l.a.back().stamp_ns - a_start_ns);
  }
  std::vector<StreamComparison> out;
  for (Loaded& l : loaded) {
    const ComparedStream& stream = *l.stream;
    const std::string& a_path = l.a_path;
    std::vector<CsvRecord>& a = l.a;
    std::vector<CsvRecord>& b = l.b;
    StreamComparison c;
    while (!a.empty() && a.back().stamp_ns - a_start_ns > complete_until_ns) {
      a.pop_back();
      ++c.past_end;
    }
    while (!b.empty() && b.back().stamp_ns - b_start_ns > complete_until_ns) {
      b.pop_back();
      ++c.past_end;
    }
    c.file = stream.file;
    c.recorded = a.size();
    c.replayed = b.size();
    const std::size_t n = std::min(a.size(), b.size());
    for (std::size_t i = 0; i < n; ++i) {
      const CsvRecord& x = a[i];
      const CsvRecord& y = b[i];
      const rt::TimeNs x_ns = x.stamp_ns - a_start_ns;
      const rt::TimeNs y_ns = y.stamp_ns - b_start_ns;
      bool same = x_ns == y_ns;
      c.max_abs_difference = std::max(c.max_abs_difference, std::abs(static_cast<double>(x_ns - y_ns)));
      std::optional<std::size_t> column;
      for (std::size_t k = 0; k < x.values.size(); ++k) {
        if (sameBits(x.values[k], y.values[k])) continue;
        same = false;
        if (!column) column = k;
        c.max_abs_difference = std::max(c.max_abs_difference, std::abs(x.values[k] - y.values[k]));
      }
      if (same) {
        ++c.identical;
        continue;
      }
      if (c.first_difference.empty()) {
        c.first_difference = a_path + ":" + std::to_string(x.line) + ": ";
        c.first_difference += x_ns != y_ns ? "time from the start " + std::to_string(x_ns) + " ns recorded, " +
                                                 std::to_string(y_ns) + " ns replayed"
                                           : stream.columns[*column] + " " + number(x.values[*column]) + " recorded, " +
                                                 number(y.values[*column]) + " replayed";
      }
    }
    if (c.first_difference.empty() && a.size() != b.size()) {
      c.first_difference =
          a_path + ": " + std::to_string(a.size()) + " records recorded, " + std::to_string(b.size()) + " replayed";
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::string formatComparison(const std::vector<StreamComparison>& comparisons) {
  std::ostringstream out;
  for (const StreamComparison& c : comparisons) {
    out << "  " << c.file << ": " << c.identical << " of " << c.recorded << " recorded records replayed identically";
    if (c.same()) {
      out << " (bit for bit)";
      if (c.past_end > 0) out << "; " << c.past_end << " past the recording's complete part, not compared";
      out << "\n";
    } else {
      out << "; " << c.replayed << " replayed, largest difference " << number(c.max_abs_difference)
          << "; first: " << c.first_difference << "\n";
    }
  }
  return out.str();
}

}  // namespace aerotrack::app
