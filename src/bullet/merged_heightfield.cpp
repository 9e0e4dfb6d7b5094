#include "merged_heightfield.hpp"

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>

namespace terracut::bullet::detail {

namespace {

// Bullet's rounding of a local coordinate to the nearest grid point.
int quantized(btScalar v) { return v < 0 ? int(v - btScalar(0.5)) : int(v + btScalar(0.5)); }

// Reports a triangle to the callback unless its height range misses the
// query box's (the same filter as Bullet 3.24's processAllTriangles).
bool report(btTriangleCallback* callback, btVector3* v, int part, int index, btScalar y0,
            btScalar y1) {
  const btScalar lo = std::min({v[0].y(), v[1].y(), v[2].y()});
  const btScalar hi = std::max({v[0].y(), v[1].y(), v[2].y()});
  if (hi < y0 || lo > y1) return false;
  callback->processTriangle(v, part, index);
  return true;
}

}  // namespace

// Hands Bullet's convex-versus-terrain callback only the triangles a contact
// can come from (merged_heightfield.hpp, "Far triangles"): a triangle goes on
// unless the body's oriented bounding box is more than `reach` from it along
// the triangle's normal or one of the box's axes. Frame: the terrain
// shape's (the triangles' and the query box's).
class NearTriangles final : public btTriangleCallback {
 public:
  // Sets it up for `callback`'s query over the box [aabb_min, aabb_max];
  // false when it cannot be culled (not Bullet's convex-versus-concave
  // callback, or its box is not the body's as this reads it), and then
  // every triangle must go to `callback` itself.
  bool init(btTriangleCallback* callback, const btCollisionShape* terrain,
            const btVector3& aabb_min, const btVector3& aabb_max) {
    auto* convex = dynamic_cast<btConvexTriangleCallback*>(callback);
    if (convex == nullptr || convex->m_manifoldPtr == nullptr) return false;
    const btPersistentManifold& manifold = *convex->m_manifoldPtr;
    const btCollisionObject* a = manifold.getBody0();
    const btCollisionObject* b = manifold.getBody1();
    if (a == nullptr || b == nullptr) return false;
    if (a->getCollisionShape() == terrain) std::swap(a, b);
    if (b->getCollisionShape() != terrain || !a->getCollisionShape()->isConvex()) return false;
    // The body in the terrain's frame, as Bullet's callback places it
    // (btConvexTriangleCallback::setTimeStepAndCounters): its box there,
    // widened by the triangles' margin and the query's closest-point
    // distance, is the query box. Anything else (a compound's child, a
    // changed Bullet) is not culled.
    const btTransform pose = b->getWorldTransform().inverse() * a->getWorldTransform();
    const btCollisionShape& shape = *a->getCollisionShape();
    btVector3 lo, hi;
    shape.getAabb(pose, lo, hi);
    const btVector3 below = lo - aabb_min, above = aabb_max - hi;
    const btScalar widen = below.x();
    constexpr btScalar kSame = btScalar(1e-6);  // metres: float rounding of the same sums
    for (int k = 0; k < 3; ++k)
      if (!(std::fabs(below[k] - widen) <= kSame && std::fabs(above[k] - widen) <= kSame)) return false;
    // The shape's local box (margin included) holds the shape: its centre
    // and axes in the terrain's frame, and its half sizes.
    btTransform identity;
    identity.setIdentity();
    shape.getAabb(identity, lo, hi);
    centre_ = pose * ((lo + hi) * btScalar(0.5));
    half_ = (hi - lo) * btScalar(0.5);
    for (int k = 0; k < 3; ++k) axis_[k] = pose.getBasis().getColumn(k);
    // A point farther than the contact breaking threshold is dropped by
    // Bullet; the triangle's margin (and a closest-point query's distance:
    // `widen`) adds to the reach, and 0.1 mm covers the float rounding of
    // these sums and of GJK's (its distance is never below the true one).
    reach_ = std::max(widen, btScalar(0)) + manifold.getContactBreakingThreshold() + btScalar(1e-4);
    next_ = callback;
    culled_ = 0;
    return true;
  }

  void processTriangle(btVector3* v, int part, int index) override {
    if (far(v)) {
      ++culled_;
      return;
    }
    next_->processTriangle(v, part, index);
  }

  int culled() const { return culled_; }
  void count_culled(int n) { culled_ += n; }

  // Whether all of the n points p are more than reach_ + slack beyond one
  // face of the box (along one of its axes, either way).
  bool beyond_a_face(const btVector3* p, int n, btScalar slack) const {
    for (int k = 0; k < 3; ++k) {
      btScalar lo = axis_[k].dot(p[0] - centre_), hi = lo;
      for (int i = 1; i < n; ++i) {
        const btScalar d = axis_[k].dot(p[i] - centre_);
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      if (lo - half_[k] > reach_ + slack || -hi - half_[k] > reach_ + slack) return true;
    }
    return false;
  }

 private:
  // Whether the box is more than reach_ from the triangle v along some axis.
  bool far(const btVector3* v) const {
    // The triangle's normal: all of it is at one offset along it.
    btVector3 n = (v[1] - v[0]).cross(v[2] - v[0]);
    const btScalar length = n.length();
    if (length > btScalar(1e-12)) {
      n /= length;
      const btScalar offset = n.dot(v[0] - centre_);
      const btScalar radius = std::fabs(n.dot(axis_[0])) * half_.x() +
                              std::fabs(n.dot(axis_[1])) * half_.y() +
                              std::fabs(n.dot(axis_[2])) * half_.z();
      if (std::fabs(offset) - radius > reach_) return true;
    }
    // The box's own axes.
    return beyond_a_face(v, 3, 0);
  }

  btTriangleCallback* next_ = nullptr;
  btVector3 centre_{0, 0, 0};
  btVector3 axis_[3]{};
  btVector3 half_{0, 0, 0};
  btScalar reach_ = 0;
  int culled_ = 0;
};

MergedHeightfield::MergedHeightfield(int cols, int rows, const float* heights,
                                     btScalar min_height, btScalar max_height, double tolerance_m,
                                     bool cull_far)
    : btHeightfieldTerrainShape(cols, rows, heights, min_height, max_height, 1, false),
      heights_(heights),
      cols_(cols),
      tolerance_m_(float(tolerance_m)),
      cull_far_(cull_far) {}

void MergedHeightfield::processAllTriangles(btTriangleCallback* callback,
                                            const btVector3& aabb_min,
                                            const btVector3& aabb_max) const {
  NearTriangles near;
  last_culled_ = 0;
  if (cull_far_ && near.init(callback, this, aabb_min, aabb_max)) {
    process(&near, &near, aabb_min, aabb_max);
    last_culled_ = near.culled();
  } else {
    process(callback, nullptr, aabb_min, aabb_max);
  }
}

void MergedHeightfield::process(btTriangleCallback* callback, NearTriangles* near,
                                const btVector3& aabb_min, const btVector3& aabb_max) const {
  if (!(tolerance_m_ > 0.0f)) {
    btHeightfieldTerrainShape::processAllTriangles(callback, aabb_min, aabb_max);
    return;
  }

  // The squares Bullet would visit: the box in unscaled grid units, rounded
  // to the nearest grid points, clamped to the shape and widened by one.
  const btVector3 inv(1 / m_localScaling.x(), 1 / m_localScaling.y(), 1 / m_localScaling.z());
  const btVector3 lo = aabb_min * inv + m_localOrigin;
  const btVector3 hi = aabb_max * inv + m_localOrigin;
  btVector3 lo_c = lo, hi_c = hi;
  lo_c.setMax(m_localAabbMin);
  lo_c.setMin(m_localAabbMax);
  hi_c.setMax(m_localAabbMin);
  hi_c.setMin(m_localAabbMax);
  const int x_begin = std::max(0, quantized(lo_c.x()) - 1);
  const int x_end = std::min(m_heightStickWidth - 1, quantized(hi_c.x()) + 1);
  const int j_begin = std::max(0, quantized(lo_c.z()) - 1);
  const int j_end = std::min(m_heightStickLength - 1, quantized(hi_c.z()) + 1);
  last_triangles_ = 0;
  const btScalar y0 = aabb_min.y(), y1 = aabb_max.y();
  // The largest rectangle: a third of the range along each side, so a body
  // on a plane still meets about 3 x 3 rectangles (18 triangles) and Bullet's
  // one GJK point per triangle still spreads over its face (a body landing
  // flat gets the corners of its face in one step, as with the squares).
  const int max_x = std::max(1, (x_end - x_begin + kSplits - 1) / kSplits);
  const int max_j = std::max(1, (j_end - j_begin + kSplits - 1) / kSplits);
  // Tiles of at most kTile x kTile squares, each merged on its own, so the
  // marks fit a fixed array (no allocation, whatever the body's size).
  for (int tj = j_begin; tj < j_end; tj += kTile)
    for (int tx = x_begin; tx < x_end; tx += kTile)
      merge_tile(callback, near, tx, std::min(tx + kTile, x_end), tj, std::min(tj + kTile, j_end),
                 max_x, max_j, y0, y1);
}

void MergedHeightfield::merge_tile(btTriangleCallback* callback, NearTriangles* near,
                                   int x_begin, int x_end, int j_begin, int j_end, int max_x,
                                   int max_j, btScalar y0, btScalar y1) const {
  std::array<std::uint8_t, std::size_t(kTile) * kTile> merged{};
  const int width = x_end - x_begin;
  auto mark = [&](int x, int j) -> std::uint8_t& {
    return merged[std::size_t(j - j_begin) * std::size_t(width) + std::size_t(x - x_begin)];
  };
  auto height = [&](int x, int j) { return heights_[std::size_t(j) * std::size_t(cols_) + x]; };
  // A sample's vertex as getVertex places it (computed the same way here, to
  // float rounding), for the test of a whole square against the body's box.
  auto corner = [&](int x, int j) {
    return btVector3(-m_width / btScalar(2) + btScalar(x), height(x, j) - m_localOrigin.y(),
                     -m_length / btScalar(2) + btScalar(j)) *
           m_localScaling;
  };
  // Whether a triangle with these heights passes report's height filter.
  auto in_range = [&](float a, float b, float c) {
    return !(std::max({a, b, c}) < y0 || std::min({a, b, c}) > y1);
  };

  btVector3 v[3];
  for (int j = j_begin; j < j_end; ++j) {
    for (int x = x_begin; x < x_end; ++x) {
      if (mark(x, j)) continue;
      // The plane through three corners of this square, in grid steps:
      // h(x', j') = h0 + (x' - x) sx + (j' - j) sj.
      const float h0 = height(x, j);
      const float sx = height(x + 1, j) - h0;
      const float sj = height(x, j + 1) - h0;
      auto on_plane = [&](int xc, int jc) {
        return std::fabs(height(xc, jc) - (h0 + float(xc - x) * sx + float(jc - j) * sj)) <=
               tolerance_m_;
      };
      if (!on_plane(x + 1, j + 1)) {
        // Not planar: Bullet's two triangles of the square, as Bullet reports them.
        mark(x, j) = 1;
        if (near != nullptr) {
          // Both would be culled when the whole square lies beyond one face
          // of the body's box (NearTriangles::far tests each triangle's
          // corners, a subset, the same way): neither is made. 10 um more
          // covers the rounding of `corner` against getVertex.
          const btVector3 c[4] = {corner(x, j), corner(x + 1, j), corner(x, j + 1),
                                  corner(x + 1, j + 1)};
          if (near->beyond_a_face(c, 4, btScalar(1e-5))) {
            const int n = (in_range(c[0].y(), c[2].y(), c[1].y()) ? 1 : 0) +
                          (in_range(c[1].y(), c[2].y(), c[3].y()) ? 1 : 0);
            near->count_culled(n);
            last_triangles_ += n;
            continue;
          }
        }
        getVertex(x, j, v[0]);
        getVertex(x, j + 1, v[1]);
        getVertex(x + 1, j, v[2]);
        last_triangles_ += report(callback, v, 2 * x, j, y0, y1) ? 1 : 0;
        getVertex(x + 1, j, v[0]);
        getVertex(x + 1, j + 1, v[2]);
        last_triangles_ += report(callback, v, 2 * x + 1, j, y0, y1) ? 1 : 0;
        continue;
      }
      // Grow along the row while the next square is free and on the plane,
      // then down while the whole span of the next row is.
      const int x_stop = std::min(x_end, x + max_x), j_stop = std::min(j_end, j + max_j);
      int x1 = x + 1;
      while (x1 < x_stop && !mark(x1, j) && on_plane(x1 + 1, j) && on_plane(x1 + 1, j + 1)) ++x1;
      int j1 = j + 1;
      while (j1 < j_stop) {
        bool fits = on_plane(x, j1 + 1);
        for (int xs = x; fits && xs < x1; ++xs) fits = !mark(xs, j1) && on_plane(xs + 1, j1 + 1);
        if (!fits) break;
        ++j1;
      }
      for (int js = j; js < j1; ++js)
        for (int xs = x; xs < x1; ++xs) mark(xs, js) = 1;
      // The rectangle's two triangles, with the corners' own heights, split
      // and wound as Bullet splits a square.
      getVertex(x, j, v[0]);
      getVertex(x, j1, v[1]);
      getVertex(x1, j, v[2]);
      last_triangles_ += report(callback, v, 2 * x, j, y0, y1) ? 1 : 0;
      getVertex(x1, j, v[0]);
      getVertex(x1, j1, v[2]);
      last_triangles_ += report(callback, v, 2 * x + 1, j, y0, y1) ? 1 : 0;
    }
  }
}

}  // namespace terracut::bullet::detail
