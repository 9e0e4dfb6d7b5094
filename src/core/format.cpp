// Numbers in messages and the range-error grammar. See format.hpp.
#include "terracut/core/format.hpp"

#include <charconv>
#include <cmath>

namespace terracut {

namespace {

// std::to_chars: for float and double without a format, the shortest text
// that reads back as the same value. 32 characters hold any float, double or
// 64-bit whole number.
template <typename T>
std::string chars(T value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

}  // namespace

// A NaN's sign (to_chars would write "-nan") means nothing in a message.
std::string format_number(double value) { return std::isnan(value) ? "nan" : chars(value); }
std::string format_number(float value) { return std::isnan(value) ? "nan" : chars(value); }

namespace detail {

std::string format_whole(long long value) { return chars(value); }
std::string format_whole(unsigned long long value) { return chars(value); }

std::string must_be_text(std::string_view field, std::string_view what, const std::string& got) {
  std::string out;
  if (!field.empty()) {
    out += field;
    out += ' ';
  }
  out += "must be ";
  out += what;
  out += ", got ";
  out += got;
  return out;
}

}  // namespace detail

}  // namespace terracut
