// A PNG's data read through by libpng before OpenCV decodes it (issue 23 item 10). OpenCV's decoder
// gives libpng no error handlers, so libpng prints its own lines ("libpng error: bad adaptive filter
// value", "libpng warning: iCCP: too short") beside ours, and a warning is no refusal. Here libpng's
// messages come back as text, and the chunks that cannot change what OpenCV decodes are dropped first,
// so that a colour profile or a text chunk cannot warn twice. Internal to hal (image_decode.cpp).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::hal::detail {

/// The PNG with only the chunks that make its pixels as OpenCV decodes them: the critical ones (IHDR,
/// PLTE, IDAT, IEND: a type whose first letter is upper case) and tRNS (transparency, which OpenCV
/// expands into alpha). OpenCV applies no gamma, colour profile or significant-bit shift, so nothing
/// else changes the image. Error: a chunk cut short.
rt::Expected<std::vector<std::uint8_t>> pngPixelChunks(std::span<const std::uint8_t> png);

/// Reads every row of the PNG through libpng (no transforms) and its end. "" when libpng had nothing
/// to say, else its first message (an error, or a warning: either is corrupt data here).
std::string checkPngData(std::span<const std::uint8_t> png);

}  // namespace aerotrack::hal::detail
