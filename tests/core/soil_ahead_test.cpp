// The depth of cut and the pile ahead of a moving edge (soil_ahead.hpp): the
// depth reads the uncut soil ahead, a pile pushed by the blade counts as a
// surcharge height, not as depth.
#include "terracut/core/soil_ahead.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "terracut/core/surface.hpp"

namespace terracut {
namespace {

// A 0.2 m layer of 5 mm cells (600 x 200) with a pile above it ahead of
// the line z = 0.4 m: top_m at the line, falling at slope k ahead, none
// behind (the pile a blade along X pushes there).
constexpr double kPileCell = 0.005, kPileLayer = 0.2, kPileLine = 0.4;
constexpr int kPileCols = 600, kPileRows = 200;
HeightGrid pile_ahead(double top_m, double k) {
  HeightGrid g(grid_of_cells(kPileCols, kPileRows, kPileCell),
               std::vector<float>(std::size_t(kPileCols) * kPileRows, float(kPileLayer)));
  std::vector<float> h(std::size_t(kPileCols) * kPileRows);
  for (int r = 0; r < kPileRows; ++r) {
    const double z = (r + 0.5) * kPileCell;
    const float pile = z >= kPileLine ? float(std::max(0.0, top_m - k * (z - kPileLine))) : 0.0f;
    for (int c = 0; c < kPileCols; ++c) h[std::size_t(r) * kPileCols + c] = float(kPileLayer) + pile;
  }
  g.set_heights({0, 0, kPileCols, kPileRows}, h.data());
  return g;
}

TEST(CutDepth, WithoutAPileTheDepthIsTheDepthAhead) {
  HeightGrid g(grid_of_cells(100, 100, 0.01), std::vector<float>(100 * 100, 0.2f));
  const Segment edge{{0.3, 0.15, 0.4}, {0.7, 0.15, 0.4}};
  const Vec3 v{0.0, 0.0, 0.5};
  const double look = depth_lookahead_m(g.spec());
  const SoilAhead a = soil_ahead(g, Representation::kSurface, edge, v, look);
  EXPECT_NEAR(a.depth_m, 0.05, 1e-6);
  EXPECT_NEAR(a.width_m, 0.4, 1e-9);
  EXPECT_EQ(a.pile_m, 0.0);
}

// Parts at different depths sum as one uniform cut with the same section
// (sum of d) and the same sum of d^2: an edge tilted across a flat layer,
// its depth falling linearly from 0.1 m at one end to 0 at the other.
TEST(CutDepth, PartsOfDifferentDepthsSumAsTheSameSectionAndWeight) {
  HeightGrid g(grid_of_cells(100, 100, 0.01), std::vector<float>(100 * 100, 0.2f));
  const Segment edge{{0.3, 0.1, 0.4}, {0.7, 0.2, 0.4}};
  const double look = depth_lookahead_m(g.spec());
  const SoilAhead a = soil_ahead(g, Representation::kSurface, edge, {0.0, 0.0, 1.0}, look);
  // n = ceil(L / cell) parts of length L / n, depth 0.1 (1 - (i + 0.5) / n) each.
  const int n = int(std::ceil(length(edge.b - edge.a) / 0.01));
  const double part = length(edge.b - edge.a) / n;
  double s1 = 0.0, s2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double d = 0.1 * (1.0 - (i + 0.5) / n);
    s1 += d;
    s2 += d * d;
  }
  EXPECT_NEAR(a.depth_m, s2 / s1, 1e-6);
  EXPECT_NEAR(a.width_m, part * s1 * s1 / s2, 1e-6);
  EXPECT_NEAR(a.width_m * a.depth_m, part * s1, 1e-7);              // the section
  EXPECT_NEAR(a.width_m * a.depth_m * a.depth_m, part * s2, 1e-8);  // the weight's d^2 w
}

// A part coming into the soil at zero depth changes the cut continuously:
// an edge lowered through the surface by tiny steps never jumps.
TEST(CutDepth, TheCutIsContinuousAsPartsEnterTheSoil) {
  HeightGrid g(grid_of_cells(100, 100, 0.01), std::vector<float>(100 * 100, 0.2f));
  const double look = depth_lookahead_m(g.spec());
  double previous_section = 0.0, previous_weight = 0.0;
  // A tilted edge whose low end enters at y = 0.2 first.
  for (int k = 0; k <= 200; ++k) {
    const double y = 0.21 - 1e-4 * k;
    const Segment edge{{0.3, y, 0.4}, {0.7, y + 0.02, 0.4}};
    const SoilAhead a = soil_ahead(g, Representation::kSurface, edge, {0.0, 0.0, 1.0}, look);
    const double section = a.width_m * a.depth_m, weight = section * a.depth_m;
    // Each step lowers every part by 1e-4 m: the section grows by at most
    // that over the whole edge, the weight by at most 2 d 1e-4 over it.
    EXPECT_LE(section - previous_section, 0.4 * 1e-4 * 1.0001) << k;
    EXPECT_LE(weight - previous_weight, 0.4 * 2.0 * 0.02 * 1e-4 * 1.0001 + 1e-12) << k;
    EXPECT_GE(section, previous_section);
    previous_section = section;
    previous_weight = weight;
  }
}

TEST(CutDepth, APileAheadIsNotDepthButSurchargeHeight) {
  // The initial layer is 0.2 m; 0.1 m of soil is piled on it ahead of the
  // edge (from z = 0.40 m on, the edge at 0.40), over more than the failure
  // wedge's length.
  std::vector<float> initial(100 * 100, 0.2f);
  HeightGrid g(grid_of_cells(100, 100, 0.01), initial);
  std::vector<float> piled(100 * 100, 0.2f);
  for (int r = 40; r < 100; ++r)
    for (int c = 0; c < 100; ++c) piled[std::size_t(r) * 100 + c] = 0.3f;
  g.set_heights({0, 0, 100, 100}, piled.data());
  const Segment edge{{0.3, 0.15, 0.4}, {0.7, 0.15, 0.4}};
  const Vec3 v{0.0, 0.0, 0.5};
  const double look = depth_lookahead_m(g.spec());
  const SoilAhead a = soil_ahead(g, Representation::kSurface, edge, v, look);
  EXPECT_NEAR(a.depth_m, 0.05, 1e-6);  // below the undisturbed surface
  EXPECT_NEAR(a.pile_m, 0.1, 1e-6);
  // The current surface alone would read the pile as depth.
  EXPECT_NEAR(surface_y_m(g, Representation::kSurface, 0.5, 0.4 + look) - 0.15, 0.15, 1e-6);
  // No horizontal motion: nothing ahead.
  EXPECT_EQ(soil_ahead(g, Representation::kSurface, edge, {0.0, -1.0, 0.0}, look).depth_m, 0.0);
}

// The pile over the wedge is a mean along the motion, read at points one
// spacing h apart, h = max(cell, the part's length): on a pile falling
// linearly ahead the midpoint rule is exact, and where the pile ends inside
// the wedge (a kink of slope k) it is off by at most k h^2 / 8 over the
// wedge's length L, plus the surface's interpolation across that kink (at
// most k cell / 4 at the one point in the kink's cell, so k cell h / (4 L)
// on the mean). Edges of 0.3 m (parts of one 5 mm cell) and 2 m (64 parts
// of 31 mm) on 5 mm cells.
TEST(CutDepth, ThePileIsTheMeanOverTheWedgeWithinItsSamplingError) {
  const double cell = kPileCell, layer = kPileLayer, edge_y = 0.15, edge_z = kPileLine, k = 0.6;
  const auto pushed = [&](double top_m) { return pile_ahead(top_m, k); };
  const double look = depth_lookahead_m(grid_of_cells(kPileCols, kPileRows, cell));
  const double depth = layer - edge_y, reach = kWedgeLengthPerDepth * depth;
  for (const double length_m : {0.3, 2.0}) {
    const Segment edge{{1.5 - 0.5 * length_m, edge_y, edge_z}, {1.5 + 0.5 * length_m, edge_y, edge_z}};
    const int parts = int(std::min(64.0, std::ceil(length_m / cell)));
    const double h = std::max(cell, length_m / parts);
    // Linear over the whole wedge: the mean is the pile at its middle.
    const HeightGrid linear = pushed(0.2);
    const SoilAhead a = soil_ahead(linear, Representation::kSurface, edge, {0.0, 0.0, 1.0}, look);
    EXPECT_NEAR(a.depth_m, depth, 1e-6) << length_m;
    EXPECT_NEAR(a.pile_m, 0.2 - k * (look + 0.5 * reach), 1e-6) << length_m;
    // Ending inside the wedge, at t = top / k - look past its start.
    const double top = 0.05, at_start = top - k * look;
    const double exact = at_start * at_start / (2.0 * k) / reach;
    const HeightGrid kinked = pushed(top);
    const SoilAhead b = soil_ahead(kinked, Representation::kSurface, edge, {0.0, 0.0, 1.0}, look);
    EXPECT_NEAR(b.pile_m, exact, k * h * h / (8.0 * reach) + k * cell * h / (4.0 * reach) + 1e-6) << length_m;
  }
}

// The pile read does not jump as the depth changes: lowering a 2 m edge
// over 5 mm cells (64 parts of 31 mm, the wedge read every 31 mm) through
// a pile that ends inside the wedge, the reading changes between depths
// 0.01 mm apart by no more than the mean over a wedge of length L can:
// |dM/dL| <= (f(L) + M) / L for the exact mean, plus (h k / 2) / L for the
// last interval's midpoint moving along the pile's slope k, with L = 2 d.
// (A count of evenly spread points, ceil(L / h), moved every point when it
// changed: steps of up to 4 % of the pile.)
TEST(CutDepth, ThePileIsContinuousInTheDepth) {
  const double layer = kPileLayer, edge_z = kPileLine, k = 0.6, top = 0.03;
  const HeightGrid g = pile_ahead(top, k);
  const double look = depth_lookahead_m(g.spec());
  const double spacing = 2.0 / 64.0, step = 1e-5;
  double previous = -1.0;
  int changed = 0;
  for (double depth = 0.02; depth <= 0.06; depth += step) {
    const double y = layer - depth;
    const SoilAhead a = soil_ahead(g, Representation::kSurface, {{0.5, y, edge_z}, {2.5, y, edge_z}}, {0.0, 0.0, 1.0}, look);
    if (previous >= 0.0) {
      const double reach = kWedgeLengthPerDepth * depth;
      const double bound = kWedgeLengthPerDepth * step * (2.0 * top + 0.5 * spacing * k) / reach;
      EXPECT_LE(std::abs(a.pile_m - previous), bound + 1e-9) << "depth " << depth;
      changed += a.pile_m != previous ? 1 : 0;
    }
    previous = a.pile_m;
  }
  EXPECT_GT(changed, 1000);  // the pile read does change with the depth
}

// The wedge's points walked in cell coordinates (with the clamps skipped
// where the walk lies inside the grid) read what the surface query reads at
// the same world points: against surface_heights_m at q + u t, with the
// same intervals, where the wedge runs off the grid, on both
// representations, on a grid one sample wide, and across a yawed motion.
TEST(CutDepth, ThePileReadsWhatTheSurfaceQueryReadsAtTheSamePoints) {
  const auto reference = [](const HeightGrid& g, Representation rep, const Segment& edge, Vec3 v, double look) {
    const GridSpec& spec = g.spec();
    const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
    const int n = int(std::clamp(std::ceil(length(edge.b - edge.a) / cell), 2.0, 64.0));
    const double part = std::hypot(edge.b.x - edge.a.x, edge.b.z - edge.a.z) / n;
    const double speed = std::hypot(v.x, v.z);
    const Vec3 u{v.x / speed, 0.0, v.z / speed};
    double sum_d = 0.0, sum_pile_d = 0.0;
    for (int i = 0; i < n; ++i) {
      const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
      const Vec3 q = p + u * look;
      const auto [now, before] = surface_heights_m(spec, g.heights(), g.initial(), rep, q.x, q.z);
      const double depth = spec.origin_m.y + std::min(now, before) - p.y;
      if (!(depth > 0.0)) continue;
      const double reach = kWedgeLengthPerDepth * depth;
      const double h = std::max({cell, part, reach / 64.0});
      const int whole = int(std::floor(reach / h));
      const double rest = reach - whole * h;
      const auto pile_at = [&](double t) {
        const Vec3 r = q + u * t;
        const auto [a, b] = surface_heights_m(spec, g.heights(), g.initial(), rep, r.x, r.z);
        return std::max(0.0, a - b);
      };
      double pile = 0.0;
      for (int k = 0; k < whole; ++k) pile += h * pile_at((k + 0.5) * h);
      if (rest > 0.0) pile += rest * pile_at(whole * h + 0.5 * rest);
      sum_d += depth;
      sum_pile_d += depth * pile / reach;
    }
    return sum_d > 0.0 ? sum_pile_d / sum_d : 0.0;
  };
  // A bumpy pile on a 0.2 m layer (heights from a formula), the cut 5 cm.
  const auto terrain = [](int cols, int rows, double cell) {
    HeightGrid g(grid_of_cells(cols, rows, cell), std::vector<float>(std::size_t(cols) * rows, 0.2f));
    std::vector<float> h(std::size_t(cols) * rows);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        h[std::size_t(r) * cols + c] = float(0.2 + 0.03 * (1.0 + std::sin(0.7 * c + 1.3 * r)) * (r > rows / 3 ? 1.0 : 0.0));
    g.set_heights({0, 0, cols, rows}, h.data());
    return g;
  };
  struct Case {
    int cols, rows;
    double cell;
    Segment edge;
    Vec3 v;
  };
  const Case cases[] = {
      {100, 60, 0.01, {{0.2, 0.15, 0.45}, {0.8, 0.15, 0.45}}, {0.0, 0.0, 1.0}},   // the wedge runs off the far side
      {100, 60, 0.01, {{0.2, 0.15, 0.3}, {0.8, 0.15, 0.3}}, {0.0, 0.0, 1.0}},     // inside the grid
      {100, 60, 0.01, {{0.3, 0.15, 0.25}, {0.7, 0.15, 0.35}}, {-0.3, 0.0, 1.0}},  // yawed, oblique motion
      {1, 200, 0.005, {{0.0, 0.15, 0.4}, {0.005, 0.15, 0.4}}, {0.0, 0.0, 1.0}},   // one sample wide
      {100, 60, 0.01, {{0.2, 0.15, 0.3}, {0.8, 0.15, 0.3}}, {0.0, 0.0, -1.0}},    // backwards, into the bare layer
  };
  for (const Case& c : cases) {
    const HeightGrid g = terrain(c.cols, c.rows, c.cell);
    const double look = depth_lookahead_m(g.spec());
    for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
      const double expected = reference(g, rep, c.edge, c.v, look);
      const SoilAhead a = soil_ahead(g, rep, c.edge, c.v, look);
      EXPECT_NEAR(a.pile_m, expected, 1e-12) << c.cols << " x " << c.rows << ", " << int(rep);
      if (c.v.z > 0.0) {
        EXPECT_GT(expected, 0.0);  // the cases read a pile
      }
    }
  }
}

TEST(Embedment, TheDepthIsReadBesideTheEdgeNotInItsOwnTrench) {
  // A 0.2 m layer with a one-cell trench cut down to 0.12 m along row 40
  // (z in [0.40, 0.41)), where a horizontal edge along X sits at y = 0.12.
  HeightGrid g(grid_of_cells(100, 100, 0.01), std::vector<float>(100 * 100, 0.2f));
  std::vector<float> row(100, 0.12f);
  g.set_heights({0, 40, 100, 41}, row.data());
  const double look = depth_lookahead_m(g.spec());
  const Segment edge{{0.3, 0.12, 0.405}, {0.7, 0.12, 0.405}};
  for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
    const Embedment e = embedment(g, rep, edge, look);
    EXPECT_NEAR(e.depth_m, 0.08, 1e-6);
    EXPECT_NEAR(e.length_m, 0.4, 1e-12);
    // Above the soil beside it: not embedded.
    const Embedment above = embedment(g, rep, {{0.3, 0.25, 0.405}, {0.7, 0.25, 0.405}}, look);
    EXPECT_EQ(above.depth_m, 0.0);
    EXPECT_EQ(above.length_m, 0.0);
  }
  // Half the edge off the terrain (x > 1 m reads the rigid ground at 0).
  const Embedment half = embedment(g, Representation::kColumns, {{0.8, 0.1, 0.405}, {1.2, 0.1, 0.405}}, look);
  EXPECT_NEAR(half.length_m, 0.2, 1e-12);
  EXPECT_NEAR(half.depth_m, 0.1, 1e-6);
  EXPECT_EQ(embedment(g, Representation::kSurface, {{0.3, std::nan(""), 0.4}, {0.7, 0.1, 0.4}}, look).length_m, 0.0);
}

TEST(TwistEngagement, ACentredBuriedEdgeIsEngagedOnBothSidesSymmetrically) {
  HeightGrid g(grid_of_cells(100, 100, 0.01), std::vector<float>(100 * 100, 0.2f));
  const double look = depth_lookahead_m(g.spec());
  const Segment edge{{0.3, 0.15, 0.5}, {0.7, 0.15, 0.5}};
  const Vec3 centre{0.5, 0.15, 0.5};
  double depth = 0.0;
  const TwistEngagement e =
      twist_engagement(g, Representation::kSurface, edge, centre, 1.0, look, depth);
  EXPECT_NEAR(e.engaged_length_m, 0.4, 1e-12);
  EXPECT_NEAR(e.signed_length_m, 0.0, 1e-12);
  // integral |s| ds = L^2 / 4 and integral s^2 ds = L^3 / 12, exactly with
  // the parts' own second moments.
  EXPECT_NEAR(e.abs_moment_m2, 0.04, 1e-12);
  EXPECT_NEAR(e.second_moment_m3, 0.064 / 12.0, 1e-12);
  EXPECT_NEAR(depth, 0.05, 1e-6);
  // Turning the other way reads the other sides: the same for a flat layer.
  const TwistEngagement back =
      twist_engagement(g, Representation::kSurface, edge, centre, -1.0, look, depth);
  EXPECT_NEAR(back.abs_moment_m2, e.abs_moment_m2, 1e-12);
  // No turning, or an edge above the soil: nothing.
  EXPECT_EQ(twist_engagement(g, Representation::kSurface, edge, centre, 0.0, look, depth)
                .engaged_length_m, 0.0);
  const Segment high{{0.3, 0.3, 0.5}, {0.7, 0.3, 0.5}};
  EXPECT_EQ(twist_engagement(g, Representation::kSurface, high, {0.5, 0.3, 0.5}, 1.0, look, depth)
                .engaged_length_m, 0.0);
  EXPECT_EQ(depth, 0.0);
}

TEST(TwistEngagement, OnlyTheSideThatMovesIntoSoilIsEngaged) {
  // Soil only at x < 0.5 (the -s half of an edge along +X centred at 0.5).
  std::vector<float> h(100 * 100, 0.0f);
  for (int r = 0; r < 100; ++r)
    for (int c = 0; c < 50; ++c) h[std::size_t(r) * 100 + c] = 0.2f;
  HeightGrid g(grid_of_cells(100, 100, 0.01), h);
  const double look = depth_lookahead_m(g.spec());
  double depth = 0.0;
  const TwistEngagement e = twist_engagement(g, Representation::kColumns,
                                             {{0.3, 0.15, 0.5}, {0.7, 0.15, 0.5}},
                                             {0.5, 0.15, 0.5}, 2.0, look, depth);
  EXPECT_NEAR(e.engaged_length_m, 0.2, 1e-12);
  EXPECT_NEAR(e.signed_length_m, -0.2, 1e-12);
  EXPECT_NEAR(e.abs_moment_m2, 0.02, 1e-12);
}

}  // namespace
}  // namespace terracut
