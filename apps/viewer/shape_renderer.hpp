// Draws the small objects of the scene: boxes (blade plate, rigid bodies),
// spheres (device and proxy), arrows (force) and lines, lit like the terrain.
#pragma once

#include <epoxy/gl.h>

#include "gfx_math.hpp"

namespace terracut::viewer {

struct Color {
  float r = 1.0f, g = 1.0f, b = 1.0f, a = 1.0f;
};

class ShapeRenderer {
 public:
  /// Builds the meshes; needs a current OpenGL 3.3 core context.
  ShapeRenderer();
  ~ShapeRenderer();
  ShapeRenderer(const ShapeRenderer&) = delete;
  ShapeRenderer& operator=(const ShapeRenderer&) = delete;

  /// Sets the camera and light for the following draws.
  void begin(const Mat4& view_projection, Vec3f eye, Vec3f light_dir);
  /// A box: the unit cube [-0.5, 0.5]^3 transformed by model.
  void box(const Mat4& model, Color color);
  void sphere(Vec3f centre, float radius, Color color);
  /// A cylinder of the given radius from a to b.
  void cylinder(Vec3f a, Vec3f b, float radius, Color color);
  /// An arrow from a to b: a shaft and a cone head (head length ~ 4 radii).
  void arrow(Vec3f a, Vec3f b, float radius, Color color);
  /// An unlit line from a to b (1 pixel).
  void line(Vec3f a, Vec3f b, Color color);

 private:
  struct Mesh {
    GLuint vao = 0, vbo = 0;
    GLsizei count = 0;
    GLenum mode = GL_TRIANGLES;
  };
  void draw(const Mesh& mesh, const Mat4& model, Color color, bool lit);
  static Mat4 segment_frame(Vec3f a, Vec3f b, float radius);

  GLuint program_ = 0;
  Mesh box_, sphere_, cylinder_, cone_, line_;
};

}  // namespace terracut::viewer
