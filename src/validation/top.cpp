// A blade's top measured (top.hpp): a 1 m blade of finite height pushed
// along its normal, every cell against it watched at the end of every step.
#include "terracut/validation/top.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "terracut/core/format.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::validation {

namespace {

constexpr double kTopDeg = std::numbers::pi / 180.0;
constexpr double kTopLayer_m = 0.2;   // the soil's surface, m
constexpr double kTopDepth_m = 0.05;  // the cut, m
constexpr double kTopBlade_m = 1.0;
constexpr double kTopTravel_m = 1.5;
constexpr double kTopSide_m = 3.0;    // the square terrain's side, m
constexpr double kTopRepose_deg = 34.0;

}  // namespace

bool TopMeasure::holds() const {
  return worst_unburied_m <= kTopSlack_m && reach_m >= -1e-3 && over_top_m3 > 0.0 &&
         behind_m3 >= over_top_m3 * (1.0 - 1e-3) && std::abs(volume_error_m3) <= volume_slack_m3;
}

std::string describe(const TopCase& c) {
  return format_number(c.height_m) + " m tall, yaw " + format_number(c.yaw_deg) + " deg" +
         (c.roll_deg != 0.0 ? ", roll " + format_number(c.roll_deg) + " deg" : "") + ", " +
         format_number(c.speed_m_per_s) + " m/s, " + format_number(c.cell_m * 1000.0) + " mm cells";
}

TopMeasure measure_top(const TopCase& c) {
  const auto bad = [&](const char* what) {
    throw std::invalid_argument(std::string("top case (") + describe(c) + "): " + what);
  };
  if (!(std::isfinite(c.height_m) && c.height_m > 0.0 && c.height_m <= 1.0)) bad("height_m must be in (0, 1] m");
  if (!std::isfinite(c.yaw_deg)) bad("yaw_deg must be finite");
  if (!(std::abs(c.roll_deg) <= 5.0)) bad("roll_deg must be within 5 degrees either way");
  if (!(c.speed_m_per_s >= 0.05 && c.speed_m_per_s <= 2.0)) bad("speed_m_per_s must be in [0.05, 2]");
  if (!(c.cell_m >= 0.005 && c.cell_m <= 0.02)) bad("cell_m must be in [0.005, 0.02] m");
  const int n = int(std::lround(kTopSide_m / c.cell_m));
  const double cell = kTopSide_m / n;
  SimParams p;
  p.grid = grid_of_cells(n, n, cell);
  p.blade.length_m = kTopBlade_m;
  p.blade.height_m = c.height_m;
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = kTopRepose_deg;
  Simulation sim(p, std::vector<float>(std::size_t(n) * n, float(kTopLayer_m)));
  const double before = sim.grid().volume_m3();
  const double yaw = c.yaw_deg * kTopDeg;
  const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw) * quat_from_axis_angle({0.0, 0.0, 1.0}, c.roll_deg * kTopDeg);
  const double up = std::max(0.0, rotate(q, {0.0, 1.0, 0.0}).y);
  const double mx = std::sin(yaw), mz = std::cos(yaw);  // the push: the blade frame's +Z, the edge's normal
  const double slope = std::tan(kTopRepose_deg * kTopDeg);
  // Half a cell's width across the edge's line, and where the displacement
  // and the spill over the top look across it.
  const double half = 0.5 * cell * (std::abs(mx) + std::abs(mz));
  const double land = 2.0 * half + 0.01 * cell;
  const double edge_y = kTopLayer_m - kTopDepth_m;
  TopMeasure m;
  m.reach_m = -std::numeric_limits<double>::infinity();
  double highest = kTopLayer_m;
  Segment edge{};
  const int steps = int(std::lround(kTopTravel_m / c.speed_m_per_s * 1000.0));
  for (int i = 0; i <= steps; ++i) {
    const double along = kTopTravel_m * (double(i) / steps - 0.5);
    const BladePose pose{{0.5 * kTopSide_m + mx * along, edge_y, 0.5 * kTopSide_m + mz * along}, q};
    m.over_top_m3 += sim.step(pose).soil.over_top_m3;
    edge = blade_segment(p.blade, pose);
    const HeightGrid& g = sim.grid();
    const double ex = edge.b.x - edge.a.x, ez = edge.b.z - edge.a.z, len = std::hypot(ex, ez);
    const int c0 = std::max(0, int(std::min(edge.a.x, edge.b.x) / cell) - 3);
    const int c1 = std::min(n - 1, int(std::max(edge.a.x, edge.b.x) / cell) + 3);
    const int r0 = std::max(0, int(std::min(edge.a.z, edge.b.z) / cell) - 3);
    const int r1 = std::min(n - 1, int(std::max(edge.a.z, edge.b.z) / cell) + 3);
    for (int r = r0; r <= r1; ++r)
      for (int col = c0; col <= c1; ++col) {
        const double x = (col + 0.5) * cell - edge.a.x, z = (r + 0.5) * cell - edge.a.z;
        const double t = (x * ex + z * ez) / (len * len), across_n = (ex * z - ez * x) / len;
        if (std::abs(across_n) > 3.0 * half || t < 0.0 || t > 1.0) continue;
        const double top = edge.a.y + t * (edge.b.y - edge.a.y) + c.height_m * up;
        const double h = g.height(col, r);
        highest = std::max(highest, h);
        m.reach_m = std::max(m.reach_m, h - top);
        if (h - top <= kTopSlack_m) continue;
        // Above the top: only where nothing more can fall over. Down the
        // other side along the edge's normal, from the first cell clear of
        // the blade, every cell must stand on the repose line falling from
        // the top there (at its own point of the edge) up to a cell above
        // that line, which stops what falls (or the grid's edge); a cell
        // below its line by more than the slack had room. The first cell
        // above the top is a buried blade.
        const double side = across_n > 0.0 ? -1.0 : 1.0;
        bool room = false;
        int prev_c = -1, prev_r = -1;
        for (int k = 0; k < 512; ++k) {
          const double dist = land + k * cell;
          const double px = edge.a.x + t * ex + side * dist * mx, pz = edge.a.z + t * ez + side * dist * mz;
          const int pc = int(std::floor(px / cell)), pr = int(std::floor(pz / cell));
          if (pc < 0 || pr < 0 || pc >= n || pr >= n) break;
          if (pc == prev_c && pr == prev_r) continue;
          prev_c = pc, prev_r = pr;
          const double xr = (pc + 0.5) * cell - edge.a.x, zr = (pr + 0.5) * cell - edge.a.z;
          const double tr = std::clamp((xr * ex + zr * ez) / (len * len), 0.0, 1.0);
          const double top_r = edge.a.y + tr * (edge.b.y - edge.a.y) + c.height_m * up;
          const double d = std::abs(ex * zr - ez * xr) / len;
          const double line = top_r - slope * std::max(0.0, d - land);
          const double hr = g.height(pc, pr);
          if (hr > line + kTopSlack_m) break;   // stops what falls (at k = 0: buried)
          if (hr < line - kTopSlack_m) {
            room = true;
            break;
          }
        }
        if (room) m.worst_unburied_m = std::max(m.worst_unburied_m, h - top);
      }
  }
  // The trench behind the last edge, within its span, back to the start.
  const HeightGrid& g = sim.grid();
  const double ex = edge.b.x - edge.a.x, ez = edge.b.z - edge.a.z, len = std::hypot(ex, ez);
  for (int r = 0; r < n; ++r)
    for (int col = 0; col < n; ++col) {
      const double x = (col + 0.5) * cell - edge.a.x, z = (r + 0.5) * cell - edge.a.z;
      const double t = (x * ex + z * ez) / (len * len), across_n = (ex * z - ez * x) / len;
      const double h = g.height(col, r);
      highest = std::max(highest, h);
      if (across_n < 0.0 && across_n > -kTopTravel_m && t >= 0.0 && t <= 1.0)
        m.behind_m3 += std::max(0.0, h - (edge.a.y + t * (edge.b.y - edge.a.y))) * cell * cell;
    }
  m.volume_error_m3 = sim.grid().volume_m3() - before;
  m.volume_slack_m3 = double(n) * n * double(std::numeric_limits<float>::epsilon()) * highest * cell * cell;
  return m;
}

std::vector<TopCase> validation_top_cases() {
  return {
      {0.1, 0.0, 0.0, 1.0, 0.01},  {0.1, 30.0, 0.0, 1.0, 0.01},  {0.1, 45.0, 0.0, 0.5, 0.01},
      {0.1, 90.0, 0.0, 2.0, 0.01}, {0.08, 0.0, 0.0, 0.25, 0.01}, {0.1, 0.0, 3.0, 1.0, 0.01},
      {0.1, 10.0, 0.0, 1.0, 0.005},
  };
}

}  // namespace terracut::validation
