// Which types may travel through a LatestSlot (copied word by word). Trivially copyable types
// qualify. Eigen's fixed-size matrices and quaternions are plain arrays of scalars but declare
// their own copy constructors, so they are not trivially copyable in the language's sense; a
// message type made only of such members and scalars opts in by specialising this trait next to
// its definition, with a static_assert that it is standard layout.
#pragma once

#include <type_traits>

namespace aerotrack::rt {

template <class T>
struct IsBitwiseCopyable : std::is_trivially_copyable<T> {};

template <class T>
inline constexpr bool kIsBitwiseCopyable = IsBitwiseCopyable<T>::value;

}  // namespace aerotrack::rt
