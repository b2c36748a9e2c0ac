// Decoding an image file from a device, a recording or the command line, within the input policy
// (rt/input_limits.hpp) and without taking a corrupt file for a picture (issue 23 items 6 and 9).
// OpenCV decodes first and tells nothing: a 20000 x 20000 PNG is allocated (2.5 GB) before anyone
// sees its size, and libjpeg patches a JPEG whose scan is cut or garbled with grey and only warns
// -- the detector then measured a 68 px torso where the photo shows 116 px, marked reliable.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal {

struct ImageSize {
  int width_px = 0;
  int height_px = 0;
};

/// The size a PNG (its IHDR) or a JPEG (its first frame header, SOFn) declares, read without
/// decoding. Error: another format, or a header cut short.
rt::Expected<ImageSize> declaredImageSize(std::span<const std::uint8_t> bytes);

/// Decodes a PNG or JPEG held in memory (flags as cv::imdecode: IMREAD_COLOR, IMREAD_UNCHANGED,
/// IMREAD_GRAYSCALE). Before decoding: at most kMaxImageFileBytes, a declared size within
/// kMaxImageSidePx and kMaxImagePixels. A JPEG's whole entropy-coded data is then read by libjpeg
/// with every warning taken as corruption; a PNG must end with its IEND chunk. The error is the
/// reason, for the caller to prefix with what the bytes are ("corrupt JPEG data: premature end").
rt::Expected<cv::Mat> decodeImage(std::span<const std::uint8_t> bytes, int flags);

/// readBoundedFile + decodeImage; errors start with the path.
rt::Expected<cv::Mat> readImageFile(const std::string& path, int flags);

}  // namespace aerotrack::hal
