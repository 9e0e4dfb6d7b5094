// Soil that flows: displacement ahead of the blade and relaxation to the
// angle of repose. See soil.hpp.
#include "terracut/core/soil.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut {
namespace {

/// Radius around the edge, in cells, of the cells whose pairs are tested
/// against the blade (a pair is at most one diagonal long).
constexpr double kBladeRadiusCells = 1.5;
/// Distance beyond the edge's line, in cells, where displaced soil is put:
/// the cell there is the first whose centre is clear of the blade (0.5 to
/// 1.5 cells ahead), so that the push shifts the profile in front of the
/// blade as a whole (at 1.5 it skipped the cell against the blade and left
/// a dip there that drained the whole face).
constexpr double kDepositAheadCells = 1.0;
/// A slope moves only when it exceeds the repose limit of a cell pair by
/// more than this fraction of the limit: 2 % of tan(repose), at most about
/// 0.5 degree above the repose angle (34 degrees: 34.4). Smaller tolerances
/// only lengthen the tail of a settling pile.
constexpr double kToleranceOfLimit = 0.02;
/// How far, in cells, the blade's ends move before the soil it held up is
/// examined again.
constexpr double kHeldMoveCells = 0.25;
/// Longest run of cells the blade pushes ahead of it, per cut sample.
constexpr int kMaxPushCells = 512;
/// Longest fall line a source's soil slides down in one pass, cells (what
/// lies beyond is reached in the next pass, from the line's end).
constexpr int kMaxFallCells = 32;
/// Rounds of the water fill after the first (each drops the cells that
/// stand above the line); what a source would still give past them stays
/// on it (a later pass moves it). Two settle nearly every source.
constexpr int kMaxExtraRounds = 2;
/// The most one examination can cost, in visits: its 8 neighbours, its
/// fall lines, and their cells read again in each further round. The work
/// cap admits a cell only with this much room left, so a step never passes
/// it (and the minimum cap, 1000, leaves room for one).
constexpr std::int64_t kMostExamineVisits = 8 + 8 * kMaxFallCells * (1 + kMaxExtraRounds);
static_assert(kMostExamineVisits <= 1000);
/// Fluxes a pass may hold per cell of the reserved active set.
constexpr std::size_t kFluxesPerActiveCell = 32;
/// The work cap's charge for a source's fall test (lowered): its 8
/// neighbours read again.
constexpr std::int64_t kFallTestVisits = 8;

// The 8 neighbours: offsets and which limit applies (0 along X, 1 along Z, 2 diagonal).
struct Neighbour {
  int dc;
  int dr;
  int kind;
};
/// The cell index standing for the bare ground beyond an open edge.
constexpr std::uint32_t kOutside = 0xffffffffu;

constexpr Neighbour kNeighbours[8] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 1},  {0, -1, 1},
                                      {1, 1, 2},  {-1, 1, 2}, {1, -1, 2}, {-1, -1, 2}};

double to_cells(double v, double origin, double cell) { return (v - origin) / cell; }

/// Writes every element of v's reserved storage once and empties it again:
/// the pages are the process's from construction on, so the first tick to
/// fill a list does not stop on page faults (a first touch of a few MiB of
/// fresh pages costs the system a millisecond or more).
template <typename T>
void touch_reserved(std::vector<T>& v) {
  v.resize(v.capacity());
  v.clear();
}

#if defined(__SSE2__)
/// The heights of an inner cell's 8 neighbours (p points at the cell; up is
/// one row along +Z), in kNeighbours' order: n0 holds k = 0..3, n1 k = 4..7.
inline void load_neighbours(const float* p, std::int64_t up, __m128& n0, __m128& n1) {
  n0 = _mm_setr_ps(p[1], p[-1], p[up], p[-up]);
  n1 = _mm_setr_ps(p[up + 1], p[up - 1], p[1 - up], p[-1 - up]);
}

/// Bit k set where lane k of (e0, e1) (k = 0..3, 4..7) is above tol.
inline unsigned above_mask(__m128 e0, __m128 e1, float tol) {
  const __m128 vt = _mm_set1_ps(tol);
  return unsigned(_mm_movemask_ps(_mm_cmpgt_ps(e0, vt))) | unsigned(_mm_movemask_ps(_mm_cmpgt_ps(e1, vt))) << 4;
}
#endif


}  // namespace

std::string_view to_string(SoilModel model) {
  return model == SoilModel::kFlow ? "flow" : "vanish";
}

std::string_view to_string(SoilEdge edge) { return edge == SoilEdge::kOpen ? "open" : "wall"; }

std::optional<SoilModel> parse_soil_model(std::string_view name) {
  if (name == "vanish") return SoilModel::kVanish;
  if (name == "flow") return SoilModel::kFlow;
  return std::nullopt;
}

std::string validate(const SoilFlowParams& p) {
  if (p.model != SoilModel::kVanish && p.model != SoilModel::kFlow)
    return "soil.model must be vanish or flow";
  if (p.edge != SoilEdge::kWall && p.edge != SoilEdge::kOpen) return "soil.edge must be wall or open";
  // The material's ranges (material.hpp): below a degree of repose the
  // material is a liquid, out of the model's reach (a repose of 1e-300
  // degrees made the tolerance 0, and float noise kept the cells moving).
  if (std::string m = validate(p.material); !m.empty()) return "soil." + m;
  if (!(p.max_pair_checks_per_step >= 1000 && p.max_pair_checks_per_step <= 1000000000))
    return must_be("soil.max_pair_checks_per_step", "in [1000, 1e9]",
                   p.max_pair_checks_per_step);
  return {};
}

double steepest_standing_slope_deg(double cell_x_m, double cell_z_m, double repose_deg) {
  const double t = std::tan(repose_deg * std::numbers::pi / 180.0);
  // The tolerance as the relaxation takes it: a fraction of the repose
  // drop over the shorter cell side, the same for every pair.
  const double tol = kToleranceOfLimit * t * std::min(cell_x_m, cell_z_m);
  // The neighbours' directions (from +X toward +Z) and each one's bound on
  // the plane's slope along its own direction: (t d + tol) / d.
  struct Dir {
    double angle, bound;
  };
  Dir dirs[8];
  for (int k = 0; k < 8; ++k) {
    const double x = kNeighbours[k].dc * cell_x_m, z = kNeighbours[k].dr * cell_z_m;
    const double d = std::hypot(x, z);
    dirs[k] = {std::atan2(z, x), (t * d + tol) / d};
  }
  std::sort(std::begin(dirs), std::end(dirs), [](const Dir& a, const Dir& b) { return a.angle < b.angle; });
  // A plane of slope s falling along theta stands while s cos(theta -
  // angle_k) <= bound_k for every neighbour ahead of it (cos > 0). Its
  // steepest standing slope over theta peaks where two adjacent
  // directions' bounds meet: with u = theta - angle_k and g the gap,
  // bound_k cos(u - g) = bound_k+1 cos(u).
  const auto standing = [&](double theta) {
    double s = std::numeric_limits<double>::infinity();
    for (const Dir& d : dirs) {
      const double c = std::cos(theta - d.angle);
      if (c > 1e-12) s = std::min(s, d.bound / c);
    }
    return s;
  };
  double steepest = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Dir& a = dirs[k];
    const Dir& b = dirs[(k + 1) % 8];
    const double g = k == 7 ? b.angle + 2.0 * std::numbers::pi - a.angle : b.angle - a.angle;
    const double u = std::atan2(b.bound - a.bound * std::cos(g), a.bound * std::sin(g));
    steepest = std::max(steepest, standing(a.angle + u));
  }
  return std::atan(steepest) * 180.0 / std::numbers::pi;
}

double bucket_retained_m3(const BladeSpec& blade, const Quat& orientation, double repose_deg) {
  const BucketSpec& bucket = blade.bucket;
  if (!bucket.enabled()) return 0.0;
  // The blade frame's Y and Z in the world, and the horizontal direction
  // into the bucket (the floor's, from the lip to the back).
  const Vec3 fy = rotate(orientation, {0.0, 1.0, 0.0}), fz = rotate(orientation, {0.0, 0.0, 1.0});
  // Something must carry the soil: the floor (inner normal +Y) or the back
  // wall (inner normal -Z) facing up; upside down it all falls out.
  if (!(std::max(fy.y, -fz.y) > 1e-9)) return 0.0;
  const double slope = std::tan(repose_deg * std::numbers::pi / 180.0);
  const double inward = std::hypot(fz.x, fz.z);
  // A section point (z, y) stands h = z fz.y + y fy.y above the lip and
  // s = (z fz + y fy) . u inward of it (u the unit inward direction); it is
  // held while h <= tan(repose) s: a z + b y <= 0.
  double a = fz.y, b = fy.y;
  if (inward > 1e-12) {
    const double ux = fz.x / inward, uz = fz.z / inward;
    a -= slope * (fz.x * ux + fz.z * uz);
    b -= slope * (fy.x * ux + fy.z * uz);
  }
  // The section's triangle clipped by that half-plane (Sutherland-Hodgman),
  // its area by the shoelace formula.
  const double tri[3][2] = {{0.0, 0.0}, {bucket.depth_m, 0.0}, {bucket.depth_m, bucket.height_m}};
  double poly[4][2];
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const double* p = tri[k];
    const double* q = tri[(k + 1) % 3];
    const double fp = a * p[0] + b * p[1], fq = a * q[0] + b * q[1];
    if (fp <= 0.0) poly[n][0] = p[0], poly[n++][1] = p[1];
    if ((fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0)) {
      const double t = fp / (fp - fq);
      poly[n][0] = p[0] + t * (q[0] - p[0]);
      poly[n++][1] = p[1] + t * (q[1] - p[1]);
    }
  }
  double twice_area = 0.0;
  for (int k = 0; k < n; ++k) {
    const double* p = poly[k];
    const double* q = poly[(k + 1) % n];
    twice_area += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * std::abs(twice_area) * blade.length_m;
}

SoilFlow::SoilFlow(const SoilFlowParams& params, const HeightGrid& grid, const BladeSpec& blade)
    : params_(params), blade_spec_(blade), cols_(grid.cols()), rows_(grid.rows()) {
  if (std::string m = validate(params); !m.empty()) throw InputError(m);
  const GridSpec& spec = grid.spec();
  dx_ = spec.cell_x_m();
  dz_ = spec.cell_z_m();
  const double slope = std::tan(params.material.repose_deg * std::numbers::pi / 180.0);
  limit_[0] = slope * dx_;
  limit_[1] = slope * dz_;
  limit_[2] = slope * std::hypot(dx_, dz_);
  tolerance_m_ = float(kToleranceOfLimit * std::min(limit_[0], limit_[1]));
  {
    // The relaxation's quantum: the float step of heights up to twice the
    // highest initial height (at least 1 m). Every height the relaxation
    // writes and every amount it moves is a multiple of it, so its float
    // additions are exact below that bound.
    double highest = 0.5;
    for (std::int64_t i = 0; i < grid.spec().sample_count(); ++i) highest = std::max(highest, double(grid.heights()[i]));
    quantum_m_ = std::ldexp(1.0, std::ilogb(2.0 * highest) - 23);
  }
  origin_x_ = spec.origin_m.x;
  origin_z_ = spec.origin_m.z;
  row_div_ = detail::IndexDivider(std::uint32_t(cols_));

  for (int k = 0; k < 8; ++k) {
    offset_[k] = std::int64_t(kNeighbours[k].dr) * cols_ + kNeighbours[k].dc;
    limit8_[k] = float(limit_[kNeighbours[k].kind]);
  }

  const std::size_t n = std::size_t(grid.spec().sample_count());
  queued_.assign(n, CellFlags(0));
  for (int c = 0; c < cols_; ++c) {
    set_flag(std::uint32_t(c), kEdge);
    set_flag(std::uint32_t(std::int64_t(rows_ - 1) * cols_ + c), kEdge);
  }
  for (int r = 0; r < rows_; ++r) {
    set_flag(std::uint32_t(std::int64_t(r) * cols_), kEdge);
    set_flag(std::uint32_t(std::int64_t(r) * cols_ + cols_ - 1), kEdge);
  }
  obstacle_.assign(n, 0);
  obstacles_.reserve(16);
  // The per-step scratch sized up front for the blade (its swept rectangle
  // and the cells near it: a square of its length plus a margin of cells)
  // and for an active set of a large pile, so that the 1 kHz loop's ticks
  // do not grow them: a haptic loop on flowing soil allocates nothing.
  const double reach_cells = blade.length_m / std::min(dx_, dz_) + 8.0;
  const std::size_t footprint = std::size_t(std::min(double(n), reach_cells * reach_cells));
  before_.reserve(footprint);
  after_cut_.reserve(footprint);
  marked_.reserve(footprint);
  const std::size_t active = std::min(n, std::max<std::size_t>(std::size_t(1) << 16, 4 * footprint));
  active_.reserve(active);
  next_.reserve(active);
  // A source's fall lines give up to 8 x kMaxFallCells fluxes, a handful as
  // a rule: a pass holds at most kFluxesPerActiveCell x active of them (a
  // larger one is split, examine's loop).
  fluxes_.reserve(kFluxesPerActiveCell * active);
  sources_.reserve(active);
  held_.reserve(footprint);
  dirty_.reserve(footprint);
  if (blade.bucket.enabled()) {
    // The hull lies within this of the lip's centre in any orientation:
    // its bounding rectangle is at most twice that across, plus a cell.
    const double reach = std::sqrt(0.25 * blade.length_m * blade.length_m + blade.bucket.depth_m * blade.bucket.depth_m +
                                   blade.bucket.height_m * blade.bucket.height_m);
    const double box = (2.0 * reach / dx_ + 3.0) * (2.0 * reach / dz_ + 3.0);
    const std::size_t hull = std::size_t(std::min(double(n), box));
    hull_cells_.reserve(hull);
    hull_under_.reserve(hull);
    hull_row_c0_.reserve(std::size_t(rows_));
    hull_row_c1_.reserve(std::size_t(rows_));
    held_.reserve(footprint + hull);
    dirty_.reserve(footprint + hull);
  }

  for (auto* v : {&before_, &after_cut_}) touch_reserved(*v);
  for (auto* v : {&marked_, &held_, &dirty_, &hull_cells_}) touch_reserved(*v);
  touch_reserved(fluxes_);
  touch_reserved(sources_);
  touch_reserved(hull_under_);

  // Every cell of a slope already steeper than the repose angle starts active.
  const float* h = grid.heights();
  for (int r = 0; r < rows_; ++r)
    for (int c = 0; c < cols_; ++c) {
      const std::uint32_t a = std::uint32_t(std::int64_t(r) * cols_ + c);
      for (const Neighbour& nb : kNeighbours) {
        const int c2 = c + nb.dc, r2 = r + nb.dr;
        if (c2 < 0 || r2 < 0 || c2 >= cols_ || r2 >= rows_) continue;
        const std::uint32_t b = std::uint32_t(std::int64_t(r2) * cols_ + c2);
        if (double(h[a]) - double(h[b]) > limit_[nb.kind] + tolerance_m_) {
          activate(a);
          activate(b);
        }
      }
    }
}

void SoilFlow::set_obstacles(std::span<const SoilObstacle> obstacles) noexcept {
  // Bodies at rest give the same list step after step: nothing to do.
  const auto clipped = [this](const SoilObstacle& o) {
    return SoilObstacle{{std::max(o.cells.c0, 0), std::max(o.cells.r0, 0), std::min(o.cells.c1, cols_),
                         std::min(o.cells.r1, rows_)},
                        o.bottom_m};
  };
  {
    std::size_t k = 0;
    bool same = true;
    for (const SoilObstacle& given : obstacles) {
      if (k == std::size_t(kMaxObstacles)) break;
      const SoilObstacle o = clipped(given);
      if (o.cells.empty() || !(o.bottom_m == o.bottom_m)) continue;
      same = same && k < obstacles_.size() && obstacles_[k].cells == o.cells && obstacles_[k].bottom_m == o.bottom_m;
      ++k;
    }
    if (same && k == obstacles_.size()) return;
  }
  // Clear the old ones; the soil banked against them may now slide on, so
  // the cells along their sides (inside and out) are examined again.
  for (const SoilObstacle& o : obstacles_) {
    for (int r = o.cells.r0; r < o.cells.r1; ++r)
      std::fill_n(obstacle_.begin() + std::int64_t(r) * cols_ + o.cells.c0, o.cells.c1 - o.cells.c0, 0);
    const int c0 = std::max(o.cells.c0 - 1, 0), c1 = std::min(o.cells.c1, cols_ - 1);
    const int r0 = std::max(o.cells.r0 - 1, 0), r1 = std::min(o.cells.r1, rows_ - 1);
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c)
        if (r <= r0 + 1 || r >= r1 - 1 || c <= c0 + 1 || c >= c1 - 1)
          activate(std::uint32_t(std::int64_t(r) * cols_ + c));
  }
  obstacles_.clear();
  for (const SoilObstacle& given : obstacles) {
    if (int(obstacles_.size()) == kMaxObstacles) break;
    const SoilObstacle o = clipped(given);
    if (o.cells.empty() || !(o.bottom_m == o.bottom_m)) continue;  // off the grid, or NaN
    obstacles_.push_back(o);
    const auto id = std::uint8_t(obstacles_.size());
    for (int r = o.cells.r0; r < o.cells.r1; ++r)
      for (int c = o.cells.c0; c < o.cells.c1; ++c) {
        std::uint8_t& mark = obstacle_[std::size_t(std::int64_t(r) * cols_ + c)];
        // Where two overlap, the lower underside counts.
        if (mark == 0 || o.bottom_m < obstacles_[mark - 1u].bottom_m) mark = id;
      }
  }
}

inline void SoilFlow::lowered(std::uint32_t cell, const float* h) {
  // Only the pairs of this cell changed: a neighbour that now stands too
  // steep above it is examined in the next pass (the same test as a pass's).
  activate(cell);
  const float hc = h[cell];
  if (!(queued_[cell] & kEdge)) {
    // All 8 tested without a branch each; the steep ones then activated.
    unsigned steep = 0;
#if defined(__SSE2__)
    // As examine's: four pairs to an instruction, the same bits.
    __m128 hb0, hb1;
    load_neighbours(h + cell, offset_[2], hb0, hb1);
    const __m128 vc = _mm_set1_ps(hc);
    const __m128 e0 = _mm_sub_ps(_mm_sub_ps(hb0, vc), _mm_loadu_ps(limit8_));
    const __m128 e1 = _mm_sub_ps(_mm_sub_ps(hb1, vc), _mm_loadu_ps(limit8_ + 4));
    steep = above_mask(e0, e1, tolerance_m_);
#else
    for (int k = 0; k < 8; ++k)
      steep |= unsigned(h[std::int64_t(cell) + offset_[k]] - hc - limit8_[k] > tolerance_m_) << k;
#endif
    for (; steep != 0; steep &= steep - 1)
      activate(std::uint32_t(std::int64_t(cell) + offset_[std::countr_zero(steep)]));
    return;
  }
  const int c = col_of(cell), r = row_of(cell);
  for (int k = 0; k < 8; ++k) {
    const int cb = c + kNeighbours[k].dc, rb = r + kNeighbours[k].dr;
    if (cb < 0 || rb < 0 || cb >= cols_ || rb >= rows_) continue;
    const std::uint32_t b = std::uint32_t(std::int64_t(cell) + offset_[k]);
    if (h[b] - hc - limit8_[k] > tolerance_m_) activate(b);
  }
}

void SoilFlow::wake_held(const Segment* edge) {
  // Soil the blade held up is examined again once the blade is elsewhere
  // (or gone); while it stands still, nothing it holds can move.
  // "Elsewhere": an end moved by a quarter of a cell or more (what the
  // blade holds changes only where its line crosses a cell's centre or
  // edge; a step of 0.6 mm on 1 cm cells would wake them every step).
  if (held_.empty()) return;
  if (edge != nullptr) {
    const double q2 = kHeldMoveCells * kHeldMoveCells * std::min(dx_ * dx_, dz_ * dz_);
    const auto near = [&](const Vec3& p, const Vec3& q) {
      const Vec3 d = p - q;
      return d.x * d.x + d.y * d.y + d.z * d.z < q2;
    };
    if (near(edge->a, held_edge_.a) && near(edge->b, held_edge_.b) &&
        (hull_cells_.empty() || (near(hull_heel_.a, held_heel_.a) && near(hull_heel_.b, held_heel_.b))))
      return;
  }
  for (std::uint32_t cell : held_) {
    clear_flag(cell, kHeld);
    activate(cell);
  }
  held_.clear();
}

void SoilFlow::wake(const Rect& rect) {
  if (rect.empty()) return;
  const int c0 = std::max(rect.c0 - 1, 0), c1 = std::min(rect.c1 + 1, cols_);
  const int r0 = std::max(rect.r0 - 1, 0), r1 = std::min(rect.r1 + 1, rows_);
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c) {
      const auto cell = std::uint32_t(std::int64_t(r) * cols_ + c);
      dirty(cell);
      activate(cell);
    }
}

void SoilFlow::before_cut(const HeightGrid& grid, const Segment& from, const Segment& to) {
  // The bounding rectangle of the four endpoints, plus a cell.
  const GridSpec& spec = grid.spec();
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  for (const Vec3& p : {from.a, from.b, to.a, to.b}) {
    const double u = to_cells(p.x, spec.origin_m.x, dx_), v = to_cells(p.z, spec.origin_m.z, dz_);
    u0 = std::min(u0, u);
    u1 = std::max(u1, u);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  Rect r;
  r.c0 = int(std::clamp(std::floor(u0) - 1.0, 0.0, double(cols_)));
  r.c1 = int(std::clamp(std::floor(u1) + 2.0, 0.0, double(cols_)));
  r.r0 = int(std::clamp(std::floor(v0) - 1.0, 0.0, double(rows_)));
  r.r1 = int(std::clamp(std::floor(v1) + 2.0, 0.0, double(rows_)));
  before_rect_ = r;
  before_.resize(std::size_t(r.area()));
  after_cut_.resize(std::size_t(r.area()));
  const float* h = grid.heights();
  std::size_t k = 0;
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = r.c0; c < r.c1; ++c) before_[k++] = h[std::int64_t(row) * cols_ + c];
}

void SoilFlow::mark_blade(const HeightGrid& grid, const Segment& edge) {
  // The cells whose centres lie within kBladeRadiusCells of the edge in
  // plan: row by row, the columns where the row's line can meet that
  // capsule (the part of the edge within the radius of the row, widened by
  // the radius), each tested exactly.
  const GridSpec& spec = grid.spec();
  const double radius = kBladeRadiusCells * std::max(dx_, dz_);
  const Vec3 d = edge.b - edge.a;
  const double plan_length = std::hypot(d.x, d.z);
  blade_ = {edge.a.x, edge.a.z, d.x, d.z, edge.a.y - spec.origin_m.y, d.y, plan_length > 0.0};
  if (!blade_.present) return;
  const double len2 = plan_length * plan_length;
  blade_.len2 = d.x * d.x + d.z * d.z;
  blade_.len = std::sqrt(blade_.len2);
  const double half_num = 0.5 * (std::abs(d.z) * dx_ + std::abs(d.x) * dz_);
  blade_.half = half_num / blade_.len;
  // Where |nb| is certainly below or above half_num (relative rounding of
  // the quotients ~1e-16; the margin 1e-12), |nb| / len < half is decided
  // without dividing (blade_blocks).
  blade_.half_lo = half_num * (1.0 - 1e-12);
  blade_.half_hi = half_num * (1.0 + 1e-12);
  const double zlo = std::min(edge.a.z, edge.b.z) - radius, zhi = std::max(edge.a.z, edge.b.z) + radius;
  const int r0 = std::max(0, int(std::floor(to_cells(zlo, spec.origin_m.z, dz_) - 0.5)));
  const int r1 = std::min(rows_ - 1, int(std::ceil(to_cells(zhi, spec.origin_m.z, dz_) - 0.5)));
  for (int r = r0; r <= r1; ++r) {
    const double z = spec.origin_m.z + (r + 0.5) * dz_;
    // The edge's parameters where it is within the radius of this row's z.
    double s0 = 0.0, s1 = 1.0;
    if (std::abs(d.z) > 1e-12) {
      const double sa = (z - radius - edge.a.z) / d.z, sb = (z + radius - edge.a.z) / d.z;
      s0 = std::max(0.0, std::min(sa, sb));
      s1 = std::min(1.0, std::max(sa, sb));
      if (s0 > s1) continue;
    } else if (std::abs(z - edge.a.z) > radius) {
      continue;
    }
    const double xa = edge.a.x + d.x * s0, xb = edge.a.x + d.x * s1;
    const int c0 = std::max(0, int(std::floor(to_cells(std::min(xa, xb) - radius, spec.origin_m.x, dx_) - 0.5)));
    const int c1 = std::min(cols_ - 1, int(std::ceil(to_cells(std::max(xa, xb) + radius, spec.origin_m.x, dx_) - 0.5)));
    for (int c = c0; c <= c1; ++c) {
      const std::uint32_t i = std::uint32_t(std::int64_t(r) * cols_ + c);
      const double x = spec.origin_m.x + (c + 0.5) * dx_;
      const double s = std::clamp(((x - edge.a.x) * d.x + (z - edge.a.z) * d.z) / len2, 0.0, 1.0);
      const double ex = x - (edge.a.x + d.x * s), ez = z - (edge.a.z + d.z * s);
      if (ex * ex + ez * ez > radius * radius) continue;
      set_flag(i, kNearBlade);
      marked_.push_back(i);
    }
  }
}

void SoilFlow::clear_blade() {
  for (std::uint32_t i : marked_) clear_flag(i, kNearBlade);
  marked_.clear();
  blade_.present = false;
}

inline bool SoilFlow::blade_blocks(int hc, int hr, int lc, int lr, float top_m) const {
  // Cell centres relative to the edge's first end, in plan.
  const double xa = (double(hc) + 0.5) * dx_ + origin_x_ - blade_.ax;
  const double za = (double(hr) + 0.5) * dz_ + origin_z_ - blade_.az;
  const double xb = (double(lc) + 0.5) * dx_ + origin_x_ - blade_.ax;
  const double zb = (double(lr) + 0.5) * dz_ + origin_z_ - blade_.az;
  const double len2 = blade_.len2;
  const double len = blade_.len;
  // Signed distances to the edge's line (their numerators na, nb over
  // len), and the half width of a cell across it (blade_.half): a cell
  // closer than that is inside the blade (the edge passes through it).
  // Most pairs lie on one side, outside the blade, and are told so without
  // a division: the sign of na / len is na's, and a |n| away from the half
  // width's numerator by more than rounding (blade_.half_lo, half_hi)
  // compares as |n| / len would.
  const double na = blade_.dx * za - blade_.dz * xa;
  const double nb = blade_.dx * zb - blade_.dz * xb;
  const double half = blade_.half;
  const auto inside = [&](double n) {
    const double q = std::abs(n);
    return q < blade_.half_lo ? true : q > blade_.half_hi ? false : std::abs(n / len) < half;
  };
  const bool low_inside = inside(nb);
  // A source inside the blade is on neither side: its soil stands against
  // the blade (the cut takes it when the edge passes its centre), and the
  // side a centre on or next to the edge's line falls on is a matter of
  // rounding (a centre exactly on the line gave na = 0, counted on the
  // negative side, and a pile stood against the blade collapsed into the
  // cut behind it). It sheds nothing across or along the blade.
  const bool high_inside = inside(na);
  if (!low_inside && !high_inside && (na > 0.0) == (nb > 0.0)) return false;  // one side, outside the blade
  // Where along the edge: at the low cell when it is inside the blade, at
  // the source when it is, else where the pair's segment meets the line.
  double px = xb, pz = zb;
  if (!low_inside) {
    if (high_inside) {
      px = xa;
      pz = za;
    } else {
      const double da = na / len, db = nb / len;
      const double w = da / (da - db);
      px = xa + (xb - xa) * w;
      pz = za + (zb - za) * w;
    }
  }
  const double t = (px * blade_.dx + pz * blade_.dz) / len2;
  if (t < 0.0 || t > 1.0) return false;  // around an end of the blade
  // The blade stops soil whose surface there is above its edge.
  return double(top_m) > blade_.ay + blade_.dy * t;
}

void SoilFlow::beside_body(const HeightGrid& grid, double x, double z, double tx, double tz,
                           std::int64_t& first, std::int64_t& second) const {
  // Walk from the point (x, z) both ways along the unit (tx, tz), a cell at
  // a time, to the first sample on each side that no body stands over.
  const GridSpec& spec = grid.spec();
  const double step = std::min(dx_ / std::max(std::abs(tx), 1e-9), dz_ / std::max(std::abs(tz), 1e-9));
  const auto at = [&](double along) -> std::int64_t {
    const double u = to_cells(x + tx * along, spec.origin_m.x, dx_);
    const double v = to_cells(z + tz * along, spec.origin_m.z, dz_);
    if (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_) return -1;
    return std::int64_t(std::floor(v)) * cols_ + std::int64_t(std::floor(u));
  };
  for (int j = 1; j <= kMaxPushCells; ++j) {
    const std::int64_t a = at(j * step), b = at(-j * step);
    const bool fa = a >= 0 && obstacle_[a] == 0, fb = b >= 0 && obstacle_[b] == 0;
    if (!fa && !fb) {
      if (a < 0 && b < 0) return;  // off the grid both ways: stays where it was
      continue;
    }
    first = fa ? a : b;
    second = fa && fb ? b : -1;
    return;
  }
}

void SoilFlow::displace(HeightGrid& grid, const Segment& from, const Segment& to,
                        double bucket_room_m3, SoilStepResult& out) {
  const GridSpec& spec = grid.spec();
  const double cell = std::max(dx_, dz_);
  // The edge's horizontal normal, turned to the side it moved to.
  const Vec3 e = to.b - to.a;
  double nx = -e.z, nz = e.x;
  const double plan_length = std::hypot(nx, nz);
  const double mx = 0.5 * ((to.a.x + to.b.x) - (from.a.x + from.b.x));
  const double mz = 0.5 * ((to.a.z + to.b.z) - (from.a.z + from.b.z));
  if (plan_length > 1e-12) {
    nx /= plan_length;
    nz /= plan_length;
  } else {
    // An edge seen end-on: push along the motion, or along +X at rest.
    const double m = std::hypot(mx, mz);
    nx = m > 1e-12 ? mx / m : 1.0;
    nz = m > 1e-12 ? mz / m : 0.0;
  }
  // One cell along the push (the longer cell side across it, so the roll
  // never skips a cell).
  const double step = std::min(dx_ / std::max(std::abs(nx), 1e-9), dz_ / std::max(std::abs(nz), 1e-9));
  // The repose drop over one such cell.
  const double limit_step = std::tan(params_.material.repose_deg * std::numbers::pi / 180.0) * step *
                            std::hypot(nx, nz);
  const double along_motion = nx * mx + nz * mz;
  const bool moving = std::abs(along_motion) > 0.01 * cell;
  if (moving && along_motion < 0.0) {
    nx = -nx;
    nz = -nz;
  }

  const HeightGrid::EditLayers layers = grid.edit_layers();
  const Rect& r = before_rect_;
  // What the cut took (exact in double: a difference of two floats) and
  // what the displacement put down, measured as it writes, so that the
  // rounding of the writes is given back at the end.
  double taken = 0.0, put = 0.0;
  std::int64_t last_put = -1;
  const auto write = [&](std::int64_t cell, float value) {
    dirty(std::uint32_t(cell));
    put += double(value) - double(layers.height_m[cell]);
    layers.height_m[cell] = value;
    last_put = cell;
  };
  // Whether the centre of cell (c, r) lies behind the edge (on the side it
  // came from, past the half cell its line passes through), within its
  // length: the cut behind the blade, where no displaced soil may go.
  const double edge_len2 = e.x * e.x + e.z * e.z;
  const auto behind_blade = [&](int c, int r) {
    if (!(edge_len2 > 0.0)) return false;
    const double x = spec.origin_m.x + (c + 0.5) * dx_ - to.a.x, z = spec.origin_m.z + (r + 0.5) * dz_ - to.a.z;
    const double t = (x * e.x + z * e.z) / edge_len2;
    return t >= 0.0 && t <= 1.0 && x * nx + z * nz < -0.5 * cell;
  };
  // Puts `add` metres on `cell`, never above the ceiling (a Bullet
  // heightfield's upper bound would clamp, and so delete, soil above it):
  // what would rise above it goes to the nearest cells around with room,
  // ring by ring, none under a body nor behind the blade.
  const auto put_down = [&](std::int64_t cell, float add) {
    float v = std::max(0.0f, layers.height_m[cell] + add);
    float over = v > ceiling_m_ ? v - ceiling_m_ : 0.0f;
    write(cell, v - over);
    const int c0 = col_of(std::uint32_t(cell)), r0 = row_of(std::uint32_t(cell));
    out.changed.include(c0, r0);
    activate(std::uint32_t(cell));
    for (int ring = 1; ring <= kMaxPushCells && over > 0.0f; ++ring)
      for (int dr = -ring; dr <= ring && over > 0.0f; ++dr)
        for (int dc = -ring; dc <= ring && over > 0.0f; dc += (dr == -ring || dr == ring) ? 1 : 2 * ring) {
          const int c = c0 + dc, r = r0 + dr;
          if (c < 0 || r < 0 || c >= cols_ || r >= rows_) continue;
          const std::int64_t j = std::int64_t(r) * cols_ + c;
          const float room = ceiling_m_ - layers.height_m[j];
          if (obstacle_[j] != 0 || !(room > 0.0f) || behind_blade(c, r)) continue;
          const float give = std::min(over, room);
          // (h + (ceiling - h) may round an ulp above the ceiling.)
          write(j, std::min(layers.height_m[j] + give, ceiling_m_));
          over -= give;
          out.changed.include(c, r);
          activate(std::uint32_t(j));
        }
  };
  // The share of each sample's cut that goes into the bucket: all of it
  // while the bucket has room for the step's cut, else what fits.
  double keep = 0.0;
  if (bucket_room_m3 > 0.0) {
    double cut = 0.0;
    std::size_t j = 0;
    for (int row = r.r0; row < r.r1; ++row)
      for (int c = r.c0; c < r.c1; ++c, ++j) {
        const float lost = before_[j] - layers.height_m[std::int64_t(row) * cols_ + c];
        if (lost > 0.0f) cut += double(lost);
      }
    cut *= spec.cell_area_m2();
    keep = cut > 0.0 ? std::min(1.0, bucket_room_m3 / cut) : 0.0;
  }
  // The heights the cut left, before any is written: soil put down on a cut
  // sample not yet handled must not shrink what that sample's cut counts
  // (else the books give back less than the cut took, and soil is lost).
  std::size_t k = 0;
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = r.c0; c < r.c1; ++c, ++k) after_cut_[k] = layers.height_m[std::int64_t(row) * cols_ + c];
  k = 0;
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = r.c0; c < r.c1; ++c, ++k) {
      const std::int64_t i = std::int64_t(row) * cols_ + c;
      const float cut = before_[k] - after_cut_[k];
      if (!(cut > 0.0f)) continue;
      // Ground: the part of the cut below the initial surface.
      out.cut_from_ground_m3 +=
          std::max(0.0, std::min(double(before_[k]), double(layers.initial_m[i])) - double(after_cut_[k])) *
          spec.cell_area_m2();
      dirty(std::uint32_t(i));
      lowered(std::uint32_t(i), layers.height_m);  // its walls may now be too steep
      const float kept = keep >= 1.0 ? cut : float(double(cut) * keep);
      out.bucket_in_m3 += double(kept) * spec.cell_area_m2();
      const float lost = cut - kept;  // what is displaced
      if (!(lost > 0.0f)) continue;
      taken += double(before_[k]) - double(after_cut_[k]) - double(kept);
      // Straight ahead of the edge: the cell centre's distance to the edge's
      // line along the normal, plus kDepositAheadCells. At rest, away from
      // the line on the cell's own side.
      const double x = spec.origin_m.x + (c + 0.5) * dx_;
      const double z = spec.origin_m.z + (row + 0.5) * dz_;
      const double s = (x - to.a.x) * nx + (z - to.a.z) * nz;
      const double side = moving || s >= 0.0 ? 1.0 : -1.0;
      const double go = side * (kDepositAheadCells * cell) - s;
      // Beyond a wall, a target is its last cell; beyond an open edge, the
      // soil leaves the terrain.
      const auto beyond = [&](double along) {
        const double u = to_cells(x + nx * along, spec.origin_m.x, dx_);
        const double v = to_cells(z + nz * along, spec.origin_m.z, dz_);
        return u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_;
      };
      const auto cell_at = [&](double along) {
        const int tc = std::clamp(int(std::floor(to_cells(x + nx * along, spec.origin_m.x, dx_))),
                                  0, cols_ - 1);
        const int tr = std::clamp(int(std::floor(to_cells(z + nz * along, spec.origin_m.z, dz_))),
                                  0, rows_ - 1);
        return std::int64_t(tr) * cols_ + tc;
      };
      // The rest of the cut lands where an avalanche down the face ahead
      // would leave it: the cells along the push from `from` (metres along
      // the normal from this sample's centre), up to the first one above
      // it, are filled to one line falling at the repose slope, the line as
      // high as the volume `volume` (metres of height on one cell) needs.
      // Cells beyond an open edge stand for the bare ground there (height
      // 0): what fills them leaves the terrain. A wall or a body ends the
      // run. Returns what found no cell (all of it when the first cell is
      // a body's or the grid's end), for the caller to put down.
      const auto fill_ahead = [&](double from, float volume) -> float {
        std::int64_t cells[kMaxPushCells];
        double reach[kMaxPushCells];  // the line's height at the first cell that just reaches this one
        int count = 0;
        double sum = 0.0, line = 0.0;
        std::int64_t last = -1;
        for (int m = 0; m < kMaxPushCells; ++m) {
          const double along = from + side * m * step;
          const bool off = params_.edge == SoilEdge::kOpen && beyond(along);
          const std::int64_t u = off ? -1 : cell_at(along);
          if (!off && (u == last || obstacle_[u] != 0)) break;  // against the grid's edge, or a body
          const double b = (off ? 0.0 : double(layers.height_m[u])) + limit_step * m;
          if (count > 0 && !(b < line)) break;  // at or above the line: nothing reaches it
          cells[count] = u;
          reach[count] = b;
          sum += b;
          ++count;
          line = (double(volume) + sum) / count;
          if (!off) last = u;
        }
        if (count == 0) return volume;
        // A cell of the run above the final line (a hump) takes nothing:
        // without it the line comes lower, until no more drop out.
        for (int in = count;;) {
          double s_in = 0.0;
          int n_in = 0;
          for (int j = 0; j < count; ++j)
            if (reach[j] < line) s_in += reach[j], ++n_in;
          if (n_in == in || n_in == 0) break;
          in = n_in;
          line = (double(volume) + s_in) / n_in;
        }
        for (int j = 0; j < count; ++j) {
          const double add = line - reach[j];
          if (!(add > 0.0)) continue;
          if (cells[j] < 0) {
            out.left_over_edge_m3 += add * spec.cell_area_m2();
            taken -= add;
          } else {
            put_down(cells[j], float(add));
          }
        }
        return 0.0f;
      };
      // The blade pushes what stands in front of it: along the push, the
      // descending profile ahead (cells above the edge's height) moves on by
      // one cell, the cut column's height taking the first cell's place, as
      // a pile pushed by a blade does; what the shift does not account for
      // (the cut layer itself) is put down just beyond the pile's toe. On
      // flat ground nothing shifts and the cut soil is put down ahead.
      const float edge_top = after_cut_[k];  // the cut column's new height
      std::int64_t ray[kMaxPushCells];
      int length = 0;
      ray[length++] = cell_at(go);
      float previous = before_[k];
      // A bucket taking soil in does not push a pile.
      if (kept == 0.0f && layers.height_m[ray[0]] < previous && !(layers.height_m[ray[0]] < edge_top) &&
          !obstructed(std::uint32_t(ray[0]))) {
        while (length < kMaxPushCells) {
          const std::int64_t next = cell_at(go + side * length * step);
          if (next == ray[length - 1]) break;  // against the grid's edge
          const float here = layers.height_m[ray[length - 1]], ahead = layers.height_m[next];
          if (!(ahead < here) || ahead < edge_top || obstructed(std::uint32_t(next))) break;
          ray[length++] = next;
        }
        for (int j = 0; j < length; ++j) {
          const std::int64_t cell_j = ray[j];
          const float old = layers.height_m[cell_j];
          write(cell_j, previous);
          out.changed.include(col_of(std::uint32_t(cell_j)), row_of(std::uint32_t(cell_j)));
          if (previous < old)
            lowered(std::uint32_t(cell_j), layers.height_m);
          else
            activate(std::uint32_t(cell_j));
          previous = old;
        }
      } else {
        length = 0;  // nothing to push: the cut soil goes to the first cell ahead
        previous = layers.height_m[ray[0]];
      }
      // What is left: the lost height less what the shift raised (which
      // telescopes to the cut column's old height less the toe's old
      // height). It extends the pile beyond its toe at the repose slope,
      // cell by cell along the push; the rest of it stays on the last cell.
      const float raised = length > 0 ? before_[k] - previous : 0.0f;
      float rest = lost - raised;
      out.displaced_volume_m3 += double(lost) * spec.cell_area_m2();
      if (rest > 0.0f) rest = fill_ahead(go, rest);
      std::int64_t t = length > 0 ? ray[length - 1] : ray[0];
      float level = length > 0 ? layers.height_m[t] : before_[k];
      // The last cell reached that is not under a rigid body (the cut
      // column itself when the body stands right ahead).
      std::int64_t free = length > 0 ? t : i;
      for (int m = length > 0 ? length : 0; m < kMaxPushCells && rest > 0.0f; ++m) {
        if (params_.edge == SoilEdge::kOpen && beyond(go + side * m * step)) {
          // Pushed off the terrain: it is gone, and counted.
          out.left_over_edge_m3 += double(rest) * spec.cell_area_m2();
          taken -= double(rest);
          rest = 0.0f;
          break;
        }
        const std::int64_t u = cell_at(go + side * m * step);
        if (u == t && m > 0) break;  // against the grid's edge
        t = u;
        if (obstacle_[u] != 0) break;  // never into, under or through a body
        const float room = level - float(limit_step) - layers.height_m[u];
        if (!(room > 0.0f)) {
          if (m > 0 || length > 0) break;
          continue;
        }
        free = u;
        const float add = std::min(rest, room);
        write(u, layers.height_m[u] + add);
        rest -= add;
        level = layers.height_m[u];
        out.changed.include(col_of(std::uint32_t(u)), row_of(std::uint32_t(u)));
        activate(std::uint32_t(u));
      }
      // What did not fit (or, by rounding, came out negative) is settled on
      // the last cell reached, keeping the volume.
      // Against a body with no free cell between it and the blade (the
      // blade at or under it), it goes round the body: to the nearest cells
      // beside it along the edge, half to each side when both are as near
      // (so a mirrored scene gives the mirrored result).
      std::int64_t t2 = -1;
      if (obstacle_[t] != 0 && rest > 0.0f) {
        t = free;
        if (free == i) beside_body(grid, x + nx * go, z + nz * go, -nz, nx, t, t2);
      }
      const float half = t2 >= 0 ? 0.5f * rest : 0.0f;
      for (const auto& [target, share] : {std::pair{t, rest - half}, std::pair{t2, half}}) {
        if (target < 0 || share == 0.0f) continue;
        put_down(target, share);
      }
    }
  // Give back the rounding of the writes on the last cell written.
  if (last_put >= 0 && put != taken) {
    give_back(layers.height_m[last_put], taken - put);
  }
}

std::int64_t SoilFlow::examine(std::uint32_t a, const float* h) {
  // Cell a, if it stands steeper than the repose angle toward some
  // neighbours, lets the soil above the repose line slide down its fall
  // lines (fall_lines): its fluxes, from the heights frozen at the pass's
  // start, are appended to the pass's list.
  // One byte holds the cell's flags (border, near the blade, ...).
  const std::uint8_t flags = queued_[a];
  const float ha = h[a];
  const float tol = tolerance_m_;
  float excess[8];
  // Bit k: neighbour k is lower by more than its limit and the tolerance;
  // bit 8 + k: neighbour k lies beyond the grid's edge. The pairs are
  // tested without a branch each (which of them is steep changes from
  // cell to cell, so a branch per pair is mispredicted often).
  unsigned steep = 0, outside = 0;
  if (!(flags & kEdge)) {
    // Inside the grid: all 8 neighbours exist.
#if defined(__SSE2__)
    // Four pairs to an instruction, in kNeighbours' order, with the same
    // operations as the scalar form below (the same bits).
    __m128 hb0, hb1;
    load_neighbours(h + a, offset_[2], hb0, hb1);
    const __m128 va = _mm_set1_ps(ha);
    const __m128 e0 = _mm_sub_ps(_mm_sub_ps(va, hb0), _mm_loadu_ps(limit8_));
    const __m128 e1 = _mm_sub_ps(_mm_sub_ps(va, hb1), _mm_loadu_ps(limit8_ + 4));
    _mm_storeu_ps(excess, e0);
    _mm_storeu_ps(excess + 4, e1);
    steep = above_mask(e0, e1, tol);
#else
    for (int k = 0; k < 8; ++k) {
      excess[k] = ha - h[std::int64_t(a) + offset_[k]] - limit8_[k];
      steep |= unsigned(excess[k] > tol) << k;
    }
#endif
  } else {
    const int ca = col_of(a), ra = row_of(a);
    for (int k = 0; k < 8; ++k) {
      const int cb = ca + kNeighbours[k].dc, rb = ra + kNeighbours[k].dr;
      if (cb < 0 || rb < 0 || cb >= cols_ || rb >= rows_) {
        // Beyond an open edge lies bare ground (height 0) that takes what
        // slides onto it; a wall takes nothing.
        outside |= 1u << k;
        excess[k] = params_.edge == SoilEdge::kOpen ? ha - limit8_[k] : 0.0f;
      } else {
        excess[k] = ha - h[std::int64_t(a) + offset_[k]] - limit8_[k];
      }
      steep |= unsigned(excess[k] > tol) << k;
    }
  }
  if (steep == 0) return 0;  // most examined cells cannot move
  const bool blade = blade_.present && (flags & kNearBlade);
  // The cell's column and row, for the blade's test only.
  const int ca = blade ? col_of(a) : 0, ra = blade ? row_of(a) : 0;
  const bool obstacles = !obstacles_.empty();
  const bool hull = !hull_cells_.empty();
  int dirs[8];
  int n = 0;
  for (unsigned bits = steep; bits != 0; bits &= bits - 1) {
    const int k = std::countr_zero(bits);
    if (!(outside & (1u << k))) {
      const std::uint32_t b = std::uint32_t(std::int64_t(a) + offset_[k]);
      if (blade || obstacles || hull) {
        const std::uint8_t fb = queued_[b];
        // The blade is a wall between the cells on its two sides, and soil
        // does not flow into the cells it passes through. What it holds up
        // is examined again once it has moved.
        if (blade && (fb & kNearBlade) &&
            blade_blocks(ca, ra, ca + kNeighbours[k].dc, ra + kNeighbours[k].dr, ha)) {
          hold(a);
          continue;
        }
        // Nor into a rigid body's footprint (soil under it may slide out).
        if (obstacles && obstructed(b)) continue;
        // Nor into a cell under the bucket's hull from higher than the hull's
        // underside there (a flux never raises a cell above its source).
        if ((fb & kHull) && ha > hull_under(b)) {
          hold(a);
          continue;
        }
      }
    }
    dirs[n++] = k | int((outside >> k) & 1u) << 8;
  }
  if (n == 0) return 0;
  return fall_lines(a, ha, h, dirs, n);
}

std::int64_t SoilFlow::fall_lines(std::uint32_t a, float ha, const float* h, const int* dirs, int n) {
  // The soil above the repose line through the source slides down its fall
  // lines and comes to rest where the line meets the ground: along each
  // steep direction k the cells from the neighbour on, as long as they
  // stand below the source by more than the repose drop back to it (their
  // reach, height + drop, under the source's height), up to the first that
  // does not, the grid's edge, the blade, the hull's underside or a body.
  // The source comes down to s and every cell of those runs whose reach is
  // below s comes up to s less its drop:
  // one line at the repose slope from the source down each fall line (the
  // 1-D water fill of fill_ahead, from a point). s balances the volume:
  // s = (h_a + sum of the reaches taken) / (1 + their count). The drop per
  // cell is the pair's limit less the tolerance, so the lines it leaves
  // stand a tolerance gentler than the threshold that moves them.
  struct Line {
    std::uint32_t cell[kMaxFallCells];
    float reach[kMaxFallCells];
    int length = 0;
  };
  // A reach marked as left out (a hump).
  constexpr float kHump = std::numeric_limits<float>::infinity();
  Line lines[8];
  const float tol = tolerance_m_;
  // A fall line from a cell far from the blade may still run into it.
  const bool blade = blade_.present;
  double total = ha;
  int count = 1;
  bool steep_below = false;
  for (int j = 0; j < n; ++j) {
    const int k = dirs[j] & 0xff;
    const float drop = limit8_[k] - 0.25f * tol;
    Line& line = lines[j];
    if (dirs[j] >> 8) {
      // Beyond an open edge: bare ground at height 0 that takes what comes.
      line.cell[0] = kOutside;
      line.reach[0] = drop;
      line.length = 1;
    } else {
      std::uint32_t cur = std::uint32_t(std::int64_t(a) + offset_[k]);
      for (int m = 1;; ++m) {
        const float reach = h[cur] + drop * float(m);
        if (!(reach < ha)) break;
        line.cell[line.length] = cur;
        line.reach[line.length++] = reach;
        if (line.length == kMaxFallCells || (queued_[cur] & kEdge)) break;
        const std::uint32_t next = std::uint32_t(std::int64_t(cur) + offset_[k]);
        const std::uint8_t fn = queued_[next];
        // A cell itself steeper than the threshold toward the next sheds
        // in this pass too: the line ends on it (beyond it the frozen
        // heights are not where the soil will rest, and two sources filling
        // the same steep slope at once would flatten it).
        if (m == 1 && h[cur] - h[next] - limit8_[k] > tol) steep_below = true;
        if (!obstacles_.empty() && obstructed(next)) break;
        if ((fn & kHull) && ha > hull_under(next)) break;
        if (blade && (queued_[cur] & kNearBlade) && (fn & kNearBlade) &&
            blade_blocks(col_of(cur), row_of(cur), col_of(next), row_of(next), ha))
          break;
        cur = next;
      }
    }
    fall_visits_ += line.length;
    for (int m = 0; m < line.length; ++m) total += line.reach[m];
    count += line.length;
  }
  // A cell whose reach is at or above s stands above the final line (a
  // hump) and takes nothing; without it s comes lower, until no more drop
  // out (as in fill_ahead). s only comes down as cells drop out, and at
  // least one cell stays (every reach is below h_a). Two or three rounds
  // settle nearly every source; after 1 + kMaxExtraRounds a cell still at
  // or above s gets nothing (its share would not be positive) and the
  // source keeps that soil for a later pass.
  double s = total / count;
  for (int round = 0; round <= kMaxExtraRounds; ++round) {
    bool changed = false;
    const bool first = round == 0;
    for (int j = 0; j < n; ++j) {
      Line& line = lines[j];
      if (!first) fall_visits_ += line.length;  // a further round reads every cell again
      for (int m = 0; m < line.length; ++m)
        if (line.reach[m] < kHump && double(line.reach[m]) >= s) {
          total -= line.reach[m];
          --count;
          line.reach[m] = kHump;
          changed = true;
        }
    }
    s = total / count;
    if (!changed) break;
  }
  std::uint32_t fluxes = 0;
  for (int j = 0; j < n; ++j)
    for (int m = 0; m < lines[j].length; ++m) {
      if (!(lines[j].reach[m] < kHump)) continue;
      const float give = quantized((steep_below ? 0.5 : 1.0) * (s - double(lines[j].reach[m])));
      if (!(give > 0.0f)) continue;
      fluxes_.push_back({lines[j].cell[m], give});
      ++fluxes;
    }
  if (fluxes == 0) return 0;
  sources_.push_back({a, fluxes, 1.0f});
  return fluxes;
}

void SoilFlow::drop_blocked_fluxes(std::uint32_t a, std::size_t end, const float* h) {
  const std::uint8_t fa = queued_[a];
  const bool blade = blade_.present && (fa & kNearBlade);
  if (!blade && hull_cells_.empty() && obstacles_.empty()) return;
  const int ca = col_of(a), ra = row_of(a);
  for (std::size_t j = applied_; j < end; ++j) {
    Flux& f = fluxes_[j];
    if (f.to == kOutside) continue;
    const std::uint8_t fb = queued_[f.to];
    const bool across = blade && (fb & kNearBlade) && blade_blocks(ca, ra, col_of(f.to), row_of(f.to), h[a]);
    const bool into_hull = (fb & kHull) && h[a] > hull_under(f.to);
    if (across || into_hull) hold(a);
    if (across || into_hull || (!obstacles_.empty() && obstructed(f.to))) f.excess = 0.0f;
  }
}

void SoilFlow::finish_pass(HeightGrid& grid, SoilStepResult& out) {
  // The fluxes cancel exactly; the float heights do not quite: what the
  // pass gained or lost by rounding was measured in double and is given
  // back to the highest cell it changed, so no bias builds up over a run.
  // When cells tie for highest (a mirror image would pick another of
  // them), they share it, so a mirrored terrain gives it to the mirrored
  // cells; more than kMaxTiedHighest, it waits for a later pass.
  const HeightGrid::EditLayers layers = grid.edit_layers();
  // The highest sources once the pass is applied (their final heights do
  // not depend on the order they were applied in).
  for (std::size_t j = 0; j < applied_sources_; ++j) {
    const std::uint32_t a = sources_[j].cell;
    const float now = layers.height_m[a];
    if (now > pass_highest_h_) {
      pass_highest_h_ = now;
      pass_highest_[0] = a;
      pass_highest_count_ = 1;
    } else if (now == pass_highest_h_ && a != pass_highest_[0]) {
      if (pass_highest_count_ < kMaxTiedHighest) pass_highest_[pass_highest_count_] = a;
      ++pass_highest_count_;
    }
  }
  if (pass_gained_m_ != 0.0 && pass_highest_h_ > 0.0f && pass_highest_count_ <= kMaxTiedHighest) {
    // Shared equally by the cells tied for highest (the same set, mirrored,
    // in a mirror image), in whole quanta (what is left under one waits for
    // a later pass), never below the floor nor above the ceiling.
    const double share = -pass_gained_m_ / pass_highest_count_;
    for (int j = 0; j < pass_highest_count_; ++j) {
      float& hh = layers.height_m[pass_highest_[j]];
      const float old = hh;
      hh = std::min(quantized(std::max(0.0, double(hh) + share)), std::max(ceiling_m_, old));
      pass_gained_m_ += double(hh) - double(old);
    }
  }
  pass_highest_h_ = -1.0f;
  pass_highest_count_ = 0;
  for (std::uint32_t cell : dirty_) clear_flag(cell, kDirty);
  dirty_.clear();
  active_.clear();
  fluxes_.clear();
  sources_.clear();
  examined_ = applied_ = applied_sources_ = 0;
  ++out.passes;
}

void SoilFlow::run_passes(HeightGrid& grid, SoilStepResult& out) {
  const HeightGrid::EditLayers layers = grid.edit_layers();
  float* h = layers.height_m;
  const double cell_area = dx_ * dz_;
  // The work of the step, in neighbour visits: 8 per cell examined, 1 per
  // flux applied and 8 per source's fall test (its neighbours read again),
  // so that a step's work tracks its time whether it examines or applies.
  // It never passes the cap: a pass too large for what is left is carried on
  // in the next step, where it stopped (its heights stay those it started
  // from until all its cells are examined), so a collapse of any size is
  // spread over ticks of bounded work.
  const std::int64_t cap = params_.max_pair_checks_per_step;
  std::int64_t work = 0;
  // A pass left over from an earlier step was examined against the blade,
  // hull and bodies of that step.
  pass_spans_steps_ = !active_.empty();
  // The rectangle of the cells that shed soil; the cells they shed to are
  // their neighbours, so the changed rectangle is that plus a cell.
  int changed_c0 = cols_, changed_c1 = -1, changed_r0 = rows_, changed_r1 = -1;
  bool out_of_work = false;
  while (!out_of_work) {
    if (active_.empty()) {
      // The next pass starts from the cells queued for it.
      if (next_.empty()) break;
      active_.swap(next_);
      for (std::uint32_t a : active_) clear_flag(a, kQueued);
      pass_spans_steps_ = false;
    }
    if (examined_ < active_.size()) {
      // 8 visits per cell examined and one per cell of the fall lines it
      // walks (fall_visits_), cell by cell while the cap leaves room for one
      // more examination and a full fall line each way.
      std::int64_t moved = 0;
      // A pass whose fluxes would outgrow their list is split: the cells
      // not examined yet go on to the next pass (a pass that large is a
      // collapse of most of a reserved active set, or a grid's worth).
      while (examined_ < active_.size() && work + kMostExamineVisits <= cap &&
             fluxes_.size() + 8 * kMaxFallCells <= fluxes_.capacity()) {
        fall_visits_ = 0;
        moved += examine(active_[examined_++], h);
        work += 8 + fall_visits_;
      }
      out.moved_pairs += moved;
      if (examined_ < active_.size()) {
        if (work + kMostExamineVisits <= cap) {
          // Split: the rest of the list is examined in the next pass.
          for (std::size_t j = examined_; j < active_.size(); ++j) activate(active_[j]);
          active_.truncate(examined_);
        } else {
          out.reached_cap = true;
          break;  // the rest in the next step
        }
      }
    }
    while (applied_sources_ < sources_.size()) {
      // A source's fluxes are contiguous: applied together, then its fall
      // tested against its neighbours.
      const std::uint32_t a = sources_[applied_sources_].cell;
      const std::size_t end = applied_ + sources_[applied_sources_].fluxes;
      const float share = sources_[applied_sources_].share;
      // No cell is dirty while dirty_ is empty (most passes: the cut marks
      // cells only in a pass it interrupts), and then nothing is read for it.
      const bool any_dirty = !dirty_.empty();
      const bool stale = any_dirty && (queued_[a] & kDirty) != 0;
      const std::int64_t cost = std::int64_t(end - applied_) + (stale ? 0 : kFallTestVisits);
      if (work + cost > cap) {
        out_of_work = true;
        out.reached_cap = true;
        break;
      }
      work += cost;
      if (stale) {
        applied_ = end;  // changed since it was examined: examined again
        ++applied_sources_;
        continue;
      }
      // A pass examined in an earlier step met the blade, the hull and the
      // bodies where they were then; they have moved since. A flux that
      // would now cross the blade, climb into the hull or enter a body is
      // dropped (its source is held, and examined again).
      if (pass_spans_steps_) drop_blocked_fluxes(a, end, h);
      // Multiples of the quantum, summed exactly in double: the order of the
      // source's fall lines (which a mirror image permutes) does not matter.
      double total_d = 0.0;
      for (std::size_t j = applied_; j < end; ++j)
        if (!any_dirty || fluxes_[j].to == kOutside || !(queued_[fluxes_[j].to] & kDirty))
          total_d += double(share * fluxes_[j].excess);
      const float total = float(total_d);
      // What the cell can give: never below the floor (the blade may have
      // cut it since the pass was examined).
      const float before = h[a];
      const float scale = total > before ? before / total : 1.0f;
      const float now = total > before ? 0.0f : quantized(double(before) - total_d);
      h[a] = now;
      // The grid's change in double: float rounding is what it gains.
      double gained = double(now) - double(before);
      const int ca = col_of(a), ra = row_of(a);
      changed_c0 = std::min(changed_c0, ca);
      changed_c1 = std::max(changed_c1, ca);
      changed_r0 = std::min(changed_r0, ra);
      changed_r1 = std::max(changed_r1, ra);
      for (; applied_ < end; ++applied_) {
        const Flux& f = fluxes_[applied_];
        if (any_dirty && f.to != kOutside && (queued_[f.to] & kDirty)) continue;
        const float give = (share * f.excess) * scale;
        if (f.to == kOutside) {
          out.left_over_edge_m3 += double(give) * cell_area;
          gained += double(give);  // what left is no rounding gain
          continue;
        }
        // Multiples of the quantum added to a multiple of it: exact, so a
        // cell's sum does not depend on the order its sources were met in.
        const float old = h[f.to], raised = quantized(double(old) + double(give));
        h[f.to] = raised;
        gained += double(raised) - double(old);
        activate(f.to);
        const int ct = col_of(f.to), rt = row_of(f.to);
        changed_c0 = std::min(changed_c0, ct);
        changed_c1 = std::max(changed_c1, ct);
        changed_r0 = std::min(changed_r0, rt);
        changed_r1 = std::max(changed_r1, rt);
      }
      pass_gained_m_ += gained;
      ++applied_sources_;
      lowered(a, h);
    }
    if (applied_sources_ < sources_.size()) break;
    finish_pass(grid, out);
  }
  out.pair_checks += work;
  if (changed_c1 >= 0) {
    out.changed.include(std::max(changed_c0 - 1, 0), std::max(changed_r0 - 1, 0));
    out.changed.include(std::min(changed_c1 + 1, cols_ - 1), std::min(changed_r1 + 1, rows_ - 1));
  }
  out.backlog_cells = active_cells();
}

SoilStepResult SoilFlow::after_cut(HeightGrid& grid, const Segment& from, const Segment& to,
                                   const Quat& orientation) {
  SoilStepResult out;
  double room = 0.0, holds = 0.0;
  if (blade_spec_.bucket.enabled()) {
    holds = bucket_retained_m3(blade_spec_, orientation, params_.material.repose_deg);
    // It takes soil in only while its lip leads: moving toward its opening
    // (the blade frame's -Z, in plan).
    const Vec3 opening = rotate(orientation, {0.0, 0.0, -1.0});
    const double mx = 0.5 * ((to.a.x + to.b.x) - (from.a.x + from.b.x));
    const double mz = 0.5 * ((to.a.z + to.b.z) - (from.a.z + from.b.z));
    if (mx * opening.x + mz * opening.z > 0.0) room = std::max(0.0, holds - load_m3_);
  }
  displace(grid, from, to, room, out);
  load_m3_ += out.bucket_in_m3;
  if (load_m3_ > holds && blade_spec_.bucket.enabled()) {
    pour(grid, to, load_m3_ - holds, out);
    load_m3_ = holds;
  }
  out.bucket_load_m3 = load_m3_;
  if (blade_spec_.bucket.enabled()) {
    // The hull at its new pose: what stands inside it is shouldered out.
    mark_hull(grid, to, orientation);
    shoulder(grid, out);
  }
  wake_held(&to);
  // The blade's wall matters only to a pass: marked only when one runs.
  if (pending()) {
    mark_blade(grid, to);
    if (held_.empty()) held_edge_ = to, held_heel_ = hull_heel_;  // where the blade and hull hold what the passes find held
    run_passes(grid, out);
    clear_blade();
  }
  out.backlog_cells = active_cells();
  return out;
}

void SoilFlow::pour(HeightGrid& grid, const Segment& lip, double volume_m3, SoilStepResult& out) {
  // Spread along the lip's plan, a point per half cell, each point's share
  // put on the cell under it (or, beyond an open edge, counted as gone).
  const GridSpec& spec = grid.spec();
  const double span = std::hypot(lip.b.x - lip.a.x, lip.b.z - lip.a.z);
  const int points = 1 + int(std::ceil(span / (0.5 * std::min(dx_, dz_))));
  const double share_m = volume_m3 / points / spec.cell_area_m2();
  const HeightGrid::EditLayers layers = grid.edit_layers();
  double put = 0.0, wanted = 0.0;
  std::int64_t last = -1;
  for (int p = 0; p < points; ++p) {
    const double t = points > 1 ? double(p) / (points - 1) : 0.5;
    const double u = to_cells(lip.a.x + t * (lip.b.x - lip.a.x), spec.origin_m.x, dx_);
    const double v = to_cells(lip.a.z + t * (lip.b.z - lip.a.z), spec.origin_m.z, dz_);
    if (params_.edge == SoilEdge::kOpen && (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_)) {
      out.left_over_edge_m3 += share_m * spec.cell_area_m2();
      continue;
    }
    const int c = std::clamp(int(std::floor(u)), 0, cols_ - 1), r = std::clamp(int(std::floor(v)), 0, rows_ - 1);
    const std::int64_t i = std::int64_t(r) * cols_ + c;
    dirty(std::uint32_t(i));
    const float now = float(double(layers.height_m[i]) + share_m);
    put += double(now) - double(layers.height_m[i]);
    wanted += share_m;
    layers.height_m[i] = now;
    last = i;
    out.changed.include(c, r);
    activate(std::uint32_t(i));
  }
  // Give back the rounding of the writes on the last cell written.
  if (last >= 0 && put != wanted) {
    give_back(layers.height_m[last], wanted - put);
  }
  out.poured_m3 += volume_m3;
}

void SoilFlow::clear_hull() {
  for (std::uint32_t cell : hull_cells_) clear_flag(cell, kHull);
  hull_cells_.clear();
  hull_under_.clear();
  hull_rect_ = {};
}

void SoilFlow::mark_hull(const HeightGrid& grid, const Segment& lip, const Quat& orientation) {
  // The floor plate runs from the lip back depth_m along the blade frame's
  // +Z, the back plate from the heel up height_m along its +Y. A cell is
  // under the hull where its centre lies in the plan of either plate; the
  // underside there is the lower plate's height over the centre.
  clear_hull();
  const GridSpec& spec = grid.spec();
  const Vec3 back = rotate(orientation, {0.0, 0.0, blade_spec_.bucket.depth_m});
  const Vec3 up = rotate(orientation, {0.0, blade_spec_.bucket.height_m, 0.0});
  const Vec3 along = lip.b - lip.a;
  hull_heel_ = {lip.a + back, lip.b + back};
  const Vec3 corners[6] = {lip.a, lip.b, hull_heel_.a, hull_heel_.b, hull_heel_.a + up, hull_heel_.b + up};
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  hull_cx_ = hull_cz_ = 0.0;
  for (const Vec3& p : corners) {
    const double u = to_cells(p.x, spec.origin_m.x, dx_), v = to_cells(p.z, spec.origin_m.z, dz_);
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    hull_cx_ += p.x / 6.0;
    hull_cz_ += p.z / 6.0;
  }
  // The cells whose centres can lie inside: centres at (c + 0.5) in cells.
  Rect r;
  r.c0 = int(std::clamp(std::ceil(u0 - 0.5), 0.0, double(cols_)));
  r.c1 = int(std::clamp(std::floor(u1 - 0.5) + 1.0, 0.0, double(cols_)));
  r.r0 = int(std::clamp(std::ceil(v0 - 0.5), 0.0, double(rows_)));
  r.r1 = int(std::clamp(std::floor(v1 - 0.5) + 1.0, 0.0, double(rows_)));
  if (r.empty()) return;
  hull_rect_ = r;
  hull_under_.assign(std::size_t(r.area()), std::numeric_limits<float>::infinity());
  hull_row_c0_.assign(std::size_t(r.r1 - r.r0), r.c1);
  hull_row_c1_.assign(std::size_t(r.r1 - r.r0), r.c0);
  struct Plate {
    Vec3 origin, s, t;
  };
  const Plate plates[2] = {{lip.a, along, back}, {hull_heel_.a, along, up}};
  const double ground = spec.origin_m.y;
  for (const Plate& p : plates) {
    // Plan coordinates (s, t) of a point: solve the 2x2 system of the
    // plate's two edges in plan; a plate seen edge-on covers no centre.
    const double det = p.s.x * p.t.z - p.s.z * p.t.x;
    const double area = std::hypot(p.s.x, p.s.z) * std::hypot(p.t.x, p.t.z);
    if (!(std::abs(det) > 1e-9 * area) || area == 0.0) continue;
    // A centre on the lip's line (to a millionth of a cell) is the lip's to
    // cut: the step's cut may just have missed it by rounding.
    const double t_min = &p == &plates[0] ? 1e-6 * std::min(dx_, dz_) * std::hypot(p.s.x, p.s.z) / std::abs(det) : 0.0;
    // Along a row s and t are linear in the column: the columns where both
    // can lie in range, widened by a cell for rounding; the test itself is
    // made on every one of them, so the cells marked are those a test of
    // the whole rectangle would mark, at a cost that follows the plate.
    const double inv_det = 1.0 / det;
    const double ds = dx_ * p.t.z * inv_det, dt = -dx_ * p.s.z * inv_det;
    const double slope_floor = 1e-9 * (1.0 + std::abs(ds) + std::abs(dt));
    const double oy = p.origin.y - ground;
    for (int row = r.r0; row < r.r1; ++row) {
      const double pz = spec.origin_m.z + (row + 0.5) * dz_ - p.origin.z;
      const double s_z = pz * p.t.x, t_z = p.s.x * pz;
      const double px0 = spec.origin_m.x + (r.c0 + 0.5) * dx_ - p.origin.x;
      const double s0 = (px0 * p.t.z - s_z) * inv_det, t0 = (t_z - p.s.z * px0) * inv_det;
      double k0 = 0.0, k1 = double(r.c1 - r.c0 - 1);
      const auto narrow = [&](double v0, double dv, double lo, double hi) {
        if (std::abs(dv) <= slope_floor) return;  // (nearly) constant along the row: test them all
        double a = (lo - v0) / dv, b = (hi - v0) / dv;
        if (a > b) std::swap(a, b);
        k0 = std::max(k0, std::floor(a) - 1.0);
        k1 = std::min(k1, std::ceil(b) + 1.0);
      };
      narrow(s0, ds, 0.0, 1.0);
      narrow(t0, dt, t_min, 1.0);
      if (k0 > k1) continue;
      const int c_first = r.c0 + int(k0), c_end = r.c0 + int(k1) + 1;
      float* under_row = &hull_under_[hull_slot(r.c0, row)];
      int first = c_end, end = c_first;
      for (int c = c_first; c < c_end; ++c) {
        const double px = spec.origin_m.x + (c + 0.5) * dx_ - p.origin.x;
        const double s = (px * p.t.z - s_z) * inv_det, t = (t_z - p.s.z * px) * inv_det;
        if (s < 0.0 || s > 1.0 || t < t_min || t > 1.0) continue;
        const float y = float(oy + s * p.s.y + t * p.t.y);
        float& under = under_row[c - r.c0];
        under = std::min(under, y);
        first = std::min(first, c);
        end = c + 1;
      }
      int& row_first = hull_row_c0_[std::size_t(row - r.r0)];
      int& row_end = hull_row_c1_[std::size_t(row - r.r0)];
      row_first = std::min(row_first, first);
      row_end = std::max(row_end, end);
    }
  }
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = hull_row_c0_[std::size_t(row - r.r0)]; c < hull_row_c1_[std::size_t(row - r.r0)]; ++c)
      if (hull_under_[hull_slot(c, row)] < std::numeric_limits<float>::infinity()) {
        const auto cell = std::uint32_t(std::int64_t(row) * cols_ + c);
        set_flag(cell, kHull);
        hull_cells_.push_back(cell);
      }
}

void SoilFlow::shoulder(HeightGrid& grid, SoilStepResult& out) {
  // Each cell under the hull with soil above the hull's underside gives
  // that excess to the first cell outside the footprint (and not under a
  // rigid body), walking away from the hull's plan centre; beyond a wall it
  // walks the other way, beyond an open edge it leaves (counted). A cell
  // too close to the ceiling takes what fits, the rest goes on outward.
  const GridSpec& spec = grid.spec();
  const HeightGrid::EditLayers layers = grid.edit_layers();
  float* h = layers.height_m;
  double taken = 0.0, put = 0.0;
  std::int64_t last_put = -1;
  // The hull's cells in the order of hull_cells_ (row by row), with their
  // columns and rows at hand.
  const Rect& hr = hull_rect_;
  for (int row = hr.r0; row < hr.r1; ++row) {
    for (int c = hull_row_c0_[std::size_t(row - hr.r0)]; c < hull_row_c1_[std::size_t(row - hr.r0)]; ++c) {
      const float covered = hull_under_[hull_slot(c, row)];
      if (!(covered < std::numeric_limits<float>::infinity())) continue;
      const auto cell = std::uint32_t(std::int64_t(row) * cols_ + c);
      const float under = std::max(0.0f, covered);
      const float now = h[cell];
      // Float rounding of the cut (which leaves the lip's height) is no excess.
      if (!(now - under > 4.0f * std::numeric_limits<float>::epsilon() * std::max(now, 1.0f))) continue;
      const double x = spec.origin_m.x + (c + 0.5) * dx_, z = spec.origin_m.z + (row + 0.5) * dz_;
      double nx = x - hull_cx_, nz = z - hull_cz_;
      const double len = std::hypot(nx, nz);
      nx = len > 1e-12 ? nx / len : 1.0;
      nz = len > 1e-12 ? nz / len : 0.0;
      const double step = std::min(dx_ / std::max(std::abs(nx), 1e-9), dz_ / std::max(std::abs(nz), 1e-9));
      float rest = now - under;
      bool moved = false;
      for (const double side : {1.0, -1.0}) {
        for (int m = 1; m <= kMaxPushCells && rest > 0.0f; ++m) {
          const double u = to_cells(x + side * nx * m * step, spec.origin_m.x, dx_);
          const double v = to_cells(z + side * nz * m * step, spec.origin_m.z, dz_);
          if (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_) {
            if (params_.edge == SoilEdge::kOpen) {
              out.left_over_edge_m3 += double(rest) * spec.cell_area_m2();
              taken -= double(rest);
              rest = 0.0f;
              moved = true;
            }
            break;
          }
          const std::int64_t t = std::int64_t(std::floor(v)) * cols_ + std::int64_t(std::floor(u));
          if ((queued_[t] & kHull) || obstacle_[t] != 0) continue;
          const float room = ceiling_m_ - h[t];
          if (!(room > 0.0f)) continue;
          const float add = std::min(rest, room);
          dirty(std::uint32_t(t));
          const float raised = h[t] + add;
          put += double(raised) - double(h[t]);
          h[t] = raised;
          last_put = t;
          rest -= add;
          moved = true;
          out.changed.include(col_of(std::uint32_t(t)), row_of(std::uint32_t(t)));
          activate(std::uint32_t(t));
        }
        if (rest <= 0.0f) break;
      }
      if (!moved) continue;  // nowhere to go: it stays (a hull filling the grid)
      // What found no room stays in the cell.
      dirty(cell);
      h[cell] = under + rest;
      taken += double(now) - double(h[cell]);
      out.changed.include(c, row);
      lowered(cell, h);
    }
  }
  // Give back the rounding of the writes on the last cell written.
  if (last_put >= 0 && put != taken) give_back(h[last_put], taken - put);
  out.shouldered_m3 += taken * spec.cell_area_m2();
}

SoilStepResult SoilFlow::relax(HeightGrid& grid) {
  SoilStepResult out;
  wake_held(nullptr);  // no blade now
  clear_hull();        // nor a bucket
  run_passes(grid, out);
  return out;
}

}  // namespace terracut
