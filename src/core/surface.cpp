// The terrain surface query. See surface.hpp.
#include "terracut/core/surface.hpp"

#include <algorithm>
#include <utility>

#include "geometry.hpp"

namespace terracut {

double surface_height_m(const GridSpec& spec, const float* h, Representation representation,
                        double x, double z) noexcept {
  return detail::SurfacePoint(spec, representation, x, z).height(h);
}

std::pair<double, double> surface_heights_m(const GridSpec& spec, const float* first_m, const float* second_m,
                                            Representation representation, double x, double z) noexcept {
  const detail::SurfacePoint p(spec, representation, x, z);
  return {p.height(first_m), p.height(second_m)};
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
