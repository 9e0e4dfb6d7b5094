// Boundary tests generated from the scenario reader's table of ranges
// (io/scenario_ranges.hpp): every entry is tried at each end, just inside
// and just beyond (1e-9 relative, or 1 for whole numbers), in a scenario
// that is valid otherwise. A value inside the range is not refused by its
// range check; a value outside is refused with "FILE:LINE: path: ... must
// be ...". Adding a field to the table adds its tests.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/io/scenario_ranges.hpp"

namespace terracut::io {
namespace {

// Every section whose fields have a range, with a mound terrain...
constexpr const char* kMound = R"(
rate_hz: 100
blade: {length_m: 0.5, bucket: {depth_m: 0.2, height_m: 0.1}}
terrain:
  generator: mound
  resolution: 12
  size_m: [1.2, 0.8]
  full_scale_m: 0.4
  mound: {centre_m: [0.6, 0.4], radius_m: 0.35}
cuts:
  - name: a
    keyframes:
      - {t_s: 0.0, position_m: [0.1, 0.2, 0.4]}
      - {t_s: 1.0, position_m: [1.1, 0.2, 0.4]}
soil: {model: flow, repose_deg: 30, max_pair_checks_per_step: 100000}
reference: {mound: {centre_m: [0.6, 0.4], radius_m: 0.35, height_m: 0.3}}
)";
// ...and a plane terrain, for the plane's own fields.
constexpr const char* kPlane = R"(
blade: {length_m: 0.5}
terrain:
  generator: plane
  resolution: 8
  size_m: [1, 1]
  full_scale_m: 0.4
  plane: {height_m: 0.1}
cuts:
  - name: a
    keyframes:
      - {t_s: 0.0, position_m: [0.1, 0.2, 0.4]}
)";

// The node at a table path ("[]" is element 0), which must exist in the base.
YAML::Node at_path(YAML::Node root, const std::string& path) {
  YAML::Node node = root;
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t dot = path.find('.', start);
    std::string part = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    int index = -1;
    if (const std::size_t b = part.find('['); b != std::string::npos) {
      const std::string inside = part.substr(b + 1, part.size() - b - 2);
      index = inside.empty() ? 0 : std::stoi(inside);
      part = part.substr(0, b);
    }
    node.reset(node[part]);
    EXPECT_TRUE(node.IsDefined()) << path;
    if (index >= 0) node.reset(node[std::size_t(index)]);
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return node;
}

// The field path a message names: "[]" as element 0.
std::string message_path(std::string path) {
  for (std::size_t p; (p = path.find("[]")) != std::string::npos;) path.replace(p, 2, "[0]");
  return path;
}

std::string text_of(double v, bool whole) {
  if (whole) return std::to_string(std::llround(v));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

struct Outcome {
  bool refused_by_range = false;
  std::string message;
};

// Parses the base with the value written at the range's path.
Outcome try_value(const yaml::Range& r, const std::string& value) {
  const std::string path(r.path);
  YAML::Node root = YAML::Load(path.find("plane") != std::string::npos ? kPlane : kMound);
  YAML::Node node = at_path(root, path);
  node = value;  // writes the scalar into the document
  YAML::Emitter out;
  out << root;
  Outcome o;
  try {
    parse_scenario(out.c_str(), "ranges.yaml");
  } catch (const InputError& e) {
    o.message = e.what();
    // A range refusal names the field at its line, and says what it must be.
    const std::string field = "ranges.yaml:";
    const std::size_t where = o.message.find(": " + message_path(path) + ": ");
    o.refused_by_range = o.message.rfind(field, 0) == 0 && where != std::string::npos &&
                         o.message.find("must be", where) != std::string::npos;
  }
  return o;
}

double beyond(double v, double direction, bool whole) {
  return whole ? v + direction : v + direction * std::max(std::abs(v), 1.0) * 1e-9;
}

TEST(ScenarioRanges, EveryTableEntryAtItsEndsAndJustBeyond) {
  const auto table = scenario_ranges();
  ASSERT_GE(table.size(), 10u);
  for (const yaml::Range& r : table) {
    SCOPED_TRACE(std::string(r.path));
    const bool low_open = r.ends == yaml::Field::Ends::kOpenLow || r.ends == yaml::Field::Ends::kOpen;
    const bool high_open = r.ends == yaml::Field::Ends::kOpenHigh || r.ends == yaml::Field::Ends::kOpen;
    struct Case {
      double value;
      bool inside;
    };
    const std::vector<Case> cases = {
        {r.lo, !low_open},
        {beyond(r.lo, -1, r.whole), false},
        {beyond(r.lo, +1, r.whole), true},
        {r.hi, !high_open},
        {beyond(r.hi, +1, r.whole), false},
        {beyond(r.hi, -1, r.whole), true},
    };
    for (const Case& c : cases) {
      const std::string value = text_of(c.value, r.whole);
      const Outcome o = try_value(r, value);
      if (c.inside) {
        EXPECT_FALSE(o.refused_by_range) << value << " is inside; refused with: " << o.message;
      } else {
        EXPECT_TRUE(o.refused_by_range) << value << " is outside; got: " << (o.message.empty() ? "accepted" : o.message);
      }
    }
  }
}

// Each entry is read through the table: the base scenarios hold every path.
TEST(ScenarioRanges, BaseScenariosAreValidAndHoldEveryPath) {
  EXPECT_NO_THROW(parse_scenario(kMound, "mound.yaml"));
  EXPECT_NO_THROW(parse_scenario(kPlane, "plane.yaml"));
  for (const yaml::Range& r : scenario_ranges()) {
    const std::string path(r.path);
    const YAML::Node node = at_path(YAML::Load(path.find("plane") != std::string::npos ? kPlane : kMound), path);
    EXPECT_TRUE(node.IsScalar()) << path;
  }
}

TEST(ScenarioRanges, AMissingEntryIsAProgrammingError) {
  EXPECT_THROW(yaml::find_range(scenario_ranges(), "no.such.field"), std::logic_error);
}

}  // namespace
}  // namespace terracut::io
