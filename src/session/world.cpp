// The simulated world of a run. See world.hpp.
#include "terracut/session/world.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/bodies_listener.hpp"
#else
namespace terracut::bullet {
class BodiesListener {};  // never built: a world with bodies throws without Bullet
}  // namespace terracut::bullet
#endif

namespace terracut::session {

#ifdef TERRACUT_HAVE_BULLET
bool bodies_available() { return true; }
#else
bool bodies_available() { return false; }
#endif

std::string bodies_unavailable_message() {
  return "bodies: this terracut was built without Bullet (libbullet-dev was not found when it "
         "was configured), so the scenario's rigid bodies cannot be simulated; install "
         "libbullet-dev and rebuild, or remove the `bodies:` list";
}

World::World(const Scenario& scenario, const WorldOptions& options) {
  const io::Scenario& sc = scenario.base;
  sim_ = std::make_unique<Simulation>(io::sim_params(sc, options.rate_hz),
                                      io::build_initial_heights(sc));
  if (scenario.bodies.empty()) return;
#ifdef TERRACUT_HAVE_BULLET
  bullet::BodiesListenerOptions bo;
  bo.csv_path = options.bodies_csv;
  bo.world.tool.force_limit_n = options.arm_force_limit_n;
  // The plate the bodies meet is as tall as the blade where it has a top
  // (blade.height_m; the plate's own bound is 100 m, and no thinner than
  // the edge is thick, below which bodies could pass through it), else the
  // plate's default.
  if (std::isfinite(sc.blade.height_m))
    bo.world.tool.height_m = std::clamp(sc.blade.height_m, std::min(sc.blade.edge_thickness_m, 100.0), 100.0);
  bodies_ = std::make_unique<bullet::BodiesListener>(*sim_, scenario.bodies, bo);
#else
  throw InputError(bodies_unavailable_message());
#endif
}

World::~World() = default;

const BodySource* World::bodies() const {
#ifdef TERRACUT_HAVE_BULLET
  return bodies_.get();
#else
  return nullptr;
#endif
}

void World::sense_heights(const Rect& rect, std::span<float> out) const {
  const HeightGrid& g = sim_->grid();
  std::size_t k = 0;
  for (int row = rect.r0; row < rect.r1; ++row)
    for (int col = rect.c0; col < rect.c1; ++col) out[k++] = g.heights()[g.index(col, row)];
#ifdef TERRACUT_HAVE_BULLET
  if (bodies_) bodies_->world().raise_to_body_tops(rect, out);
#endif
}

Rect World::take_moved_body_rect() {
#ifdef TERRACUT_HAVE_BULLET
  if (bodies_) return bodies_->world().take_moved_rect();
#endif
  return {};
}

std::optional<ArmState> World::limited_arm() const {
#ifdef TERRACUT_HAVE_BULLET
  if (bodies_ && bodies_->world().tool_limited())
    return ArmState{bodies_->world().tool_blade_pose(), bodies_->world().last().tool_stalled};
#endif
  return std::nullopt;
}

void World::finish() {
#ifdef TERRACUT_HAVE_BULLET
  if (bodies_) bodies_->finish();
#endif
}

}  // namespace terracut::session
