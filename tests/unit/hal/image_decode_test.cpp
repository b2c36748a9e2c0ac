// Image decoding within the input policy (hal/image_decode.hpp): the declared size read from the
// header against a hand-made one, a pixel bomb refused before any decoding, a JPEG whose scan was
// cut or garbled but still ends in EOI refused (OpenCV decoded it, patched with grey), a PNG without
// IEND refused, and a good image decoded exactly as OpenCV decodes it. PNG data checked by libpng
// itself (issue 23 item 10): a CRC error or a bad row filter refused in one message of ours with
// nothing printed by libpng, a broken colour profile dropped unseen, and every PNG opencv-doc ships
// (gamma, sBIT, sRGB, palettes, alpha) decoded to the same pixels as OpenCV's own decoding.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
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

/// CRC-32 of PNG chunks (ISO 3309, the polynomial reflected), bit by bit: for test data only.
std::uint32_t crc32(const std::uint8_t* data, std::size_t size) {
  std::uint32_t crc = 0xFFFFFFFFU;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1U) ^ (0xEDB88320U & (0U - (crc & 1U)));
  }
  return crc ^ 0xFFFFFFFFU;
}

void putBigEndian32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

/// The PNG with a chunk of `type` and `data` (its CRC right) inserted after IHDR.
std::vector<std::uint8_t> withChunkAfterHeader(const std::vector<std::uint8_t>& png, const char* type,
                                               const std::string& data) {
  std::vector<std::uint8_t> chunk;
  putBigEndian32(chunk, static_cast<std::uint32_t>(data.size()));
  for (int i = 0; i < 4; ++i) chunk.push_back(static_cast<std::uint8_t>(type[i]));
  for (const char c : data) chunk.push_back(static_cast<std::uint8_t>(c));
  putBigEndian32(chunk, crc32(chunk.data() + 4, chunk.size() - 4));
  // Byte by byte: GCC 12's -O3 warns (falsely) of overflow on vector::insert here.
  std::vector<std::uint8_t> out;
  for (std::size_t i = 0; i < png.size(); ++i) {
    if (i == 33) {  // after the signature (8) and IHDR (25)
      for (const std::uint8_t b : chunk) out.push_back(b);
    }
    out.push_back(png[i]);
  }
  return out;
}

TEST(ImageDecode, GivenAPngWithACorruptRowOrCrcThenOneMessageOfOursAndNothingFromLibpng) {
  const std::vector<std::uint8_t> good = encoded(".png", 64, 48);
  std::vector<std::uint8_t> bad_crc = good;
  bad_crc[good.size() / 2] ^= 0x5AU;  // inside IDAT: its CRC no longer matches
  testing::internal::CaptureStderr();
  const auto image = decodeImage(bad_crc, cv::IMREAD_COLOR);
  const std::string printed = testing::internal::GetCapturedStderr();
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().message, "corrupt PNG data: IDAT: CRC error");
  EXPECT_EQ(printed, "");
}

TEST(ImageDecode, GivenAPngWithABrokenColourProfileThenItIsDecodedAsOpenCvDecodesItWithNoWarningPrinted) {
  const std::vector<std::uint8_t> good = encoded(".png", 64, 48);
  const std::vector<std::uint8_t> with_bad_profile = withChunkAfterHeader(good, "iCCP", std::string("x\0\0ab", 5));
  testing::internal::CaptureStderr();
  const auto image = decodeImage(with_bad_profile, cv::IMREAD_COLOR);
  const std::string printed = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(image) << image.error().message;
  EXPECT_EQ(printed, "");  // OpenCV's own decoding printed "libpng warning: iCCP: ..."
  EXPECT_EQ(cv::norm(*image, cv::imdecode(good, cv::IMREAD_COLOR), cv::NORM_INF), 0.0);
}

TEST(ImageDecode, GivenAColourPngWithTransparencyThenTheAlphaOpenCvMakesOfItIsKept) {
  cv::Mat bgr(8, 8, CV_8UC3, cv::Scalar(7, 7, 7));
  bgr(cv::Rect(0, 0, 4, 8)).setTo(cv::Scalar(200, 100, 50));
  std::vector<std::uint8_t> png;
  ASSERT_TRUE(cv::imencode(".png", bgr, png));
  // tRNS of an RGB image: the 16-bit colour that is transparent, (7, 7, 7).
  const std::vector<std::uint8_t> transparent = withChunkAfterHeader(png, "tRNS", std::string("\0\7\0\7\0\7", 6));
  const auto image = decodeImage(transparent, cv::IMREAD_UNCHANGED);
  ASSERT_TRUE(image) << image.error().message;
  const cv::Mat reference = cv::imdecode(transparent, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(reference.channels(), 4);  // the transparency became alpha
  ASSERT_EQ(image->type(), reference.type());
  EXPECT_EQ(cv::norm(*image, reference, cv::NORM_INF), 0.0);
}

TEST(ImageDecode, GivenEveryPngOpenCvDocShipsThenTheSamePixelsAsOpenCvDecodingTheFileItself) {
  // An independent check of dropping the ancillary chunks: gamma, sBIT, sRGB, chromaticities, text,
  // palettes and alpha, as OpenCV decodes them without us.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/usr/share/doc/opencv-doc/examples/data")) {
    if (entry.path().extension() != ".png") continue;
    const std::string path = entry.path().string();
    for (const int flags : {cv::IMREAD_UNCHANGED, cv::IMREAD_COLOR}) {
      const auto image = readImageFile(path, flags);
      ASSERT_TRUE(image) << image.error().message;
      const cv::Mat reference = cv::imread(path, flags);
      ASSERT_EQ(image->type(), reference.type()) << path;
      ASSERT_EQ(image->size(), reference.size()) << path;
      EXPECT_EQ(cv::norm(*image, reference, cv::NORM_INF), 0.0) << path;
    }
    ++files;
  }
  EXPECT_GE(files, 30);
}

TEST(ImageDecode, GivenAMissingFileThenTheErrorNamesIt) {
  const auto image = readImageFile("/nonexistent/frame.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(image);
  EXPECT_EQ(image.error().message, "/nonexistent/frame.png: cannot open file: no such file or directory");
}

}  // namespace
}  // namespace aerotrack::hal
