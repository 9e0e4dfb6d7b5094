// Contact length by walking only the cells under the edge. Inside each cell
// (columns) or each triangle of the surface, both the material top and the
// edge height are linear in the edge parameter, so the inside length is exact
// for the representation.
//
// The walk is done along the edge's major axis (X when the edge's footprint
// runs more along X than Z, else Z), one column of cells at a time: the edge
// crosses at most one line of the minor axis per column, so each column is
// one or two cells with straight-line code, no division, and (for the
// surface, away from the half-cell border) no index clamping; where the edge
// runs close to the axis, two columns go at once in SSE2 lanes. The
// surface's triangulation is symmetric under swapping X and Z, so one
// routine serves both axes with the roles of the strides swapped. The border
// ring of the surface and partial columns go through a general cell-by-cell
// walk (Amanatides-Woo) with clamped lookups.
#include "terracut/core/contact.hpp"

#include <algorithm>
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

/// Minimum, maximum and clamp of doubles by value (std::min and friends
/// return references, which can keep values in memory in the hot loops).
inline double min_d(double a, double b) { return b < a ? b : a; }
inline double max_d(double a, double b) { return a < b ? b : a; }
inline double clamp_d(double x, double lo, double hi) { return min_d(max_d(x, lo), hi); }

/// The contact found so far, in edge-parameter units (scaled to metres at
/// the end): inside length, twice the section area, largest depth (metres).
struct ContactSums {
  double length = 0.0;
  double area2 = 0.0;
  double max_depth = 0.0;
  double min_piece = 0.0;  // shortest piece (edge parameter) whose depth counts for max_depth
};

/// Adds a piece [s0, s1] of the edge over which the depth below the material
/// top is linear, d0 at s0 and d1 at s1 (metres); material where the depth
/// exceeds eps. Most pieces are wholly in or wholly out, which is tested
/// first; only a piece that leaves or enters material needs its root.
inline void add_piece(double s0, double s1, double d0, double d1, double eps, ContactSums& sums) {
  double ds = s1 - s0;
  if (d0 > eps && d1 > eps) {
    if (ds > 0.0) {
      sums.length += ds;
      sums.area2 += ds * (d0 + d1);
      if (ds >= sums.min_piece) sums.max_depth = max_d(sums.max_depth, max_d(d0, d1));
    }
    return;
  }
  if (!(d0 > eps) && !(d1 > eps)) return;
  if (!(ds > 0.0)) return;
  double fa = d0 - eps, fb = d1 - eps;
  double root = fa / (fa - fb);
  double t0 = 0.0, t1 = 1.0;
  if (fa > 0.0) {
    t1 = root;
  } else {
    t0 = root;
  }
  if (!(t1 > t0)) return;
  double e0 = d0 + (d1 - d0) * t0, e1 = d0 + (d1 - d0) * t1;
  double len = (t1 - t0) * ds;
  sums.length += len;
  sums.area2 += len * (e0 + e1);
  if (len >= sums.min_piece) sums.max_depth = max_d(sums.max_depth, max_d(e0, e1));
}

/// The edge in grid coordinates, oriented along its major axis: p is the
/// major coordinate (increasing, dp >= |dq|), q the minor one; y is the edge
/// height above the ground. Cell or node (P, Q) lies at h[P * sp + Q * sq].
struct Line {
  double p0, q0, dp, dq;
  double y0, dy;
  std::int64_t sp, sq;
  int np, nq;  // cells or nodes along p and q
};

/// Builds the line for edge a -> b whose grid coordinates are (u, v) = (u0 +
/// s du, v0 + s dv), s in [0, 1]. When the edge runs backwards along its
/// major axis it is reversed (s -> 1 - s); contact does not depend on the
/// direction.
Line make_line(const Segment& edge, double u0, double v0, double du, double dv, double ground_y,
               int cols, int rows) {
  Line l;
  double y0 = edge.a.y - ground_y, dy = edge.b.y - edge.a.y;
  if (std::abs(du) >= std::abs(dv)) {
    l = {u0, v0, du, dv, y0, dy, 1, cols, cols, rows};
  } else {
    l = {v0, u0, dv, du, y0, dy, cols, 1, rows, cols};
  }
  if (l.dp < 0.0) {
    l.p0 += l.dp;
    l.q0 += l.dq;
    l.y0 += l.dy;
    l.dp = -l.dp;
    l.dq = -l.dq;
    l.dy = -l.dy;
  }
  return l;
}

/// Walks the cells [pmin, pmax] x [qmin, qmax] (cell P covers [P, P+1)) that
/// the line crosses for s in [s_lo, s_hi], calling visit(P, Q, sa, sb) for
/// each cell with its parameter range, in order (Amanatides-Woo).
template <class Visit>
inline std::int64_t traverse(const Line& l, double s_lo, double s_hi, int pmin, int pmax, int qmin,
                             int qmax, Visit&& visit) {
  double ps = l.p0 + s_lo * l.dp, qs = l.q0 + s_lo * l.dq;
  int i = std::clamp(int(std::floor(ps)), pmin, pmax);
  int j = std::clamp(int(std::floor(qs)), qmin, qmax);
  int step_j = l.dq > 0.0 ? 1 : -1;
  double next_u = l.dp > 0.0 ? (i + 1 - l.p0) / l.dp : kInf;
  double next_v = l.dq != 0.0 ? ((l.dq > 0.0 ? j + 1 : j) - l.q0) / l.dq : kInf;
  double delta_u = l.dp > 0.0 ? 1.0 / l.dp : kInf;
  double delta_v = l.dq != 0.0 ? std::abs(1.0 / l.dq) : kInf;
  double s = s_lo;
  std::int64_t visited = 0;
  // Bounded by the number of cells on the way (plus slack for boundary starts).
  std::int64_t max_cells = std::int64_t(pmax - pmin) + (qmax - qmin) + 4;
  while (visited < max_cells) {
    double s_next = std::min(std::min(next_u, next_v), s_hi);
    visit(i, j, s, std::max(s, s_next));
    ++visited;
    if (s_next >= s_hi) break;
    s = std::max(s, s_next);
    if (next_u < next_v) {
      ++i;
      next_u += delta_u;
      if (i > pmax) break;
    } else {
      j += step_j;
      next_v += delta_v;
      if (j < qmin || j > qmax) break;
    }
  }
  return visited;
}

/// Prefetches the nodes (rows Q and Q + 1) of columns [P0, P1) of the line
/// l, given the minor coordinate q_at_P0 at column P0: one hint per cache
/// line along a row (x-major) or per column (z-major). On a terrain larger
/// than the caches each new row the blade reaches would otherwise cost a
/// memory round trip before the hardware prefetcher locks on; the walks call
/// this a chunk ahead.
inline void prefetch_columns(const float* h, const Line& l, int P0, int P1, double q_at_P0) {
  const int stride = l.sp == 1 ? 16 : 1;
  const double r = l.dq / l.dp;
  for (int P = P0; P < P1; P += stride) {
    int Q = std::clamp(int(q_at_P0 + r * (P - P0)), 1, l.nq - 3);
    const float* node = h + P * l.sp + std::int64_t(Q) * l.sq;
    detail::prefetch<>(node - l.sq);
    detail::prefetch<>(node);
    detail::prefetch<>(node + l.sq);
    detail::prefetch<>(node + 2 * l.sq);
  }
}

/// floor(x) for x in int range.
inline int floor_int(double x) {
  int i = int(x);
  return i - (double(i) > x);
}

// ---------------------------------------------------------------------------
// Columns: cell (P, Q) is a box of height h over [P, P+1) x [Q, Q+1).

/// The general walk over [sa, sb], cell by cell.
std::int64_t columns_general(const float* h, const Line& l, double sa, double sb, double eps,
                             ContactSums& sums) {
  if (!(sb >= sa)) return 0;
  return traverse(l, sa, sb, 0, l.np - 1, 0, l.nq - 1, [&](int i, int j, double s_a, double s_b) {
    double top = h[i * l.sp + j * l.sq];
    add_piece(s_a, s_b, top - (l.y0 + s_a * l.dy), top - (l.y0 + s_b * l.dy), eps, sums);
  });
}

/// A piece of the edge in s-units, [s0, s1], with its depths at the ends,
/// set aside by the fast walks for the careful treatment after a chunk.
struct Pending {
  double s0, s1, d0, d1;
};

/// Columns ahead of the surface's fast walk along the columns (z-major) whose
/// nodes it asks for, column by column, besides the chunks' prefetch. A
/// blade within 45 degrees of the columns reads one or two cache lines a
/// row, 4 * cols bytes apart; on a power-of-two side those lines fall into
/// few L1 and L2 sets, so the lines a chunk's prefetch brought in evicted
/// one another before they were read, and rows waited on L3. Measured on the
/// direction benchmark (`terracut_bench --benchmark_filter=direction/`,
/// 4096^2, surface contact p50, docs/bench/direction.md): yaw 53 12.4 ->
/// 9.3 us, 60 13.5 -> 9.9, 75 13.5 -> 9.9, 82 13.0 -> 9.0, 89 24.1 -> 16.0,
/// 90 23.5 -> 15.5; 8, 12 and 16 columns ahead measured within a
/// microsecond of 24.
constexpr int kAheadRows = 24;

/// The same for the columns' fast walk: 8 columns ahead, into L1, where the
/// edge is off the columns by more than 1 in 64. Measured on the direction
/// benchmark (4096^2, columns contact p50): yaw 53 10.7 -> 8.1 us, 60 10.7
/// -> 7.9, 75 11.4 -> 7.8, 82 10.8 -> 8.1, 89 14.6 -> 15.5 (24 columns
/// ahead to L2: 8.0 to 8.8 us at 53 to 82). At yaw 90 (an edge along the
/// columns, where the chunks' prefetch finds every line) it took 13.4 to
/// 16.1-17.2 us, hence the limit (13.6 -> 14.1 us with it).
constexpr int kAheadCellRows = 8;

/// Columns per chunk of the fast walks. Pieces that enter or leave material
/// are queued (at most four per column) and added after each chunk, so the
/// walks' loops make no calls and keep their sums in registers (every SSE
/// register is caller-saved on x86-64).
constexpr int kChunkColumns = 64;
constexpr int kMaxPending = 4 * kChunkColumns;

/// Whether the fast walks try two columns at once (in SSE2 lanes): only
/// when the edge is closer to its major axis than 1 in 2 (|dq / dp| < 1/2),
/// as only then do two columns in a row without a minor crossing happen
/// often. The walks are instantiated with and without the two-column path:
/// without it, its accumulators and constants no longer hold registers
/// through the oblique walks' loops, which then keep fewer of their values
/// on the stack (GCC 12 still keeps twice the area there in the columns'
/// two-cell branch).
inline bool pair_columns(const Line& l) { return std::abs(l.dq * (1.0 / l.dp)) < 0.5; }

/// Calls walk(up, pairs) with the instance of a fast walk that the line l
/// needs: up, whether its minor coordinate does not decrease (dq >= 0), and
/// pairs, pair_columns(l), both as std::bool_constant.
template <class Walk>
std::int64_t fast_walk(const Line& l, Walk&& walk) {
  const bool up = l.dq >= 0.0;
  if (pair_columns(l)) {
    return up ? walk(std::true_type{}, std::true_type{}) : walk(std::false_type{}, std::true_type{});
  }
  return up ? walk(std::true_type{}, std::false_type{}) : walk(std::false_type{}, std::false_type{});
}

/// Adds the queued pieces.
void add_pending(const Pending* pending, int n, double eps, ContactSums& sums) {
  for (int k = 0; k < n; ++k) add_piece(pending[k].s0, pending[k].s1, pending[k].d0, pending[k].d1, eps, sums);
}

/// The fast walk over the full columns P in [p_first, p_end): per column one
/// cell, or two where the edge crosses a minor line. Measured in a = p - P as
/// for the surface (see surface_columns): the minor offset b = q - Q and the
/// edge height y advance by constants per column; a column wholly in
/// material adds (d_in + d_out) to twice the area, in a-units.
template <bool kUp, bool kPairs>
std::int64_t columns_full(const float* h, const Line& l, int p_first, int p_end, double eps,
                          ContactSums& sums) {
  const double inv_dp = 1.0 / l.dp;
  const double r = l.dq * inv_dp, ky = l.dy * inv_dp;
  const double inv_r = 1.0 / r;  // a of a minor crossing (unused when r = 0)
  const std::int64_t sp = l.sp, sq = l.sq;
  const double s_first = (p_first - l.p0) * inv_dp;
  double q_in = l.q0 + s_first * l.dq;
  int Q = std::clamp(floor_int(q_in), 0, l.nq - 1);
  double b = q_in - Q;
  double y = l.y0 + s_first * l.dy;
  const float* cell = h + p_first * sp + std::int64_t(Q) * sq;
  Pending pending[kMaxPending];
  std::int64_t visited = 0;
  // Along the columns (z-major), the edge off them by more than 1 in 64: see
  // kAheadCellRows.
  const bool rows_apart = sp != 1 && std::abs(r) > 1.0 / 64.0;
  prefetch_columns(h, l, p_first, std::min(p_end, p_first + kChunkColumns), q_in);
  for (int chunk = p_first; chunk < p_end; chunk += kChunkColumns) {
    int chunk_end = std::min(p_end, chunk + kChunkColumns);
    prefetch_columns(h, l, chunk_end, std::min(p_end, chunk_end + kChunkColumns),
                     Q + b + r * (chunk_end - chunk));
    int n = 0;
    // The chunk's columns wholly in material, twice their area (a-units), the depth.
    std::int64_t columns = 0;
    double area2 = 0.0, max_depth = sums.max_depth;
#if defined(__SSE2__)
    // Pair sums of the two-column path (lane 0: column P, lane 1: P + 1).
    __m128d area2_pair = _mm_setzero_pd(), max_pair = _mm_set1_pd(max_depth);
    const __m128d ky_pair = _mm_set1_pd(ky), eps_pair = _mm_set1_pd(eps);
    // Two columns in a row without a minor crossing are only likely when
    // the edge is closer to the major axis than 1 in 2 (pair_columns).
    constexpr bool pairs = kPairs;
#endif
    for (int P = chunk; P < chunk_end; ++P) {
      if (rows_apart && P + kAheadCellRows + 1 < p_end) {
        detail::prefetch<>(cell + kAheadCellRows * sp);
        detail::prefetch<>(cell + (kAheadCellRows + 1) * sp);
      }
#if defined(__SSE2__)
      // Two one-cell columns at once, in SSE2 lanes (the same arithmetic as
      // the one-cell branch below, per lane).
      if (pairs && P + 1 < chunk_end && (kUp ? b + 2.0 * r <= 1.0 : b + 2.0 * r >= 0.0)) {
        __m128d top = _mm_set_pd(cell[sp], cell[0]);
        __m128d y_in = _mm_set_pd(y + ky, y), y_out = _mm_add_pd(y_in, ky_pair);
        __m128d d0 = _mm_sub_pd(top, y_in), d1 = _mm_sub_pd(top, y_out);
        if (_mm_movemask_pd(_mm_cmpgt_pd(_mm_min_pd(d0, d1), eps_pair)) == 3) {
          columns += 2;
          area2_pair = _mm_add_pd(area2_pair, _mm_add_pd(d0, d1));
          max_pair = _mm_max_pd(max_pair, _mm_max_pd(d0, d1));
          b += 2.0 * r;
          y += 2.0 * ky;
          cell += 2 * sp;
          visited += 2;
          ++P;
          continue;
        }
      }
#endif
      double b_out = b + r, y_out = y + ky;
      double top = *cell;
      if (kUp ? (b_out > 1.0 && Q + 1 < l.nq) : (b_out < 0.0 && Q > 0)) {
        // Two cells, [0, a_c] and [a_c, 1]; the depth jumps at the wall.
        double a_c = clamp_d((kUp ? 1.0 - b : -b) * inv_r, 0.0, 1.0);
        double y_c = y + ky * a_c;
        double top2 = cell[kUp ? sq : -sq];
        double d0 = top - y, d1 = top - y_c, d2 = top2 - y_c, d3 = top2 - y_out;
        double d_min = min_d(min_d(d0, d1), min_d(d2, d3));
        if (d_min > eps && a_c > 0.0 && a_c < 1.0) {
          ++columns;
          area2 += a_c * (d0 + d1) + (1.0 - a_c) * (d2 + d3);
          // A sliver cell at a corner crossing adds no depth (kMinDepthPieceCells).
          double m01 = a_c >= detail::kMinDepthPieceCells ? max_d(d0, d1) : 0.0;
          double m23 = 1.0 - a_c >= detail::kMinDepthPieceCells ? max_d(d2, d3) : 0.0;
          max_depth = max_d(max_depth, max_d(m01, m23));
        } else {
          double s_in = (P - l.p0) * inv_dp, s_c = s_in + a_c * inv_dp, s_out = s_in + inv_dp;
          pending[n++] = {s_in, s_c, d0, d1};
          pending[n++] = {s_c, s_out, d2, d3};
        }
        b = kUp ? b_out - 1.0 : b_out + 1.0;
        Q += kUp ? 1 : -1;
        cell += kUp ? sq : -sq;
        visited += 2;
      } else {
        double d0 = top - y, d1 = top - y_out;
        if (d0 > eps && d1 > eps) {
          ++columns;
          area2 += d0 + d1;
          max_depth = max_d(max_depth, max_d(d0, d1));
        } else if (d0 > eps || d1 > eps) {
          double s_in = (P - l.p0) * inv_dp;
          pending[n++] = {s_in, s_in + inv_dp, d0, d1};
        }
        b = b_out;
        visited += 1;
      }
      cell += sp;
      y = y_out;
    }
#if defined(__SSE2__)
    area2 += _mm_cvtsd_f64(area2_pair) + _mm_cvtsd_f64(_mm_unpackhi_pd(area2_pair, area2_pair));
    max_depth = max_d(max_depth, max_d(_mm_cvtsd_f64(max_pair), _mm_cvtsd_f64(_mm_unpackhi_pd(max_pair, max_pair))));
#endif
    sums.length += double(columns) * inv_dp;
    sums.area2 += area2 * inv_dp;
    sums.max_depth = max_depth;
    add_pending(pending, n, eps, sums);
  }
  return visited;
}

ContactResult contact_columns(const HeightGrid& grid, const Segment& edge) {
  GridFrame f(grid);
  ContactResult out;
  Vec3 d = edge.b - edge.a;
  double u0 = (edge.a.x - f.x0) * f.inv_cx, v0 = (edge.a.z - f.z0) * f.inv_cz;
  double du = d.x * f.inv_cx, dv = d.z * f.inv_cz;
  double s0 = 0.0, s1 = 1.0;
  if (!detail::clip_axis(u0, du, 0.0, f.cols, s0, s1)) return out;
  if (!detail::clip_axis(v0, dv, 0.0, f.rows, s0, s1)) return out;
  // Below the ground (the rigid floor) nothing counts.
  if (!detail::clip_axis(edge.a.y - f.ground_y, d.y, 0.0, kInf, s0, s1)) return out;
  Line l = make_line(edge, u0, v0, du, dv, f.ground_y, f.cols, f.rows);
  // The reversal maps s -> 1 - s.
  if ((std::abs(du) >= std::abs(dv) ? du : dv) < 0.0) {
    double t = s0;
    s0 = 1.0 - s1;
    s1 = 1.0 - t;
  }
  const float* h = grid.heights();
  const double eps = f.min_contact_depth_m(Representation::kColumns);
  ContactSums sums;
  sums.min_piece = detail::min_depth_piece(l.dp);
  std::int64_t visited = 0;
  // Full columns take the fast walk, the partial first and last the general one.
  int p_first = 0, p_end = 0;
  if (l.dp > 0.0) {
    const double inv_dp = 1.0 / l.dp;
    p_first = std::clamp(int(std::ceil(l.p0 + s0 * l.dp)), 0, l.np);
    p_end = std::clamp(int(std::floor(l.p0 + s1 * l.dp)), 0, l.np);
    while (p_first < p_end && (p_first - l.p0) * inv_dp < s0) ++p_first;
    while (p_end > p_first && (p_end - l.p0) * inv_dp > s1) --p_end;
  }
  if (p_end > p_first) {
    const double inv_dp = 1.0 / l.dp;
    double s_first = (p_first - l.p0) * inv_dp;
    double s_end = (p_end - l.p0) * inv_dp;
    if (s_first > s0) visited += columns_general(h, l, s0, s_first, eps, sums);
    visited += fast_walk(l, [&](auto up, auto pairs) {
      return columns_full<up(), pairs()>(h, l, p_first, p_end, eps, sums);
    });
    if (s1 > s_end) visited += columns_general(h, l, s_end, s1, eps, sums);
  } else {
    visited += columns_general(h, l, s0, s1, eps, sums);
  }
  double seg_len = length(d);
  out.length_m = sums.length * seg_len;
  out.section_area_m2 = 0.5 * sums.area2 * seg_len;
  out.max_depth_m = sums.max_depth;
  out.cells_visited = visited;
  return out;
}

// ---------------------------------------------------------------------------
// Surface: node (P, Q) is sample (P, Q) (or its transpose); the node square
// (P, Q) is split along its diagonal from (P+1, Q) to (P, Q+1) into a lower
// triangle (a + b <= 1) and an upper one, a = p - P, b = q - Q.

/// Height of node (P, Q), indices clamped (the flat half-cell border).
inline double node_clamped(const float* h, const Line& l, int P, int Q) {
  P = std::clamp(P, 0, l.np - 1);
  Q = std::clamp(Q, 0, l.nq - 1);
  return h[P * l.sp + Q * l.sq];
}

/// The general walk over [sa, sb]: square by square, clamped lookups,
/// pieces split at the diagonal and evaluated with their triangle.
std::int64_t surface_general(const float* h, const Line& l, double sa, double sb, double eps,
                             ContactSums& sums) {
  if (!(sb >= sa)) return 0;
  double w0 = l.p0 + l.q0, dw = l.dp + l.dq;
  return traverse(l, sa, sb, -1, l.np - 1, -1, l.nq - 1, [&](int i, int j, double s_a, double s_b) {
    double h00 = node_clamped(h, l, i, j);
    double h10 = node_clamped(h, l, i + 1, j);
    double h01 = node_clamped(h, l, i, j + 1);
    double h11 = node_clamped(h, l, i + 1, j + 1);
    double cuts[3] = {s_a, s_b, s_b};
    int n = 2;
    if (dw != 0.0) {
      double sd = (1.0 + i + j - w0) / dw;
      if (sd > s_a && sd < s_b) {
        cuts[1] = sd;
        n = 3;
      }
    }
    for (int k = 0; k + 1 < n; ++k) {
      double pa = cuts[k], pb = cuts[k + 1];
      double mid = 0.5 * (pa + pb);
      bool lower = (l.p0 + mid * l.dp - i) + (l.q0 + mid * l.dq - j) <= 1.0;
      double top_a = detail::surface_in_square(h00, h10, h01, h11, l.p0 + pa * l.dp - i,
                                               l.q0 + pa * l.dq - j, lower);
      double top_b = detail::surface_in_square(h00, h10, h01, h11, l.p0 + pb * l.dp - i,
                                               l.q0 + pb * l.dq - j, lower);
      add_piece(pa, pb, top_a - (l.y0 + pa * l.dy), top_b - (l.y0 + pb * l.dy), eps, sums);
    }
  });
}

/// The fast walk over the full columns P in [p_first, p_end) of the interior
/// (every node looked up exists): per column, one square (split once at its
/// diagonal) or, where the edge crosses a minor line, two squares.
///
/// Within a column everything is measured in a = p - P in [0, 1] (the edge
/// parameter is s = s_in + a / dp): the minor offset b = q - Q and the edge
/// height y advance by the constants r = dq / dp and ky = dy / dp per column,
/// so a column costs a few multiply-adds, three or four height loads and no
/// division. In a full column the diagonal crossings always fall inside the
/// column's range (a + b is non-decreasing since |r| <= 1); they are clamped
/// against rounding. b and y are carried from column to column; their
/// rounding stays many orders below the float heights' (b in [0, 1]).
/// kUp: the edge's minor coordinate does not decrease (dq >= 0).
template <bool kUp, bool kPairs>
std::int64_t surface_columns(const float* h, const Line& l, int p_first, int p_end, double eps,
                             ContactSums& sums) {
  const double inv_dp = 1.0 / l.dp;
  const double r = l.dq * inv_dp, ky = l.dy * inv_dp;
  // a of the diagonal: (1 - b) / (1 + r). An edge parallel to the diagonals
  // (r = -1, a blade at 45 degrees) crosses none: it takes the one-square
  // branch only on a diagonal itself (b = 1, the surface linear along it),
  // where a_d = 0 is as good as any point, and the down branch otherwise.
  const double inv_1r = 1.0 + r > 0.0 ? 1.0 / (1.0 + r) : 0.0;
  const double inv_r = 1.0 / r;                 // a of a minor crossing (unused when r = 0)
  const std::int64_t sp = l.sp, sq = l.sq;
  const double s_first = (p_first - l.p0) * inv_dp;
  double q_in = l.q0 + s_first * l.dq;
  int Q = std::clamp(floor_int(q_in), 0, l.nq - 2);
  int q_top = l.nq - 2;                         // last square row with a row above it
  double b = q_in - Q;
  double y = l.y0 + s_first * l.dy;
  const float* base = h + p_first * sp + std::int64_t(Q) * sq;  // node (P, Q)
  double d_in = (base[0] + b * (double(base[sq]) - base[0])) - y;
  // The depth where the walk starts: the two-column path takes each column's
  // largest depth from its later points, and an edge that starts exactly on
  // the first column's line has no piece before it that would hold this one
  // (in material here means in material just after: the surface is continuous).
  if (d_in > eps) sums.max_depth = max_d(sums.max_depth, d_in);
  // Columns wholly in material are summed in a-units (each is 1 / dp long).
  Pending pending[kMaxPending];
  std::int64_t visited = 0;
  // Walking along the columns (z-major), each column's nodes are a row
  // apart: see kAheadRows.
  const bool rows_apart = sp != 1;
  prefetch_columns(h, l, p_first, std::min(p_end, p_first + kChunkColumns), q_in);
  for (int chunk = p_first; chunk < p_end; chunk += kChunkColumns) {
    int chunk_end = std::min(p_end, chunk + kChunkColumns);
    prefetch_columns(h, l, chunk_end, std::min(p_end, chunk_end + kChunkColumns),
                     Q + b + r * (chunk_end - chunk));
    int n = 0;
    std::int64_t columns = 0;
    double area2 = 0.0, max_depth = sums.max_depth;
    // Queues the pieces of column P through the points (a[k], d[k]).
    auto queue = [&](int P, const double* a, const double* d, int points) {
      double s_in = (P - l.p0) * inv_dp;
      for (int k = 0; k + 1 < points; ++k) {
        pending[n++] = {s_in + a[k] * inv_dp, s_in + a[k + 1] * inv_dp, d[k], d[k + 1]};
      }
    };
#if defined(__SSE2__)
    // Pair sums of the two-column path (lane 0: column P, lane 1: P + 1).
    __m128d area2_pair = _mm_setzero_pd(), max_pair = _mm_set1_pd(max_depth);
    const __m128d r_pair = _mm_set1_pd(r), ky_pair = _mm_set1_pd(ky), one = _mm_set1_pd(1.0);
    const __m128d inv_1r_pair = _mm_set1_pd(inv_1r), eps_pair = _mm_set1_pd(eps);
    // Two columns in a row without a minor crossing are only likely when
    // the edge is closer to the major axis than 1 in 2 (pair_columns).
    constexpr bool pairs = kPairs;
#endif
    for (int P = chunk; P < chunk_end; ++P) {
      if (rows_apart && P + kAheadRows + 1 < p_end) {
        detail::prefetch<false, 2>(base + kAheadRows * sp);
        detail::prefetch<false, 2>(base + (kAheadRows + 1) * sp);
      }
#if defined(__SSE2__)
      // Two one-square columns at once, in SSE2 lanes: the common case of a
      // blade inside material whose edge crosses no minor line for a while.
      // The same arithmetic as the one-square branch below, per lane.
      if (pairs && P + 1 < chunk_end && (kUp ? b + 2.0 * r <= 1.0 : b + 2.0 * r >= 0.0)) {
        __m128d b_in = _mm_set_pd(b + r, b), y_in = _mm_set_pd(y + ky, y);
        __m128d b_out = _mm_add_pd(b_in, r_pair), y_out = _mm_add_pd(y_in, ky_pair);
        __m128d h10 = _mm_set_pd(base[2 * sp], base[sp]);
        __m128d h01 = _mm_set_pd(base[sp + sq], base[sq]);
        __m128d h11 = _mm_set_pd(base[2 * sp + sq], base[sp + sq]);
        __m128d a_d = _mm_mul_pd(_mm_sub_pd(one, b_in), inv_1r_pair);
        __m128d top_d = _mm_add_pd(h10, _mm_mul_pd(_mm_add_pd(b_in, _mm_mul_pd(r_pair, a_d)), _mm_sub_pd(h01, h10)));
        __m128d d_d = _mm_sub_pd(top_d, _mm_add_pd(y_in, _mm_mul_pd(ky_pair, a_d)));
        __m128d d_out = _mm_sub_pd(_mm_add_pd(h10, _mm_mul_pd(b_out, _mm_sub_pd(h11, h10))), y_out);
        __m128d d_first = _mm_unpacklo_pd(_mm_set_sd(d_in), d_out);  // [d_in, d_out of column P]
        __m128d d_min = _mm_min_pd(d_first, _mm_min_pd(d_d, d_out));
        if (_mm_movemask_pd(_mm_cmpgt_pd(d_min, eps_pair)) == 3) {
          columns += 2;
          area2_pair = _mm_add_pd(area2_pair, _mm_add_pd(_mm_add_pd(d_d, _mm_mul_pd(a_d, d_first)),
                                                         _mm_mul_pd(_mm_sub_pd(one, a_d), d_out)));
          max_pair = _mm_max_pd(max_pair, _mm_max_pd(d_d, d_out));
          b += 2.0 * r;
          y += 2.0 * ky;
          d_in = _mm_cvtsd_f64(_mm_unpackhi_pd(d_out, d_out));
          base += 2 * sp;
          visited += 2;
          ++P;
          continue;
        }
      }
#endif
      double h10 = base[sp], h01 = base[sq], h11 = base[sp + sq];
      double b_out = b + r, y_out = y + ky;
      double d_out;
      if (kUp ? (b_out > 1.0 && Q < q_top) : (b_out < 0.0 && Q > 0)) {
        if (kUp) {
          // Up through the line q = Q + 1: square (P, Q), then (P, Q + 1).
          double h02 = base[2 * sq], h12 = base[sp + 2 * sq];
          double a_c = clamp_d((1.0 - b) * inv_r, 0.0, 1.0);
          double a_1 = clamp_d((1.0 - b) * inv_1r, 0.0, a_c);
          double a_2 = clamp_d((2.0 - b) * inv_1r, a_c, 1.0);
          double d_1 = (h10 + (b + r * a_1) * (h01 - h10)) - (y + ky * a_1);
          double d_c = (h01 + a_c * (h11 - h01)) - (y + ky * a_c);
          double d_2 = (h11 + (b - 1.0 + r * a_2) * (h02 - h11)) - (y + ky * a_2);
          d_out = (h11 + (b_out - 1.0) * (h12 - h11)) - y_out;
          double d_min = min_d(min_d(min_d(d_in, d_1), min_d(d_c, d_2)), d_out);
          if (d_min > eps) {
            ++columns;
            area2 += a_1 * (d_in + d_1) + (a_c - a_1) * (d_1 + d_c) + (a_2 - a_c) * (d_c + d_2) +
                     (1.0 - a_2) * (d_2 + d_out);
            max_depth = max_d(max_depth, max_d(max_d(max_d(d_in, d_1), max_d(d_c, d_2)), d_out));
          } else {
            const double a[5] = {0.0, a_1, a_c, a_2, 1.0};
            const double d[5] = {d_in, d_1, d_c, d_2, d_out};
            queue(P, a, d, 5);
          }
          b = b_out - 1.0;
          ++Q;
          base += sq;
        } else {
          // Down through the line q = Q: the lower triangle of square (P, Q),
          // then the upper triangle of (P, Q - 1); no diagonal on the way.
          double h00 = base[0], h1m = base[sp - sq];
          double a_c = clamp_d(-b * inv_r, 0.0, 1.0);
          double d_c = (h00 + a_c * (h10 - h00)) - (y + ky * a_c);
          d_out = (h1m + (b_out + 1.0) * (h10 - h1m)) - y_out;
          double d_min = min_d(min_d(d_in, d_c), d_out);
          if (d_min > eps) {
            ++columns;
            area2 += a_c * (d_in + d_c) + (1.0 - a_c) * (d_c + d_out);
            max_depth = max_d(max_depth, max_d(max_d(d_in, d_c), d_out));
          } else {
            const double a[3] = {0.0, a_c, 1.0};
            const double d[3] = {d_in, d_c, d_out};
            queue(P, a, d, 3);
          }
          b = b_out + 1.0;
          --Q;
          base -= sq;
        }
        visited += 2;
      } else {
        // One square: enter on a = 0, leave on a = 1, crossing the diagonal once.
        double a_d = clamp_d((1.0 - b) * inv_1r, 0.0, 1.0);
        double d_d = (h10 + (b + r * a_d) * (h01 - h10)) - (y + ky * a_d);
        d_out = (h10 + b_out * (h11 - h10)) - y_out;
        double d_min = min_d(d_in, min_d(d_d, d_out));
        if (d_min > eps) {
          // Twice the area over the column, in a-units: the trapezoids
          // a_d (d_in + d_d) + (1 - a_d) (d_d + d_out), simplified.
          ++columns;
          area2 += d_d + a_d * d_in + (1.0 - a_d) * d_out;
          max_depth = max_d(max_depth, max_d(d_in, max_d(d_d, d_out)));
        } else if (max_d(d_in, max_d(d_d, d_out)) > eps) {
          const double a[3] = {0.0, a_d, 1.0};
          const double d[3] = {d_in, d_d, d_out};
          queue(P, a, d, 3);
        }
        b = b_out;
        visited += 1;
      }
      base += sp;
      y = y_out;
      d_in = d_out;
    }
#if defined(__SSE2__)
    area2 += _mm_cvtsd_f64(area2_pair) + _mm_cvtsd_f64(_mm_unpackhi_pd(area2_pair, area2_pair));
    max_depth = max_d(max_depth, max_d(_mm_cvtsd_f64(max_pair), _mm_cvtsd_f64(_mm_unpackhi_pd(max_pair, max_pair))));
#endif
    sums.length += double(columns) * inv_dp;
    sums.area2 += area2 * inv_dp;
    sums.max_depth = max_depth;
    add_pending(pending, n, eps, sums);
  }
  return visited;
}

ContactResult contact_surface(const HeightGrid& grid, const Segment& edge) {
  GridFrame f(grid);
  ContactResult out;
  Vec3 d = edge.b - edge.a;
  // Node coordinates: sample (c, r) sits at integer (c, r); the surface spans
  // [-0.5, cols - 0.5] x [-0.5, rows - 0.5] (the half-cell border is flat).
  double u0 = (edge.a.x - f.x0) * f.inv_cx - 0.5, v0 = (edge.a.z - f.z0) * f.inv_cz - 0.5;
  double du = d.x * f.inv_cx, dv = d.z * f.inv_cz;
  double s0 = 0.0, s1 = 1.0;
  if (!detail::clip_axis(u0, du, -0.5, f.cols - 0.5, s0, s1)) return out;
  if (!detail::clip_axis(v0, dv, -0.5, f.rows - 0.5, s0, s1)) return out;
  // Below the ground (the rigid floor) nothing counts.
  if (!detail::clip_axis(edge.a.y - f.ground_y, d.y, 0.0, kInf, s0, s1)) return out;
  Line l = make_line(edge, u0, v0, du, dv, f.ground_y, f.cols, f.rows);
  bool reversed = (std::abs(du) >= std::abs(dv) ? du : dv) < 0.0;
  if (reversed) {
    double t = s0;
    s0 = 1.0 - s1;
    s1 = 1.0 - t;
  }
  const float* h = grid.heights();
  const double eps = f.min_contact_depth_m(Representation::kSurface);
  ContactSums sums;
  sums.min_piece = detail::min_depth_piece(l.dp);
  std::int64_t visited = 0;
  // The interior part, where every node of the squares crossed exists: p in
  // [0, np - 1] and q in [0, nq - 1]. Its full columns take the fast walk;
  // the rest (border ring, partial first and last columns) the general one.
  // An edge with no footprint crosses no column: it takes the general walk.
  // (|dq| <= dp: dp + dq >= 0, 0 for an edge parallel to the diagonals.)
  double sa = s0, sb = s1;
  bool interior = l.dp > 0.0 && l.dp + l.dq >= 0.0 && l.np >= 2 && l.nq >= 2 &&
                  detail::clip_axis(l.p0, l.dp, 0.0, l.np - 1.0, sa, sb) &&
                  detail::clip_axis(l.q0, l.dq, 0.0, l.nq - 1.0, sa, sb);
  int p_first = 0, p_end = 0;
  if (interior) {
    p_first = std::clamp(int(std::ceil(l.p0 + sa * l.dp)), 0, l.np - 1);
    p_end = std::clamp(int(std::floor(l.p0 + sb * l.dp)), 0, l.np - 1);
    // The fast walk's ends must lie inside [s0, s1] (rounding at the ends).
    const double inv_dp = 1.0 / l.dp;
    while (p_first < p_end && (p_first - l.p0) * inv_dp < s0) ++p_first;
    while (p_end > p_first && (p_end - l.p0) * inv_dp > s1) --p_end;
  }
  if (p_end > p_first) {
    const double inv_dp = 1.0 / l.dp;
    double s_first = (p_first - l.p0) * inv_dp;
    double s_end = (p_end - l.p0) * inv_dp;
    visited += surface_general(h, l, s0, s_first, eps, sums);
    visited += fast_walk(l, [&](auto up, auto pairs) {
      return surface_columns<up(), pairs()>(h, l, p_first, p_end, eps, sums);
    });
    visited += surface_general(h, l, s_end, s1, eps, sums);
  } else {
    visited += surface_general(h, l, s0, s1, eps, sums);
  }
  double seg_len = length(d);
  out.length_m = sums.length * seg_len;
  out.section_area_m2 = 0.5 * sums.area2 * seg_len;
  out.max_depth_m = sums.max_depth;
  out.cells_visited = visited;
  return out;
}

}  // namespace

ContactResult measure_contact(const HeightGrid& grid, Representation representation,
                              const Segment& edge) {
  if (!is_finite(edge.a) || !is_finite(edge.b)) return {};
  return representation == Representation::kColumns ? contact_columns(grid, edge)
                                                    : contact_surface(grid, edge);
}

}  // namespace terracut
