// Cameras of the viewer: an orbit camera (perspective, turned with the right
// mouse button) and a fixed top-down orthographic camera used by the tests.
#pragma once

#include "gfx_math.hpp"
#include "terracut/core/grid.hpp"

namespace terracut::viewer {

/// Which camera draws the scene.
enum class CameraMode {
  kOrbit,  ///< perspective, orbiting a target point
  /// Orthographic, looking straight down (-Y) with +X to the right of the
  /// image and +Z down the image. The terrain's extent is fitted, aspect kept,
  /// into the viewport shrunk by kTopMarginFraction on every side and centred.
  kTop,
};

/// Fraction of the viewport's width and height left empty on each side by the top camera.
inline constexpr float kTopMarginFraction = 0.1f;

/// A world-space ray (origin and unit direction).
struct Ray {
  Vec3f origin{};
  Vec3f direction{0.0f, -1.0f, 0.0f};
};

/// Camera state; the matrices are derived from it for a viewport aspect ratio.
struct Camera {
  CameraMode mode = CameraMode::kOrbit;
  Vec3f target{};              ///< orbit centre, world metres
  float yaw_rad = 0.6f;        ///< rotation about +Y of the eye around the target, rad
  float pitch_rad = 0.55f;     ///< elevation of the eye above the target's horizon, rad, (0, pi/2)
  float distance_m = 2.0f;     ///< eye distance from the target, metres, > 0
  float fov_y_rad = 0.7f;      ///< vertical field of view, rad
  float scene_radius_m = 1.0f; ///< radius of the scene (near/far planes), metres
  /// Top camera: the world rectangle to fit (x0, z0, x1, z1), metres.
  float top_x0 = 0.0f, top_z0 = 0.0f, top_x1 = 1.0f, top_z1 = 1.0f;
  float top_y_max = 1.0f;  ///< top camera: highest world Y drawn, metres

  /// Frames the terrain of spec (whose heights reach at most max_height_m).
  void frame_terrain(const GridSpec& spec, double max_height_m);
  Vec3f eye() const;
  Mat4 view() const;
  Mat4 projection(float aspect) const;
  /// The ray under a viewport point (x, y in [0, 1], y down), world frame.
  Ray ray(float x01, float y01, float aspect) const;
};

}  // namespace terracut::viewer
