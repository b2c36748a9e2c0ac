// libpng's check of a PNG's data: see png_check.hpp.
#include "png_check.hpp"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>

#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::hal::detail {
namespace {

constexpr std::size_t kSignatureBytes = 8;
// The longest row libpng can hand back: 8 bytes a pixel (16-bit RGBA) at the widest image allowed.
constexpr std::size_t kMaxRowBytes = 8 * static_cast<std::size_t>(rt::limits::kMaxImageSidePx);

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24U) | (static_cast<std::uint32_t>(p[1]) << 16U) |
         (static_cast<std::uint32_t>(p[2]) << 8U) | p[3];
}

/// What libpng's callbacks share: the bytes it reads, and its first message.
struct PngReader {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at;
  int messages;
  char first_message[256];
};

void note(PngReader* reader, png_const_charp message) {
  if (reader->messages++ == 0) std::snprintf(reader->first_message, sizeof(reader->first_message), "%s", message);
}

// libpng's documented error handling (libpng-manual.txt, "Error handling"): an error must not
// return, it unwinds to the setjmp of png_jmpbuf; a warning is noted and reading goes on.
[[noreturn]] void onError(png_structp png, png_const_charp message) {
  note(static_cast<PngReader*>(png_get_error_ptr(png)), message);
  png_longjmp(png, 1);
}

void onWarning(png_structp png, png_const_charp message) {
  note(static_cast<PngReader*>(png_get_error_ptr(png)), message);
}

void readBytes(png_structp png, png_bytep out, png_size_t length) {
  auto* reader = static_cast<PngReader*>(png_get_io_ptr(png));
  if (length > reader->size - reader->at) png_error(png, "PNG data cut short");
  std::memcpy(out, reader->data + reader->at, length);
  reader->at += length;
}

/// Every row, then the end. Only trivially destructible locals: png_longjmp skips destructors.
void readThrough(PngReader& reader, std::uint8_t* row) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &reader, onError, onWarning);
  if (png == nullptr) {
    note(&reader, "libpng could not start");
    return;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png)) != 0) {  // NOLINT(cert-err52-cpp): libpng's error idiom
    png_destroy_read_struct(&png, info != nullptr ? &info : nullptr, nullptr);
    if (reader.messages == 0) note(&reader, "libpng could not start");
    return;
  }
  png_set_read_fn(png, &reader, readBytes);
  png_read_info(png, info);
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) > kMaxRowBytes) png_error(png, "a row longer than any image allowed");
  const png_uint_32 height = png_get_image_height(png, info);
  for (int pass = 0; pass < passes; ++pass)
    for (png_uint_32 y = 0; y < height; ++y) png_read_row(png, row, nullptr);
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
}

}  // namespace

rt::Expected<std::vector<std::uint8_t>> pngPixelChunks(std::span<const std::uint8_t> png) {
  std::vector<std::uint8_t> out(png.begin(), png.begin() + static_cast<std::ptrdiff_t>(kSignatureBytes));
  out.reserve(png.size());
  std::size_t at = kSignatureBytes;
  while (at < png.size()) {
    // length (4), type (4), data, CRC (4)
    if (png.size() - at < 12) return rt::Error{"a PNG chunk cut short"};
    const std::uint32_t length = bigEndian32(png.data() + at);
    if (length > png.size() - at - 12) return rt::Error{"a PNG chunk cut short"};
    const std::size_t end = at + 12 + length;
    const std::uint8_t* type = png.data() + at + 4;
    const bool critical = type[0] >= 'A' && type[0] <= 'Z';
    if (critical || std::memcmp(type, "tRNS", 4) == 0)
      out.insert(out.end(), png.begin() + static_cast<std::ptrdiff_t>(at),
                 png.begin() + static_cast<std::ptrdiff_t>(end));
    at = end;
    if (std::memcmp(type, "IEND", 4) == 0) break;  // bytes after the end are nobody's
  }
  return out;
}

std::string checkPngData(std::span<const std::uint8_t> png) {
  PngReader reader{png.data(), png.size(), 0, 0, {}};
  std::vector<std::uint8_t> row(kMaxRowBytes);
  readThrough(reader, row.data());
  return reader.messages > 0 ? reader.first_message : "";
}

}  // namespace aerotrack::hal::detail
