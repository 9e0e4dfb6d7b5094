#include "terracut/core/bodies.hpp"

#include <cctype>
#include <cmath>

#include "terracut/core/format.hpp"

namespace terracut {

std::string_view to_string(BodyShape shape) {
  switch (shape) {
    case BodyShape::kBox:
      return "box";
    case BodyShape::kSphere:
      return "sphere";
    case BodyShape::kCylinder:
      return "cylinder";
  }
  return "unknown";
}

std::optional<BodyShape> parse_body_shape(std::string_view name) {
  if (name == "box") return BodyShape::kBox;
  if (name == "sphere") return BodyShape::kSphere;
  if (name == "cylinder") return BodyShape::kCylinder;
  return std::nullopt;
}

namespace {

bool valid_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxBodyNameLength) return false;
  for (char ch : name) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
  }
  return true;
}

// "FIELD must be in (0, max] metres, got V" when v is not a valid dimension, else "".
std::string check_dimension(const char* field, double v) {
  if (std::isfinite(v) && v > 0.0 && v <= kMaxBodyDimensionM) return {};
  return must_be(field, "in (0, " + format_number(kMaxBodyDimensionM) + "] metres", v);
}

}  // namespace

std::string validate(const BodySpec& spec) {
  if (!valid_name(spec.name))
    return "name '" + spec.name + "' must be 1 to " + format_number(kMaxBodyNameLength) +
           " characters among letters, digits, '_', '-' and '.'";
  std::string m;
  switch (spec.shape) {
    case BodyShape::kBox:
      if (!(m = check_dimension("size_m[0]", spec.size_m.x)).empty() ||
          !(m = check_dimension("size_m[1]", spec.size_m.y)).empty() ||
          !(m = check_dimension("size_m[2]", spec.size_m.z)).empty())
        return m;
      break;
    case BodyShape::kSphere:
      if (!(m = check_dimension("radius_m", spec.radius_m)).empty()) return m;
      break;
    case BodyShape::kCylinder:
      if (!(m = check_dimension("radius_m", spec.radius_m)).empty() ||
          !(m = check_dimension("height_m", spec.height_m)).empty())
        return m;
      break;
    default:
      return "shape must be box, sphere or cylinder";
  }
  if (!(std::isfinite(spec.mass_kg) && spec.mass_kg >= 0.0))
    return must_be("mass_kg", "finite and >= 0 (0 = static)", spec.mass_kg);
  if (!is_finite(spec.position_m)) return "position_m must be finite";
  if (!is_finite(spec.rotation_deg)) return "rotation_deg must be finite";
  if (!(spec.friction >= 0.0 && spec.friction <= 10.0))
    return must_be("friction", "in [0, 10]", spec.friction);
  if (!(spec.restitution >= 0.0 && spec.restitution <= 1.0))
    return must_be("restitution", "in [0, 1]", spec.restitution);
  return {};
}

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
