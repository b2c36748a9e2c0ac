// A flat JSON object written into a fixed buffer, for the flight log's per-message values (issue 24
// item 5: the log's hot path allocates nothing). nlohmann::json, used everywhere else, builds a tree
// on the heap; these objects are a dozen numbers, so they are printed straight into the buffer.
// Checked against nlohmann's parser (tests/unit/app/foxglove_messages_test.cpp).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string_view>

namespace aerotrack::app {

class JsonLine {
 public:
  static constexpr std::size_t kCapacity = 1024;

  JsonLine& number(std::string_view key, double value);  ///< 9 significant digits; NaN and inf as null
  JsonLine& integer(std::string_view key, std::int64_t value);
  JsonLine& boolean(std::string_view key, bool value);
  JsonLine& text(std::string_view key, std::string_view value);  ///< escaped
  JsonLine& vector3(std::string_view key, const Eigen::Vector3d& value);
  /// The object, closed. One that outgrew kCapacity is `{"truncated":true}` instead (never half an object).
  std::string_view view();

 private:
  void key(std::string_view k);
  void raw(std::string_view s);
  void printNumber(double value);

  std::array<char, kCapacity> buffer_{};
  std::size_t size_ = 0;
  bool overflow_ = false;
  bool closed_ = false;
};

}  // namespace aerotrack::app
