// A Bullet rigid-body world that shares the deformable terrain.
//
// TerrainWorld owns a btDiscreteDynamicsWorld whose ground is a
// btHeightfieldTerrainShape reading the HeightGrid's own heights() array in
// place (no copy): cuts made by the Simulation are seen by Bullet at once and
// the shape is never recreated. Loose rigid bodies (BodySpec: box, sphere,
// cylinder) rest on it, and the blade is a plate that pushes them:
// kinematic (it goes where the blade goes), or, with the arm's force limit
// (ToolPlateSpec::force_limit_n), a dynamic body driven to the blade pose
// by a servo whose force is capped at the limit less the soil's force, so
// that it stops short against a body it cannot move (docs/bullet.md, "The
// arm's force limit").
//
// Placement (see docs/bullet.md): Bullet vertex (x, j) of the heightfield is
// grid sample (c, r) = (x, j), at world
//   (sample_x(c), origin_m.y + height(c, r), sample_z(r)).
// Bullet triangulates each square of four neighbouring samples along the
// diagonal from sample (c+1, r) to (c, r+1), which is terracut's `surface`
// representation; the surface's flat half-cell border around the grid is not
// part of the Bullet shape (a static floor plane at the ground level catches
// whatever leaves the terrain).
//
// Height bounds: Bullet needs every height inside [min, max] fixed at
// construction. min = 0 (the rigid floor: HeightGrid never goes below it);
// max = TerrainWorldParams::max_height_m, or by default
// max(2 * full_scale_m, highest initial height + full_scale_m): room for
// piles at least one full scale above the initial terrain. After an edit,
// terrain_changed() lowers any sample above max to max and counts it
// (BoundsReport); it is never silent.
//
// After an edit of a rectangle of samples, terrain_changed() wakes the bodies
// whose bounding box overlaps the triangles touching that rectangle and drops
// their cached contact points with the terrain, so they fall at once instead
// of hovering on stale contacts.
//
// Buried bodies (BodySpec::buried: the soil covers them) are held still,
// static in Bullet and touching nothing (the soil carries them; a buried
// body that fell would sink through the heightfield, which is only a
// surface), until the blade reaches one: the cut lowers the soil over its
// footprint to its top, or the tool plate's box meets its box; with a
// force-limited plate, until the plate pushes it harder than its break-out
// force (break_out_resistance_n: the soil's passive earth pressure on it
// and the shear under it), or a cut takes the soil under its centre down
// to its bottom. Then it is released: it becomes dynamic, and the soil it stood in (the samples under
// its bounding box and one more all round, so that no terrain triangle cuts
// into it) is lowered to its lowest point, where it rests; the plate then
// meets it through Bullet. docs/bullet.md, "Buried bodies".
//
// Piles (TerrainWorldParams::pile, on with soil that flows): the soil
// keeps a ring of one sample free round each body (soil_obstacle), a body
// that moved into soil pushes what stands in its ring a sample out, and the
// soil outside the ring presses on the body's sides with Rankine's active
// earth pressure, instead of the ramp a heightfield makes from a pile to
// the samples under a body (which Bullet climbed). docs/bullet.md, "Piles
// against bodies".
//
// The code has one room per model: src/bullet/terrain_world.cpp (the world,
// its step, terrain edits, the tool plate), buried_bodies.cpp (holding and
// releasing buried bodies, their break-out force), pile_pressure.cpp (the rings, the soil a body
// sheds and the earth pressure; its parameters in pile_pressure.hpp).
//
// One step (step(out)) after each Simulation::step: terrain_changed(changed
// rectangle), move the tool plate to the blade pose, advance Bullet by exactly
// 1 / rate_hz (one fixed sub-step: deterministic), and sum the tool's contact
// impulses into a force. After the first steps (Bullet's internal arrays grow
// to their working size) a step allocates nothing.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "terracut/bullet/pile_pressure.hpp"
#include "terracut/core/bodies.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/core/soil.hpp"

class btDiscreteDynamicsWorld;
class btVector3;
class btRigidBody;
class btHeightfieldTerrainShape;

namespace terracut::bullet {

/// The kinematic tool: a thin box plate whose bottom long edge is the cutting
/// edge. In the blade frame it spans x in [-L/2, L/2] (L = blade length),
/// y in [0, height_m] (rising from the edge along the blade's local +Y) and
/// z in [-thickness_m/2, thickness_m/2].
struct ToolPlateSpec {
  bool enabled = true;         ///< false: no tool body (bodies only meet the terrain)
  double height_m = 0.1;       ///< extent above the edge along blade local +Y, metres, in (0, 100]
  double thickness_m = 0.02;   ///< extent along blade local Z, metres, in (0, 100]
  double friction = 0.5;       ///< Coulomb friction coefficient, [0, 10]
  /// The arm's force limit, N: 0 = none (the plate is kinematic: it goes
  /// where the blade goes, whatever it meets). > 0 (finite): the plate is a
  /// dynamic body (gravity off, mass_kg, its rotation the blade's) driven
  /// towards the blade pose by a servo whose force is clamped to this limit
  /// less the soil's force on the tool (set_tool_load): against a body it
  /// cannot move the plate stops short of the pose (the arm stalls), and
  /// the bodies' force on it stays within the limit plus the plate's
  /// momentum over a step (mass_kg x its speed / dt). With a limit, a
  /// buried body is released by its break-out force (BreakOutSpec) instead
  /// of the plate's first touch. docs/bullet.md, "The arm's force limit".
  double force_limit_n = 0.0;
  /// The plate's mass with a force limit, kg, in (0, 1e4]: the inertia the
  /// bodies meet (the arm's moving mass at the tool).
  double mass_kg = 5.0;
};

/// The soil that holds a buried body, for its break-out force (with a tool
/// force limit): the simulation's soil material (BodiesListener sets it).
struct BreakOutSpec {
  double unit_weight_n_per_m3 = 16.25e3;  ///< gamma, N/m^3, finite, > 0
  double cohesion_pa = 0.0;               ///< c, Pa, finite, >= 0
  double friction_angle_deg = 30.0;       ///< phi, degrees, [0, 89]
};

/// A buried body's geometry against the soil, for break_out_resistance_n.
struct BreakOutGeometry {
  double width_m = 0.0;           ///< the face that pushes the soil, across the push, m
  double top_depth_m = 0.0;       ///< that face's top below the soil surface beside it, m (>= 0)
  double bottom_depth_m = 0.0;    ///< its bottom below the same surface, m (>= top_depth_m)
  double footprint_m2 = 0.0;      ///< the body's plan area, m^2
  double overburden_m = 0.0;      ///< soil over its top, m (>= 0)
  double weight_n = 0.0;          ///< the body's weight, N
  double down_push_n = 0.0;       ///< the tool's downward push on it, N (>= 0)
};

/// The soil's horizontal resistance to a buried body pushed out of it, N:
/// Rankine's passive earth pressure on the face that pushes the soil,
///   sigma_p(z) = K_p gamma z + 2 c sqrt(K_p),  K_p = tan^2(45 deg + phi / 2),
/// integrated from the face's top depth z_t to its bottom depth z_b over its
/// width w,
///   P_p = w (K_p gamma (z_b^2 - z_t^2) / 2 + 2 c sqrt(K_p) (z_b - z_t)),
/// plus the shear under its base (Mohr-Coulomb on the soil it stands on:
/// its plan area's cohesion and the friction of its weight, the soil over it
/// and the tool's downward push), c A + (W + gamma d A + F_down) tan(phi) (Rankine 1857;
/// Terzaghi 1943, "Theoretical Soil Mechanics", ch. 2 and 4).
double break_out_resistance_n(const BreakOutSpec& soil, const BreakOutGeometry& g);

/// The soil's resistance to a buried body lifted out of it, N: its weight
/// and the soil over it, W + gamma d A.
double lift_out_resistance_n(const BreakOutSpec& soil, const BreakOutGeometry& g);

/// Parameters of the Bullet world; validated at construction, read-only during a run.
struct TerrainWorldParams {
  /// Gravitational acceleration along -Y, m/s^2, in [0, 1000].
  double gravity_m_s2 = 9.81;
  /// Upper bound of heights given to Bullet, metres above ground; 0 = automatic
  /// (max(2 * full_scale_m, highest initial height + full_scale_m)). When
  /// given, it must be finite and >= the highest initial height.
  double max_height_m = 0.0;
  /// Friction coefficient of the soil surface, [0, 10].
  double terrain_friction = 0.8;
  /// Restitution of the soil surface, [0, 1].
  double terrain_restitution = 0.0;
  /// Adds a static plane at the ground level (origin_m.y), the rigid floor
  /// under the soil; it holds bodies that leave the terrain's extent.
  bool floor = true;
  /// Collision margin of box and cylinder bodies, metres, in [0, 0.1]; each
  /// body's margin is at most 0.2 x its smallest half extent. The outer shape
  /// keeps its size (Bullet rounds the corners by the margin). A sphere's
  /// margin is its radius.
  double convex_margin_m = 0.005;
  /// Constraint solver iterations per step, in [1, 1000].
  int solver_iterations = 10;
  /// Coplanar merging of the terrain's collision triangles, metres, in
  /// [0, 0.001]. A body's contacts with the terrain are found triangle by
  /// triangle (GJK); under a body the squares of samples that lie on one
  /// plane, every sample within this distance of it, are handed to Bullet as
  /// rectangles (two triangles each, at most a third of the body's range per
  /// side) instead of two triangles per square, so a 0.3 m box on 2 cm cells
  /// of level or evenly sloping soil meets at most 18 triangles instead of
  /// about 450. The surface is the same to this distance. 0 = Bullet's own
  /// two triangles per square everywhere.
  double merge_tolerance_m = 1e-5;
  /// Hands Bullet's narrow phase only the terrain triangles a body's contact
  /// can come from: a triangle farther from the body's oriented bounding box
  /// than Bullet's contact breaking threshold (along the triangle's normal
  /// or one of the box's axes) gives no contact point in Bullet either, and
  /// is skipped before its GJK run. The contacts and the motion are the same
  /// bit for bit; a body tilted over uneven soil meets far fewer triangles.
  /// false = every triangle in the body's axis-aligned box, as Bullet does.
  bool cull_far_triangles = true;
  ToolPlateSpec tool{};
  PilePressureSpec pile{};
  /// The soil that holds buried bodies (used with tool.force_limit_n > 0).
  BreakOutSpec break_out{};
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const TerrainWorldParams& params);

/// Height bounds of the Bullet heightfield and what was clamped to them.
struct BoundsReport {
  double min_height_m = 0.0;             ///< lower bound, metres above ground (always 0)
  double max_height_m = 0.0;             ///< upper bound, metres above ground
  std::int64_t clamped_total = 0;        ///< samples lowered to max_height_m since construction
  /// Samples lowered by the terrain changes of the last step (those made
  /// between the previous advance() and the last one).
  std::int64_t clamped_last_step = 0;
  double highest_clamped_m = 0.0;        ///< largest height ever found above the bound, metres (0 if none)
  /// The soil those lowerings deleted since construction: the sum of each
  /// sample's height above the bound times its cell's area, m^3.
  double clamped_volume_m3 = 0.0;
};

/// A body's state after the last step, world frame, SI.
struct BodyState {
  Vec3 position_m{};            ///< centre of the body, metres
  Quat orientation{};           ///< body frame -> world (unit quaternion)
  Vec3 velocity_m_s{};          ///< linear velocity, m/s
  Vec3 angular_velocity_rad_s{};  ///< angular velocity, rad/s
  bool active = true;           ///< false when Bullet has put it to sleep
  bool held = false;            ///< buried and not yet reached by the blade: held still
};

/// What the last step did.
struct WorldStepInfo {
  std::int64_t step = 0;            ///< index of the last step, from 0 (-1 before any step)
  double t_s = 0.0;                 ///< simulated time after the last step, seconds
  /// Force the bodies exert on the tool plate, world frame, newtons: the sum
  /// over the tool's contact points of (normal + friction impulses) / dt.
  /// Zero when nothing touches the tool. The operator feels this force.
  Vec3 tool_force_n{};
  int tool_contact_points = 0;      ///< contact points between the tool and bodies
  int bodies_woken = 0;             ///< bodies woken by the last terrain change
  /// Buried bodies released in the last step, and the samples lowered under
  /// them (the caller tells whoever caches heights: BodiesListener adds it
  /// to the step's changed rectangle).
  int bodies_released = 0;
  Rect released_rect{};
  /// Soil moved out of the rings round the bodies in the last step
  /// (PilePressureSpec: a body that moved into soil pushes it a sample out),
  /// m^3, and the samples that changed (the caller tells whoever caches
  /// heights, as for released_rect).
  double shed_m3 = 0.0;
  Rect shed_rect{};
  /// Sum over the bodies of the horizontal earth pressure of the piles
  /// against them in the last step (PilePressureSpec), newtons.
  double pile_force_n = 0.0;
  /// The same pushes as vectors, summed over the bodies (horizontal: each
  /// along the inward normal of the face it presses on), newtons.
  Vec3 pile_thrust_n{};
  /// With a tool force limit: the largest horizontal force of the plate on
  /// a held body in the last step, N, and that body's break-out force
  /// against it (break_out_resistance_n; 0 when no held body was touched).
  /// A push above its break-out force releases the body before the next step.
  double held_push_n = 0.0;
  double held_resistance_n = 0.0;
  /// With a tool force limit: the plate stopped short of the blade pose
  /// (the servo's force reached the limit in the last step).
  bool tool_stalled = false;
  double physics_s = 0.0;           ///< wall-clock time of Bullet's step, seconds
  double total_s = 0.0;             ///< wall-clock time of the whole step(), seconds
};

class TerrainWorld {
 public:
  /// Builds the world over a simulation's grid, rate and blade. The
  /// simulation owns the heights: the world reads them in place and changes
  /// them only through it (Simulation::lower_sample, move_height), from its
  /// listener's callbacks (BodiesListener). It must outlive the world.
  /// Throws terracut::InputError naming the bad field when params or bodies
  /// are invalid, or the grid has fewer than 2 samples along a side
  /// (Bullet's heightfield needs 2 x 2).
  TerrainWorld(Simulation& sim, std::vector<BodySpec> bodies,
               const TerrainWorldParams& params = {});
  /// The same over a bare grid that no simulation owns (tests, tools): the
  /// world changes its heights itself. `grid` must outlive the world and
  /// keep its heights array (HeightGrid guarantees that). rate_hz is the
  /// fixed rate (Bullet advances 1 / rate_hz per step); blade gives the tool
  /// plate's length.
  TerrainWorld(HeightGrid& grid, double rate_hz, const BladeSpec& blade,
               std::vector<BodySpec> bodies, const TerrainWorldParams& params = {});
  ~TerrainWorld();
  TerrainWorld(const TerrainWorld&) = delete;
  TerrainWorld& operator=(const TerrainWorld&) = delete;

  const TerrainWorldParams& params() const { return params_; }
  double dt_s() const { return dt_s_; }

  /// One step after Simulation::step: terrain_changed(out.changed),
  /// set_tool_pose(out.pose), advance(). Allocation-free once warm; never throws.
  void step(const StepOutput& out);

  /// Tells the world that heights inside `changed` were edited (any rectangle;
  /// clipped to the grid): clamps them to the bounds (counted), wakes the
  /// bodies over triangles whose samples now differ from what the body last
  /// saw (samples inside `changed` only) and drops their cached terrain
  /// contacts. Call it after every edit made outside step() (set_heights,
  /// Simulation::reset with the whole grid's rectangle).
  void terrain_changed(const Rect& changed);

  /// Moves the tool plate to the blade pose (takes effect in the next
  /// advance). The plate's velocity is the pose change over dt, so it pushes
  /// what it meets; the first pose, and the first after lift_tool(), places
  /// the plate without a velocity.
  void set_tool_pose(const BladePose& pose);
  /// The soil's force on the tool this step, world N (Simulation's
  /// out.force.total_n before the listeners; step(out) sets it): with a
  /// force limit it counts against the limit, so the plate's servo has the
  /// limit less its magnitude (none when the soil alone reaches the limit:
  /// the plate holds, as the arm stalled in the soil would).
  void set_tool_load(const Vec3& soil_force_n) { tool_load_n_ = length(soil_force_n); }
  /// True when the plate is force-limited (params().tool.force_limit_n > 0).
  bool tool_limited() const { return params_.tool.enabled && params_.tool.force_limit_n > 0.0; }
  /// The blade pose the plate is at now (its edge; the pose last set when
  /// the plate is kinematic): where a force-limited arm actually is.
  BladePose tool_blade_pose() const;
  /// The next set_tool_pose jumps to its pose (use with Simulation::lift():
  /// between separate cuts the blade does not sweep through the air).
  void lift_tool() { tool_teleport_ = true; }

  /// Advances Bullet by dt_s() and updates last().
  void advance();

  /// The heights a depth camera looking straight down would see over rect
  /// (clipped to the grid; out holds rect.area() values, row-major, metres
  /// above ground, the soil's heights on entry): each sample becomes the
  /// higher of its value and the top of a body over it, by a vertical ray
  /// test against each body whose bounding box overlaps the rectangle (held
  /// buried bodies are under the soil: skipped). Returns how many samples a
  /// body raised. Allocation-free; not during advance().
  int raise_to_body_tops(const Rect& rect, std::span<float> out) const;

  /// The samples under the bodies that moved (awake, dynamic) in the steps
  /// since the last call, and one more all round (empty: none moved):
  /// where a camera's view of the bodies may have changed although no soil
  /// did. Clears the record.
  Rect take_moved_rect();

  /// Where soil that flows may not go for body i: the samples whose centres
  /// lie under its bounding box, and one more all round (clipped to the
  /// grid; empty when the body's box is not finite), with the box's lowest
  /// point, metres above ground. The ring keeps a pile's last slope outside
  /// the body (PilePressureSpec).
  SoilObstacle soil_obstacle(int i) const;

  /// Held bodies (buried, not yet reached by the blade).
  int held_count() const;
  /// Held body i's geometry against the soil now for a push along the
  /// horizontal direction `push` (world; its Y is ignored), and the tool's
  /// downward push down_n: the face across the push (its bounding box's),
  /// the soil beside that face (the mean height of the samples one cell out
  /// of its footprint on the side the push goes), the soil over it (the
  /// mean over its footprint).
  BreakOutGeometry break_out_geometry(int i, Vec3 push, double down_n) const;

  int body_count() const { return int(specs_.size()); }
  const BodySpec& body_spec(int i) const { return specs_[std::size_t(i)]; }
  BodyState body_state(int i) const;
  const WorldStepInfo& last() const { return info_; }
  const BoundsReport& bounds() const { return bounds_; }
  std::int64_t step_count() const { return steps_; }
  double time_s() const { return double(steps_) * dt_s_; }

  /// World pose of the tool plate's centre (meaningful after the first set_tool_pose).
  BladePose tool_plate_pose() const;

  /// Bullet access for tests, renderers and ray queries. Do not add or remove
  /// objects, and do not change the terrain shape.
  btDiscreteDynamicsWorld& dynamics_world();
  const btDiscreteDynamicsWorld& dynamics_world() const;
  btRigidBody& body(int i);
  /// The tool plate's body; only when params().tool.enabled.
  btRigidBody& tool_body();
  btRigidBody& terrain_body();
  const btHeightfieldTerrainShape& terrain_shape() const;
  /// Number of collision shapes this world owns (terrain, floor, tool, one per body).
  int shape_count() const;

 private:
  struct Impl;

  TerrainWorld(const HeightGrid& grid, Simulation* owner, HeightGrid* bare, double rate_hz,
               const BladeSpec& blade, std::vector<BodySpec> bodies,
               const TerrainWorldParams& params);
  // The only two edits the world makes to the heights: through the
  // simulation that owns them, or on the bare grid it was given.
  void lower_sample(std::int64_t i, float height_m);
  void move_height(std::int64_t from, std::int64_t to, float amount_m);

  const HeightGrid& grid_;  // read in place (Bullet's heightfield too)
  Simulation* owner_ = nullptr;  // the simulation that owns grid_, or
  HeightGrid* bare_ = nullptr;   // grid_ itself when no simulation owns it
  TerrainWorldParams params_;
  BladeSpec blade_;
  std::vector<BodySpec> specs_;
  double dt_s_ = 0.0;
  std::unique_ptr<Impl> impl_;
  BoundsReport bounds_{};
  WorldStepInfo info_{};
  std::int64_t steps_ = 0;
  bool tool_teleport_ = true;
  int pending_woken_ = 0;

  // Buried bodies (buried_bodies.cpp): Impl::held marks the held ones.
  int pending_released_ = 0;
  Rect pending_released_rect_{};
  Rect moved_rect_{};  // take_moved_rect()
  /// Releases the held bodies the blade reached this step (changed: the
  /// step's cut), before Bullet advances.
  void release_reached(const Rect& changed);
  void release(int i);
  /// With a force limit: the plate's force on each held body in the last
  /// step (world N), summed from the contacts in advance().
  std::vector<Vec3> held_push_n_;
  double tool_load_n_ = 0.0;
  BladePose tool_target_{};   // the blade pose last set (force-limited plate)
  bool tool_has_target_ = false;
  Vec3 tool_last_centre_{};   // the plate's target centre at the last drive_tool
  bool tool_has_last_centre_ = false;
  /// Drives the force-limited plate towards tool_target_ for the next step.
  void drive_tool();
  /// After a step with a force-limited plate: each held body the plate
  /// pushed harder than its break-out force is marked for release (in the
  /// next step's release_reached), and info_.held_push_n is set.
  void judge_held_pushes();

  // Piles against the bodies (pile_pressure.cpp).
  /// Applies the piles' earth pressure (params_.pile) to the dynamic bodies,
  /// for the next advance; wakes a sleeping body when the soil that presses
  /// on it changed since the last call (SoilView::band_changed). Sums the
  /// forces into pending_pile_force_n_.
  void apply_pile_pressure();
  /// Moves the soil standing in a body's ring (soil_obstacle minus its
  /// footprint) higher than its lowest point plus the collision margin one
  /// sample further out, away from the body (not onto another body's
  /// obstacle, not past the upper bound): a body that moved into soil pushes
  /// it aside instead of riding up the slope the heightfield makes there.
  void shed_rings();
  /// soil_obstacle(i) before clipping to the grid (at most one sample past an edge).
  SoilObstacle ring_around(int i) const;
  double pending_pile_force_n_ = 0.0;
  Vec3 pending_pile_thrust_n_{};
  double pending_shed_m3_ = 0.0;
  Rect pending_shed_rect_{};
  std::vector<SoilObstacle> obstacles_;  // per body, this step's soil_obstacle (reserved)
  /// The samples that press on body i's sides (apply_pile_pressure): its
  /// soil_obstacle and one more all round (clipped).
  Rect pile_band(const SoilObstacle& o) const;

  // What each body sees of the soil (terrain_world.cpp; the piles' band
  // fields are pile_pressure.cpp's).
  /// The samples whose centres lie under a world box's X-Z extent (clipped).
  Rect samples_under(const btVector3& lo, const btVector3& hi) const;
  /// r and one more sample all round, clipped to the grid.
  Rect grown_by_one(const Rect& r) const;
  /// The tool plate's centre for a blade edge at `edge` turned by q (the
  /// plate stands tool.height_m above its edge, centred on it).
  Vec3 plate_centre(const Vec3& edge, const Quat& q) const;
  /// What a dynamic body last saw of the soil round it: the samples whose
  /// triangles reach its box and two more all round (its pile band), and
  /// their heights. A reported change wakes the body (and drops its terrain
  /// contacts) only where one of those heights differs, so the one rectangle
  /// a step reports round everything the soil moved does not wake bodies
  /// the change never reached.
  struct SoilView {
    Rect region{};                 ///< samples, clipped to the grid; empty: nothing seen yet
    std::vector<float> heights_m;  ///< region rows x cols, row-major, metres (capacity reserved)
    /// A sample of the pile band changed since the last apply_pile_pressure.
    bool band_changed = false;
    /// The pile's push on the body as apply_pile_pressure last found it while
    /// the body slept (total magnitude, N, and net force, world N): while it
    /// sleeps on and its band does not change, the same (it reads only the
    /// band's heights and the body's box), so it is not summed again.
    bool pile_asleep = false;
    double pile_magnitude_n = 0.0;
    Vec3 pile_force_n{};
  };
  std::vector<SoilView> views_;  // one per body
  /// Body i's samples whose triangles reach its box (`reached`, not clipped)
  /// and those it sees (`seen`: two more all round, clipped); false when its
  /// box is not finite.
  bool view_region(int i, Rect& reached, Rect& seen) const;
  /// Copies the heights over `seen` into the view (none when it does not fit).
  void see(SoilView& view, const Rect& seen) const;
  /// Each awake body that moved to other samples sees what they hold now.
  void refresh_views();
  std::int64_t pending_clamped_ = 0;
};

}  // namespace terracut::bullet
