// Reading a whole input file within a size limit (the policy: input_limits.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::rt {

/// The bytes of the file at `path`, at most max_bytes of them. One-line errors naming the file:
/// no such file, a directory, not readable, larger than the limit. A regular file's size is
/// checked before anything is allocated; a pipe or a device (/dev/zero) is read in chunks and
/// given up as soon as it passes the limit.
Expected<std::string> readBoundedFile(const std::string& path, std::uint64_t max_bytes);

/// Whether `path` can be opened as an input file: the same one-line errors as readBoundedFile for a
/// missing path or a directory, and for a regular file over max_bytes (0: no size check).
Status checkInputFile(const std::string& path, std::uint64_t max_bytes = 0);

/// Text from a file, fit to quote in a one-line error: in single quotes, at most max_chars of it
/// (then "..."), every byte that is not printable ASCII as \xNN -- a binary header echoed raw would
/// garble the terminal and spread the message over many lines.
std::string quoteForMessage(std::string_view text, std::size_t max_chars = 60);

/// "4 MiB", "256 KiB", "123 bytes": a limit as a person reads it.
std::string formatBytes(std::uint64_t bytes);

}  // namespace aerotrack::rt
