// Built-in terrains sampled at cell centres, and the exact dome geometry.
#include "terracut/core/generators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace terracut {
namespace {

// A grid whose origin is off zero and whose cells are not square, so that a
// mix-up of X and Z, or of cell corners and centres, shows.
GridSpec odd_grid() {
  GridSpec spec;
  spec.cols = 9;
  spec.rows = 6;
  spec.size_x_m = 1.8;
  spec.size_z_m = 0.9;
  spec.origin_m = {-0.4, 0.25, 1.1};
  spec.full_scale_m = 0.3;
  return spec;
}

// The sample points, computed as HeightGrid documents them.
double centre_x(const GridSpec& s, int c) { return s.origin_m.x + (c + 0.5) * s.cell_x_m(); }
double centre_z(const GridSpec& s, int r) { return s.origin_m.z + (r + 0.5) * s.cell_z_m(); }

TEST(Generators, MoundSamplesTheDomeFormulaAtCellCentres) {
  const GridSpec spec = odd_grid();
  Generator gen = default_generator(GeneratorKind::kMound, spec);
  gen.mound = {0.3, 1.4, 0.6, 0.25};
  const std::vector<float> h = generate_heights(spec, gen);
  ASSERT_EQ(h.size(), std::size_t(spec.cols * spec.rows));
  int inside = 0;
  for (int r = 0; r < spec.rows; ++r)
    for (int c = 0; c < spec.cols; ++c) {
      const double dx = centre_x(spec, c) - 0.3;
      const double dz = centre_z(spec, r) - 1.4;
      const double rr = std::sqrt(dx * dx + dz * dz);
      const double expected = rr < 0.6 ? 0.25 * std::sqrt(1.0 - (rr / 0.6) * (rr / 0.6)) : 0.0;
      if (expected > 0.0) ++inside;
      // Stored as float: relative rounding of 2^-24 of the peak.
      EXPECT_NEAR(h[std::size_t(r * spec.cols + c)], expected, 0.25 * 1e-7)
          << "sample (" << c << ", " << r << ")";
    }
  EXPECT_GT(inside, 4);
  EXPECT_LT(inside, spec.cols * spec.rows);
}

TEST(Generators, MoundDefaultsAreCentredWithRadiusFourTenthsOfTheShorterSide) {
  const GridSpec spec = odd_grid();
  const Generator gen = default_generator(GeneratorKind::kMound, spec);
  EXPECT_DOUBLE_EQ(gen.mound.centre_x_m, -0.4 + 0.9);
  EXPECT_DOUBLE_EQ(gen.mound.centre_z_m, 1.1 + 0.45);
  EXPECT_DOUBLE_EQ(gen.mound.radius_m, 0.4 * 0.9);
  EXPECT_DOUBLE_EQ(gen.mound.height_m, spec.full_scale_m);
  EXPECT_DOUBLE_EQ(height_at(gen, gen.mound.centre_x_m, gen.mound.centre_z_m), spec.full_scale_m);
}

TEST(Generators, BoxIsFullHeightWhereTheCellCentreIsInsideBoundariesIncluded) {
  const GridSpec spec = odd_grid();
  Generator gen = default_generator(GeneratorKind::kBox, spec);
  // Low edges exactly on cell centres (column 2, row 1): those samples are inside.
  gen.box = {centre_x(spec, 2), centre_z(spec, 1), 0.75, 1.7, 0.2};
  const std::vector<float> h = generate_heights(spec, gen);
  for (int r = 0; r < spec.rows; ++r)
    for (int c = 0; c < spec.cols; ++c) {
      const double x = centre_x(spec, c);
      const double z = centre_z(spec, r);
      const bool in = c >= 2 && r >= 1 && x <= 0.75 && z <= 1.7;
      EXPECT_EQ(h[std::size_t(r * spec.cols + c)], in ? 0.2f : 0.0f) << c << "," << r;
    }
}

TEST(Generators, DefaultBoxCoversEverySample) {
  const GridSpec spec = odd_grid();
  const std::vector<float> h = generate_heights(spec, default_generator(GeneratorKind::kBox, spec));
  for (float v : h) EXPECT_EQ(v, float(spec.full_scale_m));
}

TEST(Generators, PlaneIsConstant) {
  const GridSpec spec = odd_grid();
  Generator gen = default_generator(GeneratorKind::kPlane, spec);
  EXPECT_DOUBLE_EQ(gen.plane.height_m, spec.full_scale_m);
  gen.plane.height_m = 0.07;
  for (float v : generate_heights(spec, gen)) EXPECT_EQ(v, 0.07f);
}

TEST(Generators, ValidateNamesTheBadField) {
  const GridSpec spec = odd_grid();
  Generator g = default_generator(GeneratorKind::kMound, spec);
  EXPECT_EQ(validate(g), "");
  g.mound.radius_m = 0.0;
  EXPECT_NE(validate(g).find("mound.radius_m"), std::string::npos);
  g.mound.radius_m = NAN;
  EXPECT_NE(validate(g).find("mound.radius_m"), std::string::npos);
  g = default_generator(GeneratorKind::kBox, spec);
  g.box.min_x_m = 2.0;
  EXPECT_NE(validate(g).find("box.min_m"), std::string::npos);
  g = default_generator(GeneratorKind::kPlane, spec);
  g.plane.height_m = -1.0;
  EXPECT_NE(validate(g).find("plane.height_m"), std::string::npos);
}

TEST(Generators, KindNamesRoundTrip) {
  for (GeneratorKind k : {GeneratorKind::kMound, GeneratorKind::kBox, GeneratorKind::kPlane})
    EXPECT_EQ(parse_enum<GeneratorKind>(to_string(k)), k);
  EXPECT_FALSE(parse_enum<GeneratorKind>("dome").has_value());
}

TEST(DomeGeometry, HorizontalChordMatchesTheCircleOfTheSection) {
  const MoundShape m{0.5, 0.5, 0.4, 0.2};
  // The paper's cut: y = H/2, section radius R*sqrt(3/4).
  const double r = 0.4 * std::sqrt(0.75);
  EXPECT_NEAR(horizontal_chord_m(m, 0.1, 0.5), 2.0 * r, 1e-12);
  EXPECT_NEAR(horizontal_chord_m(m, 0.1, 0.5 + 0.2), 2.0 * std::sqrt(r * r - 0.04), 1e-12);
  EXPECT_EQ(horizontal_chord_m(m, 0.1, 0.5 + r + 1e-9), 0.0);
  EXPECT_EQ(horizontal_chord_m(m, 0.25, 0.5), 0.0);  // above the peak
  EXPECT_EQ(horizontal_chord_m(m, -0.01, 0.5), 0.0); // below the ground
}

TEST(DomeGeometry, ContactOfALongHorizontalBladeEqualsTheChord) {
  const MoundShape m{0.5, 0.5, 0.4, 0.2};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> y(0.0, 0.2);
  std::uniform_real_distribution<double> z(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const double yy = y(rng);
    const double zz = z(rng);
    const Segment blade{{-0.1, 1.0 + yy, zz}, {1.1, 1.0 + yy, zz}};  // ground at y = 1
    EXPECT_NEAR(contact_length(m, 1.0, blade), horizontal_chord_m(m, yy, zz), 1e-9);
  }
}

TEST(DomeGeometry, ContactOfAnyLineMatchesPointSampling) {
  // Count points along the segment inside the solid; the fraction times the
  // length approaches the exact contact to within length / samples.
  const MoundShape m{0.2, -0.3, 0.5, 0.3};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.6, 0.8);
  std::uniform_real_distribution<double> v(-0.1, 0.4);
  const int samples = 20000;
  for (int i = 0; i < 50; ++i) {
    const Segment s{{u(rng), v(rng), u(rng) - 0.3}, {u(rng), v(rng), u(rng) - 0.3}};
    const double len = length(s.b - s.a);
    int inside = 0;
    for (int k = 0; k < samples; ++k) {
      const Vec3 p = lerp(s.a, s.b, (k + 0.5) / samples);
      if (p.y >= 0.0 && p.y <= height_at(m, p.x, p.z)) ++inside;
    }
    EXPECT_NEAR(contact_length(m, 0.0, s), len * inside / samples, 2.0 * len / samples) << i;
  }
}

TEST(DomeGeometry, VerticalLineThroughTheAxisIsClippedAtTheGround) {
  const MoundShape m{0.0, 0.0, 0.4, 0.2};
  EXPECT_NEAR(contact_length(m, 0.0, {{0.0, -1.0, 0.0}, {0.0, 1.0, 0.0}}), 0.2, 1e-12);
  EXPECT_NEAR(contact_length(m, 0.0, {{0.0, 0.05, 0.0}, {0.0, 1.0, 0.0}}), 0.15, 1e-12);
  EXPECT_EQ(contact_length(m, 0.0, {{1.0, 0.1, 0.0}, {2.0, 0.1, 0.0}}), 0.0);
}

}  // namespace
}  // namespace terracut
