// The `haptics:` section of a scenario file -> validated HapticSettings.
// Written with the section-reader toolkit (yaml_reader.hpp) alone, so that it
// refuses what the scenario reader refuses, with the same messages.
#include "terracut/haptics/settings_yaml.hpp"

#include <fstream>
#include <sstream>
#include <string_view>

#include "terracut/io/yaml_reader.hpp"

namespace terracut::haptics {

namespace yaml = io::yaml;
namespace {

// A key of the old layout, where a field that moved is named: its new home.
void moved(const yaml::Map& map, std::string_view key, std::string_view to,
           std::string_view why = "the soil's material and the blade's shape are written once, "
                                  "for every force and program") {
  if (const auto f = map.get(key))
    f->fail("moved to " + std::string(to) + " (" + std::string(why) +
            ": docs/scenario-format.md)");
}

void parse_forces(const yaml::Map& f, ForceModelParams& p) {
  if (const auto c = f.get("cutting"))
    p.cutting = c->choice(
        {CuttingModel::kNone, CuttingModel::kContactDrag, CuttingModel::kEarthmoving});
  f.read_number("force_scale", p.force_scale);
  f.read_number("low_speed_damping_n_s_per_m", p.low_speed_damping_n_s_per_m);
  if (const auto g = f.get("project_width_on_motion"))
    g->fail("removed: the cutting force always takes the engaged width across the motion (a blade "
            "sliding along its own edge cuts nothing)");
  f.read_boolean("twist_enabled", p.twist_enabled);
  const yaml::Map pen = f.section("penetration", {"enabled", "edge_thickness_m"});
  pen.read_boolean("enabled", p.penetration_enabled);
  moved(pen, "edge_thickness_m", "blade.edge_thickness_m");
  if (const auto policy = f.get("policy"))
    p.policy = policy->choice({LimitPolicy::kClamp, LimitPolicy::kRefuse});

  const yaml::Map drag = f.section("contact_drag", {"drag_n_per_m", "viscous_n_s_per_m2"});
  drag.read_number("drag_n_per_m", p.contact_drag.drag_n_per_m);
  drag.read_number("viscous_n_s_per_m2", p.contact_drag.viscous_n_s_per_m2);

  const yaml::Map em = f.section("earthmoving", {"soil", "rake_angle_deg"});
  moved(em, "soil", "the top-level soil: section (soil.preset, soil.unit_weight_n_per_m3, "
                    "soil.internal_friction_deg, soil.cohesion_pa, soil.soil_tool_friction_deg, "
                    "soil.adhesion_pa)");
  moved(em, "rake_angle_deg", "blade.rake_angle_deg");

  const yaml::Map surface =
      f.section("surface", {"enabled", "stiffness_n_per_m", "damping_n_s_per_m"});
  surface.read_boolean("enabled", p.surface_enabled);
  surface.read_number("stiffness_n_per_m", p.surface.stiffness_n_per_m);
  surface.read_number("damping_n_s_per_m", p.surface.damping_n_s_per_m);

  const yaml::Map dev = f.section("device", {"max_force_n", "max_stiffness_n_per_m",
                                             "max_damping_n_s_per_m", "inherent_damping_n_s_per_m"});
  dev.read_number("max_force_n", p.device.max_force_n);
  dev.read_number("max_stiffness_n_per_m", p.device.max_stiffness_n_per_m);
  dev.read_number("max_damping_n_s_per_m", p.device.max_damping_n_s_per_m);
  dev.read_number("inherent_damping_n_s_per_m", p.device.inherent_damping_n_s_per_m);
}


}  // namespace

HapticSettings parse_haptics(const YAML::Node& node, const std::string& file) {
  HapticSettings s;
  if (node.IsNull()) return s;  // "haptics:" with nothing under it: the defaults
  const yaml::Field root(yaml::Context(file), node, "haptics", node.Mark());
  const yaml::Map top(
      root, {"rate_hz", "device", "cut", "duration_s", "settle_s", "workspace", "tool",
             "velocity_cutoff_hz", "surface_reference", "cut_depth", "forces", "safety", "hand",
             "udp"});

  moved(top, "rate_hz", "the top-level rate_hz",
        "one rate for the simulation and its haptic loop; `terracut haptics --rate` overrides it "
        "for a session");
  if (const auto f = top.get("device"))
    s.device = f->choice({DeviceKind::kScript, DeviceKind::kSim, DeviceKind::kUdp});
  top.read_text("cut", s.cut);
  if (const auto f = top.get("duration_s")) s.duration_s = f->number();
  top.read_number("settle_s", s.settle_s);

  const yaml::Map ws = top.section("workspace", {"scale", "offset_m", "yaw_deg"});
  ws.read_number("scale", s.workspace.scale);
  ws.read_vec3("offset_m", s.workspace.offset_m);
  ws.read_number("yaw_deg", s.workspace.yaw_deg);

  const yaml::Map tool = top.section("tool", {"rotation_deg"});
  if (const auto f = tool.get("rotation_deg")) s.tool_rotation_deg = f->vec3();

  top.read_number("velocity_cutoff_hz", s.velocity_cutoff_hz);
  if (const auto f = top.get("surface_reference"))
    s.surface_reference = f->choice({SurfaceReference::kGround, SurfaceReference::kTerrain});
  if (const auto f = top.get("cut_depth"))
    f->fail("removed: the depth of cut is the physical force's, the undisturbed soil ahead of the "
            "edge (the step's force.cut_depth_m)");

  parse_forces(top.section("forces", {"cutting", "force_scale", "low_speed_damping_n_s_per_m",
                                      "project_width_on_motion", "twist_enabled", "penetration",
                                      "policy", "contact_drag",
                                      "earthmoving", "surface", "device"}),
               s.forces);

  const yaml::Map safety =
      top.section("safety", {"max_force_n", "max_force_rate_n_per_s", "rise_time_s",
                             "watchdog_timeout_s", "watchdog_ramp_s"});
  s.safety.max_force_n = s.forces.device.max_force_n;
  safety.read_number("max_force_n", s.safety.max_force_n);
  safety.read_number("max_force_rate_n_per_s", s.safety.max_force_rate_n_per_s);
  safety.read_number("rise_time_s", s.safety.rise_time_s);
  safety.read_number("watchdog_timeout_s", s.safety.watchdog_timeout_s);
  safety.read_number("watchdog_ramp_s", s.safety.watchdog_ramp_s);

  const yaml::Map hand = top.section(
      "hand", {"mass_kg", "stiffness_n_per_m", "damping_n_s_per_m", "substeps", "start_offset_m"});
  hand.read_number("mass_kg", s.hand.mass_kg);
  hand.read_number("stiffness_n_per_m", s.hand.stiffness_n_per_m);
  hand.read_number("damping_n_s_per_m", s.hand.damping_n_s_per_m);
  hand.read_integer("substeps", s.hand.substeps);
  hand.read_vec3("start_offset_m", s.hand.start_offset_m);

  const yaml::Map udp = top.section("udp", {"address", "port"});
  udp.read_text("address", s.udp.address);
  udp.read_integer("port", s.udp.port);

  // Range checks, reported at the line of the field they concern: the
  // message starts with the field's path ("hand.mass_kg must be ...").
  if (const std::string problem = validate(s); !problem.empty()) {
    const yaml::Problem p = yaml::split_problem(problem);
    root.fail_at(p.path, p.what);
  }
  return s;
}

HapticSettings load_haptics(const std::filesystem::path& scenario_path) {
  const yaml::Context ctx(scenario_path.string());
  std::ifstream in(scenario_path, std::ios::binary);
  if (!in) ctx.fail(YAML::Mark::null_mark(), "", "cannot open the scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  // "not valid YAML": the phrase this reader has always used (the scenario
  // reader says "malformed YAML").
  const yaml::Field root(ctx, yaml::parse_text(ctx, text.str(), "not valid YAML"), "",
                         YAML::Mark());
  if (!root.is_map())
    ctx.fail(YAML::Mark::null_mark(), "", "expected a mapping at the top of the scenario");
  // Only this key is read: the rest of the file is the scenario reader's.
  const std::optional<yaml::Field> haptics = root.lookup("haptics");
  return haptics ? parse_haptics(haptics->node(), ctx.file()) : HapticSettings{};
}

}  // namespace terracut::haptics
