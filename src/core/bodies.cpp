#include "terracut/core/bodies.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "terracut/core/format.hpp"

namespace terracut {

namespace {

bool valid_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxBodyNameLength) return false;
  for (char ch : name) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
  }
  return true;
}

constexpr Range kRanges[] = {
    {"size_m[0]", 0.0, kMaxBodyDimensionM, RangeEnds::kOpenLow},
    {"size_m[1]", 0.0, kMaxBodyDimensionM, RangeEnds::kOpenLow},
    {"size_m[2]", 0.0, kMaxBodyDimensionM, RangeEnds::kOpenLow},
    {"radius_m", 0.0, kMaxBodyDimensionM, RangeEnds::kOpenLow},
    {"height_m", 0.0, kMaxBodyDimensionM, RangeEnds::kOpenLow},
    {"mass_kg", 0.0, kRangeMax, RangeEnds::kClosed},  // 0: static
    {"friction", 0.0, 10.0, RangeEnds::kClosed},
    {"restitution", 0.0, 1.0, RangeEnds::kClosed},
};

// "FIELD must be ..." when v is outside its entry of kRanges, else "".
std::string check_number(std::string_view field, double v) {
  return check(find_range(kRanges, field), v);
}

}  // namespace

std::string validate(const BodySpec& spec) {
  if (!valid_name(spec.name))
    return "name '" + spec.name + "' must be 1 to " + format_number(kMaxBodyNameLength) +
           " characters among letters, digits, '_', '-' and '.'";
  std::string m;
  switch (spec.shape) {
    case BodyShape::kBox:
      if (!(m = check_number("size_m[0]", spec.size_m.x)).empty() ||
          !(m = check_number("size_m[1]", spec.size_m.y)).empty() ||
          !(m = check_number("size_m[2]", spec.size_m.z)).empty())
        return m;
      break;
    case BodyShape::kSphere:
      if (!(m = check_number("radius_m", spec.radius_m)).empty()) return m;
      break;
    case BodyShape::kCylinder:
      if (!(m = check_number("radius_m", spec.radius_m)).empty() ||
          !(m = check_number("height_m", spec.height_m)).empty())
        return m;
      break;
    default:
      return "shape must be box, sphere or cylinder";
  }
  if (auto m = check_number("mass_kg", spec.mass_kg); !m.empty()) return m;
  if (!is_finite(spec.position_m)) return "position_m must be finite";
  if (!is_finite(spec.rotation_deg)) return "rotation_deg must be finite";
  if (auto m = check_number("friction", spec.friction); !m.empty()) return m;
  return check_number("restitution", spec.restitution);
}

std::span<const Range> body_ranges() { return kRanges; }

std::string validate(const std::vector<BodySpec>& bodies) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    std::string problem = validate(bodies[i]);
    if (problem.empty()) {
      for (std::size_t j = 0; j < i; ++j) {
        if (bodies[j].name == bodies[i].name) {
          problem = "duplicate name (also bodies[" + format_number(j) + "])";
          break;
        }
      }
    }
    if (!problem.empty())
      return "bodies[" + format_number(i) + "] (" + bodies[i].name + "): " + problem;
  }
  return {};
}

Quat initial_orientation(const BodySpec& spec) { return quat_from_euler_deg(spec.rotation_deg); }

Vec3 half_extents_m(const BodySpec& spec) {
  switch (spec.shape) {
    case BodyShape::kBox:
      return spec.size_m * 0.5;
    case BodyShape::kSphere:
      return {spec.radius_m, spec.radius_m, spec.radius_m};
    case BodyShape::kCylinder:
      return {spec.radius_m, spec.height_m * 0.5, spec.radius_m};
  }
  return {};
}

}  // namespace terracut

namespace terracut {

std::pair<Vec3, Vec3> initial_bounds_m(const BodySpec& spec) {
  const Vec3 h = half_extents_m(spec);
  const Quat q = normalized(initial_orientation(spec));
  // The body's local axes in the world.
  const Vec3 ax = rotate(q, {1.0, 0.0, 0.0}), ay = rotate(q, {0.0, 1.0, 0.0}),
             az = rotate(q, {0.0, 0.0, 1.0});
  Vec3 e{};
  switch (spec.shape) {
    case BodyShape::kSphere:
      e = h;
      break;
    case BodyShape::kBox:
      e = {std::fabs(ax.x) * h.x + std::fabs(ay.x) * h.y + std::fabs(az.x) * h.z,
           std::fabs(ax.y) * h.x + std::fabs(ay.y) * h.y + std::fabs(az.y) * h.z,
           std::fabs(ax.z) * h.x + std::fabs(ay.z) * h.y + std::fabs(az.z) * h.z};
      break;
    case BodyShape::kCylinder: {
      // The axis' half length plus the rim's reach: r sqrt(1 - axis_i^2).
      const auto reach = [&](double a) {
        return std::fabs(a) * h.y + spec.radius_m * std::sqrt(std::max(0.0, 1.0 - a * a));
      };
      e = {reach(ay.x), reach(ay.y), reach(ay.z)};
      break;
    }
  }
  return {spec.position_m - e, spec.position_m + e};
}

std::string buried_problem(const BodySpec& body, const GridSpec& g, const float* heights) {
  if (!body.buried) return {};
  const auto [lo, hi] = initial_bounds_m(body);
  // The samples whose centres lie under the bounding box.
  const int c0 = std::max(0, int(std::ceil((lo.x - g.origin_m.x) / g.cell_x_m() - 0.5)));
  const int c1 = std::min(g.cols, int(std::floor((hi.x - g.origin_m.x) / g.cell_x_m() - 0.5)) + 1);
  const int r0 = std::max(0, int(std::ceil((lo.z - g.origin_m.z) / g.cell_z_m() - 0.5)));
  const int r1 = std::min(g.rows, int(std::floor((hi.z - g.origin_m.z) / g.cell_z_m() - 0.5)) + 1);
  if (c0 >= c1 || r0 >= r1)
    return "buried: the body is not over the terrain (no sample lies under it)";
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c) {
      const double soil_y = g.origin_m.y + double(heights[std::int64_t(r) * g.cols + c]);
      if (!(soil_y > hi.y))
        return "buried: the body's top (y = " + format_number(hi.y) +
               " m) is not under the soil at x = " +
               format_number(g.origin_m.x + (c + 0.5) * g.cell_x_m()) +
               " m, z = " + format_number(g.origin_m.z + (r + 0.5) * g.cell_z_m()) +
               " m (soil surface y = " + format_number(soil_y) +
               " m); a buried body must be covered over its whole footprint";
    }
  return {};
}

}  // namespace terracut
