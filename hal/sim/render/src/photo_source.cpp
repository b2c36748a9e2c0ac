// Reading photos and video frames for person sprites. See photo_source.hpp.
#include "photo_source.hpp"

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "aerotrack/hal/image_decode.hpp"

namespace aerotrack::hal::sim {
namespace {

rt::Status checkFile(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) return rt::Error{path + ": no such file"};
  if (std::filesystem::is_directory(status)) return rt::Error{path + ": is a directory, not a photo or video"};
  if (!std::filesystem::is_regular_file(status)) return rt::Error{path + ": not a regular file"};
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return rt::Error{path + ": cannot read its size"};
  if (size > static_cast<std::uintmax_t>(kMaxPhotoFileBytes))
    return rt::Error{path + ": " + std::to_string(size) + " bytes, more than the " +
                     std::to_string(kMaxPhotoFileBytes) + " a person's photo or video may have"};
  return rt::ok();
}

rt::Status checkDecoded(const std::string& path, const cv::Mat& image) {
  if (image.empty()) return rt::Error{path + ": cannot decode (not an image, or corrupt)"};
  if (image.cols > kMaxPhotoSidePx || image.rows > kMaxPhotoSidePx)
    return rt::Error{path + ": " + std::to_string(image.cols) + " x " + std::to_string(image.rows) +
                     " px, larger than " + std::to_string(kMaxPhotoSidePx) + " px a side"};
  return rt::ok();
}

}  // namespace

rt::Expected<cv::Mat> readPhoto(const std::string& path, int frame) {
  if (frame >= 0) {
    auto frames = readVideoFrames(path, {frame});
    if (!frames) return frames.error();
    return frames->front();
  }
  if (auto status = checkFile(path); !status) return status.error();
  auto image = readImageFile(path, cv::IMREAD_COLOR);  // sizes and corrupt data checked before decoding
  if (!image) return image.error();
  if (auto status = checkDecoded(path, *image); !status) return status.error();
  return image;
}

rt::Expected<std::vector<cv::Mat>> readVideoFrames(const std::string& path, const std::vector<int>& frames) {
  if (auto status = checkFile(path); !status) return status.error();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (frames[i] < 0 || frames[i] > kMaxVideoFrame || (i > 0 && frames[i] < frames[i - 1]))
      return rt::Error{path + ": frames must be in [0, " + std::to_string(kMaxVideoFrame) + "], in order"};
  }
  std::vector<cv::Mat> out;
  if (frames.empty()) return out;
  try {
    cv::VideoCapture video(path, cv::CAP_FFMPEG);
    if (!video.isOpened()) return rt::Error{path + ": cannot open as a video"};
    cv::Mat image;
    std::size_t next = 0;
    for (int f = 0; f <= frames.back(); ++f) {
      if (!video.read(image) || image.empty())
        return rt::Error{path + ": frame " + std::to_string(frames[next]) + " is past the video's end (" +
                         std::to_string(f) + " frames)"};
      while (next < frames.size() && frames[next] == f) {
        if (auto status = checkDecoded(path, image); !status) return status.error();
        if (image.type() != CV_8UC3) return rt::Error{path + ": frames are not 8-bit BGR"};
        out.push_back(image.clone());
        ++next;
      }
    }
  } catch (const cv::Exception& e) {
    return rt::Error{path + ": cannot decode: " + e.what()};
  }
  return out;
}

}  // namespace aerotrack::hal::sim
