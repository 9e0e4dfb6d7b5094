// The names of an enumeration, in one table per enumeration: the scenario
// files, the command line, the outputs and the Python module read and write
// these names, and every one of them goes through the two functions below.
//
//   enum class SoilModel { kVanish, kFlow };
//   inline constexpr EnumName<SoilModel> kSoilModelNames[] = {{SoilModel::kVanish, "vanish"},
//                                                             {SoilModel::kFlow, "flow"}};
//   constexpr std::span<const EnumName<SoilModel>> enum_names(SoilModel) { return kSoilModelNames; }
//
//   to_string(SoilModel::kFlow)        // "flow"
//   parse_enum<SoilModel>("vanish")    // SoilModel::kVanish; nullopt for an unknown name
//
// enum_names is found by argument-dependent lookup, so an enumeration of any
// namespace takes part by declaring it beside itself (and `using
// terracut::to_string;` in its namespace when that namespace is not
// terracut).
#pragma once

#include <concepts>
#include <optional>
#include <span>
#include <string_view>

namespace terracut {

/// One value of an enumeration and its name.
template <typename E>
struct EnumName {
  E value;
  std::string_view name;
};

/// An enumeration with a table of names (enum_names(E) beside it).
template <typename E>
concept NamedEnum = std::is_enum_v<E> && requires(E e) {
  { enum_names(e) } -> std::convertible_to<std::span<const EnumName<E>>>;
};

/// The value's name; "unknown" for a value outside the table (a cast).
template <NamedEnum E>
constexpr std::string_view to_string(E value) {
  for (const EnumName<E>& n : enum_names(value))
    if (n.value == value) return n.name;
  return "unknown";
}

/// The value of a name; nullopt for anything else.
template <NamedEnum E>
constexpr std::optional<E> parse_enum(std::string_view name) {
  for (const EnumName<E>& n : enum_names(E{}))
    if (n.name == name) return n.value;
  return std::nullopt;
}

}  // namespace terracut
