#include "shape_renderer.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "gl_util.hpp"

namespace terracut::viewer {
namespace {

const char* kShapeVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_vp;
uniform mat4 u_model;
out vec3 v_world;
out vec3 v_normal;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_world = w.xyz;
  v_normal = transpose(inverse(mat3(u_model))) * a_normal;
  gl_Position = u_vp * w;
}
)";

const char* kShapeFragmentShader = R"(#version 330 core
in vec3 v_world;
in vec3 v_normal;
uniform vec4 u_color;
uniform vec3 u_light;
uniform vec3 u_eye;
uniform int u_lit;
out vec4 o_color;
void main() {
  if (u_lit == 0) { o_color = u_color; return; }
  vec3 n = normalize(v_normal);
  vec3 v = normalize(u_eye - v_world);
  if (dot(n, v) < 0.0) n = -n;
  vec3 l = normalize(u_light);
  float diffuse = max(dot(n, l), 0.0);
  float spec = pow(max(dot(n, normalize(l + v)), 0.0), 48.0) * 0.35;
  vec3 c = u_color.rgb * (0.30 + 0.20 * (0.5 + 0.5 * n.y) + 0.6 * diffuse) + vec3(spec);
  o_color = vec4(c, u_color.a);
}
)";

struct V {
  float px, py, pz, nx, ny, nz;
};

void push_tri(std::vector<V>& out, Vec3f a, Vec3f b, Vec3f c, Vec3f n) {
  out.push_back({a.x, a.y, a.z, n.x, n.y, n.z});
  out.push_back({b.x, b.y, b.z, n.x, n.y, n.z});
  out.push_back({c.x, c.y, c.z, n.x, n.y, n.z});
}

std::vector<V> box_vertices() {
  std::vector<V> v;
  // Six faces, each two triangles, with the face normal.
  const Vec3f normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3f& n : normals) {
    Vec3f u = std::abs(n.y) > 0.5f ? Vec3f{1, 0, 0} : Vec3f{0, 1, 0};
    Vec3f w = cross(n, u);
    Vec3f c = n * 0.5f;
    Vec3f p0 = c - u * 0.5f - w * 0.5f, p1 = c + u * 0.5f - w * 0.5f;
    Vec3f p2 = c + u * 0.5f + w * 0.5f, p3 = c - u * 0.5f + w * 0.5f;
    push_tri(v, p0, p1, p2, n);
    push_tri(v, p0, p2, p3, n);
  }
  return v;
}

std::vector<V> sphere_vertices(int slices, int stacks) {
  std::vector<V> v;
  auto point = [&](int i, int j) {
    float th = float(std::numbers::pi) * float(j) / float(stacks);
    float ph = 2.0f * float(std::numbers::pi) * float(i) / float(slices);
    return Vec3f{std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)};
  };
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      Vec3f a = point(i, j), b = point(i + 1, j), c = point(i + 1, j + 1), d = point(i, j + 1);
      for (Vec3f p : {a, b, c, a, c, d}) v.push_back({p.x, p.y, p.z, p.x, p.y, p.z});
    }
  return v;
}

// Unit cylinder (radius 1, y from 0 to 1) or cone (base radius 1 at y = 0, tip at y = 1).
std::vector<V> round_vertices(int slices, bool cone) {
  std::vector<V> v;
  float slope = cone ? 1.0f : 0.0f;
  for (int i = 0; i < slices; ++i) {
    float a0 = 2.0f * float(std::numbers::pi) * float(i) / float(slices);
    float a1 = 2.0f * float(std::numbers::pi) * float(i + 1) / float(slices);
    Vec3f b0{std::cos(a0), 0, std::sin(a0)}, b1{std::cos(a1), 0, std::sin(a1)};
    Vec3f n0 = normalize({b0.x, slope, b0.z}), n1 = normalize({b1.x, slope, b1.z});
    Vec3f t0 = cone ? Vec3f{0, 1, 0} : Vec3f{b0.x, 1, b0.z};
    Vec3f t1 = cone ? Vec3f{0, 1, 0} : Vec3f{b1.x, 1, b1.z};
    v.push_back({b0.x, b0.y, b0.z, n0.x, n0.y, n0.z});
    v.push_back({b1.x, b1.y, b1.z, n1.x, n1.y, n1.z});
    v.push_back({t1.x, t1.y, t1.z, n1.x, n1.y, n1.z});
    v.push_back({b0.x, b0.y, b0.z, n0.x, n0.y, n0.z});
    v.push_back({t1.x, t1.y, t1.z, n1.x, n1.y, n1.z});
    v.push_back({t0.x, t0.y, t0.z, n0.x, n0.y, n0.z});
    // Base cap (and top cap for the cylinder).
    push_tri(v, {0, 0, 0}, b1, b0, {0, -1, 0});
    if (!cone) push_tri(v, {0, 1, 0}, t0, t1, {0, 1, 0});
  }
  return v;
}

}  // namespace

ShapeRenderer::ShapeRenderer() {
  program_ = build_program("shapes", kShapeVertexShader, kShapeFragmentShader);
  auto make = [](Mesh& m, const std::vector<V>& v, GLenum mode, bool dynamic) {
    glGenVertexArrays(1, &m.vao);
    glGenBuffers(1, &m.vbo);
    glBindVertexArray(m.vao);
    glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(V)), v.data(),
                 dynamic ? GL_DYNAMIC_DRAW : GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(V), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(V),
                          reinterpret_cast<void*>(3 * sizeof(float)));
    glBindVertexArray(0);
    m.count = GLsizei(v.size());
    m.mode = mode;
  };
  make(box_, box_vertices(), GL_TRIANGLES, false);
  make(sphere_, sphere_vertices(24, 12), GL_TRIANGLES, false);
  make(cylinder_, round_vertices(16, false), GL_TRIANGLES, false);
  make(cone_, round_vertices(20, true), GL_TRIANGLES, false);
  make(line_, std::vector<V>{{0, 0, 0, 0, 1, 0}, {1, 1, 1, 0, 1, 0}}, GL_LINES, true);
  check_gl("creating the shape meshes");
}

ShapeRenderer::~ShapeRenderer() {
  for (Mesh* m : {&box_, &sphere_, &cylinder_, &cone_, &line_}) {
    glDeleteBuffers(1, &m->vbo);
    glDeleteVertexArrays(1, &m->vao);
  }
  glDeleteProgram(program_);
}

void ShapeRenderer::begin(const Mat4& view_projection, Vec3f eye, Vec3f light_dir) {
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_vp"), 1, GL_FALSE, view_projection.data());
  glUniform3f(uniform(program_, "u_eye"), eye.x, eye.y, eye.z);
  glUniform3f(uniform(program_, "u_light"), light_dir.x, light_dir.y, light_dir.z);
}

void ShapeRenderer::draw(const Mesh& mesh, const Mat4& model, Color color, bool lit) {
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_model"), 1, GL_FALSE, model.data());
  glUniform4f(uniform(program_, "u_color"), color.r, color.g, color.b, color.a);
  glUniform1i(uniform(program_, "u_lit"), lit ? 1 : 0);
  glBindVertexArray(mesh.vao);
  glDrawArrays(mesh.mode, 0, mesh.count);
  glBindVertexArray(0);
}

void ShapeRenderer::box(const Mat4& model, Color color) { draw(box_, model, color, true); }

void ShapeRenderer::sphere(Vec3f centre, float radius, Color color) {
  draw(sphere_, translation(centre) * scaling({radius, radius, radius}), color, true);
}

Mat4 ShapeRenderer::segment_frame(Vec3f a, Vec3f b, float radius) {
  // Local +Y along a->b (scaled to its length), X and Z across (scaled to radius).
  Vec3f d = b - a;
  float len = length(d);
  Vec3f y = len > 0.0f ? d * (1.0f / len) : Vec3f{0, 1, 0};
  Vec3f helper = std::abs(y.y) < 0.9f ? Vec3f{0, 1, 0} : Vec3f{1, 0, 0};
  Vec3f x = normalize(cross(helper, y));
  Vec3f z = cross(x, y);
  return translation(a) * basis(x, y, z) * scaling({radius, len, radius});
}

void ShapeRenderer::cylinder(Vec3f a, Vec3f b, float radius, Color color) {
  draw(cylinder_, segment_frame(a, b, radius), color, true);
}

void ShapeRenderer::arrow(Vec3f a, Vec3f b, float radius, Color color) {
  float len = length(b - a);
  if (len <= 0.0f) return;
  float head = std::min(4.0f * radius, 0.5f * len);
  Vec3f dir = (b - a) * (1.0f / len);
  Vec3f neck = b - dir * head;
  cylinder(a, neck, radius, color);
  draw(cone_, segment_frame(neck, b, 2.2f * radius), color, true);
}

void ShapeRenderer::line(Vec3f a, Vec3f b, Color color) {
  const V v[2] = {{a.x, a.y, a.z, 0, 1, 0}, {b.x, b.y, b.z, 0, 1, 0}};
  glBindBuffer(GL_ARRAY_BUFFER, line_.vbo);
  glBufferSubData(GL_ARRAY_BUFFER, 0, sizeof v, v);
  draw(line_, Mat4{}, color, false);
}

}  // namespace terracut::viewer
