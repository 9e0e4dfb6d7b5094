// What the rooms of TerrainWorld share (src/bullet, not installed): its
// Bullet objects (Impl) and the conversions between terracut's types and
// Bullet's. The rooms:
//   terrain_world.cpp   the Bullet world over the terrain: construction,
//                       the step, terrain edits (bounds, waking bodies),
//                       the tool plate, queries
//   buried_bodies.cpp   bodies held under the soil until the blade reaches
//                       them, and their release
//   pile_pressure.cpp   soil that flows against bodies: the free ring round
//                       each, the soil it sheds, Rankine's earth pressure
#pragma once

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>

#include <memory>
#include <vector>

#include "terracut/bullet/terrain_world.hpp"

namespace terracut::bullet {
namespace detail {

inline btVector3 to_bt(Vec3 v) { return btVector3(btScalar(v.x), btScalar(v.y), btScalar(v.z)); }
inline Vec3 from_bt(const btVector3& v) { return {double(v.x()), double(v.y()), double(v.z())}; }
inline btQuaternion to_bt(Quat q) {
  return btQuaternion(btScalar(q.x), btScalar(q.y), btScalar(q.z), btScalar(q.w));
}
inline Quat from_bt(const btQuaternion& q) { return {double(q.w()), double(q.x()), double(q.y()), double(q.z())}; }

// Collision groups besides Bullet's own (btBroadphaseProxy's first six
// bits): the force-limited tool plate, and the held bodies it presses on.
inline constexpr int kToolGroup = 1 << 6;
inline constexpr int kHeldGroup = 1 << 7;

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

}  // namespace detail

// Bullet objects, in construction order (members are destroyed in reverse:
// bodies before the world that holds them).
struct TerrainWorld::Impl {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  detail::ReservedSolver solver;
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
  std::vector<btVector3> inertia;  // per body, for a held one's release
  std::vector<char> held;          // per body: buried, not yet reached
  std::vector<char> breaking;      // per held body: the plate's push exceeded its break-out force

  ~Impl() {
    for (auto& b : bodies) world.removeRigidBody(b.get());
    if (tool_body) world.removeRigidBody(tool_body.get());
    if (floor_body) world.removeRigidBody(floor_body.get());
    if (terrain_body) world.removeRigidBody(terrain_body.get());
  }
};

}  // namespace terracut::bullet
