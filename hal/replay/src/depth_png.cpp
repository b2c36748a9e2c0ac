// Depth frames as 16-bit PNG: see depth_png.hpp.
#include "aerotrack/hal/replay/depth_png.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

namespace aerotrack::hal::replay {

std::string depthFrameFileName(std::uint64_t sequence) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06llu.png", static_cast<unsigned long long>(sequence));
  return name;
}

rt::Expected<cv::Mat> depthToMillimetres(const cv::Mat& depth_m) {
  if (depth_m.type() != CV_32FC1) return rt::Error{"depth image: expected 32-bit float metres (CV_32FC1)"};
  cv::Mat mm(depth_m.rows, depth_m.cols, CV_16UC1);
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    auto* out = mm.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const double z_m = static_cast<double>(in[u]);
      // The comparisons are false for NaN: no return.
      out[u] = z_m > 0.0 && z_m <= kMaxPngDepthM ? static_cast<std::uint16_t>(std::lround(z_m * 1000.0)) : 0;
    }
  }
  return mm;
}

rt::Status writeDepthPng(const std::string& path, const cv::Mat& depth_m) {
  auto mm = depthToMillimetres(depth_m);
  if (!mm) return rt::Error{path + ": " + mm.error().message};
  std::vector<std::uint8_t> png;
  try {
    if (!cv::imencode(".png", *mm, png, {cv::IMWRITE_PNG_COMPRESSION, 1}))  // fast: the recorder keeps up
      return rt::Error{path + ": cannot encode the PNG"};
  } catch (const cv::Exception& e) {
    return rt::Error{path + ": cannot encode the PNG: " + e.what()};
  }
  const std::string part = path + ".part";
  {
    std::ofstream out(part, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(png.data()),  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
              static_cast<std::streamsize>(png.size()));
    out.close();
    if (!out) return rt::Error{path + ": cannot write " + part};
  }
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  if (ec) return rt::Error{path + ": cannot rename " + part + ": " + ec.message()};
  return rt::ok();
}

rt::Expected<cv::Mat> readDepthPng(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return rt::Error{path + ": missing depth frame"};
  cv::Mat mm;
  try {
    mm = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return rt::Error{path + ": not a readable PNG: " + e.what()};
  }
  if (mm.empty()) return rt::Error{path + ": not a readable PNG (corrupt or truncated)"};
  if (mm.type() != CV_16UC1) return rt::Error{path + ": expected a 16-bit single-channel PNG in millimetres"};
  cv::Mat depth_m;
  mm.convertTo(depth_m, CV_32FC1, 1e-3);
  return depth_m;
}

const std::vector<std::string>& DepthIndexCodec::columns() {
  static const std::vector<std::string> kColumns{"sequence"};
  return kColumns;
}

rt::Expected<LoadedDepthStream> loadDepthStream(const std::string& index_path, const CameraIntrinsics& intrinsics,
                                                const Eigen::Isometry3d& T_BC, BadRowPolicy policy) {
  auto reader = CsvStreamReader::open(index_path, DepthIndexCodec::columns(), policy);
  if (!reader) return reader.error();
  LoadedDepthStream stream;
  stream.path = index_path;
  const std::filesystem::path folder = std::filesystem::path(index_path).parent_path();
  std::uint64_t bad_frames = 0;
  for (;;) {
    auto record = reader->next();
    if (!record) return record.error();
    if (!record->has_value()) break;
    const CsvRecord& row = **record;
    const double sequence = row.values[0];
    std::string problem;
    if (!(sequence >= 0.0 && sequence <= 9.0e15 && sequence == std::floor(sequence))) {
      problem = index_path + ":" + std::to_string(row.line) + ": sequence is not a whole number >= 0";
    }
    DepthFrame frame;
    if (problem.empty()) {
      frame.sequence = static_cast<std::uint64_t>(sequence);
      const std::string file = (folder / depthFrameFileName(frame.sequence)).string();
      auto depth = readDepthPng(file);
      if (!depth) {
        problem = index_path + ":" + std::to_string(row.line) + ": " + depth.error().message;
      } else if (depth->cols != intrinsics.width_px || depth->rows != intrinsics.height_px) {
        problem = file + ": " + std::to_string(depth->cols) + " x " + std::to_string(depth->rows) +
                  " px, the manifest says " + std::to_string(intrinsics.width_px) + " x " +
                  std::to_string(intrinsics.height_px);
      } else {
        frame.depth_m = std::move(*depth);
      }
    }
    if (!problem.empty()) {
      if (policy == BadRowPolicy::kStrict) return rt::Error{problem};
      if (stream.first_skip_message.empty()) stream.first_skip_message = problem;
      ++bad_frames;
      continue;
    }
    frame.stamp_ns = row.stamp_ns;
    frame.intrinsics = intrinsics;
    frame.T_BC = T_BC;
    stream.frames.push_back(std::move(frame));
  }
  stream.skipped_rows = reader->skippedRows() + bad_frames;
  if (stream.first_skip_message.empty()) stream.first_skip_message = reader->firstSkipMessage();
  stream.truncated_tail = reader->truncatedTail();
  return stream;
}

}  // namespace aerotrack::hal::replay
