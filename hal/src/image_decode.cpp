// Image decoding within the input policy: see image_decode.hpp.
#include "aerotrack/hal/image_decode.hpp"

#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include <jpeglib.h>
#include <opencv2/imgcodecs.hpp>

#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"
#include "png_check.hpp"

namespace aerotrack::hal {
namespace {

bool isPng(std::span<const std::uint8_t> b) {
  static constexpr std::uint8_t kMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  return b.size() >= 8 && std::memcmp(b.data(), kMagic, 8) == 0;
}

bool isJpeg(std::span<const std::uint8_t> b) {
  return b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF;
}

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24U) | (static_cast<std::uint32_t>(p[1]) << 16U) |
         (static_cast<std::uint32_t>(p[2]) << 8U) | p[3];
}

std::uint32_t bigEndian16(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 8U) | p[1];
}

rt::Expected<ImageSize> pngSize(std::span<const std::uint8_t> b) {
  // Signature (8), IHDR length (4) and type (4), then width and height, big-endian.
  if (b.size() < 24 || std::memcmp(b.data() + 12, "IHDR", 4) != 0) return rt::Error{"PNG header cut short"};
  const std::uint32_t w = bigEndian32(b.data() + 16);
  const std::uint32_t h = bigEndian32(b.data() + 20);
  if (w == 0 || h == 0 || w > 0x7FFFFFFFU || h > 0x7FFFFFFFU)
    return rt::Error{"PNG header declares an empty or invalid size"};
  return ImageSize{static_cast<int>(w), static_cast<int>(h)};
}

rt::Expected<ImageSize> jpegSize(std::span<const std::uint8_t> b) {
  // Markers from SOI on; each segment but the standalone ones carries its length. The first
  // SOFn (C0-CF except DHT C4, JPG C8 and DAC CC) holds precision, height and width.
  std::size_t i = 2;
  while (i + 4 <= b.size()) {
    if (b[i] != 0xFF) return rt::Error{"JPEG header: no marker where one is due"};
    const std::uint8_t marker = b[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      i += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) break;  // end of image or start of scan before any frame header
    const std::uint32_t length = bigEndian16(b.data() + i + 2);
    if (length < 2) return rt::Error{"JPEG header: a segment of length < 2"};
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (i + 9 > b.size()) break;
      const std::uint32_t h = bigEndian16(b.data() + i + 5);
      const std::uint32_t w = bigEndian16(b.data() + i + 7);
      if (w == 0 || h == 0) return rt::Error{"JPEG header declares an empty size"};
      return ImageSize{static_cast<int>(w), static_cast<int>(h)};
    }
    i += 2 + length;
  }
  return rt::Error{"JPEG header cut short (no frame header)"};
}

// libjpeg reports through callbacks: a warning (corrupt data it patched over) is counted, a fatal
// error unwinds with longjmp -- the library's own documented way (libjpeg.txt, "Error handling").
struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg hands back a pointer to it
  std::jmp_buf unwind;
  int warnings;
  char first_message[JMSG_LENGTH_MAX];
};

void noteMessage(j_common_ptr cinfo, int level) {
  auto* errors = reinterpret_cast<JpegErrors*>(cinfo->err);  // NOLINT: libjpeg's error manager idiom
  if (level >= 0) return;                                    // trace messages
  if (errors->warnings++ == 0) (*cinfo->err->format_message)(cinfo, errors->first_message);
}

[[noreturn]] void failFatally(j_common_ptr cinfo) {
  auto* errors = reinterpret_cast<JpegErrors*>(cinfo->err);  // NOLINT: libjpeg's error manager idiom
  (*cinfo->err->format_message)(cinfo, errors->first_message);
  std::longjmp(errors->unwind, 1);  // NOLINT(cert-err52-cpp): nothing with a destructor lives in between
}

/// Reads every DCT coefficient (the whole entropy-coded data, no inverse transform): all that
/// decoding would read. Its cost on a 30 Hz MJPG stream was not measured. "" when libjpeg had nothing to say, else its
/// first message. Only trivially destructible locals here: longjmp skips destructors.
void checkJpegData(const std::uint8_t* data, std::size_t size, char* why) {
  jpeg_decompress_struct cinfo{};
  JpegErrors errors{};
  cinfo.err = jpeg_std_error(&errors.manager);
  errors.manager.emit_message = noteMessage;
  errors.manager.error_exit = failFatally;
  if (setjmp(errors.unwind) != 0) {  // NOLINT(cert-err52-cpp): see failFatally
    jpeg_destroy_decompress(&cinfo);
    std::snprintf(why, JMSG_LENGTH_MAX, "%s", errors.first_message);
    return;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));  // NOLINT(google-runtime-int): libjpeg's type
  jpeg_read_header(&cinfo, TRUE);
  jpeg_read_coefficients(&cinfo);
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  std::snprintf(why, JMSG_LENGTH_MAX, "%s", errors.warnings > 0 ? errors.first_message : "");
}

bool endsWithIend(std::span<const std::uint8_t> b) {
  // IEND's type, then its CRC (4 bytes); a few trailing bytes after it are tolerated.
  const std::size_t from = b.size() > 64 ? b.size() - 64 : 0;
  for (std::size_t i = from; i + 8 <= b.size(); ++i)
    if (std::memcmp(b.data() + i, "IEND", 4) == 0) return true;
  return false;
}

}  // namespace

rt::Expected<ImageSize> declaredImageSize(std::span<const std::uint8_t> bytes) {
  if (isPng(bytes)) return pngSize(bytes);
  if (isJpeg(bytes)) return jpegSize(bytes);
  return rt::Error{"not a PNG or JPEG image (the formats aerotrack reads)"};
}

rt::Expected<cv::Mat> decodeImage(std::span<const std::uint8_t> bytes, int flags) {
  if (bytes.size() > rt::limits::kMaxImageFileBytes)
    return rt::Error{"larger than the limit of " + rt::formatBytes(rt::limits::kMaxImageFileBytes) + " for an image"};
  const rt::Expected<ImageSize> size = declaredImageSize(bytes);
  if (!size) return size.error();
  if (size->width_px > rt::limits::kMaxImageSidePx || size->height_px > rt::limits::kMaxImageSidePx ||
      static_cast<std::uint64_t>(size->width_px) * static_cast<std::uint64_t>(size->height_px) >
          rt::limits::kMaxImagePixels)
    return rt::Error{"declares " + std::to_string(size->width_px) + "x" + std::to_string(size->height_px) +
                     " pixels, past the limit of " + std::to_string(rt::limits::kMaxImageSidePx) + " a side and " +
                     std::to_string(rt::limits::kMaxImagePixels) + " pixels"};
  if (isJpeg(bytes)) {
    char why[JMSG_LENGTH_MAX] = {};
    checkJpegData(bytes.data(), bytes.size(), why);
    if (why[0] != '\0') {
      std::string reason = why;
      reason[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(reason[0])));
      return rt::Error{"corrupt JPEG data: " + reason};
    }
  }
  std::vector<std::uint8_t> png;  // a PNG without the chunks that do not change its pixels
  if (isPng(bytes)) {
    if (!endsWithIend(bytes)) return rt::Error{"the PNG data is truncated (no IEND chunk at the end)"};
    auto pixels = detail::pngPixelChunks(bytes);
    if (!pixels) return pixels.error();
    png = std::move(pixels.value());
    if (const std::string why = detail::checkPngData(png); !why.empty()) return rt::Error{"corrupt PNG data: " + why};
    bytes = png;
  }
  cv::Mat image;
  try {
    const cv::Mat wrapped(1, static_cast<int>(bytes.size()), CV_8UC1,
                          const_cast<std::uint8_t*>(bytes.data()));  // NOLINT: read only
    image = cv::imdecode(wrapped, flags);
  } catch (const cv::Exception&) {
    image.release();  // OpenCV throws on some malformed streams: the same as undecodable
  }
  if (image.empty()) return rt::Error{"cannot decode the image (corrupt or not an image)"};
  return image;
}

rt::Expected<cv::Mat> readImageFile(const std::string& path, int flags) {
  const rt::Expected<std::string> bytes = rt::readBoundedFile(path, rt::limits::kMaxImageFileBytes);
  if (!bytes) return bytes.error();
  auto image = decodeImage(
      std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(bytes->data()), bytes->size()),  // NOLINT
      flags);
  if (!image) return rt::Error{path + ": " + image.error().message};
  return image;
}

}  // namespace aerotrack::hal
