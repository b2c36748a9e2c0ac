// A flat JSON object in a fixed buffer: see json_line.hpp.
#include "json_line.hpp"

#include <cmath>
#include <cstdio>

namespace aerotrack::app {

void JsonLine::raw(std::string_view s) {
  if (overflow_ || closed_) return;
  if (size_ + s.size() + 1 > kCapacity) {  // room for the closing brace
    overflow_ = true;
    return;
  }
  for (const char c : s) buffer_[size_++] = c;
}

void JsonLine::key(std::string_view k) {
  raw(size_ == 0 ? "{\"" : ",\"");
  raw(k);  // keys are ours: plain identifiers, no escaping needed
  raw("\":");
}

void JsonLine::printNumber(double value) {
  if (!std::isfinite(value)) {
    raw("null");
    return;
  }
  char text[32];
  const int n = std::snprintf(text, sizeof(text), "%.9g", value);
  raw(std::string_view(text, static_cast<std::size_t>(n)));
}

JsonLine& JsonLine::number(std::string_view k, double value) {
  key(k);
  printNumber(value);
  return *this;
}

JsonLine& JsonLine::integer(std::string_view k, std::int64_t value) {
  key(k);
  char text[24];
  const int n = std::snprintf(text, sizeof(text), "%lld", static_cast<long long>(value));
  raw(std::string_view(text, static_cast<std::size_t>(n)));
  return *this;
}

JsonLine& JsonLine::boolean(std::string_view k, bool value) {
  key(k);
  raw(value ? "true" : "false");
  return *this;
}

JsonLine& JsonLine::text(std::string_view k, std::string_view value) {
  key(k);
  raw("\"");
  for (const char c : value) {
    if (c == '"' || c == '\\') {
      const char escaped[2] = {'\\', c};
      raw(std::string_view(escaped, 2));
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      raw(std::string_view(escaped, 6));
    } else {
      raw(std::string_view(&c, 1));
    }
  }
  raw("\"");
  return *this;
}

JsonLine& JsonLine::vector3(std::string_view k, const Eigen::Vector3d& value) {
  key(k);
  raw("[");
  printNumber(value.x());
  raw(",");
  printNumber(value.y());
  raw(",");
  printNumber(value.z());
  raw("]");
  return *this;
}

std::string_view JsonLine::view() {
  if (overflow_) return R"({"truncated":true})";
  if (!closed_) {
    if (size_ == 0) buffer_[size_++] = '{';
    buffer_[size_++] = '}';
    closed_ = true;
  }
  return {buffer_.data(), size_};
}

}  // namespace aerotrack::app
