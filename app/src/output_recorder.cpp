// Output streams: see output_recorder.hpp.
#include "output_recorder.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <utility>

#include "aerotrack/hal/replay/stream_codecs.hpp"

namespace aerotrack::app {
namespace {

void put(std::vector<double>& out, const Eigen::Vector3d& v) {
  out.insert(out.end(), {v.x(), v.y(), v.z()});
}

/// FNV-1a over the bytes of a double.
void digest(std::uint64_t& h, double x) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof(bits));
  for (int i = 0; i < 8; ++i) {
    h ^= (bits >> (8 * i)) & 0xffU;
    h *= 1099511628211ULL;
  }
}

}  // namespace

const std::vector<std::string>& EstimateCodec::columns() {
  static const std::vector<std::string> kColumns = [] {
    std::vector<std::string> c = {"initialised",     "lost", "px_m", "py_m", "pz_m", "vx_mps", "vy_mps", "vz_mps",
                                  "last_accepted_ns"};
    for (int r = 0; r < 6; ++r)
      for (int k = r; k < 6; ++k) c.push_back("cov" + std::to_string(r) + std::to_string(k));
    return c;
  }();
  return kColumns;
}

std::vector<double> EstimateCodec::encode(const estimation::TargetEstimate& e) {
  std::vector<double> out = {e.initialised ? 1.0 : 0.0, e.lost ? 1.0 : 0.0};
  put(out, e.p_WT_m);
  put(out, e.v_WT_mps);
  out.push_back(static_cast<double>(e.last_accepted_ns));
  for (int r = 0; r < 6; ++r)
    for (int k = r; k < 6; ++k) out.push_back(e.covariance(r, k));
  return out;
}

rt::Expected<estimation::TargetEstimate> EstimateCodec::decode(const hal::replay::CsvRecord& record,
                                                               const std::string& path) {
  const std::vector<double>& v = record.values;
  if (v.size() != columns().size()) return rt::Error{path + ":" + std::to_string(record.line) + ": wrong field count"};
  for (const double x : v) {
    if (!std::isfinite(x)) return rt::Error{path + ":" + std::to_string(record.line) + ": a value is not finite"};
  }
  estimation::TargetEstimate e;
  e.stamp_ns = record.stamp_ns;
  e.initialised = v[0] != 0.0;
  e.lost = v[1] != 0.0;
  e.p_WT_m = {v[2], v[3], v[4]};
  e.v_WT_mps = {v[5], v[6], v[7]};
  e.last_accepted_ns = static_cast<rt::TimeNs>(v[8]);
  std::size_t i = 9;
  for (int r = 0; r < 6; ++r) {
    for (int k = r; k < 6; ++k) e.covariance(r, k) = e.covariance(k, r) = v[i++];
  }
  return e;
}

const std::vector<std::string>& TrajectoryCodec::columns() {
  static const std::vector<std::string> kColumns = {"start_ns",  "duration_s", "source_capture_ns",
                                                    "digest_hi", "digest_lo",  "p0x_m",
                                                    "p0y_m",     "p0z_m",      "pmx_m",
                                                    "pmy_m",     "pmz_m",      "pex_m",
                                                    "pey_m",     "pez_m"};
  return kColumns;
}

std::vector<double> TrajectoryCodec::encode(const trajectory_server::TimedTrajectory& t) {
  const trajectory_server::Trajectory& trajectory = *t.trajectory;
  const double duration_s = trajectory.durationS();
  std::uint64_t h = 14695981039346656037ULL;
  for (int i = 0; i <= kTrajectoryDigestSamples; ++i) {
    const trajectory_server::TrajectorySample s = trajectory.sample(duration_s * i / kTrajectoryDigestSamples);
    for (const Eigen::Vector3d* v : {&s.p_W_m, &s.v_W_mps, &s.a_W_mps2})
      for (int k = 0; k < 3; ++k) digest(h, (*v)(k));
  }
  std::vector<double> out = {static_cast<double>(t.start_ns), duration_s, static_cast<double>(t.source_capture_ns),
                             static_cast<double>(h >> 32), static_cast<double>(h & 0xffffffffULL)};
  for (const double at_s : {0.0, 0.5 * duration_s, duration_s}) put(out, trajectory.sample(at_s).p_W_m);
  return out;
}

rt::Expected<std::unique_ptr<OutputRecorderTask>> OutputRecorderTask::create(
    const std::string& dir, const rt::LatestSlot<hal::DetectionFrame>& detections,
    const rt::LatestSlot<estimation::TargetEstimate>& estimates,
    const rt::SharedSlot<trajectory_server::TimedTrajectory>& trajectories) {
  const std::filesystem::path folder = std::filesystem::path(dir) / "outputs";
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) return rt::Error{"record: " + folder.string() + ": cannot create: " + ec.message()};
  std::vector<hal::replay::CsvStreamWriter> writers;
  const std::pair<const char*, const std::vector<std::string>*> files[] = {
      {"detections.csv", &hal::replay::DetectionCodec::columns()},
      {"estimates.csv", &EstimateCodec::columns()},
      {"trajectories.csv", &TrajectoryCodec::columns()}};
  for (const auto& [name, columns] : files) {
    auto writer = hal::replay::CsvStreamWriter::create((folder / name).string(), *columns);
    if (!writer) return rt::Error{"record: " + writer.error().message};
    writers.push_back(std::move(writer.value()));
  }
  return std::unique_ptr<OutputRecorderTask>(
      new OutputRecorderTask(detections, estimates, trajectories, std::move(writers)));
}

rt::Status OutputRecorderTask::write(std::size_t stream, rt::TimeNs stamp_ns, const std::vector<double>& values,
                                     std::uint64_t& written) {
  rt::Status s = writers_[stream].write(stamp_ns, values);
  if (s) ++written;
  return s;
}

void OutputRecorderTask::step(rt::TimeNs now_ns) {
  if (!first_error_) return;  // the disk failed: the run goes on without these streams
  if (const auto detection = detections_.read();
      detection && (detection->sequence != last_detection_sequence_ || detection->stamp_ns != last_detection_ns_) &&
      detection->stamp_ns >= last_detection_ns_) {
    last_detection_sequence_ = detection->sequence;
    last_detection_ns_ = detection->stamp_ns;
    first_error_ = write(0, detection->stamp_ns, hal::replay::DetectionCodec::encode(*detection), detections_written_);
  }
  if (const auto estimate = estimates_.read(); first_error_ && estimate && estimate->stamp_ns > last_estimate_ns_) {
    last_estimate_ns_ = estimate->stamp_ns;
    first_error_ = write(1, estimate->stamp_ns, EstimateCodec::encode(*estimate), estimates_written_);
  }
  if (auto trajectory = trajectories_.read();
      first_error_ && trajectory && trajectory != last_trajectory_ && trajectory->trajectory) {
    last_trajectory_ = std::move(trajectory);
    first_error_ = write(2, now_ns, TrajectoryCodec::encode(*last_trajectory_), trajectories_written_);
  }
}

rt::Status OutputRecorderTask::finish() {
  for (hal::replay::CsvStreamWriter& w : writers_) {
    if (rt::Status s = w.close(); !s && first_error_) first_error_ = s;
  }
  return first_error_;
}

}  // namespace aerotrack::app
