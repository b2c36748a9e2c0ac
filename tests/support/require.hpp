// Values a test cannot go on without, for the helpers and harnesses that return them, where ASSERT_
// cannot stop the test (it only returns from a void function). `EXPECT_TRUE(x); return *x;` records
// a failure and then dereferences nothing: undefined behaviour for a pointer or an optional, a crash
// that takes the whole test binary down. require() instead fails the test there with the reason and
// where it was required: it throws, and GoogleTest reports the exception as this test's failure
// ("C++ exception with description "...: <why>" thrown in the test body") and runs the next test.
// In a test body, or any void function, prefer ASSERT_TRUE(x) << ...; before using x.
#pragma once

#include <optional>
#include <source_location>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::test {

/// What require() throws: a value the test needed is missing.
class MissingValue : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {
[[noreturn]] inline void missing(std::string_view what, std::string_view why, const std::source_location& where) {
  throw MissingValue(std::string(where.file_name()) + ":" + std::to_string(where.line()) + ": " + std::string(what) +
                     ": " + std::string(why));
}
}  // namespace detail

/// The value of `result`; an error fails the test (see above), naming `what` and the error.
template <class T>
T require(rt::Expected<T> result, std::string_view what,
          const std::source_location& where = std::source_location::current()) {
  if (!result) detail::missing(what, result.error().message, where);
  return std::move(result).value();
}

/// *pointer; a null pointer fails the test (see above), naming `what`.
template <class T>
T& require(T* pointer, std::string_view what, const std::source_location& where = std::source_location::current()) {
  if (pointer == nullptr) detail::missing(what, "null", where);
  return *pointer;
}

/// The value of `value`; nothing fails the test (see above), naming `what`.
template <class T>
T require(std::optional<T> value, std::string_view what,
          const std::source_location& where = std::source_location::current()) {
  if (!value) detail::missing(what, "nothing", where);
  return std::move(*value);
}

}  // namespace aerotrack::test
