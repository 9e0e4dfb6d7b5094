// Bullet's heightfield over the grid's heights, handing coplanar squares to a
// collision query as one rectangle. Internal to terracut::bullet.
//
// Bullet finds a convex body's contacts with a heightfield one triangle at a
// time (btConvexTriangleCallback: a GJK run per triangle under the body's
// bounding box). On 2 cm cells a 0.3 m box meets about 450 triangles, and a
// profile of the rescue scenario spends about 80 % of the Bullet step in
// those GJK runs. Soil that was cut level, or left untouched, is planar over
// most of a body's footprint, and a plane's triangles all give the same
// contacts as larger triangles over the same plane would. MergedHeightfield
// overrides processAllTriangles (the query every convex-concave collision
// uses): over the same range of squares that Bullet would visit, it grows
// rectangles of squares whose samples lie on one plane (each within
// `tolerance_m` of the plane of the rectangle's first square) and reports
// each rectangle as two triangles; squares off every plane are reported
// exactly as Bullet reports them (same vertices, order, winding and
// indices). A rectangle spans at most a third of the range along each side:
// Bullet keeps one GJK point per triangle, so a body on a plane must still
// meet a few triangles (about 3 x 3 rectangles) for its contact points to
// spread over its face in one step; with one rectangle a box landing on a
// level cut floor touched at one or two corners and slid (the test
// BodyFallsByTheCutDepthAndOthersStayPut measured 12 mm of slide). Ray
// tests (performRaycast) and everything else are Bullet's own.
//
// The range is merged in tiles of at most kTile x kTile squares (rectangles
// do not cross tiles), so the marks of the squares already reported fit a
// fixed array on the stack: a query allocates nothing. The shape is queried
// from one thread at a time (the world's stepping thread).
//
// Far triangles are not handed to Bullet's narrow phase (`cull_far`). Bullet
// keeps a triangle's contact only when its GJK distance to the body is within
// the manifold's contact breaking threshold (btManifoldResult::addContactPoint),
// and tests every triangle whose bounding box meets the body's axis-aligned
// box. A body tilted over uneven soil (the rescue's block_b lying on its side
// on the sand that slid into its trench) has a world box far larger than
// itself, and most of the triangles in that box lie centimetres below the
// body: on the rescue with soil that flows they were about three quarters of
// every GJK run. A triangle is dropped when a separating axis (the
// triangle's normal or one of the body's own axes) shows the body's oriented
// bounding box (its shape's local box, margin included) more than the
// threshold, the triangle's margin and 0.1 mm away from it: GJK's distance is
// never below the true distance, so Bullet would have added no point for it,
// and the contacts, and so the bodies' motion, are the same bit for bit. Only
// Bullet's convex-versus-concave query (btConvexTriangleCallback) is culled;
// rays and every other query get every triangle.
#pragma once

#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>


namespace terracut::bullet::detail {

class NearTriangles;  // the cull of far triangles (merged_heightfield.cpp)

class MergedHeightfield final : public btHeightfieldTerrainShape {
 public:
  /// As btHeightfieldTerrainShape(cols, rows, heights, min, max, 1 (Y up),
  /// false): float heights, row-major (index = row * cols + col), Y up, no
  /// flipped quad edges. tolerance_m <= 0 reports Bullet's own triangles.
  /// cull_far: drop the triangles no contact can come from (above).
  MergedHeightfield(int cols, int rows, const float* heights, btScalar min_height,
                    btScalar max_height, double tolerance_m, bool cull_far);

  void processAllTriangles(btTriangleCallback* callback, const btVector3& aabb_min,
                           const btVector3& aabb_max) const override;

  /// Triangles reported by the last processAllTriangles (merged path), for
  /// tests and profiles; those culled as far are counted too.
  int last_triangle_count() const { return last_triangles_; }
  /// Of the triangles of the last processAllTriangles, those culled as far.
  int last_culled_count() const { return last_culled_; }

 private:
  static constexpr int kTile = 64;   ///< squares per side of a merging tile
  static constexpr int kSplits = 3;  ///< a rectangle spans at most 1/kSplits of the range per side

  // The query itself (merged or Bullet's), to callback; near: the cull
  // (callback itself) or null, so that a square beyond the body is skipped
  // before its triangles are made.
  void process(btTriangleCallback* callback, NearTriangles* near, const btVector3& aabb_min,
               const btVector3& aabb_max) const;

  // Merges and reports the squares [x_begin, x_end) x [j_begin, j_end).
  // Rectangles span at most max_x x max_j squares.
  void merge_tile(btTriangleCallback* callback, NearTriangles* near, int x_begin, int x_end,
                  int j_begin, int j_end, int max_x, int max_j, btScalar y0, btScalar y1) const;

  const float* heights_;
  int cols_;
  float tolerance_m_;
  bool cull_far_;
  mutable int last_triangles_ = 0;
  mutable int last_culled_ = 0;
};

}  // namespace terracut::bullet::detail
