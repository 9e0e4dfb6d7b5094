#include "terracut/core/bodies.hpp"

#include <cctype>
#include <cmath>
#include <sstream>

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

// Appends "FIELD must be in (0, max], got V" to msg when v is not a valid dimension.
bool check_dimension(std::ostringstream& msg, const char* field, double v) {
  if (std::isfinite(v) && v > 0.0 && v <= kMaxBodyDimensionM) return true;
  msg << field << " must be in (0, " << kMaxBodyDimensionM << "] metres, got " << v;
  return false;
}

}  // namespace

std::string validate(const BodySpec& spec) {
  std::ostringstream msg;
  if (!valid_name(spec.name)) {
    msg << "name '" << spec.name << "' must be 1 to " << kMaxBodyNameLength
        << " characters among letters, digits, '_', '-' and '.'";
    return msg.str();
  }
  switch (spec.shape) {
    case BodyShape::kBox:
      if (!check_dimension(msg, "size_m[0]", spec.size_m.x) ||
          !check_dimension(msg, "size_m[1]", spec.size_m.y) ||
          !check_dimension(msg, "size_m[2]", spec.size_m.z))
        return msg.str();
      break;
    case BodyShape::kSphere:
      if (!check_dimension(msg, "radius_m", spec.radius_m)) return msg.str();
      break;
    case BodyShape::kCylinder:
      if (!check_dimension(msg, "radius_m", spec.radius_m) ||
          !check_dimension(msg, "height_m", spec.height_m))
        return msg.str();
      break;
    default:
      return "shape must be box, sphere or cylinder";
  }
  if (!(std::isfinite(spec.mass_kg) && spec.mass_kg >= 0.0)) {
    msg << "mass_kg must be finite and >= 0 (0 = static), got " << spec.mass_kg;
  } else if (!is_finite(spec.position_m)) {
    msg << "position_m must be finite";
  } else if (!is_finite(spec.rotation_deg)) {
    msg << "rotation_deg must be finite";
  } else if (!(spec.friction >= 0.0 && spec.friction <= 10.0)) {
    msg << "friction must be in [0, 10], got " << spec.friction;
  } else if (!(spec.restitution >= 0.0 && spec.restitution <= 1.0)) {
    msg << "restitution must be in [0, 1], got " << spec.restitution;
  }
  return msg.str();
}

std::string validate(const std::vector<BodySpec>& bodies) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    std::string problem = validate(bodies[i]);
    if (problem.empty()) {
      for (std::size_t j = 0; j < i; ++j) {
        if (bodies[j].name == bodies[i].name) {
          problem = "duplicate name (also bodies[" + std::to_string(j) + "])";
          break;
        }
      }
    }
    if (!problem.empty())
      return "bodies[" + std::to_string(i) + "] (" + bodies[i].name + "): " + problem;
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
