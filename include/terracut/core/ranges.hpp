// Tables of ranges: the one place a number's range is declared. A struct
// whose fields have ranges (SafetyParams, SoilParams, BodySpec, a section's
// settings...) declares them once in a table of Range entries; its
// validate() checks the fields through the table, the scenario readers read
// the same fields through the same entries (io/yaml_reader.hpp
// Field::in), and the boundary tests are generated from the tables
// (session::scenario_ranges(), docs/reliability.md). So a range cannot be
// one thing in the file and another in the struct.
//
//   constexpr Range kSafetyRanges[] = {{"max_force_n", 0.0, kRangeMax, RangeEnds::kOpenLow}, ...};
//   if (auto m = check(find_range(kSafetyRanges, "max_force_n"), p.max_force_n); !m.empty()) return m;
#pragma once

#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace terracut {

/// The largest magnitude of a number in a scenario file (1e9, SI units):
/// an entry whose upper end is kRangeMax has no upper end of its own (its
/// struct takes any finite value; the file caps it here).
inline constexpr double kRangeMax = 1e9;

/// Whether the ends of a range belong to it: [lo, hi], (lo, hi], [lo, hi), (lo, hi).
enum class RangeEnds { kClosed, kOpenLow, kOpenHigh, kOpen };

/// The range of one number, by its path relative to its table's struct or
/// section ("rate_hz", "size_m[0]", "surface.stiffness_n_per_m";
/// "[]" for every element of a list).
struct Range {
  std::string_view path;
  double lo = -kRangeMax;
  double hi = kRangeMax;
  RangeEnds ends = RangeEnds::kClosed;
  bool whole = false;  ///< a whole number (lo and hi whole too)
};

/// Every rate of a step or a tick, Hz: the simulation's, the haptic loop's,
/// the pacer's, the Bullet world's and the force model's take it from here.
inline constexpr Range kRateRange{"rate_hz", 0.0, 1e6, RangeEnds::kOpenLow};

/// "(0, 1000]": the range written with its ends.
std::string range_text(double lo, double hi, RangeEnds ends);

/// Whether value is finite and within the range (within [lo, +inf) when hi
/// is kRangeMax, and likewise for lo = -kRangeMax; a whole range also needs a
/// whole value).
bool in_range(const Range& range, double value) noexcept;

/// "" when value is in the range, else "FIELD must be WHAT, got VALUE"
/// (core/format.hpp must_be) with FIELD the entry's path, or field when given
/// (a struct nested in another reports its own part of the path). WHAT:
/// "finite and > 0" / "finite and >= 0" for an entry without ends of its
/// own, "in (0, 10]" otherwise.
std::string check(const Range& range, double value, std::string_view field = {});

/// The entry of table for path; a path missing from the table is a
/// programming error (std::logic_error; at compile time, no constant). A
/// reader's own table takes its entries from the struct's table this way:
///   constexpr Range kFileRanges[] = {find_range(kSimParamsRanges, "rate_hz"), ...};
constexpr const Range& find_range(std::span<const Range> table, std::string_view path) {
  for (const Range& r : table)
    if (r.path == path) return r;
  throw std::logic_error("no range declared for '" + std::string(path) + "'");
}

/// The entry at another path (a struct's field read under a section's name,
/// "max_pair_checks_per_step" as "soil.max_pair_checks_per_step").
constexpr Range at_path(Range range, std::string_view path) {
  range.path = path;
  return range;
}

}  // namespace terracut
