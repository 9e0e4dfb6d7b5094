// The Bullet world over the terrain (terrain_world.hpp): construction, the
// step, the terrain's edits (bounds, waking the bodies over them, what each
// body sees), the tool plate and its force, and the queries. The buried
// bodies are in buried_bodies.cpp, the piles against bodies in
// pile_pressure.cpp; terrain_world_impl.hpp holds what they share.
#include "terracut/bullet/terrain_world.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/ranges.hpp"
#include "merged_heightfield.hpp"
#include "terrain_world_impl.hpp"

namespace terracut::bullet {

using detail::from_bt;
using detail::to_bt;

namespace {

double now_s() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

// Where a ray from `from` along the unit `d` (both in the body's frame)
// enters the body's shape, as the distance along it; NaN when it misses.
// Exact for the shapes' outer surfaces (a box's edges are Bullet's rounded
// by its margin: up to the margin lower there).
double ray_entry(const BodySpec& b, Vec3 from, Vec3 d) {
  constexpr double kMiss = std::numeric_limits<double>::quiet_NaN();
  const Vec3 h = half_extents_m(b);
  switch (b.shape) {
    case BodyShape::kBox: {
      double enter = -1e300, leave = 1e300;
      const double o[3] = {from.x, from.y, from.z}, v[3] = {d.x, d.y, d.z}, e[3] = {h.x, h.y, h.z};
      for (int k = 0; k < 3; ++k) {
        if (std::fabs(v[k]) < 1e-12) {
          if (std::fabs(o[k]) > e[k]) return kMiss;
          continue;
        }
        const double t0 = (-e[k] - o[k]) / v[k], t1 = (e[k] - o[k]) / v[k];
        enter = std::max(enter, std::min(t0, t1));
        leave = std::min(leave, std::max(t0, t1));
      }
      return enter <= leave && enter >= 0.0 ? enter : kMiss;
    }
    case BodyShape::kSphere: {
      const double bb = dot(from, d), c = dot(from, from) - b.radius_m * b.radius_m;
      const double disc = bb * bb - c;
      return disc >= 0.0 ? -bb - std::sqrt(disc) : kMiss;
    }
    case BodyShape::kCylinder: {
      // The side (radius r about local Y, |y| <= h.y) and the two caps.
      double best = kMiss;
      const auto take = [&](double t) {
        if (t >= 0.0 && !(t >= best)) best = t;
      };
      const double a = d.x * d.x + d.z * d.z;
      if (a > 1e-12) {
        const double bb = from.x * d.x + from.z * d.z;
        const double c = from.x * from.x + from.z * from.z - b.radius_m * b.radius_m;
        const double disc = bb * bb - a * c;
        if (disc >= 0.0) {
          const double t = (-bb - std::sqrt(disc)) / a;
          if (std::fabs(from.y + t * d.y) <= h.y) take(t);
        }
      }
      if (std::fabs(d.y) > 1e-12)
        for (double cap : {-h.y, h.y}) {
          const double t = (cap - from.y) / d.y;
          const double x = from.x + t * d.x, z = from.z + t * d.z;
          if (x * x + z * z <= b.radius_m * b.radius_m) take(t);
        }
      return best;
    }
  }
  return kMiss;
}

// The range check shared by the friction-like fields.
bool in_range(double v, double lo, double hi) { return v >= lo && v <= hi; }

// The highest initial height of the grid, metres.
double highest_initial_m(const HeightGrid& grid) {
  const float* h = grid.initial();
  float top = 0.0f;
  for (std::int64_t i = 0; i < grid.spec().sample_count(); ++i) top = std::max(top, h[i]);
  return double(top);
}

const TerrainWorldParams& checked(const TerrainWorldParams& params) {
  if (std::string e = validate(params); !e.empty()) throw InputError(e);
  return params;
}

}  // namespace

std::string validate(const TerrainWorldParams& p) {
  if (!in_range(p.gravity_m_s2, 0.0, 1000.0))
    return must_be("gravity_m_s2", "in [0, 1000]", p.gravity_m_s2);
  if (!(std::isfinite(p.max_height_m) && p.max_height_m >= 0.0))
    return must_be("max_height_m", "finite and >= 0 (0 = automatic)", p.max_height_m);
  if (!in_range(p.terrain_friction, 0.0, 10.0))
    return must_be("terrain_friction", "in [0, 10]", p.terrain_friction);
  if (!in_range(p.terrain_restitution, 0.0, 1.0))
    return must_be("terrain_restitution", "in [0, 1]", p.terrain_restitution);
  if (!in_range(p.convex_margin_m, 0.0, 0.1))
    return must_be("convex_margin_m", "in [0, 0.1]", p.convex_margin_m);
  if (p.solver_iterations < 1 || p.solver_iterations > 1000)
    return must_be("solver_iterations", "in [1, 1000]", p.solver_iterations);
  if (!in_range(p.merge_tolerance_m, 0.0, 0.001))
    return must_be("merge_tolerance_m", "in [0, 0.001]", p.merge_tolerance_m);
  if (p.tool.enabled && !(p.tool.height_m > 0.0 && p.tool.height_m <= 100.0))
    return must_be("tool.height_m", "in (0, 100]", p.tool.height_m);
  if (p.tool.enabled && !(p.tool.thickness_m > 0.0 && p.tool.thickness_m <= 100.0))
    return must_be("tool.thickness_m", "in (0, 100]", p.tool.thickness_m);
  if (p.tool.enabled && !in_range(p.tool.friction, 0.0, 10.0))
    return must_be("tool.friction", "in [0, 10]", p.tool.friction);
  if (!(std::isfinite(p.tool.force_limit_n) && p.tool.force_limit_n >= 0.0))
    return must_be("tool.force_limit_n", "finite and >= 0 (0 = no limit)", p.tool.force_limit_n);
  if (!(p.tool.mass_kg > 0.0 && p.tool.mass_kg <= 1e4))
    return must_be("tool.mass_kg", "in (0, 10000]", p.tool.mass_kg);
  if (!(std::isfinite(p.break_out.unit_weight_n_per_m3) && p.break_out.unit_weight_n_per_m3 > 0.0))
    return must_be("break_out.unit_weight_n_per_m3", "finite and > 0",
                   p.break_out.unit_weight_n_per_m3);
  if (!(std::isfinite(p.break_out.cohesion_pa) && p.break_out.cohesion_pa >= 0.0))
    return must_be("break_out.cohesion_pa", "finite and >= 0", p.break_out.cohesion_pa);
  if (!in_range(p.break_out.friction_angle_deg, 0.0, 89.0))
    return must_be("break_out.friction_angle_deg", "in [0, 89]", p.break_out.friction_angle_deg);
  if (std::string e = validate(p.pile); !e.empty()) return e;
  return {};
}

TerrainWorld::TerrainWorld(Simulation& sim, std::vector<BodySpec> bodies,
                           const TerrainWorldParams& params)
    : TerrainWorld(sim.grid(), &sim, nullptr, sim.params().rate_hz, sim.params().blade,
                   std::move(bodies), params) {}

TerrainWorld::TerrainWorld(HeightGrid& grid, double rate_hz, const BladeSpec& blade,
                           std::vector<BodySpec> bodies, const TerrainWorldParams& params)
    : TerrainWorld(grid, nullptr, &grid, rate_hz, blade, std::move(bodies), params) {}

void TerrainWorld::lower_sample(std::int64_t i, float height_m) {
  if (owner_) owner_->lower_sample(i, height_m);
  else bare_->lower(i, height_m);
}

void TerrainWorld::move_height(std::int64_t from, std::int64_t to, float amount_m) {
  if (owner_) {
    owner_->move_height(from, to, amount_m);
  } else {
    float* h = bare_->edit_layers().height_m;
    h[from] -= amount_m;
    h[to] += amount_m;
  }
}

TerrainWorld::TerrainWorld(const HeightGrid& grid, Simulation* owner, HeightGrid* bare,
                           double rate_hz, const BladeSpec& blade, std::vector<BodySpec> bodies,
                           const TerrainWorldParams& params)
    : grid_(grid), owner_(owner), bare_(bare), params_(checked(params)), blade_(blade),
      specs_(std::move(bodies)) {
  // Settings: everything is checked here so the step can trust it.
  if (std::string e = check(kRateRange, rate_hz); !e.empty()) throw InputError(e);
  if (params_.tool.enabled && !(std::isfinite(blade.length_m) && blade.length_m > 0.0))
    throw InputError("blade.length_m must be finite and > 0 for the tool plate");
  if (grid.cols() < 2 || grid.rows() < 2)
    throw InputError("the Bullet heightfield needs at least 2 x 2 samples, the grid has " +
                     format_number(grid.cols()) + " x " + format_number(grid.rows()));
  if (std::string e = validate(specs_); !e.empty()) throw InputError(e);
  for (std::size_t i = 0; i < specs_.size(); ++i)
    if (std::string e = buried_problem(specs_[i], grid.spec(), grid.heights()); !e.empty())
      throw InputError("bodies[" + format_number(i) + "] (" + specs_[i].name + "): " + e);
  dt_s_ = 1.0 / rate_hz;

  // Height bounds: [0, max] with room for piles above the initial terrain.
  const GridSpec& spec = grid.spec();
  const double top = highest_initial_m(grid);
  double max_h = params_.max_height_m;
  if (max_h == 0.0) {
    max_h = std::max(2.0 * spec.full_scale_m, top + spec.full_scale_m);
  } else if (max_h < top) {
    throw InputError(must_be(
        "max_height_m", "0 or at least the highest initial height " + format_number(top), max_h));
  }
  bounds_.min_height_m = 0.0;
  bounds_.max_height_m = double(btScalar(max_h));
  info_.step = -1;

  impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  m.world.setGravity(btVector3(0, btScalar(-params_.gravity_m_s2), 0));
  btContactSolverInfo& solver = m.world.getSolverInfo();
  solver.m_numIterations = params_.solver_iterations;
  // Penetration is always resolved by split impulse (a position correction
  // that adds no momentum). Bullet's default uses Baumgarte's velocity bias
  // for penetrations under 4 cm, which at 1 kHz turns a 1 mm landing overlap
  // into a 0.2 m/s bounce.
  solver.m_splitImpulse = 1;
  solver.m_splitImpulsePenetrationThreshold = 0;

  // The terrain: width = cols along X, length = rows along Z, reading the
  // grid's heights in place. Bullet centres the shape on its bounding box, so
  // the body sits at the terrain's centre in X-Z and at the middle of the
  // height bounds in Y; then sample (c, r) lands at
  // (sample_x(c), origin.y + height, sample_z(r)).
  // Coplanar squares under a body reach the collision query as one rectangle,
  // and triangles no contact can come from do not reach GJK
  // (merged_heightfield.hpp); the surface and the ray tests are Bullet's own.
  m.terrain_shape = std::make_unique<detail::MergedHeightfield>(
      grid.cols(), grid.rows(), grid.heights(), btScalar(bounds_.min_height_m),
      btScalar(bounds_.max_height_m), params_.merge_tolerance_m, params_.cull_far_triangles);
  m.terrain_shape->setLocalScaling(
      btVector3(btScalar(spec.cell_x_m()), btScalar(1.0), btScalar(spec.cell_z_m())));
  btTransform terrain_pose;
  terrain_pose.setIdentity();
  terrain_pose.setOrigin(
      btVector3(btScalar(spec.origin_m.x + 0.5 * spec.size_x_m),
                btScalar(spec.origin_m.y + 0.5 * (bounds_.min_height_m + bounds_.max_height_m)),
                btScalar(spec.origin_m.z + 0.5 * spec.size_z_m)));
  {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, m.terrain_shape.get());
    info.m_startWorldTransform = terrain_pose;
    info.m_friction = btScalar(params_.terrain_friction);
    info.m_restitution = btScalar(params_.terrain_restitution);
    m.terrain_body = std::make_unique<btRigidBody>(info);
    m.world.addRigidBody(m.terrain_body.get());
  }

  // The rigid floor under the soil.
  if (params_.floor) {
    m.floor_shape = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0),
                                                         btScalar(spec.origin_m.y));
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, m.floor_shape.get());
    info.m_friction = btScalar(params_.terrain_friction);
    info.m_restitution = btScalar(params_.terrain_restitution);
    m.floor_body = std::make_unique<btRigidBody>(info);
    m.world.addRigidBody(m.floor_body.get());
  }

  // The tool plate: kinematic (no force limit) or dynamic (drive_tool),
  // never sleeping; it has no contact response until its first pose is set.
  if (params_.tool.enabled) {
    m.tool_shape = std::make_unique<btBoxShape>(
        btVector3(btScalar(0.5 * blade.length_m), btScalar(0.5 * params_.tool.height_m),
                  btScalar(0.5 * params_.tool.thickness_m)));
    m.tool_shape->setMargin(btScalar(
        std::min({params_.convex_margin_m, 0.2 * 0.5 * params_.tool.thickness_m,
                  0.2 * 0.5 * params_.tool.height_m})));
    btTransform start;
    start.setIdentity();
    m.tool_motion = std::make_unique<btDefaultMotionState>(start);
    if (!tool_limited()) {
      btRigidBody::btRigidBodyConstructionInfo info(0, m.tool_motion.get(), m.tool_shape.get());
      info.m_friction = btScalar(params_.tool.friction);
      m.tool_body = std::make_unique<btRigidBody>(info);
      m.tool_body->setCollisionFlags(m.tool_body->getCollisionFlags() |
                                     btCollisionObject::CF_KINEMATIC_OBJECT |
                                     btCollisionObject::CF_NO_CONTACT_RESPONSE);
      m.tool_body->setActivationState(DISABLE_DEACTIVATION);
      m.world.addRigidBody(m.tool_body.get());
    } else {
      // Dynamic, without gravity, its rotation fixed by the blade (the
      // angular factor 0: contacts do not turn it); it meets the loose
      // bodies and the held ones (their own group), not the terrain or the
      // floor (it cuts through the soil, whose force is the soil model's).
      const btScalar mass = btScalar(params_.tool.mass_kg);
      btVector3 inertia(0, 0, 0);
      m.tool_shape->calculateLocalInertia(mass, inertia);
      btRigidBody::btRigidBodyConstructionInfo info(mass, m.tool_motion.get(), m.tool_shape.get(),
                                                    inertia);
      info.m_friction = btScalar(params_.tool.friction);
      m.tool_body = std::make_unique<btRigidBody>(info);
      m.tool_body->setFlags(m.tool_body->getFlags() | BT_DISABLE_WORLD_GRAVITY);
      m.tool_body->setGravity(btVector3(0, 0, 0));
      m.tool_body->setAngularFactor(btScalar(0));
      m.tool_body->setCollisionFlags(m.tool_body->getCollisionFlags() |
                                     btCollisionObject::CF_NO_CONTACT_RESPONSE);
      m.tool_body->setActivationState(DISABLE_DEACTIVATION);
      m.world.addRigidBody(m.tool_body.get(), detail::kToolGroup,
                           btBroadphaseProxy::DefaultFilter | detail::kHeldGroup);
    }
  }

  // Every body may touch the terrain, the floor, the plate and every other
  // body (up to 64 others each: past that, Bullet grows the arrays itself).
  {
    const int n = int(specs_.size());
    const int objects = n + 3;
    m.solver.reserve(objects, 3 * n + n * std::min(n - 1, 64) / 2 + 1);
  }

  // The loose bodies, in the order given (the order fixes Bullet's results).
  for (const BodySpec& b : specs_) {
    std::unique_ptr<btCollisionShape> shape;
    const Vec3 half = half_extents_m(b);
    const double margin =
        std::min(params_.convex_margin_m, 0.2 * std::min({half.x, half.y, half.z}));
    switch (b.shape) {
      case BodyShape::kBox:
        shape = std::make_unique<btBoxShape>(to_bt(half));
        shape->setMargin(btScalar(margin));
        break;
      case BodyShape::kSphere:
        shape = std::make_unique<btSphereShape>(btScalar(b.radius_m));
        break;
      case BodyShape::kCylinder:
        shape = std::make_unique<btCylinderShape>(to_bt(half));
        shape->setMargin(btScalar(margin));
        break;
    }
    btVector3 inertia(0, 0, 0);
    if (b.mass_kg > 0.0) shape->calculateLocalInertia(btScalar(b.mass_kg), inertia);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(b.mass_kg), nullptr, shape.get(),
                                                  inertia);
    info.m_startWorldTransform =
        btTransform(to_bt(normalized(initial_orientation(b))), to_bt(b.position_m));
    info.m_friction = btScalar(b.friction);
    info.m_restitution = btScalar(b.restitution);
    auto body = std::make_unique<btRigidBody>(info);
    // A buried body is held: static (no gravity, no integration) and, as
    // static, in no pair with the terrain, the floor or the plate.
    const bool held = b.buried && b.mass_kg > 0.0;
    if (held) body->setMassProps(0, btVector3(0, 0, 0));
    body->setUserIndex(int(m.bodies.size()));  // its index, for the plate's contacts
    if (held && tool_limited()) {
      // A force-limited plate presses on it (its break-out force).
      m.world.addRigidBody(body.get(), btBroadphaseProxy::StaticFilter | detail::kHeldGroup,
                           btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
    } else {
      m.world.addRigidBody(body.get());
    }
    m.inertia.push_back(inertia);
    m.held.push_back(held ? 1 : 0);
    m.breaking.push_back(0);
    obstacles_.reserve(specs_.size());
    // Its soil view holds the samples round the widest box the body can
    // have (its bounding sphere about its origin, with 5 cm for Bullet's
    // contact threshold and margin): under it, the triangles' reach (one
    // more) and the band (two more) on each side, and one for rounding.
    btVector3 sphere_centre;
    btScalar radius = 0;
    shape->getBoundingSphere(sphere_centre, radius);
    const double half_m = double(sphere_centre.length() + radius) + 0.05;
    const auto across = [&](double cell_m) { return int(std::ceil(2.0 * half_m / cell_m)) + 1 + 2 * 4; };
    SoilView view;
    view.heights_m.reserve(std::size_t(across(grid_.spec().cell_x_m())) *
                           std::size_t(across(grid_.spec().cell_z_m())));
    views_.push_back(std::move(view));
    m.body_shapes.push_back(std::move(shape));
    m.bodies.push_back(std::move(body));
  }
  held_push_n_.assign(specs_.size(), Vec3{});
  refresh_views();  // what each body sees before the first edit
}

TerrainWorld::~TerrainWorld() = default;

void TerrainWorld::step(const StepOutput& out) {
  const double start = now_s();
  terrain_changed(out.changed);
  // The soil's force on the tool (the listeners' part is added after them).
  set_tool_load(out.force.total_n);
  set_tool_pose(out.pose);
  release_reached(out.changed);
  shed_rings();
  apply_pile_pressure();
  advance();
  info_.total_s = now_s() - start;
}

void TerrainWorld::terrain_changed(const Rect& changed) {
  const Rect r{std::max(changed.c0, 0), std::max(changed.r0, 0),
               std::min(changed.c1, grid_.cols()), std::min(changed.r1, grid_.rows())};
  if (r.empty()) return;

  // Keep every edited height inside the bounds Bullet was given. HeightGrid
  // never goes below 0 (the lower bound); anything above the upper bound is
  // lowered to it and counted.
  const float* h = grid_.heights();
  const float max_h = float(bounds_.max_height_m);
  std::int64_t clamped = 0;
  double above_m = 0.0;
  for (int row = r.r0; row < r.r1; ++row) {
    for (int col = r.c0; col < r.c1; ++col) {
      const std::int64_t i = grid_.index(col, row);
      if (h[i] > max_h) {
        bounds_.highest_clamped_m = std::max(bounds_.highest_clamped_m, double(h[i]));
        above_m += double(h[i]) - double(max_h);
        lower_sample(i, max_h);
        ++clamped;
      }
    }
  }
  bounds_.clamped_total += clamped;
  bounds_.clamped_volume_m3 += above_m * grid_.spec().cell_area_m2();
  pending_clamped_ += clamped;

  Impl& m = *impl_;
  btOverlappingPairCache* pairs = m.world.getPairCache();
  btBroadphaseProxy* terrain_proxy = m.terrain_body->getBroadphaseHandle();
  const auto wake_and_retest = [&](btRigidBody& body) {
    body.activate(true);
    // Drop the cached contact points with the terrain: the persistent
    // manifold keeps them in the terrain's frame at the old surface.
    if (btBroadphasePair* pair = pairs->findPair(body.getBroadphaseHandle(), terrain_proxy))
      pairs->cleanOverlappingPair(*pair, &m.dispatcher);
    ++pending_woken_;
  };
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    btRigidBody& body = *m.bodies[i];
    if (body.isStaticObject()) continue;
    SoilView& view = views_[i];
    Rect reached{}, seen{};
    if (!view_region(int(i), reached, seen)) {
      // A body gone to NaN sees nothing; it is woken as it always was.
      view.region = {};
      wake_and_retest(body);
      continue;
    }
    const Rect band = params_.pile.enabled ? pile_band(soil_obstacle(int(i))) : Rect{};
    // Compare the edited samples it sees with what it saw; a sample it did
    // not see before counts as changed.
    bool under = false, differs = false;
    const Rect e{std::max(r.c0, seen.c0), std::max(r.r0, seen.r0), std::min(r.c1, seen.c1),
                 std::min(r.r1, seen.r1)};
    const Rect& old = view.region;
    for (int row = e.r0; row < e.r1; ++row)
      for (int col = e.c0; col < e.c1; ++col) {
        const bool known = col >= old.c0 && col < old.c1 && row >= old.r0 && row < old.r1;
        if (known && view.heights_m[std::size_t((row - old.r0) * (old.c1 - old.c0) + (col - old.c0))] ==
                         h[grid_.index(col, row)])
          continue;
        differs = true;
        under = under || (col >= reached.c0 && col < reached.c1 && row >= reached.r0 && row < reached.r1);
        view.band_changed = view.band_changed ||
                            (col >= band.c0 && col < band.c1 && row >= band.r0 && row < band.r1);
      }
    // What it sees now (when it moved, or the soil it sees changed).
    if (!(seen == old) || differs) see(view, seen);
    // An awake body over the reported rectangle is re-tested as before:
    // keeping its manifold across the piles' small changes made its steps
    // dearer (docs/bullet.md, "Cost"). A sleeping one only for its own soil.
    const bool over = reached.c0 < r.c1 && reached.c1 > r.c0 && reached.r0 < r.r1 && reached.r1 > r.r0;
    if (under || (over && body.isActive())) wake_and_retest(body);
  }
}

bool TerrainWorld::view_region(int i, Rect& reached, Rect& seen) const {
  const btRigidBody& body = *impl_->bodies[std::size_t(i)];
  const btBroadphaseProxy* proxy = body.getBroadphaseHandle();
  // The broadphase box already includes the contact breaking threshold.
  // With piles (PilePressureSpec) the body's own box: the soil it banks
  // against changes every step a sample outside its ring, on triangles
  // the body does not reach, and dropping its contacts for that would
  // cost it its static friction (it would creep under the pile's thrust).
  btVector3 lo = proxy->m_aabbMin, hi = proxy->m_aabbMax;
  if (params_.pile.enabled) body.getAabb(lo, hi);
  if (!(std::isfinite(lo.x()) && std::isfinite(hi.x()) && std::isfinite(lo.z()) &&
        std::isfinite(hi.z())))
    return false;
  // The triangles that use sample c span world X from origin + (c - 0.5) *
  // cell to origin + (c + 1.5) * cell (Z likewise): the first and the last
  // sample whose triangles the box meets, per axis. Far outside the grid a
  // box meets the same samples as at two cells out (and indices stay small).
  const GridSpec& spec = grid_.spec();
  const auto reach = [](btScalar lo_m, btScalar hi_m, double origin, double cell, int n, int& first,
                        int& end) {
    const double lo = std::clamp(double(lo_m), origin - 2.0 * cell, origin + (n + 2.0) * cell);
    const double hi = std::clamp(double(hi_m), origin - 2.0 * cell, origin + (n + 2.0) * cell);
    first = int(std::ceil((lo - origin) / cell - 1.5));
    while (!(lo > origin + (first - 1 + 1.5) * cell)) --first;
    while (lo > origin + (first + 1.5) * cell) ++first;
    int last = int(std::floor((hi - origin) / cell + 0.5));
    while (!(hi < origin + (last + 1 - 0.5) * cell)) ++last;
    while (hi < origin + (last - 0.5) * cell) --last;
    end = last + 1;
  };
  reach(lo.x(), hi.x(), spec.origin_m.x, spec.cell_x_m(), spec.cols, reached.c0, reached.c1);
  reach(lo.z(), hi.z(), spec.origin_m.z, spec.cell_z_m(), spec.rows, reached.r0, reached.r1);
  // The samples it sees: the reach and its pile band (clipped).
  seen = {std::max(reached.c0 - 2, 0), std::max(reached.r0 - 2, 0),
          std::min(reached.c1 + 2, grid_.cols()), std::min(reached.r1 + 2, grid_.rows())};
  return true;
}

void TerrainWorld::see(SoilView& view, const Rect& seen) const {
  if (seen.empty() || std::size_t(seen.area()) > view.heights_m.capacity()) {
    view.region = {};  // off the grid, or wider than any box the body can have: sees nothing
    return;
  }
  const float* h = grid_.heights();
  view.region = seen;
  view.heights_m.resize(std::size_t(seen.area()));
  float* to = view.heights_m.data();
  for (int row = seen.r0; row < seen.r1; ++row, to += seen.c1 - seen.c0)
    std::copy_n(h + grid_.index(seen.c0, row), seen.c1 - seen.c0, to);
}

Rect TerrainWorld::take_moved_rect() {
  const Rect r = moved_rect_;
  moved_rect_ = {};
  return r;
}

void TerrainWorld::refresh_views() {
  for (std::size_t i = 0; i < views_.size(); ++i) {
    const btRigidBody& body = *impl_->bodies[i];
    if (body.isStaticObject() || !body.isActive()) continue;  // it did not move
    {
      btVector3 lo, hi;
      body.getAabb(lo, hi);
      const bool finite = std::isfinite(lo.x()) && std::isfinite(lo.z()) &&
                          std::isfinite(hi.x()) && std::isfinite(hi.z());
      const Rect f = finite ? samples_under(lo, hi) : Rect{};
      if (!f.empty()) moved_rect_.include(grown_by_one(f));
    }
    Rect reached{}, seen{};
    if (!view_region(int(i), reached, seen)) seen = {};
    if (!(seen == views_[i].region)) see(views_[i], seen);
  }
}

void TerrainWorld::set_tool_pose(const BladePose& pose) {
  if (!params_.tool.enabled) return;
  Impl& m = *impl_;
  const btTransform t(to_bt(normalized(pose.orientation)),
                      to_bt(plate_centre(pose.position_m, pose.orientation)));
  if (tool_limited()) {
    // The servo drives the plate towards the pose in advance() (drive_tool).
    tool_target_ = pose;
    tool_has_target_ = true;
    if (tool_teleport_) {
      m.tool_motion->setWorldTransform(t);
      m.tool_body->setWorldTransform(t);
      m.tool_body->setInterpolationWorldTransform(t);
      m.tool_body->setLinearVelocity(btVector3(0, 0, 0));
      m.tool_body->setCollisionFlags(m.tool_body->getCollisionFlags() &
                                     ~btCollisionObject::CF_NO_CONTACT_RESPONSE);
      tool_teleport_ = false;
      tool_has_last_centre_ = false;  // a jump to the pose is no motion of it
    }
    return;
  }
  m.tool_motion->setWorldTransform(t);
  m.tool_body->setWorldTransform(t);
  if (tool_teleport_) {
    // A jump: no velocity from the previous pose, and contacts from now on.
    m.tool_body->setInterpolationWorldTransform(t);
    m.tool_body->setCollisionFlags(m.tool_body->getCollisionFlags() &
                                   ~btCollisionObject::CF_NO_CONTACT_RESPONSE);
    tool_teleport_ = false;
  }
}

void TerrainWorld::drive_tool() {
  Impl& m = *impl_;
  btRigidBody& plate = *m.tool_body;
  // Its rotation is the blade's; its velocity is what the servo's force,
  // clamped to the limit less the soil's force, makes of the velocity it
  // kept after the last step (contacts included), aiming at the blade pose
  // in one step: dv = clamp(x_target - x) / dt - v, F dt / m).
  const Quat q = normalized(tool_target_.orientation);
  const Vec3 centre = plate_centre(tool_target_.position_m, q);
  btTransform t = plate.getWorldTransform();
  t.setRotation(to_bt(q));
  plate.setWorldTransform(t);
  m.tool_motion->setWorldTransform(t);
  const double budget_n = params_.tool.force_limit_n - tool_load_n_;
  const Vec3 v = from_bt(plate.getLinearVelocity());
  Vec3 wanted = (centre - from_bt(t.getOrigin())) * (1.0 / dt_s_);
  // The pose's own velocity (0 after a jump to it).
  const Vec3 u = tool_has_last_centre_ ? (centre - tool_last_centre_) * (1.0 / dt_s_) : Vec3{};
  tool_last_centre_ = centre;
  tool_has_last_centre_ = true;
  if (budget_n > 0.0) {
    // Brakes for the pose: the speed towards it relative to its own motion
    // is at most what the servo's deceleration a = F / m stops within the
    // distance left, c = -a dt / 2 + sqrt((a dt / 2)^2 + 2 a d). It binds
    // only where that speed is over a dt, the most one step can change: the
    // plate left behind (a stall let go), not while it follows the pose.
    // Without it the one-step target arrives at full speed and swings past
    // the pose by about the distance it made up, for most of a second.
    const double a = budget_n / params_.tool.mass_kg;
    const Vec3 rel = wanted - u;
    const double r = length(rel);
    const double h = 0.5 * a * dt_s_;
    const double brake = -h + std::sqrt(h * h + 2.0 * a * r * dt_s_);
    if (r > brake) wanted = u + rel * (brake / r);
  }
  Vec3 dv = wanted - v;
  bool stalled = false;
  if (budget_n <= 0.0) {
    // The soil alone holds the arm: it stops where it is.
    dv = v * -1.0;
    stalled = length(wanted) > 0.0;
  } else {
    const double most = budget_n * dt_s_ / params_.tool.mass_kg;
    const double l = length(dv);
    if (l > most) {
      dv = dv * (most / l);
      stalled = true;
    }
  }
  plate.setLinearVelocity(to_bt(v + dv));
  plate.setAngularVelocity(btVector3(0, 0, 0));
  info_.tool_stalled = stalled;
}

void TerrainWorld::advance() {
  Impl& m = *impl_;
  const double start = now_s();
  const bool limited = tool_limited() && tool_has_target_;
  if (limited) drive_tool();
  else info_.tool_stalled = false;
  // Exactly one internal step of dt (maxSubSteps = 0: no time accumulator, no
  // interpolation), so the world is a deterministic function of its inputs.
  m.world.stepSimulation(btScalar(dt_s_), 0, btScalar(dt_s_));
  info_.physics_s = now_s() - start;

  // The force the bodies exert on the tool: Bullet applies +impulse along the
  // normal (which points from body B to body A) to body A, and the opposite to B.
  btVector3 impulse(0, 0, 0);
  int points = 0;
  if (m.tool_body) {
    const int manifolds = m.dispatcher.getNumManifolds();
    for (int k = 0; k < manifolds; ++k) {
      const btPersistentManifold* pm = m.dispatcher.getManifoldByIndexInternal(k);
      const bool tool_is_a = pm->getBody0() == m.tool_body.get();
      const bool tool_is_b = pm->getBody1() == m.tool_body.get();
      if (!tool_is_a && !tool_is_b) continue;
      const btScalar sign = tool_is_a ? btScalar(1) : btScalar(-1);
      for (int p = 0; p < pm->getNumContacts(); ++p) {
        const btManifoldPoint& pt = pm->getContactPoint(p);
        if (pt.getAppliedImpulse() == btScalar(0) && pt.m_appliedImpulseLateral1 == btScalar(0) &&
            pt.m_appliedImpulseLateral2 == btScalar(0))
          continue;
        const btVector3 j = sign * (pt.m_normalWorldOnB * pt.getAppliedImpulse() +
                                    pt.m_lateralFrictionDir1 * pt.m_appliedImpulseLateral1 +
                                    pt.m_lateralFrictionDir2 * pt.m_appliedImpulseLateral2);
        impulse += j;
        ++points;
        // The plate's push on a held body: the opposite of the body's on it.
        if (limited) {
          const int i = (tool_is_a ? pm->getBody1() : pm->getBody0())->getUserIndex();
          if (i >= 0 && m.held[std::size_t(i)])
            held_push_n_[std::size_t(i)] = held_push_n_[std::size_t(i)] - from_bt(j) * (1.0 / dt_s_);
        }
      }
    }
  }
  info_.tool_force_n = from_bt(impulse) * (1.0 / dt_s_);
  if (limited) judge_held_pushes();
  info_.tool_contact_points = points;
  info_.bodies_woken = pending_woken_;
  pending_woken_ = 0;
  info_.pile_force_n = pending_pile_force_n_;
  info_.pile_thrust_n = pending_pile_thrust_n_;
  pending_pile_force_n_ = 0.0;
  pending_pile_thrust_n_ = {};
  info_.shed_m3 = pending_shed_m3_;
  info_.shed_rect = pending_shed_rect_;
  pending_shed_m3_ = 0.0;
  pending_shed_rect_ = {};
  info_.bodies_released = pending_released_;
  info_.released_rect = pending_released_rect_;
  pending_released_ = 0;
  pending_released_rect_ = {};
  bounds_.clamped_last_step = pending_clamped_;
  pending_clamped_ = 0;
  info_.step = steps_;
  ++steps_;
  info_.t_s = time_s();
  info_.total_s = info_.physics_s;
  // A body that moved sees other samples: what they hold before the next edit.
  refresh_views();
}

BodyState TerrainWorld::body_state(int i) const {
  const btRigidBody& b = *impl_->bodies[std::size_t(i)];
  BodyState s;
  const btTransform& t = b.getWorldTransform();
  s.position_m = from_bt(t.getOrigin());
  s.orientation = from_bt(t.getRotation());
  s.velocity_m_s = from_bt(b.getLinearVelocity());
  s.angular_velocity_rad_s = from_bt(b.getAngularVelocity());
  s.active = b.isActive();
  s.held = impl_->held[std::size_t(i)] != 0;
  return s;
}

Rect TerrainWorld::samples_under(const btVector3& lo, const btVector3& hi) const {
  // A sample on the box's side counts as under it (Bullet's float box
  // reaches it within a micrometre).
  const GridSpec& g = grid_.spec();
  constexpr double kOn = 1e-6;
  const auto first = [](double v, double origin, double cell) {
    return int(std::ceil((v - kOn - origin) / cell - 0.5));
  };
  const auto end = [](double v, double origin, double cell) {
    return int(std::floor((v + kOn - origin) / cell - 0.5)) + 1;
  };
  return {std::clamp(first(lo.x(), g.origin_m.x, g.cell_x_m()), 0, g.cols),
          std::clamp(first(lo.z(), g.origin_m.z, g.cell_z_m()), 0, g.rows),
          std::clamp(end(hi.x(), g.origin_m.x, g.cell_x_m()), 0, g.cols),
          std::clamp(end(hi.z(), g.origin_m.z, g.cell_z_m()), 0, g.rows)};
}

int TerrainWorld::raise_to_body_tops(const Rect& rect, std::span<float> out) const {
  const Rect r{std::max(rect.c0, 0), std::max(rect.r0, 0), std::min(rect.c1, grid_.cols()),
               std::min(rect.r1, grid_.rows())};
  if (r.empty() || out.size() < std::size_t(rect.area())) return 0;
  const double ground = grid_.spec().origin_m.y;
  const int width = rect.c1 - rect.c0;
  int raised = 0;
  for (std::size_t i = 0; i < impl_->bodies.size(); ++i) {
    if (impl_->held[i]) continue;
    const btRigidBody& b = *impl_->bodies[i];
    btVector3 lo, hi;
    b.getAabb(lo, hi);
    const Rect under = samples_under(lo, hi);
    const Rect s{std::max(under.c0, r.c0), std::max(under.r0, r.r0), std::min(under.c1, r.c1),
                 std::min(under.r1, r.r1)};
    if (s.empty()) continue;
    const btTransform& t = b.getWorldTransform();
    const BodySpec& spec = specs_[i];
    const Quat q = from_bt(t.getRotation());
    const Quat inverse{q.w, -q.x, -q.y, -q.z};
    const Vec3 centre = from_bt(t.getOrigin());
    const double above = double(hi.y()) + 1.0;
    const Vec3 down = rotate(inverse, {0.0, -1.0, 0.0});  // the ray, in the body's frame
    for (int row = s.r0; row < s.r1; ++row)
      for (int col = s.c0; col < s.c1; ++col) {
        const Vec3 from = rotate(inverse, Vec3{grid_.sample_x(col), above, grid_.sample_z(row)} - centre);
        const double hit = ray_entry(spec, from, down);
        if (!(hit >= 0.0)) continue;  // misses (NaN)
        const float top = float(above - hit - ground);
        float& v = out[std::size_t((row - rect.r0) * width + (col - rect.c0))];
        if (top > v) {
          v = top;
          ++raised;
        }
      }
  }
  return raised;
}

Vec3 TerrainWorld::plate_centre(const Vec3& edge, const Quat& q) const {
  return edge + rotate(q, {0.0, 0.5 * params_.tool.height_m, 0.0});
}

Rect TerrainWorld::grown_by_one(const Rect& r) const {
  return {std::max(r.c0 - 1, 0), std::max(r.r0 - 1, 0), std::min(r.c1 + 1, grid_.cols()),
          std::min(r.r1 + 1, grid_.rows())};
}

BladePose TerrainWorld::tool_blade_pose() const {
  if (!impl_->tool_body) return {};
  const btTransform& t = impl_->tool_body->getWorldTransform();
  const Quat q = from_bt(t.getRotation());
  return {from_bt(t.getOrigin()) - rotate(q, {0.0, 0.5 * params_.tool.height_m, 0.0}), q};
}

BladePose TerrainWorld::tool_plate_pose() const {
  if (!impl_->tool_body) return {};
  const btTransform& t = impl_->tool_body->getWorldTransform();
  return {from_bt(t.getOrigin()), from_bt(t.getRotation())};
}

btDiscreteDynamicsWorld& TerrainWorld::dynamics_world() { return impl_->world; }
const btDiscreteDynamicsWorld& TerrainWorld::dynamics_world() const { return impl_->world; }
btRigidBody& TerrainWorld::body(int i) { return *impl_->bodies[std::size_t(i)]; }
btRigidBody& TerrainWorld::tool_body() { return *impl_->tool_body; }
btRigidBody& TerrainWorld::terrain_body() { return *impl_->terrain_body; }
const btHeightfieldTerrainShape& TerrainWorld::terrain_shape() const { return *impl_->terrain_shape; }

int TerrainWorld::shape_count() const {
  return 1 + (impl_->floor_shape ? 1 : 0) + (impl_->tool_shape ? 1 : 0) +
         int(impl_->body_shapes.size());
}

}  // namespace terracut::bullet
