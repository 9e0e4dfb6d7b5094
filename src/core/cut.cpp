// Swept cutting, visiting only the samples under the swept region: the two
// triangles of a sweep are rasterised row by row together (sample rows for
// the surface representation, cell rows for columns), so the cost follows
// the swept area.
//
// - Each triangle is walked by its edges with its vertices sorted by z (the
//   classic scanline set-up: a long edge A-C and a short chain A-B-C), so a
//   row costs a few multiply-adds and no polygon clipping.
// - Surface: along a row the height is linear; with the plane's slope when
//   the triangle is well inclined (no division per row).
// - Columns: a cell's height is the lowest point of the row's polygon over
//   it, found from the polygon's vertices and its crossings with the cells'
//   side lines, each crossing computed once for the two cells it bounds.
// - A row's samples are lowered as one span (SSE2, four at a time), with the
//   same values HeightGrid::lower would write.
// - Surface, a translation's band of rows near the columns' direction (a
//   sample or none a row): walked along the columns instead, each column's
//   run of rows found once; the same result, bit for bit.
// - Spans are prefetched on big terrains, and so is the strip the blade will
//   sweep next if it keeps its motion.
#include "terracut/core/cut.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "geometry.hpp"

namespace terracut {

namespace {

using detail::GridFrame;

constexpr double kInf = std::numeric_limits<double>::infinity();

/// std::min and std::max by value (the same result, the first argument on a
/// tie): references to locals keep GCC's operands on the stack in hot loops.
inline double min_value(double a, double b) { return b < a ? b : a; }
inline double max_value(double a, double b) { return a < b ? b : a; }

/// What lowering one row (or part of it) changed: the removed heights summed
/// (metres), the first and last sample changed (-1 when none), the samples
/// examined.
struct RowChange {
  double removed_m = 0.0;
  int first = -1;
  int last = -1;
  int visited = 0;
};

/// HeightGrid::lower for sample c of the row starting at index row, with
/// target t (metres above the ground), booked in change (first and last
/// sample, removed height; not visited, which the caller counts).
inline void lower_one(const HeightGrid::EditLayers& layers, std::int64_t row, int c, float t, RowChange& change) {
  float h = t > 0.0f ? t : 0.0f;
  float old = layers.height_m[row + c];
  if (!(h < old)) return;
  layers.height_m[row + c] = h;
  change.removed_m += double(old - h);
  if (change.first < 0) change.first = c;
  change.last = c;
}

/// lower_one for sample c of row (the row's first sample) written without
/// an if on the data, for the columns band: its rows hold two to four
/// cells, lowered or not in a pattern that shifts from row to row, and there
/// a mispredicted branch waited for the sample's load from memory before
/// the walk went on. (Where nearly every sample is lowered, as in the surface
/// walks, the branch predicts well and this form measured no faster.) The
/// source has no branch, but GCC 12 at -O3 still compiles the float
/// comparisons into conditional jumps (`g++ -O3 -S` of this function in a
/// loop, 2026-12-05: three data-dependent jumps, one cmov); a form with
/// SSE minss / maxss and no jump measured 2 to 5 us slower in the
/// benchmark at yaw 30 to 82 (docs/performance.md, "Every direction,
/// seventh look"). The minimum keeps the old bits where
/// the target is not lower (stored back unchanged), and a drop of +0
/// leaves the sum's bits as they are: the values of lower_one, bit for bit.
inline void lower_one_unbranched(float* row, int c, float t, RowChange& change) {
  const float h = t > 0.0f ? t : 0.0f;
  const float old = row[c];
  const float now = h < old ? h : old;
  row[c] = now;
  change.removed_m += double(old - now);
  const bool lowered = now < old;
  change.first = lowered && change.first < 0 ? c : change.first;
  change.last = lowered ? c : change.last;
}

/// What a cut has changed so far: height removed (sum over samples, metres),
/// the rectangle of changed samples (as plain inclusive bounds), samples
/// examined. Kept as a local of each rasteriser so that it stays in registers.
struct CutBook {
  double removed_m = 0.0;
  int c0 = INT_MAX, r0 = INT_MAX, c1 = INT_MIN, r1 = INT_MIN;
  std::int64_t visited = 0;

  void add(int r, const RowChange& change) {
    visited += change.visited;
    if (change.last < 0) return;
    removed_m += change.removed_m;
    c0 = std::min(c0, change.first);
    c1 = std::max(c1, change.last);
    r0 = std::min(r0, r);
    r1 = std::max(r1, r);
  }
  void add(const CutBook& other) {
    visited += other.visited;
    removed_m += other.removed_m;
    c0 = std::min(c0, other.c0);
    c1 = std::max(c1, other.c1);
    r0 = std::min(r0, other.r0);
    r1 = std::max(r1, other.r1);
  }
  Rect changed() const { return c1 < c0 ? Rect{} : Rect{c0, r0, c1 + 1, r1 + 1}; }
};

/// A vertex of a swept triangle, its height relative to the ground level.
struct Point {
  double x, y, z;
};

/// Sorts three points by z (ascending).
inline void sort_by_z(Point& a, Point& b, Point& c) {
  if (b.z < a.z) std::swap(a, b);
  if (c.z < b.z) std::swap(b, c);
  if (b.z < a.z) std::swap(a, b);
}

/// What lowering a span of samples did: the removed heights summed (metres)
/// and the first and last sample changed (-1 when none), from the span's start.
struct SpanResult {
  double removed_m = 0.0;
  int first = -1;
  int last = -1;
};

/// HeightGrid::lower applied to the n samples from height[0] with targets
/// t[0..n): each sample goes down to max(t, 0) when that is lower. Same
/// values, bit for bit, as calling HeightGrid::lower per sample (only the
/// order of the removed-height sum differs), four samples at a time with
/// SSE2 where available.
SpanResult lower_span(float* height, const float* t, int n) {
  SpanResult out;
  int k = 0;
#if defined(__SSE2__) && defined(__GNUC__)
  const __m128 zero = _mm_setzero_ps();
  __m128d sum_lo = _mm_setzero_pd(), sum_hi = _mm_setzero_pd();
  for (; k + 4 <= n; k += 4) {
    __m128 target = _mm_max_ps(_mm_loadu_ps(t + k), zero);  // NaN -> 0, as lower()
    __m128 old = _mm_loadu_ps(height + k);
    __m128 lowered = _mm_min_ps(target, old);                 // target < old ? target : old
    __m128 changed = _mm_cmplt_ps(lowered, old);
    int mask = _mm_movemask_ps(changed);
    if (mask == 0) continue;
    _mm_storeu_ps(height + k, lowered);  // unchanged lanes keep their bits (min returns old)
    __m128 drop = _mm_sub_ps(old, lowered);  // 0 where unchanged
    sum_lo = _mm_add_pd(sum_lo, _mm_cvtps_pd(drop));
    sum_hi = _mm_add_pd(sum_hi, _mm_cvtps_pd(_mm_movehl_ps(drop, drop)));
    if (out.first < 0) out.first = k + __builtin_ctz(unsigned(mask));
    out.last = k + 31 - __builtin_clz(unsigned(mask));
  }
  __m128d sum = _mm_add_pd(sum_lo, sum_hi);
  out.removed_m = _mm_cvtsd_f64(sum) + _mm_cvtsd_f64(_mm_unpackhi_pd(sum, sum));
#endif
  for (; k < n; ++k) {
    float h = t[k] > 0.0f ? t[k] : 0.0f;
    float old = height[k];
    if (!(h < old)) continue;
    height[k] = h;
    out.removed_m += double(old - h);
    if (out.first < 0) out.first = k;
    out.last = k;
  }
  return out;
}

/// Samples per batch of targets.
constexpr int kBatch = 256;
/// Samples of a row whose cache lines are requested before it is lowered.
constexpr int kPrimeSamples = 1024;
/// Spans up to this many samples are lowered by a plain inline loop.
constexpr int kSmallSpan = 8;

/// Lowers samples c in [c_lo, c_hi] of row r to the targets that
/// fill(c, n, t) writes for samples c .. c + n - 1 (metres above the ground,
/// float; +inf leaves a sample as it is), kBatch at a time, and returns the
/// change. The height layer is written in place through
/// HeightGrid::edit_layers (grid.hpp), exactly as HeightGrid::lower would
/// write it.
template <class Fill>
inline RowChange lower_row(HeightGrid& grid, int r, int c_lo, int c_hi, Fill&& fill) {
  const std::int64_t row = grid.index(0, r);
  const HeightGrid::EditLayers layers = grid.edit_layers();
  float* height = layers.height_m + row;
  RowChange change;
  change.visited = c_hi - c_lo + 1;
  if (change.visited <= kSmallSpan) {
    // A few samples (a thin sliver crossing the row, as when the blade
    // moves obliquely): inline, without the batch machinery.
    float t[kSmallSpan];
    fill(c_lo, change.visited, t);
    for (int k = 0; k < change.visited; ++k) lower_one(layers, row, c_lo + k, t[k], change);
    return change;
  }
  // Ask for the row's first cache lines at once, so that on a terrain
  // larger than the caches their misses overlap instead of queueing one
  // after the other (the hardware prefetcher takes long rows from there).
  for (int c = c_lo; c <= std::min(c_hi, c_lo + kPrimeSamples - 1); c += 16) detail::prefetch<false, 2>(height + c);
  float t[kBatch];
  for (int c = c_lo; c <= c_hi; c += kBatch) {
    int n = std::min(kBatch, c_hi - c + 1);
    fill(c, n, t);
    SpanResult span = lower_span(height + c, t, n);
    if (span.last >= 0) {
      change.removed_m += span.removed_m;
      if (change.first < 0) change.first = c + span.first;
      change.last = c + span.last;
    }
  }
  return change;
}

/// lower_row with the targets already computed: targets[k] for sample c_lo + k.
inline RowChange lower_row_targets(HeightGrid& grid, int r, int c_lo, int c_hi, const float* targets) {
  const std::int64_t row = grid.index(0, r) + c_lo;
  float* height = grid.edit_layers().height_m + row;
  int n = c_hi - c_lo + 1;
  for (int k = 0; k < std::min(n, kPrimeSamples); k += 16) detail::prefetch<false, 2>(height + k);
  SpanResult span = lower_span(height, targets, n);
  RowChange change;
  change.visited = n;
  if (span.last >= 0) {
    change.removed_m = span.removed_m;
    change.first = c_lo + span.first;
    change.last = c_lo + span.last;
  }
  return change;
}

/// Targets of a row along which y is linear: y(c) = base + c * step.
inline auto linear_targets(double base, double step) {
  return [base, step](int c0, int n, float* t) {
    for (int k = 0; k < n; ++k) t[k] = float(base + double(c0 + k) * step);
  };
}

/// floor and ceil of x clamped to [lo, hi] (grid index ranges; also keeps
/// far-away coordinates inside int range).
inline int floor_clamped(double x, int lo, int hi) {
  if (!(x > lo)) return lo;
  if (!(x < hi)) return hi;
  int i = int(x);  // truncation, then the fix for negatives
  return i - (double(i) > x);
}
inline int ceil_clamped(double x, int lo, int hi) {
  if (!(x > lo)) return lo;
  if (!(x < hi)) return hi;
  int i = int(x);
  return i + (double(i) < x);
}

/// The triangle's edges, walked by z: the long edge A-C and the short chain
/// A-B-C (vertices sorted by z, heights relative to the ground). Meaningful
/// when c.z > a.z.
struct Scanline {
  Point a, b, c;
  double ac_kx, ac_ky, ab_kx, ab_ky, bc_kx, bc_ky;  // dx/dz and dy/dz per edge

  Scanline(const Point& p0, const Point& p1, const Point& p2) : a(p0), b(p1), c(p2) {
    sort_by_z(a, b, c);
    // Divisions, not products with a reciprocal: an edge whose dx/dz is
    // representable (along a row or column, diagonal, 2:1, ...) then puts
    // its crossings exactly, so a sample or cell corner exactly on it is
    // found on it (the boundary is closed, docs/model.md).
    auto slope = [](double d, double dz) { return dz > 0.0 ? d / dz : 0.0; };
    ac_kx = slope(c.x - a.x, c.z - a.z);
    ac_ky = slope(c.y - a.y, c.z - a.z);
    ab_kx = slope(b.x - a.x, b.z - a.z);
    ab_ky = slope(b.y - a.y, b.z - a.z);
    bc_kx = slope(c.x - b.x, c.z - b.z);
    bc_ky = slope(c.y - b.y, c.z - b.z);
  }

  /// The point of the long edge at z (a.z <= z <= c.z).
  Point long_at(double z) const { return {a.x + (z - a.z) * ac_kx, a.y + (z - a.z) * ac_ky, z}; }
  /// The point of the short chain at z (a.z <= z <= c.z).
  Point short_at(double z) const {
    if (z < b.z) return {a.x + (z - a.z) * ab_kx, a.y + (z - a.z) * ab_ky, z};
    if (c.z > b.z) return {b.x + (z - b.z) * bc_kx, b.y + (z - b.z) * bc_ky, z};
    return b;
  }
};

/// One sample row's part of a triangle (surface representation): samples
/// [c_lo, c_hi] go down to base + c * step (metres above the ground).
struct Section {
  int c_lo, c_hi;
  double base, step;
};

/// A swept triangle set up for the surface rasteriser. Each sample row's
/// section of the triangle (its intersection with the plane z = row's z) runs
/// from the long edge to the short chain, and y is linear along it: with the
/// slope of the triangle's plane along x when the triangle is well inclined
/// (no division per row), else from the section's two ends. A section that
/// is a point or vertical (a triangle standing on edge) counts with its
/// lowest point. Triangles with all three vertices at one z ("flat") are
/// handled apart (cut_flat_points).
struct SurfaceTriangle {
  Point q[3];
  Scanline tri;
  bool flat = false;
  bool planar = false;
  double slope_x = 0.0;
  bool long_on_left = false;
  int r_lo = 0, r_hi = -1;  // sample rows the triangle spans

  SurfaceTriangle(const Vec3 (&p)[3], const GridFrame& f)
      : q{{p[0].x, p[0].y - f.ground_y, p[0].z},
          {p[1].x, p[1].y - f.ground_y, p[1].z},
          {p[2].x, p[2].y - f.ground_y, p[2].z}},
        tri(q[0], q[1], q[2]) {
    double zmin = tri.a.z, zmax = tri.c.z;
    r_lo = ceil_clamped((zmin - f.z0) * f.inv_cz - 0.5, 0, f.rows);
    r_hi = floor_clamped((zmax - f.z0) * f.inv_cz - 0.5, -1, f.rows - 1);
    flat = !(zmax > zmin);
    if (flat) return;
    // The plane's slope along x, when the footprint is far from degenerate
    // (its area not lost to cancellation).
    double ex1 = tri.b.x - tri.a.x, ez1 = tri.b.z - tri.a.z, ey1 = tri.b.y - tri.a.y;
    double ex2 = tri.c.x - tri.a.x, ez2 = tri.c.z - tri.a.z, ey2 = tri.c.y - tri.a.y;
    double det = ex1 * ez2 - ex2 * ez1;
    planar = std::abs(det) > 1e-6 * (std::abs(ex1 * ez2) + std::abs(ex2 * ez1));
    slope_x = planar ? (ey1 * ez2 - ey2 * ez1) / det : 0.0;
    // The long edge lies on one side of the short chain for the whole
    // height: B's side of the line A-C.
    long_on_left = ex1 > ex2 * (ez1 / ez2);
  }

  /// The section in row r (rd = r); false when the row misses the triangle.
  bool section(const GridFrame& f, double rd, Section& s) const {
    double zr = f.z0 + (rd + 0.5) * f.cz;
    if (zr < tri.a.z || zr > tri.c.z) return false;  // rounding at the first and last row
    Point e_long = tri.long_at(zr), e_short = tri.short_at(zr);
    const Point& e1 = long_on_left ? e_long : e_short;
    const Point& e2 = long_on_left ? e_short : e_long;
    s.c_lo = ceil_clamped((std::min(e1.x, e2.x) - f.x0) * f.inv_cx - 0.5, 0, f.cols);
    s.c_hi = floor_clamped((std::max(e1.x, e2.x) - f.x0) * f.inv_cx - 0.5, -1, f.cols - 1);
    if (s.c_lo > s.c_hi) return false;
    double span = e2.x - e1.x;
    double slope;
    if (planar) {
      slope = slope_x;
    } else if (span > 1e-12 * f.cx || span < -1e-12 * f.cx) {
      slope = (e2.y - e1.y) / span;
    } else {
      s.base = std::min(e1.y, e2.y);
      s.step = 0.0;
      return true;
    }
    // y at sample c's centre, x0 + (c + 0.5) cx, as base + c * step.
    s.base = e1.y + (f.x0 + 0.5 * f.cx - e1.x) * slope;
    s.step = f.cx * slope;
    return true;
  }
};

/// A flat triangle (all three vertices on the plane z = zmax, as when a
/// blade along X slides along its own line): it cuts only when that plane is
/// a sample row's, along the triangle's extent in x, down to its lowest
/// point over each sample. The triangle is then a vertical figure whose
/// lowest points are on its edges, so a sample's target is the lowest of the
/// edges over it (their x ranges together cover the extent; one pass).
void cut_flat_points(HeightGrid& grid, const GridFrame& f, const SurfaceTriangle& t, CutBook& book) {
  const Point* q = t.q;
  for (int r = t.r_lo; r <= t.r_hi; ++r) {
    if (f.z0 + (r + 0.5) * f.cz != q[0].z) continue;
    Section edges[3];  // each edge's samples and its height over them
    int n = 0, c_lo = INT_MAX, c_hi = INT_MIN;
    for (int k = 0; k < 3; ++k) {
      const Point& a = q[k].x <= q[(k + 1) % 3].x ? q[k] : q[(k + 1) % 3];
      const Point& b = q[k].x <= q[(k + 1) % 3].x ? q[(k + 1) % 3] : q[k];
      Section& e = edges[n];
      e.c_lo = ceil_clamped((a.x - f.x0) * f.inv_cx - 0.5, 0, f.cols);
      e.c_hi = floor_clamped((b.x - f.x0) * f.inv_cx - 0.5, -1, f.cols - 1);
      if (e.c_lo > e.c_hi) continue;
      double span = b.x - a.x;
      if (!(span > 1e-12 * f.cx)) {
        e.base = std::min(a.y, b.y);
        e.step = 0.0;
      } else {
        double slope = (b.y - a.y) / span;
        e.base = a.y + (f.x0 + 0.5 * f.cx - a.x) * slope;
        e.step = f.cx * slope;
      }
      c_lo = std::min(c_lo, e.c_lo);
      c_hi = std::max(c_hi, e.c_hi);
      ++n;
    }
    if (n == 0) continue;
    book.add(r, lower_row(grid, r, c_lo, c_hi, [&edges, n](int c0, int count, float* target) {
      for (int k = 0; k < count; ++k) target[k] = float(kInf);
      for (int j = 0; j < n; ++j) {
        const Section& e = edges[j];
        int k0 = std::max(e.c_lo - c0, 0), k1 = std::min(e.c_hi - c0, count - 1);
        for (int k = k0; k <= k1; ++k) target[k] = std::min(target[k], float(e.base + double(c0 + k) * e.step));
      }
    }));
  }
}

/// Sections further apart than this many samples are lowered separately
/// rather than as one span.
constexpr int kMaxGap = 64;

/// Surface representation: lowers every sample point under the swept region
/// (both triangles) to the region's height there. The two triangles are
/// walked row by row together: in a row their sections usually meet at the
/// shared edge, and are lowered as one span (one pass over the row's memory,
/// one set-up); where they overlap (on the shared edge) the lower counts.
void cut_sweep_points(HeightGrid& grid, const GridFrame& f, const Vec3 (&tris)[2][3], CutBook& book) {
  const SurfaceTriangle t0(tris[0], f), t1(tris[1], f);
  const SurfaceTriangle* walk[2];
  int n_walk = 0;
  for (const SurfaceTriangle* t : {&t0, &t1}) {
    if (t->r_lo > t->r_hi) continue;
    if (t->flat) {
      cut_flat_points(grid, f, *t, book);
    } else {
      walk[n_walk++] = t;
    }
  }
  if (n_walk == 0) return;
  CutBook rows;  // a local, so that its fields stay in registers
  int r_lo = walk[0]->r_lo, r_hi = walk[0]->r_hi;
  for (int k = 1; k < n_walk; ++k) {
    r_lo = std::min(r_lo, walk[k]->r_lo);
    r_hi = std::max(r_hi, walk[k]->r_hi);
  }
  double rd = r_lo;
  for (int r = r_lo; r <= r_hi; ++r, rd += 1.0) {
    Section s[2];
    int n = 0;
    for (int k = 0; k < n_walk; ++k) {
      if (r >= walk[k]->r_lo && r <= walk[k]->r_hi && walk[k]->section(f, rd, s[n])) ++n;
    }
    if (n == 0) continue;
    if (n == 2 && s[1].c_lo < s[0].c_lo) std::swap(s[0], s[1]);
    if (n == 1 || s[1].c_lo - s[0].c_hi - 1 > kMaxGap) {
      for (int k = 0; k < n; ++k) {
        rows.add(r, lower_row(grid, r, s[k].c_lo, s[k].c_hi, linear_targets(s[k].base, s[k].step)));
      }
      continue;
    }
    const Section a = s[0], b = s[1];
    rows.add(r, lower_row(grid, r, a.c_lo, std::max(a.c_hi, b.c_hi), [a, b](int c0, int count, float* t) {
      // Each section's part of the batch [c0, c0 + count), then the lower of
      // the two where they overlap (rounding to float keeps the order).
      for (int k = 0; k < count; ++k) t[k] = float(kInf);
      for (const Section& sec : {a, b}) {
        int k0 = std::max(sec.c_lo - c0, 0), k1 = std::min(sec.c_hi - c0, count - 1);
        for (int k = k0; k <= k1; ++k) t[k] = std::min(t[k], float(sec.base + double(c0 + k) * sec.step));
      }
    }));
  }
  book.add(rows);
}

/// A sweep that is a translation (the edge's vector the same at both ends,
/// to rounding) sweeps a parallelogram, one plane, the union of its two
/// triangles. When it crosses many sample rows (an edge oblique to the rows)
/// most rows hold a sample or two, and the per-row set-up of the two
/// triangles' sections, not the samples, is the cost. This walks the
/// parallelogram itself instead: each side not parallel to the rows bounds a
/// row's section on one side, as a linear function of the row index set up
/// once, so a row costs a few multiply-adds (no division, no branch on the
/// geometry), and the height is the plane's, linear in the row and column.
/// The samples are those whose centres lie in the closed parallelogram, as
/// for the two triangles; heights agree with theirs to rounding.
struct ObliqueSweep {
  /// Bounds of a row's section in column units (sample c's centre at u = c):
  /// u(rd) = u_p + (rd - rd_p) * u_k, measured from the side's first vertex
  /// so that rounding stays at the scale of the side's own extent.
  static constexpr int kBounds = 3;
  double lo_u[kBounds], lo_r[kBounds], lo_k[kBounds];
  double hi_u[kBounds], hi_r[kBounds], hi_k[kBounds];
  double base0 = 0.0, base_k = 0.0, step = 0.0;  // y = base0 + rd * base_k + c * step
  int r_lo = 0, r_hi = -1;
  /// The band of rows [band_r0, band_r1] whose bounds are each one line,
  /// lo_*[band_lo] and hi_*[band_hi] (see straight_band); empty when none.
  int band_r0 = 0, band_r1 = -1, band_lo = 0, band_hi = 0;
};

/// The value at x of the line through (at, base) with the given slope, as
/// every bound and chain of the parallelogram walks evaluates it.
inline double line_at(double base, double at, double slope, double x) { return base + (x - at) * slope; }

/// The line a among n (base[a] + (x - at[a]) * slope[a]) such that over x in
/// [x0, x1] every other line lies below max(line a, clip) (largest true;
/// else above min(line a, clip)) by more than rounding: a maximum (minimum)
/// of clip and the n lines anywhere in [x0, x1] is then that of clip and
/// line a, bit for bit. With clip -inf (+inf) that is the line that is the
/// maximum (minimum) itself; with a row's line as clip, a chain's envelope
/// clipped to the row. The gap to each line is piecewise linear with one
/// kink (where line a crosses clip), so it is checked at x0, x1 and there.
/// Lines at +-inf (padding) are never a and always lie beyond. -1 when no
/// line is such.
int dominant_line(const double* base, const double* at, const double* slope, int n, double x0, double x1,
                  bool largest, double clip) {
  for (int a = 0; a < n; ++a) {
    if (!std::isfinite(base[a])) continue;
    double points[3] = {x0, x1, x0};
    if (slope[a] != 0.0) {
      const double kink = at[a] + (clip - base[a]) / slope[a];
      if (kink > x0 && kink < x1) points[2] = kink;
    }
    bool wins = true;
    for (double x : points) {
      const double line_a = line_at(base[a], at[a], slope[a], x);
      if (!std::isfinite(line_a)) wins = false;
      const double envelope = largest ? std::max(line_a, clip) : std::min(line_a, clip);
      for (int i = 0; i < n && wins; ++i) {
        if (i == a) continue;
        const double vi = line_at(base[i], at[i], slope[i], x);
        if (!std::isfinite(vi)) {
          wins = largest ? vi < 0.0 : vi > 0.0;
          continue;
        }
        const double margin = 1e-9 * (1.0 + std::abs(line_a) + std::abs(base[a]) + std::abs((x - at[a]) * slope[a]) +
                                      std::abs(base[i]) + std::abs((x - at[i]) * slope[i]));
        wins = largest ? envelope - vi > margin : vi - envelope > margin;
      }
    }
    if (wins) return a;
  }
  return -1;
}

/// The second and third smallest of four values (a sorting network: of
/// the two pairs' minima the larger, of their maxima the smaller).
inline void middle_two(const double (&v)[4], double& second, double& third) {
  const double a = std::min(v[0], v[1]), b = std::max(v[0], v[1]);
  const double c = std::min(v[2], v[3]), d = std::max(v[2], v[3]);
  const double x = std::max(a, c), y = std::min(b, d);
  second = std::min(x, y);
  third = std::max(x, y);
}

/// The rows strictly between the parallelogram's second and third vertex
/// (in row units, vert_rd) hold no vertex, so each of their section bounds
/// is one side's line: finds those lines over rows [r0, r1] (r1 + reach the
/// last row coordinate evaluated) and sets w.band_*; the band stays empty
/// when a bound has no single line there (lines too close to call).
void straight_band(ObliqueSweep& w, const double (&vert_rd)[4], int rows, int reach) {
  double second = 0.0, third = 0.0;
  middle_two(vert_rd, second, third);
  const int r0 = floor_clamped(second, -1, rows) + 1;
  const int r1 = ceil_clamped(third, 0, rows + 1) - 1 - reach;
  w.band_r0 = 0, w.band_r1 = -1;
  if (r0 > r1) return;
  const int lo = dominant_line(w.lo_u, w.lo_r, w.lo_k, ObliqueSweep::kBounds, r0, r1 + reach, true, -kInf);
  const int hi = dominant_line(w.hi_u, w.hi_r, w.hi_k, ObliqueSweep::kBounds, r0, r1 + reach, false, kInf);
  if (lo < 0 || hi < 0) return;
  w.band_r0 = r0, w.band_r1 = r1, w.band_lo = lo, w.band_hi = hi;
}

/// Rows crossed from which a translation takes the parallelogram walk.
constexpr double kObliqueMinRows = 8.0;

/// A sweep that is a translation, as a parallelogram: its vertices (from.a,
/// from.b, to.b, to.a, heights relative to the ground) and its plane,
/// y = v[0].y + slope_x (x - v[0].x) + slope_z (z - v[0].z).
struct Parallelogram {
  Point v[4];
  bool ccw = false;  ///< counter-clockwise seen with x right and z up
  double slope_x = 0.0, slope_z = 0.0;
  double zmin = 0.0, zmax = 0.0;
};

/// The sweep as a parallelogram; false when it is not a translation crossing
/// at least kObliqueMinRows rows with a well-shaped footprint (then the
/// triangles' walk takes it).
bool translation_parallelogram(const GridFrame& f, const Segment& from, const Segment& to, Parallelogram& p) {
  Vec3 e = from.b - from.a, e_to = to.b - to.a, sh = to.a - from.a;
  double e_len = std::abs(e.x) + std::abs(e.y) + std::abs(e.z);
  Vec3 de = e_to - e;
  if (!(std::abs(de.x) + std::abs(de.y) + std::abs(de.z) <= 1e-9 * e_len)) return false;
  // The footprint (x-z) far from degenerate: the plane's slopes are well defined.
  double det = e.x * sh.z - e.z * sh.x;
  if (!(std::abs(det) > 1e-6 * (std::abs(e.x * sh.z) + std::abs(e.z * sh.x)))) return false;
  const Vec3 v[4] = {from.a, from.b, to.b, to.a};
  p.zmin = v[0].z, p.zmax = v[0].z;
  for (int k = 0; k < 4; ++k) {
    p.v[k] = {v[k].x, v[k].y - f.ground_y, v[k].z};
    p.zmin = std::min(p.zmin, v[k].z);
    p.zmax = std::max(p.zmax, v[k].z);
  }
  if (!((p.zmax - p.zmin) * f.inv_cz >= kObliqueMinRows)) return false;
  p.ccw = det > 0.0;
  // The plane spanned by the edge and the shift.
  p.slope_x = (e.y * sh.z - e.z * sh.y) / det;
  p.slope_z = (e.x * sh.y - e.y * sh.x) / det;
  return std::isfinite(p.slope_x) && std::isfinite(p.slope_z);
}

/// The parallelogram's section bounds in w (see ObliqueSweep), in grid
/// coordinates u = (x - x0) / cx - centre and rd = (z - z0) / cz - centre:
/// centre 0.5 puts sample c's centre at u = c (surface), centre 0 puts cell
/// c at [c, c + 1] (columns). False when a side is nearly along a row.
bool set_section_bounds(const GridFrame& f, const Parallelogram& p, double centre, ObliqueSweep& w) {
  // Sides going up in z bound the section from one side, sides going down
  // from the other (which is which depends on the winding); sides along a
  // row lie at the footprint's lowest or highest z and bound only the rows.
  int n_lo = 0, n_hi = 0;
  for (int k = 0; k < 4; ++k) {
    const Point& a = p.v[k];
    const Point& b = p.v[(k + 1) % 4];
    double dz = b.z - a.z;
    // A side along a row, or within rounding of one (a yaw of 90 degrees
    // leaves cos(pi/2) ~ 6e-17 in the shift), bounds only the rows.
    if (!(std::abs(dz) >= 1e-9 * f.cz)) continue;
    double u_p = (a.x - f.x0) * f.inv_cx - centre;
    double rd_p = (a.z - f.z0) * f.inv_cz - centre;
    double u_k = (b.x - a.x) / dz * f.cz * f.inv_cx;
    // Counter-clockwise, the inside is left of each side: a side going up
    // bounds x from above.
    if ((dz > 0.0) == p.ccw) {
      if (n_hi == ObliqueSweep::kBounds) return false;
      w.hi_u[n_hi] = u_p, w.hi_r[n_hi] = rd_p, w.hi_k[n_hi++] = u_k;
    } else {
      if (n_lo == ObliqueSweep::kBounds) return false;
      w.lo_u[n_lo] = u_p, w.lo_r[n_lo] = rd_p, w.lo_k[n_lo++] = u_k;
    }
  }
  if (n_lo == 0 || n_hi == 0) return false;
  for (; n_lo < ObliqueSweep::kBounds; ++n_lo) w.lo_u[n_lo] = -kInf, w.lo_r[n_lo] = 0.0, w.lo_k[n_lo] = 0.0;
  for (; n_hi < ObliqueSweep::kBounds; ++n_hi) w.hi_u[n_hi] = kInf, w.hi_r[n_hi] = 0.0, w.hi_k[n_hi] = 0.0;
  return true;
}

/// Sets up the parallelogram walk of the surface representation.
bool setup_oblique(const GridFrame& f, const Parallelogram& p, ObliqueSweep& w) {
  if (!set_section_bounds(f, p, 0.5, w)) return false;
  // The plane at sample centres: y = base0 + rd * base_k + c * step.
  double y_origin = p.v[0].y + p.slope_x * (f.x0 + 0.5 * f.cx - p.v[0].x) +
                    p.slope_z * (f.z0 + 0.5 * f.cz - p.v[0].z);
  w.base0 = y_origin;
  w.base_k = p.slope_z * f.cz;
  w.step = p.slope_x * f.cx;
  w.r_lo = ceil_clamped((p.zmin - f.z0) * f.inv_cz - 0.5, 0, f.rows);
  w.r_hi = floor_clamped((p.zmax - f.z0) * f.inv_cz - 0.5, -1, f.rows - 1);
  double vert_rd[4];
  for (int k = 0; k < 4; ++k) vert_rd[k] = (p.v[k].z - f.z0) * f.inv_cz - 0.5;
  straight_band(w, vert_rd, f.rows, 0);
  return std::isfinite(w.base0) && std::isfinite(w.base_k) && std::isfinite(w.step);
}

/// Rows of the band the column walk takes at a time: their removed heights
/// are summed per row in a buffer of this many doubles on the stack.
constexpr int kColumnWalkRows = 256;
/// The band is walked along columns when both its bounds move at most this
/// many columns a row (the sides bounding it within 11.3 degrees of the
/// columns' direction, z): a column then holds a run of five rows or more,
/// while a row holds a sample or none. Measured on the direction benchmark
/// (a 0.6-cell sliver, 4096^2): the column walk cuts in 12 to 19 us at yaw
/// 82 to 90 against 17 to 35 us by rows, the same at yaw 75 (slope 0.27),
/// and 1.7 to 2.2x slower at yaw 45 to 60, where its runs are a row long.
constexpr double kColumnWalkMaxSlope = 0.2;

/// The surface band (rows [r0, r1] of an ObliqueSweep whose section bounds
/// are each one line, lo(rd) = lo_u + (rd - lo_r) lo_k and the same for hi)
/// walked along columns instead of rows. Where the band is steep (the blade
/// near the columns' direction) a row holds one sample or none, and the row
/// walk paid a row's set-up (its bounds, two roundings, a loop of varying
/// trip count, the bookkeeping) for each; a column holds a run of rows, found
/// once, and its samples cost a multiply-add and a lowering each.
///
/// The result is the row walk's, bit for bit: the same samples (sample
/// (c, r) is in when lo(r) <= c <= hi(r), the test ceil/floor of the row
/// walk amounts to for c inside the grid, evaluated by the same expression;
/// each evaluation is monotone in r, being a chain of monotone roundings, so
/// a column's rows are an interval found by stepping from an estimate), the
/// same targets (base0 + rd base_k, plus c step, rounded to float), the same
/// heights, and the same removed sum: each row's drops are added up in
/// column order in a buffer and the rows' sums added to the book in row
/// order, as the row walk does.
void cut_band_columns(HeightGrid& grid, const GridFrame& f, const ObliqueSweep& w, double lo_u, double lo_r,
                      double lo_k, double hi_u, double hi_r, double hi_k, int r0, int r1, CutBook& rows) {
  float* const height = grid.edit_layers().height_m;
  const std::int64_t stride = f.cols;
  const double base0 = w.base0, base_k = w.base_k, step = w.step;
  auto lo_at = [=](int r) { return lo_u + (double(r) - lo_r) * lo_k; };
  auto hi_at = [=](int r) { return hi_u + (double(r) - hi_r) * hi_k; };
  // The rows of [a, b] where holds(r) when it holds on a ray of them: up
  // (for r from some row on) or down (up to some row); est is a guess of
  // the ray's first row (up) or last (down). Narrows [a, b] to the ray.
  auto narrow = [](auto&& holds, bool up, double est, int& a, int& b) {
    if (up) {
      const int lo = a, hi = b;
      int x = std::isfinite(est) ? int(std::clamp(std::ceil(est), double(lo), double(hi) + 1.0)) : lo;
      while (x - 1 >= lo && holds(x - 1)) --x;
      while (x <= hi && !holds(x)) ++x;
      a = x;
    } else {
      const int lo = a, hi = b;
      int x = std::isfinite(est) ? int(std::clamp(std::floor(est), double(lo) - 1.0, double(hi))) : hi;
      while (x + 1 <= hi && holds(x + 1)) ++x;
      while (x >= lo && !holds(x)) --x;
      b = x;
    }
  };
  double dropped[kColumnWalkRows];
  for (int ra = r0; ra <= r1; ra += kColumnWalkRows) {
    const int rb = std::min(r1, ra + kColumnWalkRows - 1);
    // The columns any row of the chunk holds: the bounds are monotone, so
    // their extremes are at the chunk's first and last rows.
    const int c_first = ceil_clamped(min_value(lo_at(ra), lo_at(rb)), 0, f.cols);
    const int c_last = floor_clamped(max_value(hi_at(ra), hi_at(rb)), -1, f.cols - 1);
    if (c_first > c_last) continue;
    std::fill(dropped, dropped + (rb - ra + 1), 0.0);
    for (int c = c_first; c <= c_last; ++c) {
      const double cd = double(c);
      int a = ra, b = rb;
      // lo(r) <= c: a ray down when lo grows with r, up when it falls.
      auto below_lo = [&](int r) { return lo_at(r) <= cd; };
      if (lo_k != 0.0) {
        narrow(below_lo, lo_k < 0.0, lo_r + (cd - lo_u) / lo_k, a, b);
      } else if (!below_lo(ra)) {
        continue;
      }
      if (a > b) continue;
      // c <= hi(r): a ray up when hi grows with r, down when it falls.
      auto above_hi = [&](int r) { return cd <= hi_at(r); };
      if (hi_k != 0.0) {
        narrow(above_hi, hi_k > 0.0, hi_r + (cd - hi_u) / hi_k, a, b);
      } else if (!above_hi(ra)) {
        continue;
      }
      if (a > b) continue;
      const double across = cd * step;
      float* p = height + std::int64_t(a) * stride + c;
      double rd = a;
      int changed_first = -1, changed_last = -1;
      for (int r = a; r <= b; ++r, rd += 1.0, p += stride) {
        const float t = float(base0 + rd * base_k + across);
        const float h = t > 0.0f ? t : 0.0f;
        const float old = *p;
        const float now = h < old ? h : old;
        *p = now;
        dropped[r - ra] += double(old - now);  // +0 where unchanged
        const bool lowered = now < old;
        changed_first = lowered && changed_first < 0 ? r : changed_first;
        changed_last = lowered ? r : changed_last;
      }
      rows.visited += b - a + 1;
      if (changed_last >= 0) {
        rows.c0 = std::min(rows.c0, c);
        rows.c1 = std::max(rows.c1, c);
        rows.r0 = std::min(rows.r0, changed_first);
        rows.r1 = std::max(rows.r1, changed_last);
      }
    }
    for (int k = 0; k <= rb - ra; ++k) rows.removed_m += dropped[k];
  }
}

/// Surface representation, a translation across many rows: lowers the
/// samples under the parallelogram, row by row from the bounds set up once.
void cut_oblique_points(HeightGrid& grid, const GridFrame& f, const ObliqueSweep& w, CutBook& book) {
  CutBook rows;  // a local, so that its fields stay in registers
  const HeightGrid::EditLayers layers = grid.edit_layers();
  const double step = w.step;
  // Row r's samples between its section bounds lo and hi (column units).
  auto cut_row = [&](int r, double rd, double lo, double hi) {
    int c_lo = ceil_clamped(lo, 0, f.cols);
    int c_hi = floor_clamped(hi, -1, f.cols - 1);
    double base = w.base0 + rd * w.base_k;
    if (c_lo > c_hi) return;
    if (c_hi - c_lo >= kSmallSpan) {
      rows.add(r, lower_row(grid, r, c_lo, c_hi, linear_targets(base, step)));
      return;
    }
    // A few samples: inline, as lower_row's small path.
    const std::int64_t row = grid.index(0, r);
    RowChange change;
    change.visited = c_hi - c_lo + 1;
    for (int c = c_lo; c <= c_hi; ++c) lower_one(layers, row, c, float(base + double(c) * step), change);
    rows.add(r, change);
  };
  // Rows with any of the sides bounding them: the lowest and highest bound.
  auto cut_rows = [&](int from, int to) {
    for (int r = from; r <= to; ++r) {
      double rd = r;
      double lo = w.lo_u[0] + (rd - w.lo_r[0]) * w.lo_k[0];
      double hi = w.hi_u[0] + (rd - w.hi_r[0]) * w.hi_k[0];
      for (int k = 1; k < ObliqueSweep::kBounds; ++k) {
        double l = w.lo_u[k] + (rd - w.lo_r[k]) * w.lo_k[k];
        double h = w.hi_u[k] + (rd - w.hi_r[k]) * w.hi_k[k];
        lo = l > lo ? l : lo;
        hi = h < hi ? h : hi;
      }
      cut_row(r, rd, lo, hi);
    }
  };
  const int band_r0 = std::max(w.band_r0, w.r_lo), band_r1 = std::min(w.band_r1, w.r_hi);
  if (band_r0 > band_r1) {
    cut_rows(w.r_lo, w.r_hi);
  } else {
    cut_rows(w.r_lo, band_r0 - 1);
    // The band: each bound one line (the others below or above it by more
    // than rounding, so the same values as the maximum and minimum above).
    const double lo_u = w.lo_u[w.band_lo], lo_r = w.lo_r[w.band_lo], lo_k = w.lo_k[w.band_lo];
    const double hi_u = w.hi_u[w.band_hi], hi_r = w.hi_r[w.band_hi], hi_k = w.hi_k[w.band_hi];
    // Steep and narrow (no row's span long enough for lower_row's batches,
    // whose removed sum is in another order): along the columns.
    const double width = max_value(hi_u + (double(band_r0) - hi_r) * hi_k - (lo_u + (double(band_r0) - lo_r) * lo_k),
                                   hi_u + (double(band_r1) - hi_r) * hi_k - (lo_u + (double(band_r1) - lo_r) * lo_k));
    if (std::abs(lo_k) <= kColumnWalkMaxSlope && std::abs(hi_k) <= kColumnWalkMaxSlope &&
        width < kSmallSpan - 1.5) {
      cut_band_columns(grid, f, w, lo_u, lo_r, lo_k, hi_u, hi_r, hi_k, band_r0, band_r1, rows);
    } else {
      for (int r = band_r0; r <= band_r1; ++r) {
        double rd = r;
        cut_row(r, rd, lo_u + (rd - lo_r) * lo_k, hi_u + (rd - hi_r) * hi_k);
      }
    }
    cut_rows(band_r1 + 1, w.r_hi);
  }
  book.add(rows);
}

/// Columns: candidate heights of one cell row, kChunk cells at a time.
constexpr int kChunk = 128;

/// A segment of a row polygon's boundary with its slope dy/dx (unused when
/// the segment is vertical seen from above).
struct Side {
  Point p, q;
  double slope;
};

/// A convex polygon in one cell row, as its sides in order (side k runs from
/// vertex k to vertex k + 1).
struct RowPolygon {
  Side sides[5];
  int n = 0;
  int c_lo = 0, c_hi = -1;  // cells it touches (closed cells)
};

/// Sets the polygon's cell range from its vertices.
inline void set_cells(RowPolygon& poly, const GridFrame& f) {
  double xmin = poly.sides[0].p.x, xmax = poly.sides[0].p.x;
  for (int k = 1; k < poly.n; ++k) {
    xmin = std::min(xmin, poly.sides[k].p.x);
    xmax = std::max(xmax, poly.sides[k].p.x);
  }
  poly.c_lo = std::max(0, ceil_clamped((xmin - f.x0) * f.inv_cx, 0, f.cols + 1) - 1);
  poly.c_hi = floor_clamped((xmax - f.x0) * f.inv_cx, -1, f.cols - 1);
}

/// Lowers every cell [c_lo, c_hi] of row r to the lowest point over the cell
/// of the convex polygons (closed cells). The lowest point of a polygon over
/// a cell is a vertex of the polygon's part there: a polygon vertex inside
/// the cell, or where the polygon's boundary crosses one of the cell's two
/// side lines. The side-line crossings are shared by neighbouring cells, so
/// each is computed once: boundary[k] holds the lowest crossing on line x =
/// x0 + (cb + k) cx over all the polygons (a crossing on a side line belongs
/// to both cells it bounds); the vertices then lower their cells' targets.
RowChange cut_row_polygons(HeightGrid& grid, const GridFrame& f, int r, const RowPolygon* polys,
                           int n_polys, int c_lo, int c_hi) {
  RowChange change;
  double boundary[kChunk + 1];
  for (int cb = c_lo; cb <= c_hi; cb += kChunk) {
    int ce = std::min(c_hi, cb + kChunk - 1);
    int cells = ce - cb + 1;
    double xb = f.x0 + cb * f.cx;  // the chunk's first side line
    // Sides spanning the whole chunk (the long sides of a sliver, most of the
    // work) are evaluated together in one pass that also initialises
    // boundary[]; up to kFused of them, padded with sides at +inf.
    constexpr int kFused = 4;
    double fused_base[kFused] = {kInf, kInf, kInf, kInf}, fused_step[kFused] = {0.0, 0.0, 0.0, 0.0};
    int n_fused = 0;
    struct Partial {
      int k0, k1;
      double base, step;
    } partial[2 * 5];
    int n_partial = 0;
    for (int p = 0; p < n_polys; ++p) {
      const RowPolygon& poly = polys[p];
      for (int s = 0; s < poly.n; ++s) {
        const Side& side = poly.sides[s];
        double lo_x = std::min(side.p.x, side.q.x), hi_x = std::max(side.p.x, side.q.x);
        if (!(hi_x > lo_x)) continue;  // seen from above a point: its ends are vertices
        int k0 = std::max(0, ceil_clamped((lo_x - xb) * f.inv_cx, -1, cells + 1));
        int k1 = std::min(cells, floor_clamped((hi_x - xb) * f.inv_cx, -1, cells + 1));
        if (k0 > k1) continue;
        // y at x0 + (cb + k) cx, as base + k * step.
        double base = side.p.y + (xb - side.p.x) * side.slope, step = f.cx * side.slope;
        if (k0 == 0 && k1 == cells && n_fused < kFused) {
          fused_base[n_fused] = base;
          fused_step[n_fused++] = step;
        } else {
          partial[n_partial++] = {k0, k1, base, step};
        }
      }
    }
    for (int k = 0; k <= cells; ++k) {
      double kd = double(k);
      double a = std::min(fused_base[0] + kd * fused_step[0], fused_base[1] + kd * fused_step[1]);
      double b = std::min(fused_base[2] + kd * fused_step[2], fused_base[3] + kd * fused_step[3]);
      boundary[k] = std::min(a, b);
    }
    for (int j = 0; j < n_partial; ++j) {
      const Partial& side = partial[j];
      for (int k = side.k0; k <= side.k1; ++k) {
        boundary[k] = std::min(boundary[k], side.base + double(k) * side.step);
      }
    }
    // The cells' targets: the lower of their two side lines, then the
    // polygon vertices inside them (rounding to float keeps the order).
    float target[kChunk];
    for (int k = 0; k < cells; ++k) {
      target[k] = float(boundary[k] < boundary[k + 1] ? boundary[k] : boundary[k + 1]);
    }
    for (int p = 0; p < n_polys; ++p) {
      const RowPolygon& poly = polys[p];
      // Each vertex counts in every closed cell that holds it (two on a side line).
      for (int s = 0; s < poly.n; ++s) {
        const Point& v = poly.sides[s].p;
        float y = float(v.y);
        int c = floor_clamped((v.x - f.x0) * f.inv_cx, cb - 1, ce + 1);
        if (c > cb - 1 && f.x0 + c * f.cx > v.x) --c;
        if (c < ce + 1 && f.x0 + (c + 1) * f.cx <= v.x) ++c;
        if (c >= cb && c <= ce) target[c - cb] = std::min(target[c - cb], y);
        if (c - 1 >= cb && c - 1 <= ce && f.x0 + c * f.cx == v.x) {
          target[c - 1 - cb] = std::min(target[c - 1 - cb], y);
        }
      }
    }
    RowChange part = lower_row_targets(grid, r, cb, ce, target);
    change.visited += part.visited;
    if (part.last >= 0) {
      change.removed_m += part.removed_m;
      if (change.first < 0) change.first = part.first;
      change.last = part.last;
    }
  }
  return change;
}

/// The side p -> q with its slope computed.
inline Side side_of(const Point& p, const Point& q) {
  double dx = q.x - p.x;
  return {p, q, dx != 0.0 ? (q.y - p.y) / dx : 0.0};
}

/// A swept triangle set up for the columns rasteriser: in each cell row it
/// is a convex polygon, the triangle clipped by the row's two lines, built
/// from the scanline's long edge and short chain. A triangle with all three
/// vertices at one z ("flat") is its own polygon, in the one or two rows
/// whose closed strip holds that plane.
struct ColumnTriangle {
  Point q[3];
  Scanline tri;
  bool flat = false;
  double ac_slope = 0.0, ab_slope = 0.0, bc_slope = 0.0;  // dy/dx along the edges
  int r_lo = 0, r_hi = -1;  // cell rows the triangle touches (closed)

  ColumnTriangle(const Vec3 (&p)[3], const GridFrame& f)
      : q{{p[0].x, p[0].y - f.ground_y, p[0].z},
          {p[1].x, p[1].y - f.ground_y, p[1].z},
          {p[2].x, p[2].y - f.ground_y, p[2].z}},
        tri(q[0], q[1], q[2]) {
    double zmin = tri.a.z, zmax = tri.c.z;
    r_lo = std::max(0, ceil_clamped((zmin - f.z0) * f.inv_cz, 0, f.rows + 1) - 1);
    r_hi = floor_clamped((zmax - f.z0) * f.inv_cz, -1, f.rows - 1);
    flat = !(zmax > zmin);
    auto slope = [](const Point& a, const Point& b) { return b.x != a.x ? (b.y - a.y) / (b.x - a.x) : 0.0; };
    ac_slope = slope(tri.a, tri.c);
    ab_slope = slope(tri.a, tri.b);
    bc_slope = slope(tri.b, tri.c);
  }

  /// The polygon in row r (rd = r); false when the row misses the triangle.
  bool polygon(const GridFrame& f, double rd, RowPolygon& poly) const {
    poly.n = 0;
    if (flat) {
      poly.sides[0] = side_of(q[0], q[1]);
      poly.sides[1] = side_of(q[1], q[2]);
      poly.sides[2] = side_of(q[2], q[0]);
      poly.n = 3;
      set_cells(poly, f);
      return true;
    }
    double z_bottom = f.z0 + rd * f.cz, z_top = f.z0 + (rd + 1.0) * f.cz;
    if (z_top < tri.a.z || z_bottom > tri.c.z) return false;
    double za = std::max(z_bottom, tri.a.z), zb = std::min(z_top, tri.c.z);
    // In order: bottom section (long -> short), the short chain up (through
    // B when B is strictly inside the row), top section (short -> long), and
    // the long edge back down.
    Point long_a = tri.long_at(za), short_a = tri.short_at(za);
    Point long_b = tri.long_at(zb), short_b = tri.short_at(zb);
    Side* sides = poly.sides;
    int n = 0;
    sides[n++] = side_of(long_a, short_a);
    if (tri.b.z > za && tri.b.z < zb) {
      sides[n++] = {short_a, tri.b, ab_slope};
      sides[n++] = {tri.b, short_b, bc_slope};
    } else {
      sides[n++] = {short_a, short_b, zb <= tri.b.z ? ab_slope : bc_slope};
    }
    sides[n++] = side_of(short_b, long_b);
    sides[n++] = {long_b, long_a, ac_slope};
    poly.n = n;
    set_cells(poly, f);
    return true;
  }
};

/// Columns representation: lowers every column whose (closed) cell the swept
/// region touches to the region's lowest point inside the cell. The two
/// triangles are walked row by row together; where their polygons touch
/// the same cells (in a row they usually cover the same span), the cells are
/// lowered once, to the lower of the two.
void cut_sweep_columns(HeightGrid& grid, const GridFrame& f, const Vec3 (&tris)[2][3], CutBook& book) {
  const ColumnTriangle t0(tris[0], f), t1(tris[1], f);
  int r_lo = std::min(t0.r_lo, t1.r_lo), r_hi = std::max(t0.r_hi, t1.r_hi);
  CutBook rows;  // a local, so that its fields stay in registers
  double rd = r_lo;
  for (int r = r_lo; r <= r_hi; ++r, rd += 1.0) {
    RowPolygon polys[2];
    int n = 0;
    for (const ColumnTriangle* t : {&t0, &t1}) {
      if (r >= t->r_lo && r <= t->r_hi && t->polygon(f, rd, polys[n]) && polys[n].c_lo <= polys[n].c_hi) ++n;
    }
    if (n == 0) continue;
    if (n == 2 && polys[1].c_lo < polys[0].c_lo) std::swap(polys[0], polys[1]);
    if (n == 1 || polys[1].c_lo - polys[0].c_hi - 1 > kMaxGap) {
      for (int k = 0; k < n; ++k) rows.add(r, cut_row_polygons(grid, f, r, &polys[k], 1, polys[k].c_lo, polys[k].c_hi));
    } else {
      rows.add(r, cut_row_polygons(grid, f, r, polys, 2, polys[0].c_lo, std::max(polys[0].c_hi, polys[1].c_hi)));
    }
  }
  book.add(rows);
}

/// Columns representation, a translation across many rows: the
/// parallelogram's cells row by row, each cell lowered to the plane's lowest
/// point over the parallelogram's part in the (closed) cell, found without
/// building the row's polygon. In grid units (cell c spans u in [c, c + 1],
/// row r spans v in [r, r + 1]) the part of the parallelogram in row r is a
/// convex polygon Q; the plane's height Y = y0 + gu u + gv v is linear, so
/// its lowest point over Q is a vertex of Q (u_star, y_min), and over the
/// part of Q in cell c it is that vertex when u_star lies in [c, c + 1], and
/// otherwise on the cell's side line nearer to it (a linear function over a
/// convex set cut by a line through it: when the unconstrained minimum is
/// beyond the line, a constrained one is on it). On a side line u = U the
/// part of Q is a chord from its lower chain to its upper chain (each the
/// envelope of the parallelogram's sides facing that way, clipped to the
/// row), and Y along it is lowest at the end gv points away from.
struct ColumnsOblique {
  ObliqueSweep bounds;  ///< the section's u bounds against v (centre 0)
  static constexpr int kChains = 3;
  /// Lower and upper chains, v(u) = v_p + (u - u_p) k, padded with lines at
  /// -inf (lower) and +inf (upper).
  double low_u[kChains], low_v[kChains], low_k[kChains];
  double up_u[kChains], up_v[kChains], up_k[kChains];
  double vert_u[4], vert_v[4];  ///< the parallelogram's vertices
  double y0 = 0.0, gu = 0.0, gv = 0.0;
  double vmin = 0.0, vmax = 0.0;
  int r_lo = 0, r_hi = -1;
  /// In the band of rows (bounds.band_r0 .. band_r1, see straight_band) the
  /// chord's chain is one line too: band_chain of the chain Y is lowest on.
  int band_chain = 0;
};

/// Q's lowest vertex (the first of the lowest, u_star and y_min) among its
/// n candidates, and its extent in u.
inline void lowest_vertex(const ColumnsOblique& w, const double* cand_u, const double* cand_v, int n, double& umin,
                          double& umax, double& u_star, double& y_min) {
  umin = cand_u[0], umax = cand_u[0], u_star = cand_u[0];
  y_min = w.y0 + w.gu * cand_u[0] + w.gv * cand_v[0];
  for (int k = 1; k < n; ++k) {
    umin = std::min(umin, cand_u[k]);
    umax = std::max(umax, cand_u[k]);
    double y = w.y0 + w.gu * cand_u[k] + w.gv * cand_v[k];
    if (y < y_min) y_min = y, u_star = cand_u[k];
  }
}

/// Sets the columns walk's band (w.bounds.band_*, band_chain): the rows
/// between the parallelogram's second and third vertex, when in all of them
/// the section bounds and the chain the chords end on are each one line (by
/// more than rounding, so the band's rows get the values of the general
/// walk bit for bit); otherwise the band is left empty.
void columns_band(ColumnsOblique& w, int rows) {
  ObliqueSweep& b = w.bounds;
  straight_band(b, w.vert_v, rows, 1);
  if (b.band_r0 > b.band_r1) return;
  const double r0 = b.band_r0, r1 = b.band_r1;
  auto lo = [&b](double v) { return line_at(b.lo_u[b.band_lo], b.lo_r[b.band_lo], b.lo_k[b.band_lo], v); };
  auto hi = [&b](double v) { return line_at(b.hi_u[b.band_hi], b.hi_r[b.band_hi], b.hi_k[b.band_hi], v); };
  // Q's extent in u over the band is that of its first and last rows'
  // corners (the bounds are straight there).
  const double u0 = std::min(lo(r0), lo(r1 + 1.0)), u1 = std::max(hi(r0), hi(r1 + 1.0));
  // A chord's end is on the chain or on the row's line (va >= r0 below,
  // vb <= r1 + 1 above), whichever is inside.
  w.band_chain = w.gv >= 0.0
                     ? dominant_line(w.low_v, w.low_u, w.low_k, ColumnsOblique::kChains, u0, u1, true, r0)
                     : dominant_line(w.up_v, w.up_u, w.up_k, ColumnsOblique::kChains, u0, u1, false, r1 + 1.0);
  if (w.band_chain < 0) b.band_r0 = 0, b.band_r1 = -1;
}

bool setup_oblique_columns(const GridFrame& f, const Parallelogram& p, ColumnsOblique& w) {
  if (!set_section_bounds(f, p, 0.0, w.bounds)) return false;
  int n_low = 0, n_up = 0;
  for (int k = 0; k < 4; ++k) {
    const Point& a = p.v[k];
    const Point& b = p.v[(k + 1) % 4];
    w.vert_u[k] = (a.x - f.x0) * f.inv_cx;
    w.vert_v[k] = (a.z - f.z0) * f.inv_cz;
    double du = (b.x - a.x) * f.inv_cx;
    // A side along a column, or within rounding of one, bounds only the
    // section's ends (the section bounds above hold it).
    if (!(std::abs(du) >= 1e-9)) continue;
    double u_p = (a.x - f.x0) * f.inv_cx, v_p = (a.z - f.z0) * f.inv_cz;
    double k_uv = (b.z - a.z) * f.inv_cz / du;
    // Counter-clockwise, the inside is left of each side: a side going
    // towards +x has the inside above it (it is on the lower chain).
    if ((du > 0.0) == p.ccw) {
      if (n_low == ColumnsOblique::kChains) return false;
      w.low_u[n_low] = u_p, w.low_v[n_low] = v_p, w.low_k[n_low++] = k_uv;
    } else {
      if (n_up == ColumnsOblique::kChains) return false;
      w.up_u[n_up] = u_p, w.up_v[n_up] = v_p, w.up_k[n_up++] = k_uv;
    }
  }
  for (; n_low < ColumnsOblique::kChains; ++n_low) w.low_u[n_low] = 0.0, w.low_v[n_low] = -kInf, w.low_k[n_low] = 0.0;
  for (; n_up < ColumnsOblique::kChains; ++n_up) w.up_u[n_up] = 0.0, w.up_v[n_up] = kInf, w.up_k[n_up] = 0.0;
  w.gu = p.slope_x * f.cx;
  w.gv = p.slope_z * f.cz;
  w.y0 = p.v[0].y + p.slope_x * (f.x0 - p.v[0].x) + p.slope_z * (f.z0 - p.v[0].z);
  w.vmin = (p.zmin - f.z0) * f.inv_cz;
  w.vmax = (p.zmax - f.z0) * f.inv_cz;
  w.r_lo = std::max(0, ceil_clamped(w.vmin, 0, f.rows + 1) - 1);
  w.r_hi = floor_clamped(w.vmax, -1, f.rows - 1);
  if (!(std::isfinite(w.y0) && std::isfinite(w.gu) && std::isfinite(w.gv))) return false;
  columns_band(w, f.rows);
  return true;
}

/// Rows ahead of the columns band whose cells are asked for, where the band
/// is steep (its bounds moving at most kColumnWalkMaxSlope columns a row).
/// There a row's cells are one cache line, the next row's 4 * cols bytes
/// further; on a power-of-two side those lines share few L1 and L2 sets, so
/// the column the band walks does not stay in the caches from one step to
/// the next, and each row waited on L3 for its load (59 % of the yaw-90
/// columns cut in a profile). Measured on the direction benchmark
/// (`terracut_bench --benchmark_filter=direction/`, 4096^2, columns cut
/// p50): yaw 89 57.7 -> 45.7 us, 90 64.9 -> 50.4 us; in a loop of contact
/// and cut alone, 16 and 32 rows ahead (to L2) were within 1.2 us of 8, and
/// at yaw 45 (not steep) it gained nothing (42.8 -> 43.2 us).
constexpr int kBandAheadRows = 8;

void cut_oblique_columns(HeightGrid& grid, const GridFrame& f, const ColumnsOblique& w, CutBook& book) {
  CutBook rows;  // a local, so that its fields stay in registers
  const HeightGrid::EditLayers layers = grid.edit_layers();
  const ObliqueSweep& b = w.bounds;
  const bool low_end = w.gv >= 0.0;  // Y along a chord is lowest at its lower end
  // The section's ends at v.
  auto ends = [&b](double v, double& lo, double& hi) {
    lo = b.lo_u[0] + (v - b.lo_r[0]) * b.lo_k[0];
    hi = b.hi_u[0] + (v - b.hi_r[0]) * b.hi_k[0];
    for (int k = 1; k < ObliqueSweep::kBounds; ++k) {
      lo = std::max(lo, b.lo_u[k] + (v - b.lo_r[k]) * b.lo_k[k]);
      hi = std::min(hi, b.hi_u[k] + (v - b.hi_r[k]) * b.hi_k[k]);
    }
  };
  // Lowers row r's cells [c_lo, c_hi] spanned by Q (u in [umin, umax]) to
  // Q's lowest point over each: the vertex (u_star, y_min) when it lies in
  // the cell, else the lowest point of the chord on the side line nearer to
  // it (chord_min(U)).
  auto cut_cells = [&](int r, double umin, double umax, double u_star, double y_min, auto&& chord_min) {
    const int c_lo = std::max(0, ceil_clamped(umin, 0, f.cols + 1) - 1);
    const int c_hi = floor_clamped(umax, -1, f.cols - 1);
    if (c_lo > c_hi) return;
    const std::int64_t row = grid.index(0, r);
    RowChange change;
    change.visited = c_hi - c_lo + 1;
    for (int c = c_lo; c <= c_hi; ++c) {
      double lowest = u_star < c ? chord_min(c) : u_star > c + 1 ? chord_min(c + 1) : y_min;
      lower_one(layers, row, c, float(lowest), change);
    }
    rows.add(r, change);
  };
  // A row's top line is the next row's bottom line: its ends are carried
  // over (the same arithmetic on the same v, so the same values).
  double carried_v = -kInf, carried_lo = 0.0, carried_hi = 0.0;
  // Any row: Q's corners and the parallelogram's vertices inside the row,
  // chords against every line of the chain.
  auto cut_rows = [&](int from, int to) {
    for (int r = from; r <= to; ++r) {
      const double va = std::max(double(r), w.vmin), vb = std::min(double(r) + 1.0, w.vmax);
      if (va > vb) continue;
      // Q's vertices: the section's ends at va and vb, and the
      // parallelogram's vertices strictly between.
      double cand_u[8], cand_v[8];
      if (va == carried_v) {
        cand_u[0] = carried_lo, cand_u[1] = carried_hi;
      } else {
        ends(va, cand_u[0], cand_u[1]);
      }
      ends(vb, cand_u[2], cand_u[3]);
      carried_v = vb, carried_lo = cand_u[2], carried_hi = cand_u[3];
      cand_v[0] = cand_v[1] = va;
      cand_v[2] = cand_v[3] = vb;
      int n = 4;
      for (int k = 0; k < 4; ++k) {
        if (w.vert_v[k] > va && w.vert_v[k] < vb) cand_u[n] = w.vert_u[k], cand_v[n++] = w.vert_v[k];
      }
      double umin, umax, u_star, y_min;
      lowest_vertex(w, cand_u, cand_v, n, umin, umax, u_star, y_min);
      // The lowest Y on the chord of Q at u = U (U within Q's extent).
      cut_cells(r, umin, umax, u_star, y_min, [&](double U) {
        double v;
        if (low_end) {
          v = va;
          for (int k = 0; k < ColumnsOblique::kChains; ++k) v = std::max(v, w.low_v[k] + (U - w.low_u[k]) * w.low_k[k]);
        } else {
          v = vb;
          for (int k = 0; k < ColumnsOblique::kChains; ++k) v = std::min(v, w.up_v[k] + (U - w.up_u[k]) * w.up_k[k]);
        }
        return w.y0 + w.gu * U + w.gv * v;
      });
    }
  };
  const int band_r0 = std::max(b.band_r0, w.r_lo), band_r1 = std::min(b.band_r1, w.r_hi);
  if (band_r0 > band_r1) {
    cut_rows(w.r_lo, w.r_hi);
    book.add(rows);
    return;
  }
  cut_rows(w.r_lo, band_r0 - 1);
  // The band (columns_band): no vertex inside a row, each bound and the
  // chain one line; the same values as cut_rows (the lines left out lie
  // beyond the kept ones by more than rounding).
  const double lo_u = b.lo_u[b.band_lo], lo_r = b.lo_r[b.band_lo], lo_k = b.lo_k[b.band_lo];
  const double hi_u = b.hi_u[b.band_hi], hi_r = b.hi_r[b.band_hi], hi_k = b.hi_k[b.band_hi];
  const int chain = w.band_chain;
  const double chain_v = low_end ? w.low_v[chain] : w.up_v[chain];
  const double chain_u = low_end ? w.low_u[chain] : w.up_u[chain];
  const double chain_k = low_end ? w.low_k[chain] : w.up_k[chain];
  const double y0 = w.y0, gu = w.gu, gv = w.gv;
  // Written out for the band's four corners, with no array, no call and no
  // branch on the data (the general walk's arrays and std::min references
  // kept its candidates on the stack, and the branches on each cell's
  // case and on whether it is lowered mispredicted on the ragged 2 to 3
  // cells a transverse row holds; each mispredict also waited on that
  // row's load from memory). The same arithmetic on the same operands as
  // lowest_vertex, cut_cells and lower_one, so the same values, bit for bit:
  // the corners of row r's bottom line are those of row r - 1's top line,
  // heights included.
  auto corner_y = [&](double u, double v) { return y0 + gu * u + gv * v; };
  double u_lo_a = 0.0, u_hi_a = 0.0, y_lo_a = 0.0, y_hi_a = 0.0;
  if (double(band_r0) == carried_v) {
    u_lo_a = carried_lo, u_hi_a = carried_hi;
  } else {
    const double va = double(band_r0);
    u_lo_a = lo_u + (va - lo_r) * lo_k, u_hi_a = hi_u + (va - hi_r) * hi_k;
  }
  y_lo_a = corner_y(u_lo_a, double(band_r0));
  y_hi_a = corner_y(u_hi_a, double(band_r0));
  float* const height = layers.height_m;
  // The loop is instantiated with and without the prefetch, so that the
  // bands that do not ask keep main's code (a flag tested in the loop
  // measured 2-3 us slower on a full-width blade at yaw 30).
  auto walk_band = [&](auto steep) {
    for (int r = band_r0; r <= band_r1; ++r) {
      const double va = double(r), vb = double(r) + 1.0;  // inside [vmin, vmax]
      const double u_lo_b = lo_u + (vb - lo_r) * lo_k, u_hi_b = hi_u + (vb - hi_r) * hi_k;
      const double y_lo_b = corner_y(u_lo_b, vb), y_hi_b = corner_y(u_hi_b, vb);
      // lowest_vertex over (u_lo_a, va), (u_hi_a, va), (u_lo_b, vb), (u_hi_b, vb):
      // the first of the lowest.
      const double umin = min_value(min_value(u_lo_a, u_hi_a), min_value(u_lo_b, u_hi_b));
      const double umax = max_value(max_value(u_lo_a, u_hi_a), max_value(u_lo_b, u_hi_b));
      double y_min = y_lo_a, u_star = u_lo_a;
      u_star = y_hi_a < y_min ? u_hi_a : u_star, y_min = y_hi_a < y_min ? y_hi_a : y_min;
      u_star = y_lo_b < y_min ? u_lo_b : u_star, y_min = y_lo_b < y_min ? y_lo_b : y_min;
      u_star = y_hi_b < y_min ? u_hi_b : u_star, y_min = y_hi_b < y_min ? y_hi_b : y_min;
      u_lo_a = u_lo_b, u_hi_a = u_hi_b, y_lo_a = y_lo_b, y_hi_a = y_hi_b;
      // The chord's lowest point on side line U (cut_cells' chord_min).
      auto chord_min = [&](double U) {
        const double chain_at = chain_v + (U - chain_u) * chain_k;
        const double v = low_end ? max_value(va, chain_at) : min_value(vb, chain_at);
        return y0 + gu * U + gv * v;
      };
      const int c_lo = std::max(0, ceil_clamped(umin, 0, f.cols + 1) - 1);
      const int c_hi = floor_clamped(umax, -1, f.cols - 1);
      if (c_lo > c_hi) continue;
      float* const cells = height + grid.index(0, r);
      if (decltype(steep)::value && r + kBandAheadRows <= band_r1) {
        const int c_ahead = std::clamp(c_lo + int(kBandAheadRows * lo_k), 0, f.cols - 1);
        detail::prefetch<true, 3>(cells + std::int64_t(kBandAheadRows) * f.cols + c_ahead);
      }
      RowChange change;
      change.visited = c_hi - c_lo + 1;
      double left = chord_min(double(c_lo));
      for (int c = c_lo; c <= c_hi; ++c) {
        const double cd = double(c);
        const double right = chord_min(cd + 1.0);
        const double lowest = u_star < cd ? left : u_star > cd + 1.0 ? right : y_min;
        left = right;
        lower_one_unbranched(cells, c, float(lowest), change);
      }
      rows.add(r, change);
    }
  };
  if (std::abs(lo_k) <= kColumnWalkMaxSlope && std::abs(hi_k) <= kColumnWalkMaxSlope) {
    walk_band(std::true_type{});
  } else {
    walk_band(std::false_type{});
  }
  carried_v = double(band_r1) + 1.0, carried_lo = u_lo_a, carried_hi = u_hi_a;
  cut_rows(band_r1 + 1, w.r_hi);
  book.add(rows);
}

/// Prefetch hints for the samples along the edge where the blade would be
/// a step from now if it kept its motion (to + (to - from)): on a terrain
/// larger than the caches the next step's cut and contact then find their
/// rows on chip instead of waiting for memory. One hint per cache line along
/// a row and per row crossed, at most kMaxAhead points; no effect on results.
void prefetch_next_sweep(const HeightGrid& grid, const GridFrame& f, const Segment& from, const Segment& to) {
  constexpr int kMaxAhead = 256;
  Vec3 a = to.a + (to.a - from.a), b = to.b + (to.b - from.b);
  double ua = (a.x - f.x0) * f.inv_cx, va = (a.z - f.z0) * f.inv_cz;
  double ub = (b.x - f.x0) * f.inv_cx, vb = (b.z - f.z0) * f.inv_cz;
  // Bounded before the conversion to int (a span of 1e300 cells was undefined
  // behaviour: found by the scenario fuzz target, on cells of 1e-302 m).
  const double span = std::max(std::abs(ub - ua) / 8.0, std::abs(vb - va));
  if (!std::isfinite(span)) return;  // NaN or inf from a far-away edge
  const int points = int(std::min(span, double(kMaxAhead - 1))) + 1;
  const float* height = grid.heights();
  for (int k = 0; k <= points; ++k) {
    double t = double(k) / points;
    int c = floor_clamped(ua + t * (ub - ua), 0, f.cols - 1);
    int r = floor_clamped(va + t * (vb - va), 0, f.rows - 1);
    detail::prefetch<false, 2>(height + grid.index(c, r));
  }
}

}  // namespace

CutResult cut_sweep(HeightGrid& grid, Representation representation, const Segment& from,
                    const Segment& to) {
  CutResult out;
  if (!is_finite(from.a) || !is_finite(from.b) || !is_finite(to.a) || !is_finite(to.b)) return out;
  GridFrame f(grid);
  CutBook book;
  auto cut_pair = [&](const Vec3 (&pair)[2][3]) {
    if (representation == Representation::kColumns) {
      cut_sweep_columns(grid, f, pair, book);
    } else {
      cut_sweep_points(grid, f, pair, book);
    }
  };
  ObliqueSweep oblique;
  ColumnsOblique oblique_columns;
  Parallelogram parallelogram;
  if (detail::sweep_above_floor(from, to, f.ground_y)) {
    bool translation = translation_parallelogram(f, from, to, parallelogram);
    if (translation && representation == Representation::kSurface && setup_oblique(f, parallelogram, oblique)) {
      cut_oblique_points(grid, f, oblique, book);
    } else if (translation && representation == Representation::kColumns &&
               setup_oblique_columns(f, parallelogram, oblique_columns)) {
      cut_oblique_columns(grid, f, oblique_columns, book);
    } else {
      Vec3 tri[2][3];
      detail::sweep_triangles(from, to, tri);
      cut_pair(tri);
    }
  } else {
    // Part of the sweep is inside the rigid floor: only the part above it
    // cuts. The triangles go in pairs (a lone one paired with itself: lowering
    // twice to the same height changes nothing).
    Vec3 clipped[4][3];
    int n = detail::sweep_triangles_above_floor(from, to, f.ground_y, clipped);
    for (int k = 0; k < n; k += 2) {
      Vec3 pair[2][3];
      for (int v = 0; v < 3; ++v) {
        pair[0][v] = clipped[k][v];
        pair[1][v] = clipped[k + 1 < n ? k + 1 : k][v];
      }
      cut_pair(pair);
    }
  }
  prefetch_next_sweep(grid, f, from, to);
  out.removed_volume_m3 = book.removed_m * f.cx * f.cz;
  out.changed = book.changed();
  out.cells_visited = book.visited;
  return out;
}

}  // namespace terracut
