// Built-in terrains and the exact dome geometry. See generators.hpp.
#include "terracut/core/generators.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut {

Generator default_generator(GeneratorKind kind, const GridSpec& spec) {
  Generator g;
  g.kind = kind;
  g.mound.centre_x_m = spec.origin_m.x + 0.5 * spec.size_x_m;
  g.mound.centre_z_m = spec.origin_m.z + 0.5 * spec.size_z_m;
  g.mound.radius_m = 0.4 * std::min(spec.size_x_m, spec.size_z_m);
  g.mound.height_m = spec.full_scale_m;
  g.box.min_x_m = spec.origin_m.x;
  g.box.min_z_m = spec.origin_m.z;
  g.box.max_x_m = spec.origin_m.x + spec.size_x_m;
  g.box.max_z_m = spec.origin_m.z + spec.size_z_m;
  g.box.height_m = spec.full_scale_m;
  g.plane.height_m = spec.full_scale_m;
  return g;
}

std::string validate(const Generator& g) {
  auto finite = [](double v) { return std::isfinite(v); };
  switch (g.kind) {
    case GeneratorKind::kMound:
      if (!finite(g.mound.centre_x_m) || !finite(g.mound.centre_z_m))
        return "mound.centre_m must be finite";
      if (!finite(g.mound.radius_m) || !(g.mound.radius_m > 0.0))
        return must_be("mound.radius_m", "finite and > 0", g.mound.radius_m);
      if (!finite(g.mound.height_m) || !(g.mound.height_m > 0.0))
        return must_be("mound.height_m", "finite and > 0", g.mound.height_m);
      return {};
    case GeneratorKind::kBox:
      if (!finite(g.box.min_x_m) || !finite(g.box.min_z_m) || !finite(g.box.max_x_m) ||
          !finite(g.box.max_z_m))
        return "box.min_m and box.max_m must be finite";
      if (!(g.box.min_x_m <= g.box.max_x_m) || !(g.box.min_z_m <= g.box.max_z_m))
        return "box.min_m must be <= box.max_m in X and in Z";
      if (!finite(g.box.height_m) || !(g.box.height_m >= 0.0))
        return must_be("box.height_m", "finite and >= 0", g.box.height_m);
      return {};
    case GeneratorKind::kPlane:
      if (!finite(g.plane.height_m) || !(g.plane.height_m >= 0.0))
        return must_be("plane.height_m", "finite and >= 0", g.plane.height_m);
      return {};
  }
  return "unknown generator kind";
}

double height_at(const MoundShape& m, double x_m, double z_m) {
  const double dx = (x_m - m.centre_x_m) / m.radius_m;
  const double dz = (z_m - m.centre_z_m) / m.radius_m;
  const double q = 1.0 - (dx * dx + dz * dz);
  return q > 0.0 ? m.height_m * std::sqrt(q) : 0.0;
}

double height_at(const BoxShape& b, double x_m, double z_m) {
  const bool inside = x_m >= b.min_x_m && x_m <= b.max_x_m && z_m >= b.min_z_m && z_m <= b.max_z_m;
  return inside ? b.height_m : 0.0;
}

double height_at(const Generator& g, double x_m, double z_m) {
  switch (g.kind) {
    case GeneratorKind::kMound:
      return height_at(g.mound, x_m, z_m);
    case GeneratorKind::kBox:
      return height_at(g.box, x_m, z_m);
    case GeneratorKind::kPlane:
      return g.plane.height_m;
  }
  return 0.0;
}

std::vector<float> generate_heights(const GridSpec& spec, const Generator& generator) {
  // Before the allocation: a spec past the caps (or with a negative side,
  // whose sample count wraps) would ask for gigabytes.
  if (const std::string problem = validate(spec); !problem.empty()) throw InputError(problem);
  std::vector<float> heights(static_cast<std::size_t>(spec.sample_count()));
  // Sample (c, r) sits at its cell centre, the same point HeightGrid uses.
  for (int r = 0; r < spec.rows; ++r) {
    const double z = spec.origin_m.z + (r + 0.5) * spec.cell_z_m();
    for (int c = 0; c < spec.cols; ++c) {
      const double x = spec.origin_m.x + (c + 0.5) * spec.cell_x_m();
      heights[static_cast<std::size_t>(r) * spec.cols + c] =
          static_cast<float>(height_at(generator, x, z));
    }
  }
  return heights;
}

double contact_length(const MoundShape& m, double ground_y_m, const Segment& edge) {
  // Work in the dome's normalised coordinates, where it is the upper half of
  // the unit ball: u = (x-xc)/R, v = (y-ground)/H, w = (z-zc)/R.
  const Vec3 a{(edge.a.x - m.centre_x_m) / m.radius_m, (edge.a.y - ground_y_m) / m.height_m,
               (edge.a.z - m.centre_z_m) / m.radius_m};
  const Vec3 b{(edge.b.x - m.centre_x_m) / m.radius_m, (edge.b.y - ground_y_m) / m.height_m,
               (edge.b.z - m.centre_z_m) / m.radius_m};
  const Vec3 d = b - a;
  const double seg_len = length(edge.b - edge.a);
  if (!(seg_len > 0.0)) return 0.0;

  // Inside the ball: |a + t d|^2 <= 1, a quadratic in t.
  const double qa = dot(d, d);
  const double qb = 2.0 * dot(a, d);
  const double qc = dot(a, a) - 1.0;
  const double disc = qb * qb - 4.0 * qa * qc;
  if (!(disc > 0.0)) return 0.0;
  const double root = std::sqrt(disc);
  double t0 = (-qb - root) / (2.0 * qa);
  double t1 = (-qb + root) / (2.0 * qa);
  t0 = std::max(t0, 0.0);
  t1 = std::min(t1, 1.0);

  // Above the ground: v(t) = a.y + t d.y >= 0, a half-line in t.
  if (d.y > 0.0) {
    t0 = std::max(t0, -a.y / d.y);
  } else if (d.y < 0.0) {
    t1 = std::min(t1, -a.y / d.y);
  } else if (a.y < 0.0) {
    return 0.0;
  }
  return t1 > t0 ? (t1 - t0) * seg_len : 0.0;
}

double horizontal_chord_m(const MoundShape& m, double y_above_ground_m, double z_m) {
  if (y_above_ground_m < 0.0 || y_above_ground_m > m.height_m) return 0.0;
  const double s = y_above_ground_m / m.height_m;
  const double r = m.radius_m * std::sqrt(std::max(0.0, 1.0 - s * s));
  const double dz = z_m - m.centre_z_m;
  const double q = r * r - dz * dz;
  return q > 0.0 ? 2.0 * std::sqrt(q) : 0.0;
}

}  // namespace terracut
