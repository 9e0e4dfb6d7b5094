// Tables of ranges: checks and messages. See ranges.hpp.
#include "terracut/core/ranges.hpp"

#include <cmath>

#include "terracut/core/format.hpp"

namespace terracut {

namespace {
bool open_low(RangeEnds e) { return e == RangeEnds::kOpenLow || e == RangeEnds::kOpen; }
bool open_high(RangeEnds e) { return e == RangeEnds::kOpenHigh || e == RangeEnds::kOpen; }
}  // namespace

std::string range_text(double lo, double hi, RangeEnds ends) {
  std::string text(open_low(ends) ? "(" : "[");
  text += format_number(lo);
  text += ", ";
  text += format_number(hi);
  text += open_high(ends) ? ")" : "]";
  return text;
}

bool in_range(const Range& r, double v) noexcept {
  if (!std::isfinite(v)) return false;
  const bool low_ok = r.lo <= -kRangeMax || (open_low(r.ends) ? v > r.lo : v >= r.lo);
  const bool high_ok = r.hi >= kRangeMax || (open_high(r.ends) ? v < r.hi : v <= r.hi);
  return low_ok && high_ok && (!r.whole || v == std::floor(v));
}

std::string check(const Range& r, double v, std::string_view field) {
  if (in_range(r, v)) return {};
  const std::string_view name = field.empty() ? r.path : field;
  std::string what;
  if (r.hi >= kRangeMax && r.lo == 0.0)
    what = open_low(r.ends) ? "finite and > 0" : "finite and >= 0";
  else if (r.hi >= kRangeMax)
    what = std::string("finite and ") + (open_low(r.ends) ? "> " : ">= ") + format_number(r.lo);
  else
    what = "in " + range_text(r.lo, r.hi, r.ends);
  return must_be(name, what, v);
}

}  // namespace terracut
