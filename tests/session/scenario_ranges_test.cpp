// Boundary tests generated from the table of every ranged number of a
// scenario file (session::scenario_ranges(): the io reader's own and those
// of the structs the haptics:, bodies: and mmt: sections fill). Every entry
// is tried at each end, just inside and just beyond (1e-9 relative, or 1 for
// whole numbers), in a scenario that is valid otherwise, read with all its
// sections as the programs read it. A value outside the range is refused
// with "FILE:LINE: path: ... must be ..."; a value inside is not refused by
// its range (another rule across fields may still refuse it: a rake angle
// that leaves no failure wedge, a safety limit above the device's). Adding a
// field to a table adds its tests.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <optional>
#include <string>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/io/scenario_ranges.hpp"
#include "terracut/net/emulator.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::session {
namespace {

// Every section whose fields have a range, with a mound terrain...
constexpr const char* kMound = R"(
rate_hz: 100
blade: {length_m: 0.5, rake_angle_deg: 60, edge_thickness_m: 0.02, bucket: {depth_m: 0.2, height_m: 0.1}}
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
soil: {model: flow, preset: dry_sand, unit_weight_n_per_m3: 16000, cohesion_pa: 0, adhesion_pa: 0,
       internal_friction_deg: 30, soil_tool_friction_deg: 20, repose_deg: 30,
       max_pair_checks_per_step: 100000}
reference: {mound: {centre_m: [0.6, 0.4], radius_m: 0.35, height_m: 0.3}}
haptics:
  duration_s: 5
  settle_s: 0.5
  workspace: {scale: 12, yaw_deg: 0}
  velocity_cutoff_hz: 100
  forces:
    force_scale: 0.02
    low_speed_damping_n_s_per_m: 60
    contact_drag: {drag_n_per_m: 400, viscous_n_s_per_m2: 0}
    surface: {stiffness_n_per_m: 10000, damping_n_s_per_m: 1}
    device: {max_force_n: 8, max_stiffness_n_per_m: 3000, max_damping_n_s_per_m: 20,
             inherent_damping_n_s_per_m: 1.5}
  safety: {max_force_n: 8, max_force_rate_n_per_s: 1000, rise_time_s: 1,
           watchdog_timeout_s: 0.05, watchdog_ramp_s: 0.1}
  hand: {mass_kg: 0.15, stiffness_n_per_m: 400, damping_n_s_per_m: 8, substeps: 20}
  udp: {port: 47000}
bodies:
  - {shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 1, position_m: [0.3, 0.5, 0.3],
     friction: 0.5, restitution: 0.1}
  - {shape: sphere, radius_m: 0.05, mass_kg: 1, position_m: [0.6, 0.5, 0.3]}
  - {shape: cylinder, radius_m: 0.05, height_m: 0.1, mass_kg: 1, position_m: [0.9, 0.5, 0.3]}
mmt:
  remote: {follower_speed_m_per_s: 1.5, follower_time_constant_s: 0.02, sense_period_s: 0.05,
           sense_radius_m: 0.3, forgetting: 0.999, estimate_period_s: 0.01,
           estimate_resend_s: 0.5,
           arm_force_limit_n: 5000, soil_change: {z_below_m: 0.0, soil: clay}}
  link: {delay_s: 0.05, jitter_s: 0.001, loss: 0.01, reorder: 0.01, reorder_delay_s: 0.005,
         retransmit_s: 0.2, seed: 3,
         burst: {p_good_to_bad: 0.01, p_bad_to_good: 0.5, loss_good: 0, loss_bad: 0.5}}
  operator: {blend_s: 0.1, max_update_step_n: 0.01, exclusion_m: 0.15, deadband: 0.05}
  timeout_s: 0.2
  link_lost_s: 5
  udp: {port: 47100}
  link_id: 1234
)";
// ...and a plane terrain, for the plane's own fields (and the soil's
// density, which the mound's soil gives as a unit weight: not both).
constexpr const char* kPlane = R"(
soil: {density_kg_per_m3: 1650}
blade: {length_m: 0.5, height_m: 0.3}
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

// The node at a table path from node, or nullopt when the document has none
// there; "[]" is the first element of the list that has the rest of the path.
std::optional<YAML::Node> at_path(YAML::Node node, std::string_view path) {
  const std::size_t dot = path.find('.');
  std::string part(path.substr(0, dot));
  const std::string_view rest = dot == std::string_view::npos ? "" : path.substr(dot + 1);
  std::optional<std::size_t> index;
  bool any = false;
  if (const std::size_t b = part.find('['); b != std::string::npos) {
    const std::string inside = part.substr(b + 1, part.size() - b - 2);
    any = inside.empty();
    if (!any) index = std::size_t(std::stoi(inside));
    part = part.substr(0, b);
  }
  if (!node.IsMap() || !node[part]) return std::nullopt;
  YAML::Node child = node[part];
  const auto descend = [&](YAML::Node n) -> std::optional<YAML::Node> {
    if (rest.empty()) return n.IsScalar() ? std::optional<YAML::Node>(n) : std::nullopt;
    return at_path(n, rest);
  };
  if (!index && !any) return descend(child);
  if (!child.IsSequence()) return std::nullopt;
  if (index) return *index < child.size() ? descend(child[*index]) : std::nullopt;
  for (std::size_t i = 0; i < child.size(); ++i)
    if (auto found = descend(child[i])) return found;
  return std::nullopt;
}

// The base document holding the path, with the field path its messages name
// ("[]" as the index of the element chosen).
struct Place {
  YAML::Node root;
  YAML::Node node;
};
std::optional<Place> place_of(std::string_view path) {
  for (const char* base : {kMound, kPlane}) {
    YAML::Node root = YAML::Load(base);
    if (auto node = at_path(root, path)) return Place{root, *node};
  }
  return std::nullopt;
}

// The path as messages name it: "[]" becomes the index of the first element
// of the list in the base that holds the rest of the path.
std::string message_path(std::string path) {
  for (std::size_t p; (p = path.find("[]")) != std::string::npos;) {
    const YAML::Node root = place_of(path)->root;
    const std::string list = path.substr(0, p);
    const std::string rest = path.substr(p + 2);
    std::size_t i = 0;
    for (;; ++i)
      if (at_path(root, list + "[" + std::to_string(i) + "]" + rest)) break;
    path.replace(p, 2, "[" + std::to_string(i) + "]");
  }
  return path;
}

std::string text_of(double v, bool whole) {
  if (whole) return std::to_string(std::llround(v));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

struct Outcome {
  bool accepted = false;
  bool refused_by_range = false;  ///< "FILE:LINE: path: ... must be ..."
  bool refused_as_out_of_range = false;  ///< "FILE:LINE: path: must be ..." (the field alone)
  std::string message;
};

// Parses the base with the value written at the range's path.
Outcome try_value(const Range& r, const std::string& value) {
  const std::string path(r.path);
  Place place = *place_of(path);
  place.node = value;  // writes the scalar into the document
  YAML::Emitter out;
  out << place.root;
  Outcome o;
  try {
    parse_scenario(out.c_str(), "ranges.yaml");
    o.accepted = true;
  } catch (const InputError& e) {
    o.message = e.what();
    const std::string field = ": " + message_path(path) + ": ";
    const std::size_t where = o.message.find(field);
    const bool at_line = o.message.rfind("ranges.yaml:", 0) == 0 && where != std::string::npos;
    o.refused_by_range = at_line && o.message.find("must be", where) != std::string::npos;
    o.refused_as_out_of_range = at_line && o.message.compare(where + field.size(), 7, "must be") == 0;
  }
  return o;
}

double beyond(double v, double direction, bool whole) {
  return whole ? v + direction : v + direction * std::max(std::abs(v), 1.0) * 1e-9;
}

TEST(ScenarioRanges, EveryTableEntryAtItsEndsAndJustBeyond) {
  const auto table = scenario_ranges();
  for (const Range& r : table) {
    SCOPED_TRACE(std::string(r.path));
    const bool low_open = r.ends == RangeEnds::kOpenLow || r.ends == RangeEnds::kOpen;
    const bool high_open = r.ends == RangeEnds::kOpenHigh || r.ends == RangeEnds::kOpen;
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
        EXPECT_FALSE(o.refused_as_out_of_range) << value << " is inside; refused with: " << o.message;
      } else {
        EXPECT_TRUE(o.refused_by_range)
            << value << " is outside; got: " << (o.accepted ? "accepted" : o.message);
      }
    }
  }
}

// The table holds every section's fields, and the base scenarios every path.
TEST(ScenarioRanges, TheTableCoversEverySectionAndTheBasesHoldEveryPath) {
  EXPECT_NO_THROW(parse_scenario(kMound, "mound.yaml"));
  EXPECT_NO_THROW(parse_scenario(kPlane, "plane.yaml"));
  std::vector<std::string> sections;
  for (const Range& r : scenario_ranges()) {
    EXPECT_TRUE(place_of(r.path)) << r.path << " is in no base scenario";
    const std::string path(r.path);
    sections.push_back(path.substr(0, path.find_first_of(".[")));
  }
  for (const char* section : {"rate_hz", "terrain", "cuts", "soil", "reference", "haptics",
                              "bodies", "mmt"})
    EXPECT_NE(std::find(sections.begin(), sections.end(), section), sections.end()) << section;
  // The struct tables are gathered whole, under their section.
  const auto count = [&](std::string_view prefix) {
    return std::count_if(scenario_ranges().begin(), scenario_ranges().end(),
                         [&](const Range& r) { return r.path.starts_with(prefix); });
  };
  EXPECT_EQ(count("haptics.forces."), std::ssize(force_ranges()));
  EXPECT_EQ(count("soil."), std::ssize(material_ranges()) + std::ssize(kSoilFlowRanges));
  EXPECT_EQ(count("haptics.safety."), std::ssize(safety_ranges()));
  EXPECT_EQ(count("bodies[]."), std::ssize(body_ranges()));
  EXPECT_EQ(count("mmt."), std::ssize(mmt_ranges()) + std::ssize(net::link_ranges()));
  EXPECT_EQ(std::ssize(scenario_ranges()),
            std::ssize(io::scenario_ranges()) + std::ssize(material_ranges()) +
                std::ssize(haptics::haptic_settings_ranges()) +
                std::ssize(force_ranges()) + std::ssize(safety_ranges()) +
                std::ssize(body_ranges()) + std::ssize(mmt_ranges()) +
                std::ssize(net::link_ranges()));
}

// Angles are degrees in the file and in the soil's material record.
TEST(ScenarioRanges, AnglesAreInDegreesInTheFile) {
  const Range& phi = find_range(scenario_ranges(), "soil.internal_friction_deg");
  EXPECT_NEAR(phi.hi, 90.0, 1e-12);
  EXPECT_NEAR(find_range(scenario_ranges(), "blade.rake_angle_deg").hi, 180.0, 1e-12);
  EXPECT_THROW(find_range(scenario_ranges(), "soil.internal_friction_rad"), std::logic_error);
}

// The table as docs/scenario-format.md shows it.
std::string markdown_table() {
  std::string out = "| field | range | kind |\n|---|---|---|\n";
  for (const Range& r : scenario_ranges()) {
    std::string range;
    const bool open_low = r.ends == RangeEnds::kOpenLow || r.ends == RangeEnds::kOpen;
    if (r.hi >= kRangeMax && r.lo == 0.0)
      range = open_low ? "> 0" : ">= 0";
    else
      range = range_text(r.lo, r.hi, r.ends);
    out += "| `" + std::string(r.path) + "` | " + range + " | " + (r.whole ? "whole number" : "number") + " |\n";
  }
  return out;
}

// docs/scenario-format.md's table of ranges is generated from the table: it
// must be the table, as it is now. TERRACUT_UPDATE_DOCS=1 rewrites it.
TEST(ScenarioRanges, TheDocsTableIsTheTable) {
  const std::filesystem::path doc = std::filesystem::path(TERRACUT_SOURCE_DIR) / "docs/scenario-format.md";
  std::ifstream in(doc);
  ASSERT_TRUE(in) << doc;
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string begin = "<!-- ranges:begin (generated from session::scenario_ranges()) -->\n";
  const std::string end = "<!-- ranges:end -->";
  const std::size_t b = s.find(begin), e = s.find(end);
  ASSERT_NE(b, std::string::npos) << "no " << begin << " in " << doc;
  ASSERT_NE(e, std::string::npos);
  const std::string shown = s.substr(b + begin.size(), e - b - begin.size());
  const std::string table = markdown_table();
  if (shown != table && std::getenv("TERRACUT_UPDATE_DOCS")) {
    s.replace(b + begin.size(), e - b - begin.size(), table);
    std::ofstream(doc) << s;
    return;
  }
  EXPECT_EQ(shown, table) << "run this test with TERRACUT_UPDATE_DOCS=1 to regenerate the table";
}

TEST(ScenarioRanges, AMissingEntryIsAProgrammingError) {
  EXPECT_THROW(find_range(scenario_ranges(), "no.such.field"), std::logic_error);
}

}  // namespace
}  // namespace terracut::session
