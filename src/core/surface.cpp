// The terrain surface query. See surface.hpp.
#include "terracut/core/surface.hpp"

#include <algorithm>
#include <utility>

#include "geometry.hpp"

namespace terracut {

namespace {

/// Where (x, z) falls among the samples, found once for any layer laid out
/// as spec says: outside the terrain (height 0), a column's sample, or a
/// square of the triangulated surface with the point's place in it.
struct SurfacePoint {
  bool outside = true;
  bool columns = false;
  std::int64_t sample = 0;  // kColumns: the cell's sample
  int i = 0, j = 0;         // kSurface: the square's first node
  double a = 0.0, b = 0.0;  // and the point's offsets in it

  SurfacePoint(const GridSpec& spec, Representation representation, double x, double z) {
    const int cols = spec.cols, rows = spec.rows;
    const double u = (x - spec.origin_m.x) / spec.cell_x_m();
    const double v = (z - spec.origin_m.z) / spec.cell_z_m();
    if (!(u >= 0.0 && u <= cols && v >= 0.0 && v <= rows)) return;
    outside = false;
    if (representation == Representation::kColumns) {
      columns = true;
      const int c = std::min(int(u), cols - 1), r = std::min(int(v), rows - 1);
      sample = std::int64_t(r) * cols + c;
      return;
    }
    // Node coordinates (sample (c, r) at integer (c, r)), clamped to the
    // outer samples: the half-cell border is flat.
    const double us = std::clamp(u - 0.5, 0.0, double(cols - 1));
    const double vs = std::clamp(v - 0.5, 0.0, double(rows - 1));
    i = std::clamp(int(us), 0, std::max(cols - 2, 0));
    j = std::clamp(int(vs), 0, std::max(rows - 2, 0));
    a = us - i;
    b = vs - j;
  }

  double height(const GridSpec& spec, const float* h) const {
    if (outside) return 0.0;
    if (columns) return h[sample];
    const int cols = spec.cols, rows = spec.rows;
    const double h00 = detail::clamped_height(h, cols, rows, i, j);
    const double h10 = detail::clamped_height(h, cols, rows, i + 1, j);
    const double h01 = detail::clamped_height(h, cols, rows, i, j + 1);
    const double h11 = detail::clamped_height(h, cols, rows, i + 1, j + 1);
    return detail::surface_in_square(h00, h10, h01, h11, a, b, a + b <= 1.0);
  }
};

}  // namespace

double surface_height_m(const GridSpec& spec, const float* h, Representation representation,
                        double x, double z) noexcept {
  return SurfacePoint(spec, representation, x, z).height(spec, h);
}

std::pair<double, double> surface_heights_m(const GridSpec& spec, const float* first_m, const float* second_m,
                                            Representation representation, double x, double z) noexcept {
  const SurfacePoint p(spec, representation, x, z);
  return {p.height(spec, first_m), p.height(spec, second_m)};
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
