// Small helpers shared by the YAML readers of the io layer (scenario,
// bodies, haptics). Internal: not part of the public API.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace terracut::io::detail {

/// A short description of a node for error messages: "'text'" for a scalar,
/// "a list", "a mapping" or "nothing".
inline std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    default:
      return "an undefined value";
  }
}

/// The node's own position in the file, or fallback when it has none.
inline YAML::Mark mark_or(const YAML::Node& node, const YAML::Mark& fallback) {
  YAML::Mark m = node.Mark();
  return m.is_null() ? fallback : m;
}

}  // namespace terracut::io::detail
