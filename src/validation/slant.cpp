// A push at a slant (validation/slant.hpp).
#include "terracut/validation/slant.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "terracut/core/simulation.hpp"

namespace terracut::validation {

namespace {

void require(bool ok, const char* field, const char* range) {
  if (!ok) throw std::invalid_argument(std::string("SlantPush::") + field + " must be " + range);
}

}  // namespace

SlantPile measure_slant(const SlantPush& push) {
  require(std::isfinite(push.yaw_deg), "yaw_deg", "finite");
  require(push.width_m > 0.0 && push.width_m <= 4.0, "width_m", "in (0, 4]");
  require(push.depth_m > 0.0 && push.depth_m < kSlantLayer_m, "depth_m", "in (0, 0.2)");
  require(push.travel_m > 0.0 && push.travel_m <= 4.0, "travel_m", "in (0, 4]");
  require(push.speed_m_per_s >= 0.01 && push.speed_m_per_s <= 2.0, "speed_m_per_s", "in [0.01, 2]");
  require(push.hold_s >= 0.0 && push.hold_s <= 10.0, "hold_s", "in [0, 10]");
  require(push.cell_m >= 0.002 && push.cell_m <= 0.05, "cell_m", "in [0.002, 0.05]");
  require(push.cap >= 1000 && push.cap <= 1000000000, "cap", "in [1000, 1e9]");
  const int n = int(std::lround((push.width_m + push.travel_m + 1.6) / push.cell_m));
  const double side = n * push.cell_m;
  SimParams params;
  params.grid = GridSpec{n, n, side, side, {0.0, 0.0, 0.0}};
  params.blade.length_m = push.width_m;
  params.soil.model = SoilModel::kFlow;
  params.soil.material.repose_deg = 34.0;
  params.soil.max_pair_checks_per_step = push.cap;
  params.soil.settle = push.settle;
  Simulation sim(params, std::vector<float>(std::size_t(n) * std::size_t(n), float(kSlantLayer_m)));
  const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, push.yaw_deg * std::numbers::pi / 180.0);
  const Vec3 t = rotate(q, {0.0, 0.0, 1.0});
  const auto at = [&](double along) {
    return Vec3{0.5 * side + t.x * along, kSlantLayer_m - push.depth_m, 0.5 * side + t.z * along};
  };
  const int steps = std::max(1, int(std::lround(push.travel_m / push.speed_m_per_s * 1000.0)));
  const int held = int(std::lround(push.hold_s * 1000.0));
  SlantPile pile;
  for (int i = 0; i <= steps + held; ++i) {
    const StepOutput& out = sim.step({at(push.travel_m * (std::min(i, steps) / double(steps) - 0.5)), q});
    pile.capped_steps += out.soil.reached_cap ? 1 : 0;
  }
  const Vec3 end = at(0.5 * push.travel_m);
  const HeightGrid& g = sim.grid();
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const double x = (c + 0.5) * push.cell_m - end.x, z = (r + 0.5) * push.cell_m - end.z;
      if (!(x * t.x + z * t.z > 0.0) || std::abs(x * t.z - z * t.x) >= 0.5 * push.width_m) continue;
      const double above = double(g.height(c, r)) - kSlantLayer_m;
      pile.ahead_m3 += std::max(0.0, above) * push.cell_m * push.cell_m;
      pile.peak_m = std::max(pile.peak_m, above);
    }
  return pile;
}

}  // namespace terracut::validation
