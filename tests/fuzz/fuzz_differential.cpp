// Differential fuzz target: the traversal (measure_contact, cut_sweep)
// against the brute-force oracle (core/brute_force.hpp), and the oracle's cut
// against an exact integer reference of the closed rule (docs/model.md,
// "Boundaries"), on terrains and poses the fuzzer chooses, in both
// representations.
//
// Everything is on a lattice, so ties are real ties: cells of exactly 1/8 m,
// an origin on multiples of 1/8 m, heights k/64 m, blade ends at multiples of
// 1/den of a cell (den 1, 2 or 4) and heights k/16 m. Edges on cell walls,
// ends on samples and sweeps through corners are frequent.
//
//   contact: fast and oracle agree (1e-9), and no contact exceeds the edge;
//   cut: the oracle lowers exactly the samples (surface) or columns the
//   closed region covers; the fast path matches the oracle sample for sample
//   where the swept triangles' edges have slopes exact in binary floating
//   point (as docs/model.md promises); elsewhere (surface) wherever a sample
//   is more than 1e-6 cell from the region's boundary. Both keep height +
//   removed = initial and never raise a sample.
//
// Input bytes: [cols, rows, origin, flags, den, 8 coordinate bytes, 2 height
// bytes, then terrain heights]; missing bytes read as 0.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "../support/lattice.hpp"
#include "fuzz_file.hpp"
#include "terracut/core/brute_force.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/cut.hpp"

namespace {

using namespace terracut;
using terracut::fuzz::check;
using test::LatticePoint;

struct Bytes {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at = 0;
  std::uint8_t next() { return at < size ? data[at++] : 0; }
};

constexpr double kCell = 0.125;

// Distance (in lattice units) from p to segment ab.
double distance(LatticePoint a, LatticePoint b, double px, double pz) {
  const double dx = double(b.x - a.x), dz = double(b.z - a.z);
  const double len2 = dx * dx + dz * dz;
  double t = len2 > 0 ? ((px - double(a.x)) * dx + (pz - double(a.z)) * dz) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(px - (double(a.x) + t * dx), pz - (double(a.z) + t * dz));
}

void check_layers(const HeightGrid& g, const char* what) {
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) {
    check(g.heights()[i] <= g.initial()[i], "fuzz_differential", what);
    check(std::abs(g.heights()[i] + g.removed_at(i) - g.initial()[i]) <= 1e-6f, "fuzz_differential", what);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in{data, size};
  const int cols = 1 + in.next() % 12, rows = 1 + in.next() % 12;
  const std::uint8_t origin = in.next();
  const std::uint8_t flags = in.next();
  const int den = 1 << (in.next() % 3);
  const Representation rep = (flags & 1u) ? Representation::kColumns : Representation::kSurface;
  const bool cut = (flags & 2u) != 0;
  GridSpec spec = grid_of_cells(cols, rows, kCell, {-kCell * (origin % 8), 0.5, -kCell * ((origin >> 3) % 8)});

  // Blade ends: lattice points up to two cells outside the grid.
  auto coord = [&](int cells) { return std::int64_t(in.next() % ((cells + 4) * den + 1)) - 2 * den; };
  LatticePoint fa{coord(cols), coord(rows)}, fb{coord(cols), coord(rows)};
  LatticePoint ta{coord(cols), coord(rows)}, tb{coord(cols), coord(rows)};
  if (flags & 16u) fb.z = fa.z;  // along a row line
  if (flags & 32u) fb.x = fa.x;  // along a column line
  if (flags & 4u) tb = {ta.x + (fb.x - fa.x), ta.z + (fb.z - fa.z)};  // a translation
  if (flags & 8u) {  // at rest
    ta = fa;
    tb = fb;
  }
  const double ya = double(1 + in.next() % 13) / 16.0, yb = double(1 + in.next() % 13) / 16.0;

  // Heights k/64: above every blade height for the cut (so a sample is
  // lowered exactly when the region covers it), anything for contact.
  std::vector<float> heights(std::size_t(spec.sample_count()));
  for (float& h : heights) h = cut ? float(58 + in.next() % 6) / 64.0f : float(in.next() % 64) / 64.0f;
  auto world = [&](LatticePoint p, double y) {
    return Vec3{spec.origin_m.x + double(p.x) / den * kCell, spec.origin_m.y + y,
                spec.origin_m.z + double(p.z) / den * kCell};
  };
  const Segment from{world(fa, ya), world(fb, yb)};
  const Segment to{world(ta, ya), world(tb, yb)};

  if (!cut) {
    const HeightGrid grid(spec, heights);
    const ContactResult fast = measure_contact(grid, rep, from);
    const ContactResult slow = measure_contact_brute_force(grid, rep, from);
    const double len = length(from.b - from.a);
    check(std::abs(fast.length_m - slow.length_m) <= 1e-9 * (1 + len), "fuzz_differential", "contact length");
    check(std::abs(fast.section_area_m2 - slow.section_area_m2) <= 1e-9 * (1 + len), "fuzz_differential",
          "contact section area");
    check(std::abs(fast.max_depth_m - slow.max_depth_m) <= 1e-9, "fuzz_differential", "contact depth");
    check(slow.length_m <= len + 1e-12 && fast.length_m <= len + 1e-12, "fuzz_differential",
          "contact no longer than the edge");
    return 0;
  }

  HeightGrid fast(spec, heights), slow(spec, heights);
  const CutResult a = cut_sweep(fast, rep, from, to);
  const CutResult b = cut_sweep_brute_force(slow, rep, from, to);
  check_layers(fast, "fast cut: height + removed = initial, never raised");
  check_layers(slow, "oracle cut: height + removed = initial, never raised");

  // The region as the cut builds it: the diagonal split, or a bow-tie's
  // lobes (the edges crossing) on a lattice sweep.scale times finer.
  const test::SweepTriangles sweep = test::sweep_triangles(fa, fb, ta, tb);
  const std::int64_t k = std::int64_t(den) * sweep.scale;  // lattice units a cell
  const test::SweepTriangles doubled = test::doubled(sweep);  // sample centres (half cells) are points of it
  bool representable = !sweep.bow_tie;
  for (const auto& t : sweep.tri)
    for (int e = 0; e < 3; ++e) representable = representable && test::representable_slope(t[e], t[(e + 1) % 3]);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      bool covered = false;
      double clearance = 1e300;  // (surface) lattice distance of the sample to the region's boundary
      for (int i = 0; i < 2; ++i) {
        const auto& t = sweep.tri[i];
        if (rep == Representation::kColumns) {
          covered |= test::touches(t, c * k, (c + 1) * k, r * k, (r + 1) * k);
        } else {
          covered |= test::holds(doubled.tri[i], {(2 * c + 1) * k, (2 * r + 1) * k});
          for (int e = 0; e < 3; ++e)
            clearance = std::min(clearance, distance(t[e], t[(e + 1) % 3], (c + 0.5) * double(k), (r + 0.5) * double(k)));
        }
      }
      // A bow-tie's crossing is rounded in the cut: on a line through it,
      // either side is right.
      const bool tie = rep == Representation::kColumns
                           ? test::on_crossing_line(sweep, c * k, (c + 1) * k, r * k, (r + 1) * k)
                           : test::on_crossing_line(doubled, {(2 * c + 1) * k, (2 * r + 1) * k});
      const float h0 = heights[std::size_t(fast.index(c, r))];
      check(tie || (slow.height(c, r) < h0) == covered, "fuzz_differential", "the oracle follows the closed rule");
      const bool compare = representable || (rep == Representation::kSurface && clearance > 1e-6 * double(k));
      if (compare)
        check(std::abs(fast.height(c, r) - slow.height(c, r)) <= 1e-6f, "fuzz_differential",
              "the fast cut matches the oracle");
    }
  }
  if (representable) {
    check(std::abs(a.removed_volume_m3 - b.removed_volume_m3) <= 1e-9 + 1e-7 * b.removed_volume_m3,
          "fuzz_differential", "removed volumes");
    if (!b.changed.empty()) check(a.changed == b.changed, "fuzz_differential", "changed rectangles");
  }
  return 0;
}
