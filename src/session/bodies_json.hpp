// The "bodies" entry of summary.json, for a batch run and a haptic session
// alike. Internal to the session layer.
#pragma once

#include <nlohmann/json.hpp>

#include "terracut/session/world.hpp"

namespace terracut::session::detail {

/// What to write: a batch run's entry, or a loop's, which adds the loop's
/// figures (engine, steps, ticks touching the tool, Bullet's step time).
enum class BodiesEntry { kRun, kLoop };

/// The entry of the world's bodies (keys in alphabetical order); null JSON
/// when the world has none.
nlohmann::json bodies_json(const World& world, BodiesEntry entry);

/// What the bodies' heightfield clamped away over the run: samples lowered
/// to its upper bound (bullet::BoundsReport), the soil that deleted, m^3,
/// and the bound, metres above the ground. Zeros without bodies.
struct BoundsClamp {
  std::int64_t samples = 0;
  double volume_m3 = 0.0;
  double max_height_m = 0.0;
};
BoundsClamp bounds_clamp(const World& world);

}  // namespace terracut::session::detail
