// Image decoding within the input policy (hal/image_decode.hpp): headers, declared sizes, libjpeg's
// check of the entropy-coded data, then OpenCV's decoder on what passed.
#include <cstddef>
#include <cstdint>
#include <span>

#include <opencv2/imgcodecs.hpp>

#include "aerotrack/hal/image_decode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  (void)aerotrack::hal::declaredImageSize(bytes);
  (void)aerotrack::hal::decodeImage(bytes, cv::IMREAD_COLOR);
  (void)aerotrack::hal::decodeImage(bytes, cv::IMREAD_UNCHANGED);
  return 0;
}
