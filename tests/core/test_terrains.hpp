// Terrains with known exact geometry, shared by the core tests, and the
// float slack of a volume kept on them.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "terracut/core/grid.hpp"

namespace terracut::test {

/// A grid of cols x rows over [0, size] x [0, size] with ground at y = 0.
inline GridSpec square_spec(int cols, int rows, double size_m = 1.0, double full_scale_m = 1.0) {
  GridSpec s;
  s.cols = cols;
  s.rows = rows;
  s.size_x_m = size_m;
  s.size_z_m = size_m;
  s.full_scale_m = full_scale_m;
  return s;
}

/// Heights of a dome h = H sqrt(1 - (r/R)^2) sampled at the cell centres.
inline std::vector<float> dome(const GridSpec& s, double cx, double cz, double radius, double height) {
  std::vector<float> h(size_t(s.sample_count()));
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) {
      double x = s.origin_m.x + (c + 0.5) * s.cell_x_m() - cx;
      double z = s.origin_m.z + (r + 0.5) * s.cell_z_m() - cz;
      double q = 1.0 - (x * x + z * z) / (radius * radius);
      h[size_t(r) * s.cols + c] = q > 0.0 ? float(height * std::sqrt(q)) : 0.0f;
    }
  }
  return h;
}

/// Exact contact of a horizontal line at height y along X through the dome,
/// at depth z (the blade spans the dome): the chord of the circular section.
inline double dome_chord(double y, double z, double cz, double radius, double height) {
  if (y < 0.0 || y >= height) return 0.0;
  double r = radius * std::sqrt(1.0 - (y / height) * (y / height));
  double dz = z - cz;
  return std::abs(dz) < r ? 2.0 * std::sqrt(r * r - dz * dz) : 0.0;
}

/// Heights H on cells [c0, c1) x [r0, r1), 0 elsewhere.
inline std::vector<float> block(const GridSpec& s, int c0, int c1, int r0, int r1, float height) {
  std::vector<float> h(size_t(s.sample_count()), 0.0f);
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c) h[size_t(r) * s.cols + c] = height;
  return h;
}

/// The volume the float heights can drift by in a run that gives each
/// step's rounding back: one float rounding (eps x the highest height) per
/// sample.
inline double float_rounding_m3(const HeightGrid& g, double highest_m) {
  return double(g.spec().sample_count()) * double(std::numeric_limits<float>::epsilon()) * highest_m *
         g.spec().cell_area_m2();
}

}  // namespace terracut::test
