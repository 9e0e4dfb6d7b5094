// The terrain surface query. See surface.hpp.
#include "terracut/core/surface.hpp"

#include <algorithm>

#include "geometry.hpp"

namespace terracut {

double surface_height_m(const GridSpec& spec, const float* h, Representation representation,
                        double x, double z) noexcept {
  const int cols = spec.cols, rows = spec.rows;
  const double u = (x - spec.origin_m.x) / spec.cell_x_m();
  const double v = (z - spec.origin_m.z) / spec.cell_z_m();
  if (!(u >= 0.0 && u <= cols && v >= 0.0 && v <= rows)) return 0.0;
  if (representation == Representation::kColumns) {
    int c = std::min(int(u), cols - 1), r = std::min(int(v), rows - 1);
    return h[std::int64_t(r) * cols + c];
  }
  // Node coordinates (sample (c, r) at integer (c, r)), clamped to the outer
  // samples: the half-cell border is flat.
  double us = std::clamp(u - 0.5, 0.0, double(cols - 1));
  double vs = std::clamp(v - 0.5, 0.0, double(rows - 1));
  int i = std::clamp(int(us), 0, std::max(cols - 2, 0));
  int j = std::clamp(int(vs), 0, std::max(rows - 2, 0));
  double a = us - i, b = vs - j;
  double h00 = detail::clamped_height(h, cols, rows, i, j);
  double h10 = detail::clamped_height(h, cols, rows, i + 1, j);
  double h01 = detail::clamped_height(h, cols, rows, i, j + 1);
  double h11 = detail::clamped_height(h, cols, rows, i + 1, j + 1);
  return detail::surface_in_square(h00, h10, h01, h11, a, b, a + b <= 1.0);
}

double surface_height_m(const HeightGrid& grid, Representation representation, double x,
                        double z) noexcept {
  return surface_height_m(grid.spec(), grid.heights(), representation, x, z);
}

double surface_y_m(const HeightGrid& grid, Representation representation, double x,
                   double z) noexcept {
  return grid.spec().origin_m.y + surface_height_m(grid, representation, x, z);
}

}  // namespace terracut
