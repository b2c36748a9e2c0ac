// Camera frame files: see frame_files.hpp.
#include "aerotrack/hal/replay/frame_files.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "aerotrack/hal/depth_units.hpp"
#include "aerotrack/hal/image_decode.hpp"

namespace aerotrack::hal::replay {

namespace {

rt::Status writeAtomically(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  const std::string part = path + ".part";
  {
    std::ofstream out(part, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) return rt::Error{path + ": cannot write " + part};
  }
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  if (ec) return rt::Error{path + ": cannot rename " + part + ": " + ec.message()};
  return rt::ok();
}

rt::Status encode(const std::string& path, const char* extension, const cv::Mat& image, const std::vector<int>& params,
                  std::vector<std::uint8_t>& bytes) {
  try {
    if (!cv::imencode(extension, image, bytes, params)) return rt::Error{path + ": cannot encode the image"};
  } catch (const cv::Exception& e) {
    return rt::Error{path + ": cannot encode the image: " + e.what()};
  }
  return rt::ok();
}

rt::Expected<cv::Mat> decode(const std::string& path, int flags) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return rt::Error{path + ": missing frame file"};
  return readImageFile(path, flags);  // sizes checked before decoding, corrupt data refused
}

}  // namespace

std::string frameFileName(std::uint64_t file_index, const std::string& extension) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06llu.", static_cast<unsigned long long>(file_index));
  return name + extension;
}

rt::Expected<cv::Mat> depthToMillimetres(const cv::Mat& depth_m) {
  if (depth_m.type() != CV_32FC1) return rt::Error{"depth image: expected 32-bit float metres (CV_32FC1)"};
  cv::Mat mm(depth_m.rows, depth_m.cols, CV_16UC1);
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    auto* out = mm.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      out[u] = depthToZ16(static_cast<double>(in[u]));
    }
  }
  return mm;
}

rt::Status writeDepthPng(const std::string& path, const cv::Mat& depth_m) {
  auto mm = depthToMillimetres(depth_m);
  if (!mm) return rt::Error{path + ": " + mm.error().message};
  std::vector<std::uint8_t> png;
  // Fast compression: the recorder keeps up with the camera.
  if (rt::Status s = encode(path, ".png", *mm, {cv::IMWRITE_PNG_COMPRESSION, 1}, png); !s) return s;
  return writeAtomically(path, png);
}

rt::Expected<cv::Mat> readDepthPng(const std::string& path) {
  auto mm = decode(path, cv::IMREAD_UNCHANGED);
  if (!mm) return mm.error();
  if (mm->type() != CV_16UC1) return rt::Error{path + ": expected a 16-bit single-channel PNG in millimetres"};
  cv::Mat depth_m(mm->rows, mm->cols, CV_32FC1);
  for (int v = 0; v < mm->rows; ++v) {
    const auto* in = mm->ptr<std::uint16_t>(v);
    auto* out = depth_m.ptr<float>(v);
    for (int u = 0; u < mm->cols; ++u) out[u] = depthFromZ16(in[u]);
  }
  return depth_m;
}

rt::Status writeImage(const std::string& path, const cv::Mat& bgr) {
  if (bgr.type() != CV_8UC3) return rt::Error{path + ": expected an 8-bit BGR image"};
  const bool jpeg = path.size() >= 4 && path.compare(path.size() - 4, 4, ".jpg") == 0;
  std::vector<std::uint8_t> bytes;
  const std::vector<int> params =
      jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, 95} : std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, 1};
  if (rt::Status s = encode(path, jpeg ? ".jpg" : ".png", bgr, params, bytes); !s) return s;
  return writeAtomically(path, bytes);
}

rt::Expected<cv::Mat> readImage(const std::string& path) {
  return decode(path, cv::IMREAD_COLOR);
}

}  // namespace aerotrack::hal::replay
