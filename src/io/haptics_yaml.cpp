// The `haptics:` section of a scenario file -> validated HapticSettings.
#include "terracut/io/haptics_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "terracut/core/error.hpp"
#include "yaml_util.hpp"

namespace terracut::io {
namespace {

using detail::describe;
using detail::mark_or;

constexpr double kDeg = std::numbers::pi / 180.0;

// Error reporting plus the line of every field read, so that a range error
// found after parsing (by validate) still names the line of its field.
class Context {
 public:
  explicit Context(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& path,
                         const std::string& what) const {
    std::string where = file_;
    if (!mark.is_null() && mark.line >= 0) where += ":" + std::to_string(mark.line + 1);
    throw InputError(where + ": " + path + ": " + what);
  }

  void remember(const std::string& path, const YAML::Mark& mark) { marks_[path] = mark; }

  // The mark of path, or of its nearest remembered parent ("a.b.c" -> "a.b" -> "a").
  YAML::Mark mark_of(std::string path, const YAML::Mark& fallback) const {
    while (true) {
      auto it = marks_.find(path);
      if (it != marks_.end()) return it->second;
      std::size_t dot = path.rfind('.');
      if (dot == std::string::npos) return fallback;
      path.resize(dot);
    }
  }

 private:
  std::string file_;
  std::map<std::string, YAML::Mark> marks_;
};

// One mapping of the section: its keys (checked against the allowed set, no
// repeats) and typed getters that name the field on error.
class Section {
 public:
  Section(Context& ctx, const YAML::Node& node, std::string path, YAML::Mark mark,
          std::vector<std::string_view> allowed)
      : ctx_(ctx), path_(std::move(path)), mark_(mark), allowed_(std::move(allowed)) {
    ctx_.remember(path_, mark_);
    if (node.IsNull()) return;
    if (!node.IsMap())
      ctx_.fail(mark_, path_,
                "expected a mapping with keys " + allowed_list() + ", got " + describe(node));
    for (const auto& kv : node) {
      const YAML::Mark key_mark = mark_or(kv.first, mark_);
      if (!kv.first.IsScalar())
        ctx_.fail(key_mark, path_, "keys must be plain names, got " + describe(kv.first));
      const std::string key = kv.first.Scalar();
      if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end())
        ctx_.fail(key_mark, path_of(key),
                  "unknown key '" + key + "'; allowed keys here: " + allowed_list());
      for (const Entry& e : entries_)
        if (e.key == key)
          ctx_.fail(key_mark, path_of(key),
                    "key given twice (first at line " + std::to_string(e.mark.line + 1) + ")");
      entries_.push_back({key, key_mark, kv.second});
      ctx_.remember(path_of(key), mark_or(kv.second, key_mark));
    }
  }

  bool has(std::string_view key) const { return find(key) != nullptr; }
  std::string path_of(std::string_view key) const { return path_ + "." + std::string(key); }
  YAML::Mark mark_of(std::string_view key) const {
    const Entry* e = find(key);
    return e ? mark_or(e->value, e->mark) : mark_;
  }
  [[noreturn]] void fail(std::string_view key, const std::string& what) const {
    ctx_.fail(mark_of(key), path_of(key), what);
  }

  // The value of a present key; a key with no value is an error.
  const YAML::Node& value(std::string_view key) const {
    const Entry* e = find(key);
    if (e->value.IsNull()) ctx_.fail(e->mark, path_of(key), "no value given");
    return e->value;
  }

  // A nested section (absent or null: an empty one, so its defaults hold).
  Section section(std::string_view key, std::vector<std::string_view> allowed) const {
    const Entry* e = find(key);
    static const YAML::Node kNull;
    return Section(ctx_, e ? e->value : kNull, path_of(key), e ? mark_or(e->value, e->mark) : mark_,
                   std::move(allowed));
  }

  void number(std::string_view key, double& out) const {
    if (has(key)) out = number_of(value(key), mark_of(key), path_of(key));
  }
  void angle_deg(std::string_view key, double& out_rad) const {
    if (has(key)) out_rad = number_of(value(key), mark_of(key), path_of(key)) * kDeg;
  }
  void integer(std::string_view key, int& out) const {
    if (!has(key)) return;
    const double v = number_of(value(key), mark_of(key), path_of(key));
    if (v != std::floor(v) || std::abs(v) > 1e9)
      fail(key, "expected a whole number, got " + describe(value(key)));
    out = static_cast<int>(v);
  }
  void boolean(std::string_view key, bool& out) const {
    if (!has(key)) return;
    const YAML::Node& v = value(key);
    bool parsed = false;
    if (!v.IsScalar() || !YAML::convert<bool>::decode(v, parsed))
      fail(key, "expected true or false, got " + describe(v));
    out = parsed;
  }
  std::string text(std::string_view key) const {
    const YAML::Node& v = value(key);
    if (!v.IsScalar()) fail(key, "expected a text value, got " + describe(v));
    return v.Scalar();
  }
  Vec3 vec3(std::string_view key) const {
    const YAML::Node& v = value(key);
    const std::string want = "expected a list of 3 numbers, got ";
    if (!v.IsSequence()) fail(key, want + describe(v));
    if (v.size() != 3) fail(key, want + "a list of " + std::to_string(v.size()));
    double c[3];
    for (std::size_t i = 0; i < 3; ++i)
      c[i] = number_of(v[i], mark_of(key), path_of(key) + "[" + std::to_string(i) + "]");
    return {c[0], c[1], c[2]};
  }

 private:
  struct Entry {
    std::string key;
    YAML::Mark mark;
    YAML::Node value;
  };

  const Entry* find(std::string_view key) const {
    for (const Entry& e : entries_)
      if (e.key == key) return &e;
    return nullptr;
  }

  double number_of(const YAML::Node& v, const YAML::Mark& fallback, const std::string& path) const {
    const YAML::Mark m = mark_or(v, fallback);
    if (!v.IsScalar()) ctx_.fail(m, path, "expected a number, got " + describe(v));
    double out = 0.0;
    try {
      out = v.as<double>();
    } catch (const YAML::Exception&) {
      ctx_.fail(m, path, "expected a number, got " + describe(v));
    }
    if (!std::isfinite(out)) ctx_.fail(m, path, "must be a finite number, got " + describe(v));
    return out;
  }

  std::string allowed_list() const {
    std::string out;
    for (std::string_view k : allowed_) {
      if (!out.empty()) out += ", ";
      out += k;
    }
    return out;
  }

  Context& ctx_;
  std::string path_;
  YAML::Mark mark_;
  std::vector<std::string_view> allowed_;
  std::vector<Entry> entries_;
};

// An enumerated text value: the parsed value, or an error listing the choices.
template <typename T, typename Parse>
void choice(const Section& s, std::string_view key, T& out, Parse parse, const char* choices) {
  if (!s.has(key)) return;
  const std::string name = s.text(key);
  const std::optional<T> parsed = parse(name);
  if (!parsed) s.fail(key, "unknown value '" + name + "'; allowed: " + choices);
  out = *parsed;
}

void parse_soil(const Section& earthmoving, SoilParams& soil) {
  if (!earthmoving.has("soil")) return;
  const YAML::Node& v = earthmoving.value("soil");
  if (v.IsScalar()) {
    choice(
        earthmoving, "soil", soil,
        [](std::string_view n) -> std::optional<SoilParams> {
          auto p = parse_soil_preset(n);
          return p ? std::optional<SoilParams>(soil_preset(*p)) : std::nullopt;
        },
        "dry_sand, loose_sand, clay");
    return;
  }
  const Section s = earthmoving.section(
      "soil", {"preset", "unit_weight_n_per_m3", "cohesion_pa", "adhesion_pa",
               "internal_friction_deg", "soil_tool_friction_deg", "surcharge_pa"});
  choice(
      s, "preset", soil,
      [](std::string_view n) -> std::optional<SoilParams> {
        auto p = parse_soil_preset(n);
        return p ? std::optional<SoilParams>(soil_preset(*p)) : std::nullopt;
      },
      "dry_sand, loose_sand, clay");
  s.number("unit_weight_n_per_m3", soil.unit_weight_n_per_m3);
  s.number("cohesion_pa", soil.cohesion_pa);
  s.number("adhesion_pa", soil.adhesion_pa);
  s.angle_deg("internal_friction_deg", soil.internal_friction_rad);
  s.angle_deg("soil_tool_friction_deg", soil.soil_tool_friction_rad);
  s.number("surcharge_pa", soil.surcharge_pa);
}

void parse_forces(const Section& f, ForceModelParams& p) {
  choice(f, "cutting", p.cutting, parse_cutting_model, "none, contact_drag, earthmoving");
  f.number("force_scale", p.force_scale);
  f.number("low_speed_damping_n_s_per_m", p.low_speed_damping_n_s_per_m);
  f.boolean("project_width_on_motion", p.project_width_on_motion);
  choice(f, "policy", p.policy, parse_limit_policy, "clamp, refuse");

  const Section drag = f.section("contact_drag", {"drag_n_per_m", "viscous_n_s_per_m2"});
  drag.number("drag_n_per_m", p.contact_drag.drag_n_per_m);
  drag.number("viscous_n_s_per_m2", p.contact_drag.viscous_n_s_per_m2);

  const Section em = f.section("earthmoving", {"soil", "rake_angle_deg"});
  parse_soil(em, p.earthmoving.soil);
  em.angle_deg("rake_angle_deg", p.earthmoving.rake_angle_rad);

  const Section surface =
      f.section("surface", {"enabled", "stiffness_n_per_m", "damping_n_s_per_m"});
  surface.boolean("enabled", p.surface_enabled);
  surface.number("stiffness_n_per_m", p.surface.stiffness_n_per_m);
  surface.number("damping_n_s_per_m", p.surface.damping_n_s_per_m);

  const Section dev = f.section("device", {"max_force_n", "max_stiffness_n_per_m",
                                           "max_damping_n_s_per_m", "inherent_damping_n_s_per_m"});
  dev.number("max_force_n", p.device.max_force_n);
  dev.number("max_stiffness_n_per_m", p.device.max_stiffness_n_per_m);
  dev.number("max_damping_n_s_per_m", p.device.max_damping_n_s_per_m);
  dev.number("inherent_damping_n_s_per_m", p.device.inherent_damping_n_s_per_m);
}

// The file's name for a field of validate()'s messages: angles are radians
// in the structs and degrees in the file.
std::string file_field(std::string field) {
  const std::string rad = "_rad";
  if (field.size() > rad.size() && field.compare(field.size() - rad.size(), rad.size(), rad) == 0)
    field.replace(field.size() - rad.size(), rad.size(), "_deg");
  return field;
}

}  // namespace

HapticSettings parse_haptics(const YAML::Node& node, const std::string& file) {
  Context ctx(file);
  HapticSettings s;
  const Section top(
      ctx, node, "haptics", node.Mark(),
      {"rate_hz", "device", "cut", "duration_s", "settle_s", "workspace", "tool",
       "velocity_cutoff_hz", "surface_reference", "cut_depth", "forces", "safety", "hand", "udp"});

  top.number("rate_hz", s.rate_hz);
  choice(top, "device", s.device, parse_device_kind, "script, sim, udp");
  if (top.has("cut")) s.cut = top.text("cut");
  if (top.has("duration_s")) {
    double d = 0.0;
    top.number("duration_s", d);
    s.duration_s = d;
  }
  top.number("settle_s", s.settle_s);

  const Section ws = top.section("workspace", {"scale", "offset_m", "yaw_deg"});
  ws.number("scale", s.workspace.scale);
  if (ws.has("offset_m")) s.workspace.offset_m = ws.vec3("offset_m");
  ws.number("yaw_deg", s.workspace.yaw_deg);

  const Section tool = top.section("tool", {"rotation_deg"});
  if (tool.has("rotation_deg")) s.tool_rotation_deg = tool.vec3("rotation_deg");

  top.number("velocity_cutoff_hz", s.velocity_cutoff_hz);
  choice(top, "surface_reference", s.surface_reference, parse_surface_reference, "ground, terrain");
  choice(top, "cut_depth", s.cut_depth, parse_cut_depth_measure, "ahead, section");

  parse_forces(top.section("forces", {"cutting", "force_scale", "low_speed_damping_n_s_per_m",
                                      "project_width_on_motion", "policy", "contact_drag",
                                      "earthmoving", "surface", "device"}),
               s.forces);

  const Section safety =
      top.section("safety", {"max_force_n", "max_force_rate_n_per_s", "rise_time_s",
                             "watchdog_timeout_s", "watchdog_ramp_s"});
  s.safety.max_force_n = s.forces.device.max_force_n;
  safety.number("max_force_n", s.safety.max_force_n);
  safety.number("max_force_rate_n_per_s", s.safety.max_force_rate_n_per_s);
  safety.number("rise_time_s", s.safety.rise_time_s);
  safety.number("watchdog_timeout_s", s.safety.watchdog_timeout_s);
  safety.number("watchdog_ramp_s", s.safety.watchdog_ramp_s);

  const Section hand = top.section(
      "hand", {"mass_kg", "stiffness_n_per_m", "damping_n_s_per_m", "substeps", "start_offset_m"});
  hand.number("mass_kg", s.hand.mass_kg);
  hand.number("stiffness_n_per_m", s.hand.stiffness_n_per_m);
  hand.number("damping_n_s_per_m", s.hand.damping_n_s_per_m);
  hand.integer("substeps", s.hand.substeps);
  if (hand.has("start_offset_m")) s.hand.start_offset_m = hand.vec3("start_offset_m");

  const Section udp = top.section("udp", {"address", "port"});
  if (udp.has("address")) s.udp.address = udp.text("address");
  udp.integer("port", s.udp.port);

  // Range checks, reported at the line of the field they concern: the
  // message starts with the field's path ("hand.mass_kg must be ...").
  const std::string problem = validate(s);
  if (!problem.empty()) {
    const std::size_t space = problem.find(' ');
    const std::string field = file_field(problem.substr(0, space));
    const std::string what = space == std::string::npos ? problem : problem.substr(space + 1);
    const std::string path = "haptics." + field.substr(0, field.find('['));
    ctx.fail(ctx.mark_of(path, node.Mark()), "haptics." + field, what);
  }
  return s;
}

HapticSettings load_haptics(const std::filesystem::path& scenario_path) {
  const std::string file = scenario_path.string();
  std::ifstream in(scenario_path, std::ios::binary);
  if (!in) throw InputError(file + ": cannot open the scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  YAML::Node root;
  try {
    root = YAML::Load(text.str());
  } catch (const YAML::ParserException& e) {
    const std::string line =
        e.mark.is_null() ? std::string() : ":" + std::to_string(e.mark.line + 1);
    throw InputError(file + line + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw InputError(file + ": expected a mapping at the top of the scenario");
  const YAML::Node haptics = root["haptics"];
  if (!haptics.IsDefined()) return HapticSettings{};
  return parse_haptics(haptics, file);
}

}  // namespace terracut::io
