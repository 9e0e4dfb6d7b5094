// The soil scenes that the tests (tests/core/soil_test.cpp), `terracut
// validate` (apps/terracut/validate_command.cpp) and the soil benchmark
// (bench/soil_bench.cpp) share, written once so they cannot drift apart.
// Heights are row-major, row r along +Z, metres. Internal to the project.
#pragma once

#include <vector>

#include "terracut/core/simulation.hpp"

namespace terracut::scenes {

/// An n x n grid with a column of height_m standing on a bare floor: the
/// samples within radius_cells of the grid's centre ((n - 1) / 2 in both
/// directions), 0 elsewhere. Relaxed, it collapses into a cone.
std::vector<float> column(int n, double radius_cells, float height_m);

/// A side x side grid with a square block of height_m on rows and columns
/// [lo, hi), 0 elsewhere (the collapse of the soil benchmark).
std::vector<float> block(int side, int lo, int hi, float height_m);

/// An n x n plane ramp on cells of cell_m: base_m + tan(slope_deg) x the
/// distance along +X from column 0 (or, diagonal, along the diagonal c = r
/// from sample (0, 0)).
std::vector<float> ramp(int n, double cell_m, double base_m, double slope_deg, bool diagonal);

/// Bulldozing: a flat layer of layer_m on cols x rows cells of cell_m, and
/// a level blade of blade_m whose edge stands depth_m into the layer at the
/// grid's middle in X, pushed along +Z.
struct Bulldoze {
  int cols = 0;
  int rows = 0;
  double cell_m = 0.01;
  double blade_m = 1.0;
  double layer_m = 0.2;
  double depth_m = 0.05;

  /// The blade's centre in X, m: the grid's middle.
  double x_m() const { return 0.5 * cols * cell_m; }
  /// The edge's height, m.
  double edge_y_m() const { return layer_m - depth_m; }
  /// The simulation's parameters: the grid, the blade's length, the soil.
  SimParams params(const SoilFlowParams& soil) const;
  /// The layer's heights.
  std::vector<float> heights() const;
  /// The blade's pose with its edge at z_m.
  BladePose pose(double z_m) const { return {{x_m(), edge_y_m(), z_m}, Quat{}}; }
};

}  // namespace terracut::scenes
