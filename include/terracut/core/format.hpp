// The one way numbers are written in messages (errors, validate() results,
// warnings), and the one grammar of a value out of its range:
//
//   FIELD must be WHAT, got VALUE       e.g. "rate_hz must be in (0, 1e6], got 0"
//
// Every layer (core, io, haptics, bullet, session, apps) writes its messages
// with these, so the same value reads the same everywhere. Output files
// (CSV, JSON) keep their own fixed formats and do not use them.
#pragma once

#include <concepts>
#include <string>
#include <string_view>
#include <type_traits>

namespace terracut {

/// The shortest text that reads back as the same value (std::to_chars), e.g.
/// "0.5", "-0.2", "250", "1e+10", "1e-07", "0.3333333333333333": exact (the
/// message shows the value that was compared) and short ("0.1", not
/// "0.10000000000000001"). "nan", "inf" and "-inf" for the non-finite.
std::string format_number(double value);
/// The same for a float: its own shortest text ("0.1" for 0.1f).
std::string format_number(float value);

namespace detail {
std::string format_whole(long long value);
std::string format_whole(unsigned long long value);
}  // namespace detail

/// A whole number in decimal ("65536", "-3"), never in exponent form.
template <std::integral T>
  requires(!std::same_as<T, bool>)
std::string format_number(T value) {
  if constexpr (std::is_signed_v<T>)
    return detail::format_whole(static_cast<long long>(value));
  else
    return detail::format_whole(static_cast<unsigned long long>(value));
}

/// What format_number writes: float, double and the whole-number types.
template <typename T>
concept MessageNumber =
    std::same_as<T, double> || std::same_as<T, float> ||
    (std::integral<T> && !std::same_as<T, bool>);

namespace detail {
std::string must_be_text(std::string_view field, std::string_view what, const std::string& got);
}  // namespace detail

/// "must be WHAT, got VALUE": for readers that put the field in front
/// themselves (e.g. "FILE:LINE: field: must be > 0, got 0").
template <MessageNumber T>
std::string must_be(std::string_view what, T got) {
  return detail::must_be_text({}, what, format_number(got));
}

/// "FIELD must be WHAT, got VALUE", e.g. must_be("grid.cols", "in [1, 65536]", 0)
/// gives "grid.cols must be in [1, 65536], got 0". WHAT is the condition the
/// value failed ("> 0", "finite and >= 0", "in [0, 10]").
template <MessageNumber T>
std::string must_be(std::string_view field, std::string_view what, T got) {
  return detail::must_be_text(field, what, format_number(got));
}

}  // namespace terracut
