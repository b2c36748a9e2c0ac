// Image decoding within the input policy (hal/image_decode.hpp): the declared size read from the
// header against a hand-made one, a pixel bomb refused before any decoding, a JPEG whose scan was
// cut or garbled but still ends in EOI refused (OpenCV decoded it, patched with grey), a PNG without
// IEND refused, and a good image decoded exactly as OpenCV decodes it.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "aerotrack/hal/image_decode.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::hal {
namespace {

std::vector<std::uint8_t> encoded(const char* extension, int width_px, int height_px) {
  cv::Mat bgr(height_px, width_px, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));  // texture: a scan with real entropy
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(extension, bgr, bytes));
  return bytes;
}

/// A PNG that declares width x height and holds nothing else: what a decoder would allocate for.
std::vector<std::uint8_t> pngHeader(std::uint32_t width_px, std::uint32_t height_px) {
  std::vector<std::uint8_t> b = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  for (const std::uint32_t v : {width_px, height_px})
    for (int shift = 24; shift >= 0; shift -= 8) b.push_back(static_cast<std::uint8_t>(v >> shift));
  for (const std::uint8_t x : {8, 0, 0, 0, 0, 0, 0, 0, 0}) b.push_back(x);  // depth, colour type, ..., CRC
  for (const char c : std::string("\0\0\0\0IEND\xae\x42\x60\x82", 12)) b.push_back(static_cast<std::uint8_t>(c));
  return b;
}

TEST(ImageDecode, GivenPngAndJpegThenTheDeclaredSizeIsReadFromTheHeader) {
  for (const char* ext : {".png", ".jpg"}) {
    const auto size = declaredImageSize(encoded(ext, 37, 21));
    ASSERT_TRUE(size) << ext << ": " << size.error().message;
    EXPECT_EQ(size->width_px, 37) << ext;
    EXPECT_EQ(size->height_px, 21) << ext;
  }
  EXPECT_EQ(declaredImageSize(pngHeader(20000, 20000))->width_px, 20000);
  const std::vector<std::uint8_t> text = {'h', 'e', 'l', 'l', 'o'};
  EXPECT_FALSE(declaredImageSize(text));
  const std::vector<std::uint8_t> jpeg = encoded(".jpg", 8, 8);
  EXPECT_FALSE(declaredImageSize(std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + 6)));
}

TEST(ImageDecode, GivenAGoodImageThenTheSamePixelsAsOpenCv) {
  for (const char* ext : {".png", ".jpg"}) {
    const std::vector<std::uint8_t> bytes = encoded(ext, 64, 48);
    const auto image = decodeImage(bytes, cv::IMREAD_COLOR);
    ASSERT_TRUE(image) << ext << ": " << image.error().message;
    const cv::Mat reference = cv::imdecode(bytes, cv::IMREAD_COLOR);
    EXPECT_EQ(cv::norm(*image, reference, cv::NORM_INF), 0.0) << ext;
  }
}

TEST(ImageDecode, GivenAPixelBombThenRefusedBeforeDecoding) {
  const auto bomb = decodeImage(pngHeader(20000, 20000), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(bomb);
  EXPECT_EQ(bomb.error().message, "declares 20000x20000 pixels, past the limit of " +
                                      std::to_string(rt::limits::kMaxImageSidePx) + " a side and " +
                                      std::to_string(rt::limits::kMaxImagePixels) + " pixels");
  EXPECT_FALSE(decodeImage(pngHeader(8000, 8000), cv::IMREAD_UNCHANGED));  // within a side, too many pixels
}

TEST(ImageDecode, GivenAJpegCutMidScanWithItsEndMarkerPutBackThenRefused) {
  std::vector<std::uint8_t> cut = encoded(".jpg", 160, 120);
  cut.resize(cut.size() / 2);
  cut.push_back(0xFF);
  cut.push_back(0xD9);
  ASSERT_FALSE(cv::imdecode(cut, cv::IMREAD_COLOR).empty());  // OpenCV takes it: the defect
  const auto image = decodeImage(cut, cv::IMREAD_COLOR);
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().message.rfind("corrupt JPEG data: ", 0), 0U) << image.error().message;
}

TEST(ImageDecode, GivenAJpegWithAGarbledScanThenRefused) {
  std::vector<std::uint8_t> garbled = encoded(".jpg", 160, 120);
  for (std::size_t i = garbled.size() / 2; i < garbled.size() / 2 + 40; ++i) garbled[i] = 0xFF;  // markers mid-scan
  const auto image = decodeImage(garbled, cv::IMREAD_COLOR);
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().message.rfind("corrupt JPEG data: ", 0), 0U) << image.error().message;
}

TEST(ImageDecode, GivenAPngWithoutItsEndThenRefused) {
  std::vector<std::uint8_t> cut = encoded(".png", 64, 48);
  cut.resize(cut.size() - 40);
  const auto image = decodeImage(cut, cv::IMREAD_COLOR);
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().message, "the PNG data is truncated (no IEND chunk at the end)");
}

TEST(ImageDecode, GivenAMissingFileThenTheErrorNamesIt) {
  const auto image = readImageFile("/nonexistent/frame.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().message, "/nonexistent/frame.png: cannot open file: no such file or directory");
}

}  // namespace
}  // namespace aerotrack::hal
