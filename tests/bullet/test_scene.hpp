// Shared set-ups of the Bullet world tests: grids, bodies and a scene with a
// cut under one body, a pushed body and two bodies away from the action.
#pragma once

#include <string>
#include <vector>

#include "terracut/bullet/terrain_world.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::bullet::test {

inline GridSpec spec(int cols, int rows, double size_x, double size_z, Vec3 origin = {},
                     double full_scale = 0.4) {
  GridSpec g;
  g.cols = cols;
  g.rows = rows;
  g.size_x_m = size_x;
  g.size_z_m = size_z;
  g.origin_m = origin;
  g.full_scale_m = full_scale;
  return g;
}

inline BodySpec box(const std::string& name, Vec3 size, double mass, Vec3 position) {
  BodySpec b;
  b.name = name;
  b.shape = BodyShape::kBox;
  b.size_m = size;
  b.mass_kg = mass;
  b.position_m = position;
  return b;
}

// 1 m x 1 m of soil that flows on 100 x 100 samples (1 cm cells), a blade
// of the given length, and a relaxation cap that keeps a pushed pile up
// with the blade.
inline SimParams flow_on_1cm(double blade_length_m) {
  SimParams p;
  p.grid = spec(100, 100, 1.0, 1.0);
  p.blade.length_m = blade_length_m;
  p.soil.model = SoilModel::kFlow;
  p.soil.max_pair_checks_per_step = 400000;
  return p;
}

inline TerrainWorldParams no_tool() {
  TerrainWorldParams p;
  p.tool.enabled = false;
  return p;
}

// A scene with a cut under one cube, a cube pushed by the plate and a sphere
// and a cylinder away from the action.
struct Scene {
  Simulation sim;
  TerrainWorld world;

  static SimParams params() {
    SimParams sp;
    sp.grid = spec(50, 50, 1.0, 1.0);
    sp.blade.length_m = 0.4;
    return sp;
  }
  static std::vector<BodySpec> bodies() {
    std::vector<BodySpec> b = {box("cut", {0.2, 0.2, 0.2}, 8.0, {0.3, 0.4, 0.5}),
                               box("pushed", {0.1, 0.1, 0.1}, 2.0, {0.75, 0.35, 0.5})};
    BodySpec s;
    s.name = "ball";
    s.shape = BodyShape::kSphere;
    s.radius_m = 0.05;
    s.position_m = {0.5, 0.35, 0.9};
    BodySpec c;
    c.name = "can";
    c.shape = BodyShape::kCylinder;
    c.radius_m = 0.04;
    c.height_m = 0.1;
    c.rotation_deg = {90, 0, 0};
    c.position_m = {0.9, 0.34, 0.1};
    b.push_back(s);
    b.push_back(c);
    return b;
  }
  Scene() : sim(params(), std::vector<float>(2500, 0.3f)), world(sim, bodies()) {}

  // Step i of a 3 s motion: a level pass 0.15 m deep under "cut" (edge along
  // Z; the 0.1 m plate stays under the soil top), then a pass 1 cm above the
  // soil pushing "pushed" along +X.
  const StepOutput& step(int i) {
    const double t = i / 1000.0;
    BladePose pose;
    pose.orientation = quat_from_euler_deg({0, 90, 0});
    if (t < 1.5) {
      pose.position_m = {0.1 + 0.4 * t / 1.5, 0.15, 0.5};
    } else {
      if (i == 1500) {
        sim.lift();
        world.lift_tool();
      }
      pose.position_m = {0.6 + 0.2 * (t - 1.5) / 1.5, 0.31, 0.5};
    }
    const StepOutput& out = sim.step(pose);
    world.step(out);
    return out;
  }
};

}  // namespace terracut::bullet::test
