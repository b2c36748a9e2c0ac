// V4L2 streaming capture: see v4l2_device.hpp.
#include "aerotrack/hal/real/v4l2_device.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <utility>

namespace aerotrack::hal::real {
namespace {

constexpr std::uint32_t kBufferCount = 4;

/// ioctl, retried when a signal interrupts it.
int xioctl(int fd, unsigned long request, void* argument) {
  int r = 0;
  do {
    r = ::ioctl(fd, request, argument);
  } while (r < 0 && errno == EINTR);
  return r;
}

bool isUnplugged(int error) {
  return error == ENODEV || error == EIO || error == ENXIO;
}

std::string cString(const std::uint8_t* text, std::size_t size) {
  std::size_t n = 0;
  while (n < size && text[n] != 0) ++n;
  return {reinterpret_cast<const char*>(text), n};  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
}

/// Opens a node and checks QUERYCAP says capture + streaming; the fd is closed on error.
rt::Expected<int> openCaptureNode(const std::string& path, v4l2_capability& caps) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return rt::Error{path + ": cannot open: " + std::strerror(errno)};
  caps = v4l2_capability{};
  if (xioctl(fd, VIDIOC_QUERYCAP, &caps) != 0) {
    ::close(fd);
    return rt::Error{path + ": not a V4L2 capture device"};
  }
  // device_caps describes this node; capabilities the whole physical device.
  const std::uint32_t node_caps =
      (caps.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? caps.device_caps : caps.capabilities;
  if ((node_caps & V4L2_CAP_VIDEO_CAPTURE) == 0 || (node_caps & V4L2_CAP_STREAMING) == 0) {
    ::close(fd);
    return rt::Error{path + ": not a V4L2 capture device"};
  }
  return fd;
}

}  // namespace

rt::Expected<std::uint32_t> fourccFromString(std::string_view text) {
  if (text.empty() || text.size() > 4)
    return rt::Error{"pixel format '" + std::string(text) + "': expected 1 to 4 characters"};
  std::uint32_t code = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const auto c = static_cast<std::uint8_t>(i < text.size() ? text[i] : ' ');
    code |= static_cast<std::uint32_t>(c) << (8U * i);
  }
  return code;
}

std::string fourccToString(std::uint32_t fourcc) {
  std::string s(4, ' ');
  for (std::size_t i = 0; i < 4; ++i) s[i] = static_cast<char>((fourcc >> (8U * i)) & 0xFFU);
  return s;
}

rt::Error V4l2Device::ioctlError(const char* what, int error) const {
  if (isUnplugged(error)) return rt::Error{path_ + ": unplugged (" + what + ": " + std::strerror(error) + ")"};
  return rt::Error{path_ + ": " + what + " failed: " + std::strerror(error)};
}

rt::Expected<V4l2Device> V4l2Device::open(const std::string& path, const V4l2Format& format) {
  v4l2_capability caps{};
  auto fd = openCaptureNode(path, caps);
  if (!fd) return fd.error();
  V4l2Device device(*fd, path);
  device.card_ = cString(caps.card, sizeof(caps.card));
  device.bus_info_ = cString(caps.bus_info, sizeof(caps.bus_info));

  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(format.width_px);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(format.height_px);
  fmt.fmt.pix.pixelformat = format.fourcc;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(device.fd_, VIDIOC_S_FMT, &fmt) != 0) return device.ioctlError("VIDIOC_S_FMT", errno);
  // Drivers adjust what they cannot do instead of failing: a different format is a refusal.
  if (fmt.fmt.pix.pixelformat != format.fourcc)
    return rt::Error{path + ": does not offer pixel format " + fourccToString(format.fourcc) + " (offered " +
                     fourccToString(fmt.fmt.pix.pixelformat) + ")"};
  if (fmt.fmt.pix.width != static_cast<std::uint32_t>(format.width_px) ||
      fmt.fmt.pix.height != static_cast<std::uint32_t>(format.height_px))
    return rt::Error{path + ": does not offer " + std::to_string(format.width_px) + "x" +
                     std::to_string(format.height_px) + " in " + fourccToString(format.fourcc) + " (nearest " +
                     std::to_string(fmt.fmt.pix.width) + "x" + std::to_string(fmt.fmt.pix.height) + ")"};
  device.format_ = format;

  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator = static_cast<std::uint32_t>(std::lround(format.rate_hz * 1000.0));
  // Some drivers have no frame-rate control: their one rate stands, so a refusal is not an error.
  if (xioctl(device.fd_, VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator != 0)
    device.format_.rate_hz = static_cast<double>(parm.parm.capture.timeperframe.denominator) /
                             static_cast<double>(parm.parm.capture.timeperframe.numerator);

  v4l2_requestbuffers request{};
  request.count = kBufferCount;
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (xioctl(device.fd_, VIDIOC_REQBUFS, &request) != 0) return device.ioctlError("VIDIOC_REQBUFS", errno);
  if (request.count < 2) return rt::Error{path + ": the driver granted fewer than 2 capture buffers"};
  for (std::uint32_t i = 0; i < request.count; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (xioctl(device.fd_, VIDIOC_QUERYBUF, &buffer) != 0) return device.ioctlError("VIDIOC_QUERYBUF", errno);
    void* start = ::mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, device.fd_, buffer.m.offset);
    if (start == MAP_FAILED) return device.ioctlError("mmap", errno);
    device.buffers_.push_back({start, buffer.length});
  }
  for (std::uint32_t i = 0; i < device.buffers_.size(); ++i) {
    if (rt::Status s = device.requeue(i); !s) return s.error();
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(device.fd_, VIDIOC_STREAMON, &type) != 0) return device.ioctlError("VIDIOC_STREAMON", errno);
  device.streaming_ = true;
  return device;
}

V4l2Device::V4l2Device(V4l2Device&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      path_(std::move(other.path_)),
      format_(other.format_),
      card_(std::move(other.card_)),
      bus_info_(std::move(other.bus_info_)),
      buffers_(std::move(other.buffers_)),
      held_(std::exchange(other.held_, std::nullopt)),
      streaming_(std::exchange(other.streaming_, false)) {
  other.buffers_.clear();
}

V4l2Device& V4l2Device::operator=(V4l2Device&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    format_ = other.format_;
    card_ = std::move(other.card_);
    bus_info_ = std::move(other.bus_info_);
    buffers_ = std::move(other.buffers_);
    other.buffers_.clear();
    held_ = std::exchange(other.held_, std::nullopt);
    streaming_ = std::exchange(other.streaming_, false);
  }
  return *this;
}

V4l2Device::~V4l2Device() {
  release();
}

void V4l2Device::release() {
  if (fd_ >= 0 && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);  // fails harmlessly on an unplugged device
  }
  streaming_ = false;
  for (const Mapping& m : buffers_) ::munmap(m.start, m.length);
  buffers_.clear();
  held_.reset();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

rt::Status V4l2Device::requeue(std::uint32_t index) {
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  buffer.index = index;
  if (xioctl(fd_, VIDIOC_QBUF, &buffer) != 0) return ioctlError("VIDIOC_QBUF", errno);
  return rt::ok();
}

rt::Expected<std::optional<V4l2Frame>> V4l2Device::dequeue() {
  if (held_) {
    const std::uint32_t index = *held_;
    held_.reset();
    if (rt::Status s = requeue(index); !s) return s.error();
  }
  std::optional<v4l2_buffer> newest;
  std::uint32_t skipped = 0;
  for (;;) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buffer) != 0) {
      const int error = errno;
      if (error == EAGAIN) break;
      if (newest) static_cast<void>(requeue(newest->index));  // best effort: the device is going away
      return ioctlError("VIDIOC_DQBUF", error);
    }
    if (buffer.index >= buffers_.size()) return rt::Error{path_ + ": the driver returned an unknown buffer index"};
    if (newest) {
      ++skipped;
      if (rt::Status s = requeue(newest->index); !s) return s.error();
    }
    newest = buffer;
  }
  if (!newest) return std::optional<V4l2Frame>{};
  held_ = newest->index;
  V4l2Frame frame;
  frame.data = static_cast<const std::uint8_t*>(buffers_[newest->index].start);
  frame.bytes_used = std::min<std::size_t>(newest->bytesused, buffers_[newest->index].length);
  frame.sequence = newest->sequence;
  frame.timestamp_ns = timevalToNs(newest->timestamp);
  frame.timestamp_monotonic = (newest->flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  frame.skipped = skipped;
  // A buffer the driver marks as an error carries a damaged frame; it is still returned (the
  // decoder above drops it if it cannot be read) but its bytes are not trusted for size.
  if ((newest->flags & V4L2_BUF_FLAG_ERROR) != 0) frame.bytes_used = 0;
  return std::optional<V4l2Frame>{frame};
}

rt::Expected<std::vector<std::uint32_t>> listPixelFormats(const std::string& path) {
  v4l2_capability caps{};
  auto fd = openCaptureNode(path, caps);
  if (!fd) return fd.error();
  std::vector<std::uint32_t> formats;
  for (std::uint32_t i = 0;; ++i) {
    v4l2_fmtdesc desc{};
    desc.index = i;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(*fd, VIDIOC_ENUM_FMT, &desc) != 0) break;  // EINVAL: the end of the list
    formats.push_back(desc.pixelformat);
  }
  ::close(*fd);
  return formats;
}

rt::Expected<std::string> findVideoNodeWithFormat(std::uint32_t fourcc, const std::string& dev_dir) {
  constexpr int kMaxNodes = 64;
  for (int n = 0; n < kMaxNodes; ++n) {
    const std::string path = (std::filesystem::path(dev_dir) / ("video" + std::to_string(n))).string();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) continue;
    const auto formats = listPixelFormats(path);
    if (!formats) continue;  // metadata nodes and busy nodes are skipped
    for (const std::uint32_t f : *formats) {
      if (f == fourcc) return path;
    }
  }
  return rt::Error{dev_dir + "/video*: no V4L2 capture node offers pixel format " + fourccToString(fourcc)};
}

}  // namespace aerotrack::hal::real
