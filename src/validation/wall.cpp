// The blade-is-a-wall measure (wall.hpp): a terrain, a blade that spans it
// or runs in a closed channel, the trench behind its start already dug, and
// every sample it has passed watched for soil above the edge's height.
#include "terracut/validation/wall.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "terracut/core/format.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::validation {

namespace {

constexpr double kWallDeg = std::numbers::pi / 180.0;
constexpr double kWallLayer_m = 0.2;   // the soil's surface, m
constexpr double kWallDepth_m = 0.05;  // the cut, m

// The square terrain's side, m: in a channel room for the blade and 0.2 m
// either side of it; spanning, 1 m.
double terrain_side_m(const WallCase& w) { return w.channel ? std::max(1.0, w.length_m + 0.4) : 1.0; }

}  // namespace

const char* motion_name(WallMotion m) {
  switch (m) {
    case WallMotion::kPush: return "push";
    case WallMotion::kPlunge: return "plunge";
    case WallMotion::kLift: return "lift";
    case WallMotion::kTurn: return "turn";
  }
  return "?";
}

double blade_length_m(const WallCase& w) {
  // Spanning the terrain, the blade is longer than the terrain's diagonal,
  // so its ends are off it.
  return w.channel ? w.length_m : 2.0 * terrain_side_m(w);
}

std::string describe(const WallCase& w) {
  const std::string blade = format_number(blade_length_m(w)) + " m blade" + (w.channel ? "" : " spanning the terrain");
  return std::string(motion_name(w.motion)) + ", " + blade + ", yaw " + format_number(w.yaw_deg) + " deg, " +
         format_number(w.speed_m_per_s) + " m/s, " + format_number(w.cell_m * 1000.0) +
         (w.cell_aspect != 1.0 ? " x " + format_number(w.cell_m * w.cell_aspect * 1000.0) : "") + " mm cells" +
         (w.columns ? " (columns)" : "") + (w.channel ? ", in a channel" : "") +
         (w.tremor_m > 0.0 ? ", tremor " + format_number(w.tremor_m * 1000.0) + " mm" : "") +
         (w.wobble_deg > 0.0 ? ", wobble " + format_number(w.wobble_deg) + " deg" : "") +
         (w.roll_deg != 0.0 ? ", roll " + format_number(w.roll_deg) + " deg" : "") +
         (w.origin_m != 0.0 ? ", terrain at " + format_number(w.origin_m) + " m" : "") + ", cap " +
         std::to_string(w.cap);
}

double worst_rise_behind(const WallCase& w) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(w.length_m) || !positive(w.speed_m_per_s) || !positive(w.cell_m) || !std::isfinite(w.yaw_deg))
    throw std::invalid_argument("worst_rise_behind: length_m, speed_m_per_s and cell_m must be finite and > 0, "
                                "yaw_deg finite (" + describe(w) + ")");
  if (w.cell_m > 0.05 || w.cell_m < 0.002 || w.speed_m_per_s < 0.001)
    throw std::invalid_argument("worst_rise_behind: cell_m must lie in [0.002, 0.05] m and speed_m_per_s be at least "
                                "0.001 m/s (" + describe(w) + ")");
  if (!(std::isfinite(w.tremor_m) && w.tremor_m >= 0.0 && w.tremor_m <= 0.02))
    throw std::invalid_argument("worst_rise_behind: tremor_m must lie in [0, 0.02] m (" + describe(w) + ")");
  if (!(std::isfinite(w.wobble_deg) && w.wobble_deg >= 0.0 && w.wobble_deg <= 5.0))
    throw std::invalid_argument("worst_rise_behind: wobble_deg must lie in [0, 5] degrees (" + describe(w) + ")");
  if (!(std::isfinite(w.origin_m) && std::abs(w.origin_m) <= 1e7))
    throw std::invalid_argument("worst_rise_behind: origin_m must lie in [-1e7, 1e7] m (" + describe(w) + ")");
  if (!(std::isfinite(w.cell_aspect) && w.cell_aspect >= 0.25 && w.cell_aspect <= 4.0))
    throw std::invalid_argument("worst_rise_behind: cell_aspect must lie in [0.25, 4] (" + describe(w) + ")");
  if (!(std::isfinite(w.roll_deg) && std::abs(w.roll_deg) <= 5.0))
    throw std::invalid_argument("worst_rise_behind: roll_deg must lie in [-5, 5] degrees (" + describe(w) + ")");
  const double cell = w.cell_m;
  const double travel = 0.3;  // m
  const double yaw = w.yaw_deg * kWallDeg;
  // Spanning the terrain, the blade travels along its normal; in a channel
  // (along +Z), along +Z whatever its yaw, as an angled blade does.
  const double nx = w.channel ? 0.0 : std::sin(yaw), nz = w.channel ? 1.0 : std::cos(yaw);
  // A square terrain; the blade's centre crosses its middle.
  const double side_m = terrain_side_m(w);
  const int n = int(std::lround(side_m / cell));
  // Rows: cells of cell_m x cell_m * cell_aspect.
  const int rows = int(std::lround(side_m / (cell * w.cell_aspect)));
  const double dx = side_m / n, dz = side_m / rows;
  // In the channel the blade starts with its centre on a row of cell
  // centres, where a level edge stands on them again and again.
  // The terrain's corner at (origin_m, 0, origin_m).
  const double o = w.origin_m;
  const double cx = o + 0.5 * side_m, cz = o + 0.5 * side_m + (w.channel ? 0.5 * dz : 0.0);
  // The cutting plane: the edge lies in it at every step, whatever the
  // motion, so each sample the edge passes is left at the plane's height and
  // no part of the edge ever comes back below a floor it cut (a part that
  // did would cut that floor with its back and push it behind the blade, as
  // a real blade does: not a leak). Through the edge's starting height at
  // the blade's centre; along the travel it falls 4 cm over the 0.3 m
  // (plunge) or rises so (lift), a ramp fixed in space and gentler than the
  // repose slope; across the travel it slopes by the roll. Its height at
  // (x, z):
  const double edge_start = kWallLayer_m - kWallDepth_m;
  const double y0 = w.motion == WallMotion::kPlunge ? kWallLayer_m - 0.01 : edge_start;
  const double along_slope = w.motion == WallMotion::kPlunge ? -0.04 / travel
                             : w.motion == WallMotion::kLift ? 0.04 / travel
                                                             : 0.0;
  const double cross_slope = std::tan(w.roll_deg * kWallDeg);
  // (gx, gz): the plane's gradient where the edge goes; along the travel
  // measured from the centre's start, across it toward the side the edge's
  // +X end points at yaw 0.
  const double gx = along_slope * nx + cross_slope * nz, gz = along_slope * nz - cross_slope * nx;
  const double start_x = cx - 0.5 * travel * nx, start_z = cz - 0.5 * travel * nz;
  // The largest angle between the edge and the normal of its travel: the
  // yaw in a channel (spanning, it travels along its normal), the turn and
  // the wobble.
  const double widest_deg =
      (w.channel ? std::abs(w.yaw_deg) : 0.0) + (w.motion == WallMotion::kTurn ? 8.0 : 0.0) + w.wobble_deg;
  // Beyond the reach of the edge along the travel (its half-length at that
  // angle, the tremor and two cells, before the start and past the end) the
  // ramp goes no further: the trench dug behind the start and the ground
  // far ahead stay above the terrain's bottom.
  const double reach =
      0.5 * blade_length_m(w) * std::sin(std::min(90.0, widest_deg) * kWallDeg) + w.tremor_m + 2.0 * cell;
  const auto plane_y = [&](double x, double z) {
    const double along = std::clamp((x - start_x) * nx + (z - start_z) * nz, -reach, travel + reach);
    const double across = (x - cx) * nz - (z - cz) * nx;
    return y0 + along_slope * along + cross_slope * across;
  };
  // Its lowest over the terrain (at a corner or the ramp's ends): it must
  // stay above the ground's bottom and the obstacles' cells.
  double lowest = kWallLayer_m;
  for (const double x : {o, o + side_m})
    for (const double z : {o, o + side_m}) {
      const double across = (x - cx) * nz - (z - cz) * nx;
      for (const double along : {-reach, travel + reach})
        lowest = std::min(lowest, y0 + along_slope * along + cross_slope * across);
    }
  if (!(lowest >= 0.03))
    throw std::invalid_argument("worst_rise_behind: the cutting plane comes within 3 cm of the terrain's bottom "
                                "(" + describe(w) + ")");
  SimParams p;
  p.grid.cols = n;
  p.grid.rows = rows;
  p.grid.size_x_m = side_m;
  p.grid.size_z_m = side_m;
  p.grid.origin_m = {o, 0.0, o};
  // Spanning the terrain: longer than its diagonal, so its ends are off it.
  p.blade.length_m = blade_length_m(w);
  p.soil.model = SoilModel::kFlow;
  p.representation = w.columns ? Representation::kColumns : Representation::kSurface;
  p.soil.material.repose_deg = 34.0;
  p.soil.max_pair_checks_per_step = w.cap;
  std::vector<float> h(std::size_t(n) * rows, float(kWallLayer_m));
  std::vector<SoilObstacle> walls;
  if (w.channel) {
    // The blade's reach across the channel at the largest yaw it takes,
    // less two cells: its ends stay over the obstacles either side, whose
    // cells stand below the plane (no soil to cut or to slide off them) and
    // are closed to soil coming in.
    const double half_channel = 0.5 * w.length_m * std::cos(widest_deg * kWallDeg) - 2.0 * cell;
    if (!(half_channel >= 2.0 * cell))
      throw std::invalid_argument("worst_rise_behind: in a channel the blade must reach across at least 8 cells "
                                  "at its largest yaw (" + describe(w) + ")");
    const int c0 = int(std::ceil((cx - o - half_channel) / dx)), c1 = int(std::floor((cx - o + half_channel) / dx));
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < n; ++c)
        if (c < c0 || c >= c1) h[std::size_t(r) * n + c] = float(lowest - 0.02);
    walls.push_back({{0, 0, c0, rows}, 0.0f});
    walls.push_back({{c1, 0, n, rows}, 0.0f});
  }
  // The pose at step s in [0, 1] (time s * travel / speed): the centre on
  // the plane, the tremor along the travel; the yaw turning from -8 to +8
  // degrees about the centre (kTurn) and wobbling, and the edge rolled
  // about its normal so that it lies in the plane at that yaw (turned about
  // the vertical alone, a rolled edge would leave the plane). Turning,
  // every point of the blade over the terrain moves forward, slowly
  // enough: none backs into the trench, beside the uncut soil ahead of the
  // starting line, but where the tremor or the wobble takes it back.
  const double seconds = travel / w.speed_m_per_s;
  const auto pose_at = [&](double s) {
    const double along =
        -0.5 * travel + travel * s + w.tremor_m * std::sin(2.0 * std::numbers::pi * kWallTremor_hz * seconds * s);
    const double x = cx + nx * along, z = cz + nz * along;
    const double turn = (w.motion == WallMotion::kTurn ? -8.0 + 16.0 * s : 0.0) +
                        w.wobble_deg * std::sin(2.0 * std::numbers::pi * kWallWobble_hz * seconds * s);
    const double yaw_now = yaw + turn * kWallDeg;
    // The edge's direction in plan at this yaw, (cos, -sin): the plane's
    // rise along it gives the roll.
    const double roll = std::atan(gx * std::cos(yaw_now) - gz * std::sin(yaw_now));
    return BladePose{{x, plane_y(x, z), z},
                     quat_from_axis_angle({0.0, 1.0, 0.0}, yaw_now) * quat_from_axis_angle({0.0, 0.0, 1.0}, roll)};
  };
  // Behind the starting line the trench is already dug, to the plane: no
  // back wall at the trench's start to slump into it.
  {
    const BladePose start = pose_at(0.0);
    const Vec3 e = rotate(start.orientation, {1.0, 0.0, 0.0});
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < n; ++c) {
        const double x = o + (c + 0.5) * dx, z = o + (r + 0.5) * dz;
        if (e.x * (z - start.position_m.z) - e.z * (x - start.position_m.x) < 0.0) {
          float& v = h[std::size_t(r) * n + c];
          v = std::min(v, float(plane_y(x, z)));
        }
      }
  }
  Simulation sim(p, h);
  if (w.channel) sim.soil()->set_obstacles(walls);
  const int steps = int(std::lround(travel / w.speed_m_per_s * 1000.0));
  double worst = -1.0;
  std::int64_t measured = 0;  // samples watched over the run
  for (int i = 0; i <= steps; ++i) {
    const double s = double(i) / steps;
    sim.step(pose_at(s));
    const Segment edge = sim.last().edge;
    const double dxl = edge.b.x - edge.a.x, dzl = edge.b.z - edge.a.z;
    const double len = std::hypot(dxl, dzl);
    const HeightGrid& g = sim.grid();
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < n; ++c) {
        const double x = o + (c + 0.5) * dx, z = o + (r + 0.5) * dz;
        const double d = (dxl * (z - edge.a.z) - dzl * (x - edge.a.x)) / len;  // signed distance to the line, + ahead
        const double t = ((x - edge.a.x) * dxl + (z - edge.a.z) * dzl) / (len * len);
        // Watched: within the blade's span, on the side it came from now,
        // more than a cell and a half from its line (every such sample was
        // dug before the start or cut to the plane since; a blade the
        // tremor or wobble takes back leaves soil that slid after it, in
        // front of it, on samples it had passed, and cuts it again as it
        // comes forward).
        if (t < 0.0 || t > 1.0 || d > -1.5 * std::max(dx, dz)) continue;
        worst = std::max(worst, double(g.height(c, r)) - plane_y(x, z));
        ++measured;
      }
  }
  // (A case whose blade never passed a sample beyond the band would pass
  // with nothing measured.)
  if (measured == 0) throw std::invalid_argument("worst_rise_behind: no sample behind the blade to watch (" + describe(w) + ")");
  return worst;
}

std::vector<WallCase> validation_wall_cases() {
  std::vector<WallCase> cases;
  // Spanning the terrain: every motion, yaws round the compass, speeds from
  // slow (0.05 m/s: 1/200 of a cell a step) to 2 m/s.
  const double speeds[] = {0.05, 0.25, 2.0};
  int k = 0;
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn})
    for (const double yaw : {0.0, 30.0, 90.0, 135.0}) cases.push_back({1.0, yaw, speeds[k++ % 3], motion, false});
  // In a channel: short and long blades, straight and yawed.
  for (const double length : {0.2, 0.5, 2.0})
    for (const double yaw : {0.0, 25.0}) cases.push_back({length, yaw, speeds[k++ % 3], WallMotion::kPush, true});
  // A hand's tremor of 4 mm backing the blade up in every cycle: every
  // motion spanning the terrain, and turning in a channel.
  const double tremor_speeds[] = {0.1, 0.2};
  k = 0;
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn}) {
    WallCase w{1.0, 10.0 + 40.0 * k, tremor_speeds[k % 2], motion, false};
    w.tremor_m = 0.004;
    cases.push_back(w);
    ++k;
  }
  WallCase turning{0.5, 10.0, 0.2, WallMotion::kTurn, true};
  turning.tremor_m = 0.004;
  cases.push_back(turning);
  // A wobble of 1.5 degrees about the vertical with a 2 mm tremor: a 2 m
  // blade spanning the terrain pushing, and a 0.8 m blade turning in a
  // channel.
  WallCase wobbling{1.0, 173.0, 0.6, WallMotion::kPush, false};
  wobbling.tremor_m = 0.002;
  wobbling.wobble_deg = 1.5;
  cases.push_back(wobbling);
  wobbling = WallCase{0.8, -30.0, 0.25, WallMotion::kTurn, true};
  wobbling.tremor_m = 0.002;
  wobbling.wobble_deg = 1.5;
  cases.push_back(wobbling);
  // Rolled blades (one end lower), each motion: a 2 m blade spanning the
  // terrain plunging with the tremor and the wobble, 1 and 1.5 m blades
  // lifting (wobbling) and pushing in a channel, and one turning with the
  // tremor.
  cases.push_back({.length_m = 1.0, .yaw_deg = 60.0, .speed_m_per_s = 0.3, .motion = WallMotion::kPlunge,
                   .tremor_m = 0.002, .wobble_deg = 1.5, .roll_deg = 3.0});
  cases.push_back({.length_m = 1.0, .yaw_deg = 20.0, .speed_m_per_s = 0.5, .motion = WallMotion::kLift,
                   .channel = true, .wobble_deg = 1.5, .roll_deg = -3.0});
  cases.push_back({.length_m = 1.5, .yaw_deg = -15.0, .speed_m_per_s = 1.0, .motion = WallMotion::kPush,
                   .channel = true, .roll_deg = 4.0});
  cases.push_back({.length_m = 1.0, .yaw_deg = 200.0, .speed_m_per_s = 0.2, .motion = WallMotion::kTurn,
                   .tremor_m = 0.004, .roll_deg = -2.5});
  // Along a lattice direction (the line through a centre every three
  // cells: tangent 1/3), turning: at the step where the turn passes 0 the
  // line lies on a row of centres. A 2 m blade spanning the terrain on 2 cm
  // cells with a 2 mm tremor, and one rolled on a terrain 1e7 m from the
  // origin (both left 1.8 to 2 cm behind the blade before 2026-12-07).
  const double lattice_deg = std::atan(1.0 / 3.0) * 180.0 / std::numbers::pi;
  cases.push_back({.length_m = 1.0, .yaw_deg = 180.0 + lattice_deg, .speed_m_per_s = 0.3,
                   .motion = WallMotion::kTurn, .cell_m = 0.02, .tremor_m = 0.002});
  cases.push_back({.length_m = 1.0, .yaw_deg = 90.0 + lattice_deg, .speed_m_per_s = 0.4,
                   .motion = WallMotion::kTurn, .roll_deg = 2.0, .origin_m = 1e7});
  return cases;
}

}  // namespace terracut::validation
