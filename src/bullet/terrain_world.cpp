#include "terracut/bullet/terrain_world.hpp"

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "merged_heightfield.hpp"

namespace terracut::bullet {

namespace {

double now_s() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

btVector3 to_bt(Vec3 v) { return btVector3(btScalar(v.x), btScalar(v.y), btScalar(v.z)); }
Vec3 from_bt(const btVector3& v) { return {double(v.x()), double(v.y()), double(v.z())}; }
btQuaternion to_bt(Quat q) {
  return btQuaternion(btScalar(q.x), btScalar(q.y), btScalar(q.z), btScalar(q.w));
}
Quat from_bt(const btQuaternion& q) { return {double(q.w()), double(q.x()), double(q.y()), double(q.z())}; }

// The range check shared by the friction-like fields.
bool in_range(double v, double lo, double hi) { return v >= lo && v <= hi; }

// The highest initial height of the grid, metres.
double highest_initial_m(const HeightGrid& grid) {
  const float* h = grid.initial();
  float top = 0.0f;
  for (std::int64_t i = 0; i < grid.spec().sample_count(); ++i) top = std::max(top, h[i]);
  return double(top);
}

// Bullet's sequential-impulse solver with its scratch arrays reserved at
// construction for the largest contact set the world is expected to reach,
// so that the first contact of a new kind late in a run (the plate meeting a
// body, bodies piling up) does not grow them inside a step. Bullet grows
// them itself, once, past the reserve.
class ReservedSolver final : public btSequentialImpulseConstraintSolver {
 public:
  /// objects: every collision object of the world; manifolds: the contact
  /// manifolds expected at once (each holds at most 4 points).
  void reserve(int objects, int manifolds) {
    const int points = 4 * manifolds;
    m_tmpSolverBodyPool.reserve(objects + 1);
    m_kinematicBodyUniqueIdToSolverBodyTable.reserve(objects + 1);
    m_tmpSolverContactConstraintPool.reserve(points);
    m_tmpSolverContactFrictionConstraintPool.reserve(2 * points);
    m_tmpSolverContactRollingFrictionConstraintPool.reserve(3 * points);
    m_orderTmpConstraintPool.reserve(2 * points);
    m_orderFrictionConstraintPool.reserve(2 * points);
  }
};

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
  return {};
}

// Bullet objects, in construction order (members are destroyed in reverse:
// bodies before the world that holds them).
struct TerrainWorld::Impl {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  ReservedSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};

  std::unique_ptr<btHeightfieldTerrainShape> terrain_shape;
  std::unique_ptr<btRigidBody> terrain_body;
  std::unique_ptr<btStaticPlaneShape> floor_shape;
  std::unique_ptr<btRigidBody> floor_body;
  std::unique_ptr<btBoxShape> tool_shape;
  std::unique_ptr<btDefaultMotionState> tool_motion;
  std::unique_ptr<btRigidBody> tool_body;
  std::vector<std::unique_ptr<btCollisionShape>> body_shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;

  ~Impl() {
    for (auto& b : bodies) world.removeRigidBody(b.get());
    if (tool_body) world.removeRigidBody(tool_body.get());
    if (floor_body) world.removeRigidBody(floor_body.get());
    if (terrain_body) world.removeRigidBody(terrain_body.get());
  }
};

TerrainWorld::TerrainWorld(Simulation& sim, std::vector<BodySpec> bodies,
                           const TerrainWorldParams& params)
    : TerrainWorld(sim.grid(), sim.params().rate_hz, sim.params().blade, std::move(bodies),
                   params) {}

TerrainWorld::TerrainWorld(HeightGrid& grid, double rate_hz, const BladeSpec& blade,
                           std::vector<BodySpec> bodies, const TerrainWorldParams& params)
    : grid_(grid), params_(checked(params)), blade_(blade), specs_(std::move(bodies)) {
  // Settings: everything is checked here so the step can trust it.
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0 && rate_hz <= 1e6))
    throw InputError(must_be("rate_hz", "in (0, 1e6]", rate_hz));
  if (params_.tool.enabled && !(std::isfinite(blade.length_m) && blade.length_m > 0.0))
    throw InputError("blade.length_m must be finite and > 0 for the tool plate");
  if (grid.cols() < 2 || grid.rows() < 2)
    throw InputError("the Bullet heightfield needs at least 2 x 2 samples, the grid has " +
                     format_number(grid.cols()) + " x " + format_number(grid.rows()));
  if (std::string e = validate(specs_); !e.empty()) throw InputError(e);
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
  // Coplanar squares under a body reach the collision query as one rectangle
  // (merged_heightfield.hpp); the surface and the ray tests are Bullet's own.
  m.terrain_shape = std::make_unique<detail::MergedHeightfield>(
      grid.cols(), grid.rows(), grid.heights(), btScalar(bounds_.min_height_m),
      btScalar(bounds_.max_height_m), params_.merge_tolerance_m);
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

  // The tool plate: kinematic, never sleeping; it has no contact response
  // until its first pose is set.
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
    btRigidBody::btRigidBodyConstructionInfo info(0, m.tool_motion.get(), m.tool_shape.get());
    info.m_friction = btScalar(params_.tool.friction);
    m.tool_body = std::make_unique<btRigidBody>(info);
    m.tool_body->setCollisionFlags(m.tool_body->getCollisionFlags() |
                                   btCollisionObject::CF_KINEMATIC_OBJECT |
                                   btCollisionObject::CF_NO_CONTACT_RESPONSE);
    m.tool_body->setActivationState(DISABLE_DEACTIVATION);
    m.world.addRigidBody(m.tool_body.get());
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
    m.world.addRigidBody(body.get());
    m.body_shapes.push_back(std::move(shape));
    m.bodies.push_back(std::move(body));
  }
}

TerrainWorld::~TerrainWorld() = default;

void TerrainWorld::step(const StepOutput& out) {
  const double start = now_s();
  terrain_changed(out.changed);
  set_tool_pose(out.pose);
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
  for (int row = r.r0; row < r.r1; ++row) {
    for (int col = r.c0; col < r.c1; ++col) {
      const std::int64_t i = grid_.index(col, row);
      if (h[i] > max_h) {
        bounds_.highest_clamped_m = std::max(bounds_.highest_clamped_m, double(h[i]));
        grid_.lower(i, max_h);
        ++clamped;
      }
    }
  }
  bounds_.clamped_total += clamped;
  pending_clamped_ += clamped;

  // The triangles that use the edited samples span from sample c0 - 1 to
  // sample c1 (and r0 - 1 to r1): that is the ground region whose bodies may
  // have lost (or gained) support.
  const GridSpec& spec = grid_.spec();
  const double x0 = spec.origin_m.x + (r.c0 - 0.5) * spec.cell_x_m();
  const double x1 = spec.origin_m.x + (r.c1 + 0.5) * spec.cell_x_m();
  const double z0 = spec.origin_m.z + (r.r0 - 0.5) * spec.cell_z_m();
  const double z1 = spec.origin_m.z + (r.r1 + 0.5) * spec.cell_z_m();
  Impl& m = *impl_;
  btOverlappingPairCache* pairs = m.world.getPairCache();
  btBroadphaseProxy* terrain_proxy = m.terrain_body->getBroadphaseHandle();
  for (auto& body : m.bodies) {
    if (body->isStaticObject()) continue;
    btBroadphaseProxy* proxy = body->getBroadphaseHandle();
    // The broadphase box already includes the contact breaking threshold.
    if (proxy->m_aabbMax.x() < x0 || proxy->m_aabbMin.x() > x1 || proxy->m_aabbMax.z() < z0 ||
        proxy->m_aabbMin.z() > z1)
      continue;
    body->activate(true);
    // Drop the cached contact points with the terrain: the persistent
    // manifold keeps them in the terrain's frame at the old surface.
    if (btBroadphasePair* pair = pairs->findPair(proxy, terrain_proxy))
      pairs->cleanOverlappingPair(*pair, &m.dispatcher);
    ++pending_woken_;
  }
}

void TerrainWorld::set_tool_pose(const BladePose& pose) {
  if (!params_.tool.enabled) return;
  Impl& m = *impl_;
  const Vec3 centre = pose.position_m + rotate(pose.orientation, {0.0, 0.5 * params_.tool.height_m, 0.0});
  const btTransform t(to_bt(normalized(pose.orientation)), to_bt(centre));
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

void TerrainWorld::advance() {
  Impl& m = *impl_;
  const double start = now_s();
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
        impulse += sign * (pt.m_normalWorldOnB * pt.getAppliedImpulse() +
                           pt.m_lateralFrictionDir1 * pt.m_appliedImpulseLateral1 +
                           pt.m_lateralFrictionDir2 * pt.m_appliedImpulseLateral2);
        ++points;
      }
    }
  }
  info_.tool_force_n = from_bt(impulse) * (1.0 / dt_s_);
  info_.tool_contact_points = points;
  info_.bodies_woken = pending_woken_;
  pending_woken_ = 0;
  bounds_.clamped_last_step = pending_clamped_;
  pending_clamped_ = 0;
  info_.step = steps_;
  ++steps_;
  info_.t_s = time_s();
  info_.total_s = info_.physics_s;
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
  return s;
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
