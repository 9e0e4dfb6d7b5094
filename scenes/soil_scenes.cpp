#include "soil_scenes.hpp"

#include <cmath>
#include <numbers>

namespace terracut::scenes {

std::vector<float> column(int n, double radius_cells, float height_m) {
  std::vector<float> h(std::size_t(n) * n, 0.0f);
  const double centre = 0.5 * (n - 1);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      if ((c - centre) * (c - centre) + (r - centre) * (r - centre) <= radius_cells * radius_cells)
        h[std::size_t(r) * n + c] = height_m;
  return h;
}

std::vector<float> block(int side, int lo, int hi, float height_m) {
  std::vector<float> h(std::size_t(side) * side, 0.0f);
  for (int r = lo; r < hi; ++r)
    for (int c = lo; c < hi; ++c) h[std::size_t(r) * side + c] = height_m;
  return h;
}

std::vector<float> ramp(int n, double cell_m, double base_m, double slope_deg, bool diagonal) {
  const double t = std::tan(slope_deg * (std::numbers::pi / 180.0));
  std::vector<float> h(std::size_t(n) * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const double along = diagonal ? (c + r) * cell_m / std::sqrt(2.0) : c * cell_m;
      h[std::size_t(r) * n + c] = float(base_m + t * along);
    }
  return h;
}

SimParams Bulldoze::params(const SoilFlowParams& soil) const {
  SimParams p;
  p.grid = grid_of_cells(cols, rows, cell_m);
  p.blade.length_m = blade_m;
  p.soil = soil;
  return p;
}

std::vector<float> Bulldoze::heights() const {
  return std::vector<float>(std::size_t(cols) * rows, float(layer_m));
}

}  // namespace terracut::scenes
