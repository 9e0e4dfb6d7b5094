// Rigid bodies of a scenario: plain data describing loose objects (rocks,
// blocks, debris) that rest on or in the soil. The core does not simulate
// them; a physics engine adapter (terracut::bullet::TerrainWorld) does.
//
// Every body is a box, a sphere or a cylinder whose centre is at
// `position_m` and whose local axes are rotated by `rotation_deg` (Euler
// angles in degrees, extrinsic X then Y then Z, the same convention as the
// blade keyframes: quat_from_euler_deg). A cylinder's axis is its local Y.
#pragma once

#include <optional>
#include <utility>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/ranges.hpp"

namespace terracut {

/// The collision shape of a rigid body.
enum class BodyShape {
  kBox,       ///< a box of full edge lengths size_m (local X, Y, Z)
  kSphere,    ///< a sphere of radius radius_m
  kCylinder,  ///< a cylinder of radius radius_m and full height height_m along local Y
};

/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<BodyShape> kBodyShapeNames[] = {
    {BodyShape::kBox, "box"},
    {BodyShape::kSphere, "sphere"},
    {BodyShape::kCylinder, "cylinder"},
};
constexpr std::span<const EnumName<BodyShape>> enum_names(BodyShape) { return kBodyShapeNames; }

/// Longest accepted body name, characters.
inline constexpr std::size_t kMaxBodyNameLength = 64;
/// Largest accepted body dimension (edge, radius, height), metres; more is refused as absurd.
inline constexpr double kMaxBodyDimensionM = 1e3;

/// One rigid body: shape, size, mass, initial pose and surface properties.
/// Parameters, read-only during a run; the body's moving pose is engine state.
struct BodySpec {
  /// Name used in outputs (bodies.csv): 1 to kMaxBodyNameLength characters
  /// among letters, digits, '_', '-' and '.'.
  std::string name = "body";
  BodyShape shape = BodyShape::kBox;
  /// Box only: FULL edge lengths along the body's local X, Y, Z (not half
  /// extents), metres, each in (0, kMaxBodyDimensionM].
  Vec3 size_m{0.1, 0.1, 0.1};
  /// Sphere and cylinder: radius, metres, in (0, kMaxBodyDimensionM].
  double radius_m = 0.05;
  /// Cylinder only: full height along the local Y axis, metres, in (0, kMaxBodyDimensionM].
  double height_m = 0.1;
  /// Mass, kilograms, >= 0 and finite; 0 makes the body static (it never moves).
  double mass_kg = 1.0;
  /// Initial world position of the body's centre (centre of mass), metres.
  Vec3 position_m{};
  /// Initial rotation, degrees, extrinsic X then Y then Z (see quat_from_euler_deg).
  Vec3 rotation_deg{};
  /// Coulomb friction coefficient, in [0, 10]. The engine combines two
  /// touching surfaces' coefficients by multiplying them.
  double friction = 0.6;
  /// Coefficient of restitution (bounciness), in [0, 1]; combined by multiplying.
  double restitution = 0.0;
  /// Buried in the soil: the soil covers the body's top over its whole
  /// footprint at the start (buried_problem checks it). The engine holds a
  /// buried body still (the soil carries it) until the blade reaches it,
  /// then it moves freely (docs/bullet.md, "Buried bodies").
  bool buried = false;
};

/// Returns an empty string when spec is valid, else a message naming the bad
/// field, e.g. "radius_m must be > 0, got -1" (the caller adds which body).
std::string validate(const BodySpec& spec);
/// The ranges of BodySpec's numbers, which validate() checks (core/ranges.hpp);
/// size_m[i] for each edge of a box.
std::span<const Range> body_ranges();

/// Checks a list of bodies: each one (validate above) and that names are
/// unique. Returns an empty string when valid, else a message naming the body
/// as "bodies[i] (NAME): problem".
std::string validate(const std::vector<BodySpec>& bodies);

/// The initial orientation of the body: quat_from_euler_deg(spec.rotation_deg).
Quat initial_orientation(const BodySpec& spec);

/// Half of the body's extent along its local axes, metres: the box's half
/// sizes, (r, r, r) for a sphere, (r, h/2, r) for a cylinder.
Vec3 half_extents_m(const BodySpec& spec);

/// The world axis-aligned box of a body at its initial pose, metres (lo, hi):
/// exact for a box's corners, a sphere and a cylinder's rims.
std::pair<Vec3, Vec3> initial_bounds_m(const BodySpec& spec);

/// For a buried body: empty when the soil covers its top over its whole
/// footprint (every sample whose centre lies under its bounding box has a
/// height above the body's highest point), else what is wrong, starting with
/// "buried: " (the caller adds which body). heights: the grid's initial
/// heights, spec.rows x spec.cols. Not buried: always empty.
std::string buried_problem(const BodySpec& body, const GridSpec& grid, const float* heights);

/// Where one rigid body is and what it looks like, as a viewer draws it.
struct BodyView {
  BodyShape shape = BodyShape::kBox;  ///< box, sphere or cylinder (axis = local Y)
  /// Half of the body's extent along its local axes, metres, each > 0: a
  /// box's half sizes, (r, r, r) for a sphere, (r, h/2, r) for a cylinder
  /// (half_extents_m() of its BodySpec).
  Vec3 half_extents_m{};
  Vec3 position_m{};    ///< centre, world metres
  Quat orientation{};   ///< body frame -> world, unit quaternion
  bool active = true;   ///< false while the physics engine has it asleep
};

/// Something that simulates the scenario's rigid bodies and can say where
/// they are (the Bullet listener, terracut/bullet/bodies_listener.hpp). The
/// haptic loop reads it for the viewer's frames; the core knows no engine.
class BodySource {
 public:
  virtual ~BodySource() = default;
  /// Number of bodies simulated.
  virtual int body_total() const noexcept = 0;
  /// Writes the first min(body_total(), out.size()) bodies into out and
  /// returns how many it wrote. Called on the stepping thread between steps;
  /// must not allocate or throw.
  virtual int write_bodies(std::span<BodyView> out) const noexcept = 0;
};

}  // namespace terracut
