// The bucket-is-a-solid measure (hull.hpp): a stroke of a bucket through a
// layer of sand, and after every step each cell centre under its plates
// checked against their undersides, worked out here from the pose.
#include "terracut/validation/hull.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "terracut/core/format.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::validation {

namespace {

constexpr double kHullDeg = std::numbers::pi / 180.0;
constexpr double kTravel_m = 0.5;

// One plate of the hull: the points o + s a + t b for s, t in [0, 1].
struct Plate {
  Vec3 o, a, b;
};

}  // namespace

bool HullMeasure::holds() const {
  return worst_above_m <= kHullSlack_m && worst_volume_error_m3 <= volume_slack_m3;
}

const char* motion_name(BucketMotion m) {
  switch (m) {
    case BucketMotion::kDig: return "dig";
    case BucketMotion::kLower: return "lower";
    case BucketMotion::kHeelFirst: return "heel first";
    case BucketMotion::kSideways: return "sideways";
    case BucketMotion::kTurn: return "dig turning";
  }
  return "?";
}

std::string describe(const BucketStroke& s) {
  return std::string(motion_name(s.motion)) + ", " + format_number(s.length_m) + " x " + format_number(s.depth_m) +
         " x " + format_number(s.height_m) + " m bucket, yaw " + format_number(s.yaw_deg) + " deg, pitch " +
         format_number(s.pitch_deg) + " deg" + (s.roll_deg != 0.0 ? ", roll " + format_number(s.roll_deg) + " deg" : "") +
         ", " + format_number(s.speed_m_per_s) + " m/s, " + "lip " + format_number(s.dig_m) + " m deep, " +
         format_number(s.cell_m * 1000.0) +
         (s.cell_aspect != 1.0 ? " x " + format_number(s.cell_m * s.cell_aspect * 1000.0) : "") + " mm cells" +
         (s.columns ? " (columns)" : "") +
         (s.tremor_m > 0.0 ? ", tremor " + format_number(s.tremor_m * 1000.0) + " mm" : "") +
         (s.wobble_deg > 0.0 ? ", wobble " + format_number(s.wobble_deg) + " deg" : "") +
         (s.origin_m != 0.0 ? ", terrain at " + format_number(s.origin_m) + " m" : "") + ", cap " +
         std::to_string(s.cap);
}

HullMeasure measure_hull(const BucketStroke& s) {
  const auto check = [&](const char* field, double v, double lo, double hi, bool open_low) {
    if (!std::isfinite(v) || v > hi || (open_low ? v <= lo : v < lo))
      throw std::invalid_argument(std::string("measure_hull: ") + field + " must lie in " + (open_low ? "(" : "[") +
                                  format_number(lo) + ", " + format_number(hi) + "], not " + format_number(v) + " (" +
                                  describe(s) + ")");
  };
  check("length_m", s.length_m, 0.0, 1.0, true);
  check("depth_m", s.depth_m, 0.0, 0.5, true);
  check("height_m", s.height_m, 0.0, 0.5, true);
  check("yaw_deg", s.yaw_deg, -1e6, 1e6, false);
  check("pitch_deg", s.pitch_deg, -40.0, 40.0, false);
  check("roll_deg", s.roll_deg, -10.0, 10.0, false);
  check("speed_m_per_s", s.speed_m_per_s, 0.01, 2.0, false);
  check("dig_m", s.dig_m, 0.0, 0.1, true);
  check("tremor_m", s.tremor_m, 0.0, 0.01, false);
  check("wobble_deg", s.wobble_deg, 0.0, 5.0, false);
  check("cell_m", s.cell_m, 0.004, 0.04, false);
  check("cell_aspect", s.cell_aspect, 0.25, 4.0, false);
  check("origin_m", s.origin_m, -1e7, 1e7, false);
  if (s.cap < 1000 || s.cap > 1000000000)
    throw std::invalid_argument("measure_hull: cap must lie in [1000, 1e9] (" + describe(s) + ")");

  // The bucket's pitch and roll do not change over a stroke; its corners'
  // heights below the lip then do not depend on the yaw.
  const Quat tilt = quat_from_axis_angle({0.0, 0.0, 1.0}, s.roll_deg * kHullDeg) *
                    quat_from_axis_angle({1.0, 0.0, 0.0}, s.pitch_deg * kHullDeg);
  double lowest = 0.0, reach = 0.0;
  for (const double x : {-0.5 * s.length_m, 0.5 * s.length_m})
    for (const Vec3& p : {Vec3{x, 0.0, 0.0}, Vec3{x, 0.0, s.depth_m}, Vec3{x, s.height_m, s.depth_m}}) {
      const Vec3 q = rotate(tilt, p);
      lowest = std::min(lowest, q.y);
      reach = std::max(reach, std::hypot(q.x, q.z));
    }
  if (kBucketLayer_m - s.dig_m + lowest < 0.02)
    throw std::invalid_argument("measure_hull: the hull would reach within 2 cm of the terrain's bottom (" +
                                describe(s) + ")");

  // A square terrain wide enough for the hull anywhere on its travel, with
  // 10 cm to spare.
  const double side = std::max(1.6, 2.0 * (0.5 * kTravel_m + s.tremor_m + reach + 0.1));
  SimParams p;
  p.grid.cols = int(std::lround(side / s.cell_m));
  p.grid.rows = int(std::lround(side / (s.cell_m * s.cell_aspect)));
  p.grid.size_x_m = side;
  p.grid.size_z_m = side;
  p.grid.origin_m = {s.origin_m, 0.0, s.origin_m};
  p.representation = s.columns ? Representation::kColumns : Representation::kSurface;
  p.blade.length_m = s.length_m;
  p.blade.bucket.depth_m = s.depth_m;
  p.blade.bucket.height_m = s.height_m;
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = 34.0;
  p.soil.max_pair_checks_per_step = s.cap;
  const int cols = p.grid.cols, rows = p.grid.rows;
  const double dx = side / cols, dz = side / rows;
  Simulation sim(p, std::vector<float>(std::size_t(cols) * rows, float(kBucketLayer_m)));
  const double initial = sim.grid().volume_m3();

  const double o = s.origin_m, cx = o + 0.5 * side, cz = o + 0.5 * side;
  const double seconds = kTravel_m / s.speed_m_per_s;
  const int steps = std::max(2, int(std::lround(seconds * 1000.0)));
  const Quat base = quat_from_axis_angle({0.0, 1.0, 0.0}, s.yaw_deg * kHullDeg);
  const Vec3 travel = rotate(base, s.motion == BucketMotion::kHeelFirst  ? Vec3{0.0, 0.0, 1.0}
                                   : s.motion == BucketMotion::kSideways ? Vec3{1.0, 0.0, 0.0}
                                                                          : Vec3{0.0, 0.0, -1.0});
  const double top = kBucketLayer_m;
  const auto pose_at = [&](double f) {
    const double t = f * seconds;
    const double yaw = s.yaw_deg + s.wobble_deg * std::sin(2.0 * std::numbers::pi * kBucketWobble_hz * t) +
                       (s.motion == BucketMotion::kTurn ? -15.0 + 30.0 * f : 0.0);
    const double tremor = s.tremor_m * std::sin(2.0 * std::numbers::pi * kBucketTremor_hz * t);
    double along = (f - 0.5) * kTravel_m + tremor, y = top;
    switch (s.motion) {
      case BucketMotion::kLower:
        along = tremor;
        y = top + 0.03 - (0.03 + s.dig_m) * std::min(1.0, 1.5 * f);
        break;
      case BucketMotion::kHeelFirst:
      case BucketMotion::kSideways: y = top - s.dig_m * std::min(1.0, 4.0 * f); break;
      case BucketMotion::kDig:
      case BucketMotion::kTurn:
        y = top + 0.01 - (0.01 + s.dig_m) * std::min(1.0, f / 0.3) +
            (0.05 + s.dig_m) * std::max(0.0, (f - 0.85) / 0.15);
        break;
    }
    return BladePose{{cx + travel.x * along, y, cz + travel.z * along},
                     quat_from_axis_angle({0.0, 1.0, 0.0}, yaw * kHullDeg) * tilt};
  };

  HullMeasure m;
  m.steps = steps + 1;
  m.worst_above_m = -std::numeric_limits<double>::infinity();
  // A centre within rounding of a plate's edge may fall either side of it:
  // 4 millionths of a cell, or 256 double steps at the terrain's largest
  // coordinate where that is more.
  const double edge_m = std::max(4e-6 * std::min(dx, dz), 256.0 * std::numeric_limits<double>::epsilon() *
                                                             (std::abs(o) + side));
  for (int i = 0; i <= steps; ++i) {
    const BladePose pose = pose_at(double(i) / steps);
    sim.step(pose);
    const SoilStepResult& soil = sim.last().soil;
    m.worst_volume_error_m3 =
        std::max(m.worst_volume_error_m3, std::abs(sim.grid().volume_m3() + soil.bucket_load_m3 - initial));
    m.shouldered_m3 += soil.shouldered_m3;
    m.load_m3 = soil.bucket_load_m3;
    const Quat& q = pose.orientation;
    const Vec3 half = rotate(q, {0.5 * s.length_m, 0.0, 0.0});
    const Vec3 lip_a = pose.position_m - half;
    const Vec3 back = rotate(q, {0.0, 0.0, s.depth_m}), up = rotate(q, {0.0, s.height_m, 0.0});
    const Plate plates[2] = {{lip_a, 2.0 * half, back}, {lip_a + back, 2.0 * half, up}};
    // Each plate's determinant in plan and edge_m in its parameters (the
    // lines s = 0 and s = 1 lie |det| / |b| apart, those of t |det| / |a|),
    // once a step; a plate seen edge-on covers no centre.
    struct Plan {
      double det, ms, mt;
      bool seen;
    };
    Plan plans[2];
    for (int k = 0; k < 2; ++k) {
      const Plate& pl = plates[k];
      const double det = pl.a.x * pl.b.z - pl.a.z * pl.b.x;
      const double la = std::hypot(pl.a.x, pl.a.z), lb = std::hypot(pl.b.x, pl.b.z);
      plans[k] = {det, edge_m * lb / std::abs(det), edge_m * la / std::abs(det), std::abs(det) > 1e-9 * la * lb};
    }
    // (s, t) of cell (c, r)'s centre in plate k's plan.
    const auto in_plan = [&](int k, int c, int r, double& ps, double& pt) {
      const Plate& pl = plates[k];
      const double px = (c + 0.5) * dx + (o - pl.o.x), pz = (r + 0.5) * dz + (o - pl.o.z);
      ps = (px * pl.b.z - pz * pl.b.x) / plans[k].det;
      pt = (pl.a.x * pz - pl.a.z * px) / plans[k].det;
    };
    for (int k = 0; k < 2; ++k) {
      const Plate& pl = plates[k];
      if (!plans[k].seen) continue;
      const double ms = plans[k].ms, mt = plans[k].mt;
      double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
      for (const Vec3& c : {pl.o, pl.o + pl.a, pl.o + pl.b, pl.o + pl.a + pl.b}) {
        x0 = std::min(x0, c.x), x1 = std::max(x1, c.x), z0 = std::min(z0, c.z), z1 = std::max(z1, c.z);
      }
      const int c0 = std::max(0, int(std::floor((x0 - o) / dx)) - 1);
      const int c1 = std::min(cols, int(std::ceil((x1 - o) / dx)) + 1);
      const int r0 = std::max(0, int(std::floor((z0 - o) / dz)) - 1);
      const int r1 = std::min(rows, int(std::ceil((z1 - o) / dz)) + 1);
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c) {
          double ps, pt;
          in_plan(k, c, r, ps, pt);
          if (ps <= ms || ps >= 1.0 - ms || pt <= mt || pt >= 1.0 - mt) continue;
          double under = pl.o.y + ps * pl.a.y + pt * pl.b.y;
          // Under the other plate too: the lower one's underside.
          const int j = 1 - k;
          double os, ot;
          if (plans[j].seen) {
            in_plan(j, c, r, os, ot);
            if (os >= 0.0 && os <= 1.0 && ot >= 0.0 && ot <= 1.0)
              under = std::min(under, plates[j].o.y + os * plates[j].a.y + ot * plates[j].b.y);
          }
          m.worst_above_m = std::max(m.worst_above_m, double(sim.grid().height(c, r)) - under);
        }
    }
  }
  // Float rounding of every height (at most the layer and the hull's
  // height above it), four steps each.
  m.volume_slack_m3 = 4.0 * double(cols) * rows * dx * dz * (kBucketLayer_m + 0.1 + s.height_m) *
                          std::numeric_limits<float>::epsilon() +
                      1e-9;
  return m;
}

std::vector<BucketStroke> validation_bucket_strokes() {
  std::vector<BucketStroke> out;
  const auto add = [&](BucketMotion motion, double yaw, double pitch, double speed) {
    BucketStroke s;
    s.motion = motion;
    s.yaw_deg = yaw;
    s.pitch_deg = pitch;
    s.speed_m_per_s = speed;
    out.push_back(s);
    return &out.back();
  };
  // Every motion at an axis yaw, an oblique one and a lattice direction
  // (tangent 1/2: the lip through a cell centre every two cells).
  const double lattice = std::atan(0.5) / kHullDeg;
  for (const double yaw : {0.0, 37.0, lattice}) {
    add(BucketMotion::kDig, yaw, -7.0, 0.5);
    add(BucketMotion::kLower, yaw, 10.0, 0.3);
    add(BucketMotion::kHeelFirst, yaw, -1.0, 0.5);
    add(BucketMotion::kSideways, yaw, 0.0, 0.5);
    add(BucketMotion::kTurn, yaw, -5.0, 0.5);
  }
  // Rolled, trembling, wobbling; a fast dig; 5 mm and oblong cells; the
  // columns; far from the origin.
  add(BucketMotion::kDig, 113.0, -12.0, 0.8)->roll_deg = 6.0;
  BucketStroke* s = add(BucketMotion::kHeelFirst, 250.0, -3.0, 0.15);
  s->tremor_m = 0.003, s->roll_deg = 4.0;
  s = add(BucketMotion::kTurn, 200.0, -6.0, 0.2);
  s->wobble_deg = 1.5, s->cell_m = 0.005;
  add(BucketMotion::kDig, -45.0, -10.0, 2.0)->cell_aspect = 0.5;
  s = add(BucketMotion::kSideways, 71.0, 1.0, 0.4);
  s->cell_aspect = 2.0, s->columns = true;
  s = add(BucketMotion::kDig, 180.0 + lattice, -8.0, 0.6);
  s->origin_m = 1e6, s->columns = true;
  // Two of the strokes that put soil inside the hull before 2026-12-07:
  // several sources filling one covered cell in the same pass (1.7 mm and
  // 2.7 cm; the slower ones a sweep found, up to 11 cm, are in
  // docs/soil.md).
  out.push_back({.length_m = 0.296, .depth_m = 0.109, .height_m = 0.286, .motion = BucketMotion::kTurn,
                 .yaw_deg = 108.435, .pitch_deg = -6.17, .speed_m_per_s = 0.116, .dig_m = 0.0456, .wobble_deg = 1.28,
                 .cell_m = 0.005, .columns = true, .cap = 1000000000});
  out.push_back({.length_m = 0.734, .depth_m = 0.276, .height_m = 0.237, .motion = BucketMotion::kHeelFirst,
                 .yaw_deg = 177.304, .pitch_deg = 2.74, .roll_deg = 4.01, .speed_m_per_s = 0.854, .dig_m = 0.0148,
                 .cell_m = 0.005, .cell_aspect = 2.0, .origin_m = 1e3, .columns = true});
  return out;
}

}  // namespace terracut::validation
