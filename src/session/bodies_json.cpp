// The "bodies" entry of summary.json. See bodies_json.hpp.
#include "bodies_json.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/bodies_listener.hpp"
#endif

namespace terracut::session::detail {

nlohmann::json bodies_json([[maybe_unused]] const World& world,
                           [[maybe_unused]] BodiesEntry entry) {
#ifdef TERRACUT_HAVE_BULLET
  const bullet::BodiesListener* listener = world.bodies_listener();
  if (!listener) return nullptr;
  const bullet::BodiesReport r = listener->report();
  nlohmann::json j;
  j["count"] = r.count;
  const std::string csv = listener->csv_name();
  if (csv.empty())
    j["csv"] = nullptr;
  else
    j["csv"] = csv;
  j["peak_tool_force_n"] = r.peak_tool_force_n;
  j["height_bounds_m"] = {r.min_height_m, r.max_height_m};
  j["samples_clamped_to_bounds"] = r.samples_clamped;
  j["soil_clamped_m3"] = r.soil_clamped_m3;
  nlohmann::json final_states = nlohmann::json::array();
  for (std::size_t i = 0; i < r.names.size(); ++i) {
    const Vec3& p = r.final_position_m[i];
    final_states.push_back({{"name", r.names[i]}, {"position_m", {p.x, p.y, p.z}}});
  }
  j["final"] = final_states;
  if (entry == BodiesEntry::kLoop) {
    j["engine"] = "bullet";
    j["ticks_touching_tool"] = r.steps_touching_tool;
    j["steps"] = r.steps;
    j["physics_us"] = {{"mean", 1e6 * r.physics_mean_s}, {"max", 1e6 * r.physics_max_s}};
  }
  return j;
#else
  return nullptr;
#endif
}

BoundsClamp bounds_clamp([[maybe_unused]] const World& world) {
  BoundsClamp c;
#ifdef TERRACUT_HAVE_BULLET
  if (const bullet::BodiesListener* listener = world.bodies_listener()) {
    const bullet::BodiesReport r = listener->report();
    c.samples = r.samples_clamped;
    c.volume_m3 = r.soil_clamped_m3;
    c.max_height_m = r.max_height_m;
  }
#endif
  return c;
}

}  // namespace terracut::session::detail
