// The viewer's 3D scene: its GL objects, the sky gradient behind it, the
// terrain, the tool (blade edge and plate, device point, proxy, drop line,
// force arrow) and the rigid bodies, and the terrain's height under a point.
#include "viewer_app_internal.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>

#include "gl_util.hpp"
#include "terracut/core/surface.hpp"

namespace terracut::viewer {
namespace {

const char* kBackgroundVertex = R"(#version 330 core
out float v_t;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  v_t = 0.5 * (p.y + 1.0);
  gl_Position = vec4(p, 0.999, 1.0);
}
)";
const char* kBackgroundFragment = R"(#version 330 core
in float v_t;
out vec4 o_color;
void main() {
  vec3 bottom = vec3(0.80, 0.84, 0.88), top = vec3(0.42, 0.55, 0.70);
  o_color = vec4(mix(bottom, top, clamp(v_t, 0.0, 1.0)), 1.0);
}
)";

}  // namespace

// Where and how large the tool's marks are: computed once a frame, drawn
// opaque first and then, see-through, over everything.
struct ViewerApp::ToolMarks {
  Vec3f a, b;           // the cutting edge's ends
  bool in_contact;      // the edge touches the soil (drawn red)
  float rod;            // the edge rod's radius
  float ground;         // the soil's height under the tool
  Mat4 plate;           // the plate's model matrix (a flat blade)
  bool bucket;          // a bucket instead of the plate
  Mat4 floor, back;     // the bucket's floor and back wall
  Mat4 load;            // the soil it carries (a box of the load's volume on the floor)
  bool loaded;
  float r;              // the device point's radius
  Vec3f device, proxy;  // the device point and the proxy
};

void ViewerApp::init_gl_objects() {
  shapes_ = std::make_unique<ShapeRenderer>();
  background_program_ = build_program("background", kBackgroundVertex, kBackgroundFragment);
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  background_vao_ = vao;
}

float ViewerApp::ground_height_at(double x, double z) const {
  // The terrain surface of the reader's frame at world (x, z), as the model
  // reads it (core/surface.hpp: the same query the force model uses).
  const haptics::ViewFrame& f = driver_->exchange().front();
  const GridSpec& spec = driver_->spec();
  return float(spec.origin_m.y + surface_height_m(spec, f.heights.data(),
                                                   driver_->representation(), x, z));
}

void ViewerApp::draw_background(int fb_width, int fb_height) {
  // The sky gradient over the whole framebuffer, then a clear depth for the scene.
  glViewport(0, 0, fb_width, fb_height);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(background_program_);
  glBindVertexArray(background_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glClear(GL_DEPTH_BUFFER_BIT);
}

void ViewerApp::draw_scene(int x, int y, int w, int h) {
  // The scene spans the framebuffer's full height (y = 0), right of the panel.
  (void)y;
  glViewport(x, 0, w, h);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  float aspect = float(w) / float(h);
  Mat4 vp = camera_.projection(aspect) * camera_.view();
  Vec3f eye = camera_.eye();
  draw_terrain(vp, eye);

  shapes_->begin(vp, eye, style_.light_dir);
  const ToolMarks m = tool_marks();
  draw_blade_edge(m);
  if (m.bucket) {
    shapes_->box(m.floor, {0.55f, 0.58f, 0.64f, 1.0f});
    shapes_->box(m.back, {0.55f, 0.58f, 0.64f, 1.0f});
    if (m.loaded) shapes_->box(m.load, {0.80f, 0.66f, 0.42f, 1.0f});  // sand
  }
  draw_bodies();
  draw_device(m);
  draw_force_arrow(m);
  draw_see_through(m);
}

void ViewerApp::draw_terrain(const Mat4& vp, Vec3f eye) {
  // The key light follows the camera: from above, a little left of and behind the eye.
  float yaw = camera_.mode == CameraMode::kTop ? 0.0f : camera_.yaw_rad;
  Vec3f right{std::cos(yaw), 0.0f, -std::sin(yaw)}, back{std::sin(yaw), 0.0f, std::cos(yaw)};
  style_.light_dir = right * -0.45f + back * 0.40f + Vec3f{0.0f, 0.85f, 0.0f};
  terrain_->draw(vp, eye, style_);
}

ViewerApp::ToolMarks ViewerApp::tool_marks() const {
  const Live& l = *live_;
  const float extent = float(std::max(driver_->spec().size_x_m, driver_->spec().size_z_m));
  const float blade_len = float(driver_->blade_length_m());
  ToolMarks m;
  // Blade: the cutting edge as a rod (red while in contact) under a thin plate.
  m.a = to_f(l.edge.a);
  m.b = to_f(l.edge.b);
  m.in_contact = l.contact.length_m > 0.0;
  m.rod = std::max(0.006f * blade_len, 0.003f * extent);
  // The plate is drawn last, see-through, so it never hides the cut behind
  // it; a blade of finite height (blade.height_m) is drawn as tall as it
  // is, one of unbounded height 0.12 blade lengths above the soil, however
  // deep the edge is.
  m.ground = ground_height_at(l.pose.position_m.x, l.pose.position_m.z);
  // (a finite plate spans from the rod to the blade's top, no taller than
  // the scene)
  const double blade_h = driver_->blade_height_m();
  float plate_h = std::isfinite(blade_h)
                      ? std::max(0.1f * m.rod, std::min(float(blade_h), 2.0f * extent) - m.rod)
                      : 0.12f * blade_len + std::max(0.0f, m.ground - float(l.pose.position_m.y));
  m.plate = translation(to_f(l.pose.position_m)) * rotation(l.pose.orientation) *
            translation({0.0f, 0.5f * plate_h + m.rod, 0.0f}) *
            scaling({blade_len, plate_h, 0.6f * m.rod});
  // A bucket: its floor from the lip back along the blade frame's +Z and its
  // back wall (blade.hpp), and the soil it carries as a box of the load's
  // volume on the floor, as deep as the floor (its section's area / depth high).
  const BucketSpec& bucket = driver_->bucket();
  m.bucket = bucket.enabled();
  m.loaded = false;
  if (m.bucket) {
    const Mat4 frame = translation(to_f(l.pose.position_m)) * rotation(l.pose.orientation);
    const float depth = float(bucket.depth_m), height = float(bucket.height_m), wall = 2.0f * m.rod;
    m.floor = frame * translation({0.0f, -0.5f * wall, 0.5f * depth}) * scaling({blade_len, wall, depth});
    m.back = frame * translation({0.0f, 0.5f * height, depth + 0.5f * wall}) * scaling({blade_len, height, wall});
    const float fill = float(l.bucket_load_m3 / (double(blade_len) * bucket.depth_m));
    m.loaded = fill > 1e-6f;
    if (m.loaded)
      m.load = frame * translation({0.0f, 0.5f * fill, 0.5f * depth}) * scaling({0.98f * blade_len, fill, 0.98f * depth});
  }
  m.r = 0.012f * extent;
  m.device = to_f(l.device_m);
  m.proxy = to_f(l.proxy_m);
  return m;
}

void ViewerApp::draw_blade_edge(const ToolMarks& m) {
  shapes_->cylinder(m.a, m.b, m.rod,
                    m.in_contact ? Color{0.92f, 0.22f, 0.15f, 1} : Color{0.25f, 0.35f, 0.55f, 1});
}

void ViewerApp::draw_bodies() {
  // Rigid bodies (the Bullet world's), lit, in cool stone colours that stand
  // apart from the soil's browns.
  static const Color kBodyColors[4] = {{0.52f, 0.60f, 0.72f, 1.0f},
                                       {0.60f, 0.64f, 0.70f, 1.0f},
                                       {0.46f, 0.56f, 0.62f, 1.0f},
                                       {0.62f, 0.58f, 0.72f, 1.0f}};
  const Live& l = *live_;
  for (int i = 0; i < l.body_count; ++i) {
    const haptics::ViewBody& body = l.bodies[std::size_t(i)];
    const Color color = kBodyColors[i % 4];
    const Vec3f centre = to_f(body.position_m);
    switch (body.shape) {
      case BodyShape::kBox:
        shapes_->box(translation(centre) * rotation(body.orientation) *
                         scaling(to_f(body.half_extents_m) * 2.0f),
                     color);
        break;
      case BodyShape::kSphere:
        shapes_->sphere(centre, float(body.half_extents_m.x), color);
        break;
      case BodyShape::kCylinder: {
        // The axis is the body's local Y.
        const Vec3 half_axis = rotate(body.orientation, Vec3{0.0, body.half_extents_m.y, 0.0});
        shapes_->cylinder(to_f(body.position_m - half_axis), to_f(body.position_m + half_axis),
                          float(body.half_extents_m.x), color);
        break;
      }
    }
  }
}

void ViewerApp::draw_device(const ToolMarks& m) {
  // Device point, proxy and the spring between them; a drop line to the ground.
  const float r = m.r;
  const Vec3f device = m.device, proxy = m.proxy;
  shapes_->sphere(device, r, {0.20f, 0.45f, 0.95f, 1.0f});
  if (length(proxy - device) > 0.5f * r) {
    shapes_->sphere(proxy, 0.8f * r, {1.0f, 0.60f, 0.10f, 1.0f});
    shapes_->line(device, proxy, {1.0f, 0.6f, 0.1f, 1.0f});
  }
  Vec3f foot{device.x, m.ground, device.z};
  if (device.y > m.ground + r) {
    shapes_->line(device, foot, {0.1f, 0.1f, 0.1f, 1.0f});
    shapes_->sphere(foot, 0.35f * r, {0.1f, 0.1f, 0.1f, 1.0f});
  }
}

void ViewerApp::draw_force_arrow(const ToolMarks& m) {
  // Force on the tool: an arrow scaled so that the largest force of the plot
  // window is arrow_length_m_ long (the label gives the value).
  const Live& l = *live_;
  float fmag = magnitude(l.force_world_n);
  if (show_force_ && fmag > 1e-3f) {
    float fmax = 1.0f;
    for (float v : l.force_hist) fmax = std::max(fmax, v);
    float len = arrow_length_m_ * std::min(1.0f, fmag / fmax);
    Vec3f dir = to_f(l.force_world_n) * (1.0f / fmag);
    shapes_->arrow(m.device, m.device + dir * len, 0.35f * m.r, {0.98f, 0.85f, 0.15f, 1.0f});
  }
}

void ViewerApp::draw_see_through(const ToolMarks& m) {
  // The plate, blended, without writing depth.
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glDepthMask(GL_FALSE);
  if (!m.bucket) shapes_->box(m.plate, {0.70f, 0.74f, 0.80f, 0.35f});
  // The edge and the device point once more, faint and without depth test, so
  // they show through the soil that hides them (a blade deep in a trench).
  glDisable(GL_DEPTH_TEST);
  shapes_->cylinder(m.a, m.b, m.rod,
                    m.in_contact ? Color{0.92f, 0.22f, 0.15f, 0.35f} : Color{0.25f, 0.35f, 0.55f, 0.35f});
  shapes_->sphere(m.device, m.r, {0.20f, 0.45f, 0.95f, 0.35f});
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}

}  // namespace terracut::viewer
