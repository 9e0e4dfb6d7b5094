#include "terrain_renderer.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "gl_util.hpp"

namespace terracut::viewer {
namespace {

constexpr GLuint kRestart = 0xFFFFFFFFu;

// One mesh vertex: where it sits (cell coordinates: x = origin.x + pos_u * cell_x),
// which texel coordinates give its height, and whether it is on the surface (1)
// or on the ground (0, the skirt's and the outer walls' foot).
struct Vertex {
  float pos_u, pos_v;
  float sample_u, sample_v;
  float top;
};

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec2 a_pos;
layout(location = 1) in vec2 a_sample;
layout(location = 2) in float a_top;
uniform mat4 u_vp;
uniform sampler2D u_heights;
uniform vec2 u_grid;    // cols, rows
uniform vec2 u_cell;    // cell size along X and Z, metres
uniform vec3 u_origin;  // world origin corner; y = ground
uniform int u_blocky;   // 1: one height per cell (texelFetch)
out vec3 v_world;
out vec2 v_sample;
void main() {
  float h = u_blocky == 1 ? texelFetch(u_heights, ivec2(floor(a_sample)), 0).r
                          : textureLod(u_heights, a_sample / u_grid, 0.0).r;
  vec3 p = vec3(u_origin.x + a_pos.x * u_cell.x, u_origin.y + a_top * h,
                u_origin.z + a_pos.y * u_cell.y);
  v_world = p;
  v_sample = a_sample;
  gl_Position = u_vp * vec4(p, 1.0);
}
)";

const char* kFragmentShader = R"(#version 330 core
in vec3 v_world;
in vec2 v_sample;
uniform sampler2D u_heights;
uniform sampler2D u_initial;
uniform vec2 u_grid;
uniform vec2 u_cell;
uniform vec3 u_origin;
uniform int u_normal_mode;  // 0: smooth from texture, 1: geometric (box mesh), 2: one per cell
uniform int u_color_mode;   // 0: height, 1: removed depth
uniform int u_skirt;        // 1: drawing the skirt (outer walls)
uniform float u_height_scale;
uniform float u_removed_scale;
uniform float u_contour;
uniform vec3 u_light;
uniform vec3 u_eye;
out vec4 o_color;

float h_lin(vec2 s) { return textureLod(u_heights, s / u_grid, 0.0).r; }
float h_cell(ivec2 c) {
  return texelFetch(u_heights, clamp(c, ivec2(0), ivec2(u_grid) - 1), 0).r;
}

// Earth tones from dark soil at the ground to pale sand at the top.
vec3 height_ramp(float t) {
  t = clamp(t, 0.0, 1.0);
  vec3 c0 = vec3(0.30, 0.26, 0.22), c1 = vec3(0.50, 0.39, 0.27);
  vec3 c2 = vec3(0.78, 0.60, 0.36), c3 = vec3(0.98, 0.89, 0.64);
  if (t < 0.35) return mix(c0, c1, t / 0.35);
  if (t < 0.7) return mix(c1, c2, (t - 0.35) / 0.35);
  return mix(c2, c3, (t - 0.7) / 0.3);
}

// Google's Turbo colour map, polynomial fit (Mikhailov 2019).
vec3 turbo(float x) {
  x = clamp(x, 0.0, 1.0);
  vec4 v4 = vec4(1.0, x, x * x, x * x * x);
  vec2 v2 = v4.zw * v4.z;
  return vec3(
    dot(v4, vec4(0.13572138, 4.61539260, -42.66032258, 132.13108234)) +
        dot(v2, vec2(-152.94239396, 59.28637943)),
    dot(v4, vec4(0.09140261, 2.19418839, 4.84296658, -14.18503333)) +
        dot(v2, vec2(4.27729857, 2.82956604)),
    dot(v4, vec4(0.10667330, 12.64194608, -60.58204836, 110.36276771)) +
        dot(v2, vec2(-89.90310912, 27.34824973)));
}

const vec3 kSand = vec3(0.76, 0.66, 0.49);

void main() {
  // Geometric normal of the drawn triangle, turned towards the eye.
  vec3 gn = normalize(cross(dFdx(v_world), dFdy(v_world)));
  if (dot(gn, u_eye - v_world) < 0.0) gn = -gn;
  bool wall = u_skirt == 1 || (u_normal_mode == 1 && abs(gn.y) < 0.5);

  vec3 n;
  float h, h0;
  vec2 s = clamp(v_sample, vec2(0.5), u_grid - 0.5);
  if (wall) {
    n = gn;
    h = v_world.y - u_origin.y;
    h0 = h;
  } else if (u_normal_mode == 0) {
    // Central differences over one cell of the bilinear height field.
    float dx = (h_lin(s + vec2(1.0, 0.0)) - h_lin(s - vec2(1.0, 0.0))) / (2.0 * u_cell.x);
    float dz = (h_lin(s + vec2(0.0, 1.0)) - h_lin(s - vec2(0.0, 1.0))) / (2.0 * u_cell.y);
    n = normalize(vec3(-dx, 1.0, -dz));
    h = h_lin(s);
    h0 = textureLod(u_initial, s / u_grid, 0.0).r;
  } else {
    ivec2 c = ivec2(floor(v_sample));
    h = h_cell(c);
    h0 = texelFetch(u_initial, clamp(c, ivec2(0), ivec2(u_grid) - 1), 0).r;
    if (u_normal_mode == 1) {
      n = gn;
    } else {
      float dx = (h_cell(c + ivec2(1, 0)) - h_cell(c - ivec2(1, 0))) / (2.0 * u_cell.x);
      float dz = (h_cell(c + ivec2(0, 1)) - h_cell(c - ivec2(0, 1))) / (2.0 * u_cell.y);
      n = normalize(vec3(-dx, 1.0, -dz));
    }
  }

  vec3 base;
  if (u_color_mode == 0) {
    base = height_ramp(h / u_height_scale);
  } else {
    float removed = h0 - h;
    base = removed > 1e-7 ? turbo(0.12 + 0.83 * clamp(removed / u_removed_scale, 0.0, 1.0))
                          : kSand * (0.8 + 0.2 * clamp(h / u_height_scale, 0.0, 1.0));
  }
  if (wall) base *= 0.72;

  // Key light, sky/ground hemisphere and a little specular.
  vec3 l = normalize(u_light);
  vec3 v = normalize(u_eye - v_world);
  float diffuse = max(dot(n, l), 0.0);
  float hemi = 0.5 + 0.5 * n.y;
  float spec = pow(max(dot(n, normalize(l + v)), 0.0), 40.0) * 0.10;
  vec3 c = base * (0.22 + 0.28 * hemi + 0.62 * diffuse) + vec3(spec);

  // Height contour lines at (k + 1/2) steps (so flat ground at 0 or at the full
  // scale never lies on one), anti-aliased by the screen-space derivative.
  if (u_contour > 0.0 && !wall) {
    float f = h / u_contour + 0.5;
    float w = max(fwidth(f), 1e-6);
    float line = abs(fract(f + 0.5) - 0.5) / w;
    // Fade lines out where they crowd (steep slopes), so they do not darken them.
    float strength = 0.22 * clamp(1.0 - (w - 0.12) / 0.25, 0.0, 1.0);
    c *= 1.0 - strength * (1.0 - clamp(line, 0.0, 1.0));
  }
  o_color = vec4(c, 1.0);
}
)";

GLuint make_height_texture(int cols, int rows, const float* data, GLint filter) {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, cols, rows, 0, GL_RED, GL_FLOAT, data);
  return t;
}

}  // namespace

TerrainRenderer::TerrainRenderer(const GridSpec& spec, Representation representation,
                                 const float* initial_m, const float* heights_m, int mesh_max)
    : spec_(spec), representation_(representation) {
  GLint max_tex = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
  if (spec.cols > max_tex || spec.rows > max_tex) {
    throw std::runtime_error("terrain of " + std::to_string(spec.cols) + "x" +
                             std::to_string(spec.rows) +
                             " samples is larger than this OpenGL's GL_MAX_TEXTURE_SIZE " +
                             std::to_string(max_tex));
  }
  mesh_max = std::max(mesh_max, 2);
  blocky_ = representation == Representation::kColumns && 2 * spec.cols <= mesh_max &&
            2 * spec.rows <= mesh_max;
  program_ = build_program("terrain", kVertexShader, kFragmentShader);
  GLint filter = representation == Representation::kColumns ? GL_NEAREST : GL_LINEAR;
  heights_tex_ = make_height_texture(spec.cols, spec.rows, heights_m, filter);
  initial_tex_ = make_height_texture(spec.cols, spec.rows, initial_m, filter);

  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glGenBuffers(1, &ibo_);
  glBindVertexArray(vao_);
  if (blocky_) {
    build_blocky_mesh();
  } else {
    build_surface_mesh(mesh_max);
  }
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<void*>(offsetof(Vertex, sample_u)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        reinterpret_cast<void*>(offsetof(Vertex, top)));
  glBindVertexArray(0);
  check_gl("creating the terrain mesh and textures");
}

TerrainRenderer::~TerrainRenderer() {
  glDeleteProgram(program_);
  glDeleteBuffers(1, &vbo_);
  glDeleteBuffers(1, &ibo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteTextures(1, &heights_tex_);
  glDeleteTextures(1, &initial_tex_);
}

void TerrainRenderer::build_surface_mesh(int mesh_max) {
  // Interior vertices from the first to the last sample centre, plus the outer
  // edge of the terrain on each side (flat half-cell border).
  auto axis = [&](int samples, std::vector<float>& pos, std::vector<float>& smp) {
    int n = std::min(samples, mesh_max);
    pos.push_back(0.0f);
    smp.push_back(0.5f);
    for (int i = 0; i < n; ++i) {
      float s = n > 1 ? 0.5f + float(i) * float(samples - 1) / float(n - 1) : 0.5f * float(samples);
      pos.push_back(s);
      smp.push_back(s);
    }
    pos.push_back(float(samples));
    smp.push_back(float(samples) - 0.5f);
  };
  std::vector<float> pu, su, pv, sv;
  axis(spec_.cols, pu, su);
  axis(spec_.rows, pv, sv);
  const int nx = int(pu.size()), nz = int(pv.size());
  mesh_cols_ = nx;
  mesh_rows_ = nz;

  std::vector<Vertex> vertices;
  vertices.reserve(std::size_t(nx) * nz + 2 * std::size_t(nx + nz));
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nx; ++i) vertices.push_back({pu[i], pv[j], su[i], sv[j], 1.0f});

  std::vector<GLuint> indices;
  indices.reserve(std::size_t(nz - 1) * (2 * std::size_t(nx) + 1) + 4 * std::size_t(nx + nz));
  for (int j = 0; j + 1 < nz; ++j) {
    for (int i = 0; i < nx; ++i) {
      indices.push_back(GLuint(j * nx + i));
      indices.push_back(GLuint((j + 1) * nx + i));
    }
    indices.push_back(kRestart);
  }
  top_index_count_ = GLsizei(indices.size());
  triangles_ = std::int64_t(nz - 1) * (nx - 1) * 2;

  // Skirt: the perimeter of the top grid, each vertex paired with one on the ground.
  std::vector<GLuint> ring;
  for (int i = 0; i < nx; ++i) ring.push_back(GLuint(i));
  for (int j = 1; j < nz; ++j) ring.push_back(GLuint(j * nx + nx - 1));
  for (int i = nx - 2; i >= 0; --i) ring.push_back(GLuint((nz - 1) * nx + i));
  for (int j = nz - 2; j >= 0; --j) ring.push_back(GLuint(j * nx));
  for (GLuint top_index : ring) {
    Vertex ground = vertices[top_index];
    ground.top = 0.0f;
    indices.push_back(top_index);
    indices.push_back(GLuint(vertices.size()));
    vertices.push_back(ground);
  }
  skirt_index_count_ = GLsizei(indices.size()) - top_index_count_;
  triangles_ += std::int64_t(ring.size() - 1) * 2;

  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(Vertex)), vertices.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)),
               indices.data(), GL_STATIC_DRAW);
}

void TerrainRenderer::build_blocky_mesh() {
  // A vertex pair at every cell edge: vertex k of the 2*n interior ones belongs
  // to cell k/2 and sits on that cell's low (k even) or high (k odd) edge, so
  // quads inside a cell are flat tops and quads between two cells are walls.
  // The outer ring lies on the ground, closing the outer walls.
  auto axis = [](int samples, std::vector<float>& pos, std::vector<float>& smp,
                 std::vector<bool>& inner) {
    pos.push_back(0.0f);
    smp.push_back(0.5f);
    inner.push_back(false);
    for (int k = 0; k < 2 * samples; ++k) {
      int cell = k / 2;
      pos.push_back(float(cell + (k % 2)));
      smp.push_back(float(cell) + 0.5f);
      inner.push_back(true);
    }
    pos.push_back(float(samples));
    smp.push_back(float(samples) - 0.5f);
    inner.push_back(false);
  };
  std::vector<float> pu, su, pv, sv;
  std::vector<bool> iu, iv;
  axis(spec_.cols, pu, su, iu);
  axis(spec_.rows, pv, sv, iv);
  const int nx = int(pu.size()), nz = int(pv.size());
  mesh_cols_ = nx;
  mesh_rows_ = nz;

  std::vector<Vertex> vertices;
  vertices.reserve(std::size_t(nx) * nz);
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nx; ++i)
      vertices.push_back({pu[i], pv[j], su[i], sv[j], (iu[i] && iv[j]) ? 1.0f : 0.0f});
  std::vector<GLuint> indices;
  indices.reserve(std::size_t(nz - 1) * (2 * std::size_t(nx) + 1));
  for (int j = 0; j + 1 < nz; ++j) {
    for (int i = 0; i < nx; ++i) {
      indices.push_back(GLuint(j * nx + i));
      indices.push_back(GLuint((j + 1) * nx + i));
    }
    indices.push_back(kRestart);
  }
  top_index_count_ = GLsizei(indices.size());
  skirt_index_count_ = 0;
  triangles_ = std::int64_t(nz - 1) * (nx - 1) * 2;

  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(Vertex)), vertices.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)),
               indices.data(), GL_STATIC_DRAW);
}

void TerrainRenderer::upload(const float* heights_m, const Rect& rect) {
  Rect r = rect;
  r.c0 = std::max(r.c0, 0);
  r.r0 = std::max(r.r0, 0);
  r.c1 = std::min(r.c1, spec_.cols);
  r.r1 = std::min(r.r1, spec_.rows);
  if (r.empty()) return;
  glBindTexture(GL_TEXTURE_2D, heights_tex_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, spec_.cols);
  glTexSubImage2D(GL_TEXTURE_2D, 0, r.c0, r.r0, r.c1 - r.c0, r.r1 - r.r0, GL_RED, GL_FLOAT,
                  heights_m + std::int64_t(r.r0) * spec_.cols + r.c0);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  uploaded_samples_ += r.area();
}

void TerrainRenderer::draw(const Mat4& view_projection, Vec3f eye, const TerrainStyle& style) {
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_vp"), 1, GL_FALSE, view_projection.data());
  glUniform2f(uniform(program_, "u_grid"), float(spec_.cols), float(spec_.rows));
  glUniform2f(uniform(program_, "u_cell"), float(spec_.cell_x_m()), float(spec_.cell_z_m()));
  glUniform3f(uniform(program_, "u_origin"), float(spec_.origin_m.x), float(spec_.origin_m.y),
              float(spec_.origin_m.z));
  glUniform1i(uniform(program_, "u_blocky"), blocky_ ? 1 : 0);
  int normal_mode = blocky_ ? 1 : (representation_ == Representation::kColumns ? 2 : 0);
  glUniform1i(uniform(program_, "u_normal_mode"), normal_mode);
  glUniform1i(uniform(program_, "u_color_mode"), style.color == ColorMode::kRemoved ? 1 : 0);
  glUniform1f(uniform(program_, "u_height_scale"), std::max(style.height_scale_m, 1e-6f));
  glUniform1f(uniform(program_, "u_removed_scale"), std::max(style.removed_scale_m, 1e-6f));
  glUniform1f(uniform(program_, "u_contour"), style.contour_step_m);
  glUniform3f(uniform(program_, "u_light"), style.light_dir.x, style.light_dir.y,
              style.light_dir.z);
  glUniform3f(uniform(program_, "u_eye"), eye.x, eye.y, eye.z);
  glUniform1i(uniform(program_, "u_heights"), 0);
  glUniform1i(uniform(program_, "u_initial"), 1);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, initial_tex_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, heights_tex_);

  glEnable(GL_PRIMITIVE_RESTART);
  glPrimitiveRestartIndex(kRestart);
  glBindVertexArray(vao_);
  glUniform1i(uniform(program_, "u_skirt"), 0);
  glDrawElements(GL_TRIANGLE_STRIP, top_index_count_, GL_UNSIGNED_INT, nullptr);
  if (skirt_index_count_ > 0) {
    glUniform1i(uniform(program_, "u_skirt"), 1);
    glDrawElements(GL_TRIANGLE_STRIP, skirt_index_count_, GL_UNSIGNED_INT,
                   reinterpret_cast<void*>(std::size_t(top_index_count_) * sizeof(GLuint)));
  }
  glBindVertexArray(0);
  glDisable(GL_PRIMITIVE_RESTART);
}

}  // namespace terracut::viewer
