#include "terrain_renderer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <stdexcept>
#include <string>
#include <vector>

#include "gl_util.hpp"

namespace terracut::viewer {
namespace {

constexpr GLuint kRestart = 0xFFFFFFFFu;

// One vertex of the columns' box mesh: where it sits (cell coordinates:
// x = origin.x + pos_u * cell_x), which texel gives its height, and whether it
// is on the surface (1) or on the ground (0, the outer walls' foot).
struct BoxVertex {
  float pos_u, pos_v;
  float sample_u, sample_v;
  float top;
};

// One vertex of the level-of-detail patch: its corner (i, j) of the patch's
// kPatchQuads x kPatchQuads quads, whether it is on the surface (1) or a
// skirt's foot on the ground (0), and whether it belongs to the skirt.
struct PatchVertex {
  float i, j;
  float top;
  float skirt;
};

const char* kBoxVertexShader = R"(#version 330 core
layout(location = 0) in vec2 a_pos;
layout(location = 1) in vec2 a_sample;
layout(location = 2) in float a_top;
uniform mat4 u_vp;
uniform sampler2D u_heights;
uniform vec2 u_grid;    // cols, rows
uniform vec2 u_cell;    // cell size along X and Z, metres
uniform vec3 u_origin;  // world origin corner; y = ground
out vec3 v_world;
out vec2 v_sample;
out float v_wall;
void main() {
  // One height per cell (texelFetch): flat tops, vertical walls.
  float h = texelFetch(u_heights, ivec2(floor(a_sample)), 0).r;
  vec3 p = vec3(u_origin.x + a_pos.x * u_cell.x, u_origin.y + a_top * h,
                u_origin.z + a_pos.y * u_cell.y);
  v_world = p;
  v_sample = a_sample;
  v_wall = 0.0;
  gl_Position = u_vp * vec4(p, 1.0);
}
)";

// Mesh lines: line 0 is the terrain's outer edge (a flat half-cell border
// reads the first sample), line k + 1 is sample k's centre, line cols + 1 the
// far edge. A chunk's vertex (i, j) sits on line chunk.xy + (i, j) * step,
// clamped to the last line (a chunk reaching past the terrain folds onto its
// edge: those triangles have no area).
const char* kLodVertexShader = R"(#version 330 core
layout(location = 0) in vec2 a_patch;
layout(location = 1) in float a_top;
layout(location = 2) in float a_skirt;
layout(location = 3) in vec3 a_chunk;  // per instance: first lines (u, v), lines per quad
uniform mat4 u_vp;
uniform sampler2D u_heights;
uniform vec2 u_grid;    // cols, rows
uniform vec2 u_cell;    // cell size along X and Z, metres
uniform vec3 u_origin;  // world origin corner; y = ground
uniform vec2 u_lines;   // last mesh line along X and Z: cols + 1, rows + 1
out vec3 v_world;
out vec2 v_sample;
out float v_wall;
void main() {
  vec2 line = min(a_chunk.xy + a_patch * a_chunk.z, u_lines);
  vec2 pos = clamp(line - 0.5, vec2(0.0), u_grid);
  vec2 s = clamp(line - 0.5, vec2(0.5), u_grid - 0.5);
  float h = textureLod(u_heights, s / u_grid, 0.0).r;
  vec3 p = vec3(u_origin.x + pos.x * u_cell.x, u_origin.y + a_top * h,
                u_origin.z + pos.y * u_cell.y);
  v_world = p;
  v_sample = s;
  // A skirt on the terrain's outer edge is its wall; inside, skirts only fill
  // the cracks between chunks of different detail and are shaded as soil.
  bool edge = line.x <= 0.0 || line.y <= 0.0 || line.x >= u_lines.x || line.y >= u_lines.y;
  v_wall = a_skirt > 0.5 && edge ? 1.0 : 0.0;
  gl_Position = u_vp * vec4(p, 1.0);
}
)";

const char* kTerrainFragmentShader = R"(#version 330 core
in vec3 v_world;
in vec2 v_sample;
in float v_wall;  // 1 on the terrain's outer walls
uniform sampler2D u_heights;
uniform sampler2D u_initial;
uniform vec2 u_grid;
uniform vec2 u_cell;
uniform vec3 u_origin;
uniform int u_normal_mode;  // 0: smooth from texture, 1: geometric (box mesh), 2: one per cell
uniform int u_color_mode;   // 0: height, 1: removed depth
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
  bool wall = v_wall > 0.99 || (u_normal_mode == 1 && abs(gn.y) < 0.5);

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

// Fills the bound vertex array's buffers with a mesh (static).
template <class V>
void upload_mesh(GLuint vbo, GLuint ibo, const std::vector<V>& vertices,
                 const std::vector<GLuint>& indices) {
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(V)), vertices.data(),
               GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(GLuint)),
               indices.data(), GL_STATIC_DRAW);
}

// Float attribute `index` of `count` components at `offset` bytes into V.
template <class V>
void float_attribute(GLuint index, GLint count, std::size_t offset) {
  glEnableVertexAttribArray(index);
  glVertexAttribPointer(index, count, GL_FLOAT, GL_FALSE, sizeof(V),
                        reinterpret_cast<void*>(offset));
}

// The largest height of a set of samples, metres (0 for none).
float highest(const float* heights_m, int cols, const Rect& r) {
  float top = 0.0f;
  for (int row = r.r0; row < r.r1; ++row) {
    const float* line = heights_m + std::int64_t(row) * cols;
    for (int c = r.c0; c < r.c1; ++c) top = std::max(top, line[c]);
  }
  return top;
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
  program_ = blocky_ ? build_program("terrain (boxes)", kBoxVertexShader, kTerrainFragmentShader)
                     : build_program("terrain", kLodVertexShader, kTerrainFragmentShader);
  GLint filter = representation == Representation::kColumns ? GL_NEAREST : GL_LINEAR;
  heights_tex_ = make_height_texture(spec.cols, spec.rows, heights_m, filter);
  initial_tex_ = make_height_texture(spec.cols, spec.rows, initial_m, filter);
  const Rect all{0, 0, spec.cols, spec.rows};
  top_m_ = std::max(highest(initial_m, spec.cols, all), highest(heights_m, spec.cols, all));

  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glGenBuffers(1, &ibo_);
  glBindVertexArray(vao_);
  if (blocky_) {
    build_blocky_mesh();
  } else {
    build_lod_patch();
    update_errors(heights_m, all);
  }
  glBindVertexArray(0);
  check_gl("creating the terrain mesh and textures");
}

TerrainRenderer::~TerrainRenderer() {
  glDeleteProgram(program_);
  glDeleteBuffers(1, &vbo_);
  glDeleteBuffers(1, &ibo_);
  glDeleteBuffers(1, &instance_vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteTextures(1, &heights_tex_);
  glDeleteTextures(1, &initial_tex_);
}

void TerrainRenderer::build_lod_patch() {
  // The one patch every chunk draws: kPatchQuads x kPatchQuads quads as
  // triangle strips split like the surface (from corner (i+1, j) to
  // (i, j+1)), then a skirt around its perimeter, each edge vertex paired
  // with one on the ground.
  const int n = kPatchQuads;
  std::vector<PatchVertex> vertices;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) vertices.push_back({float(i), float(j), 1.0f, 0.0f});
  std::vector<GLuint> indices;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i <= n; ++i) {
      indices.push_back(GLuint(j * (n + 1) + i));
      indices.push_back(GLuint((j + 1) * (n + 1) + i));
    }
    indices.push_back(kRestart);
  }
  // The perimeter, closed: along j = 0, i = n, j = n backwards, i = 0 backwards.
  std::vector<std::pair<int, int>> ring;
  for (int i = 0; i < n; ++i) ring.push_back({i, 0});
  for (int j = 0; j < n; ++j) ring.push_back({n, j});
  for (int i = n; i > 0; --i) ring.push_back({i, n});
  for (int j = n; j > 0; --j) ring.push_back({0, j});
  ring.push_back(ring.front());
  for (const auto& [i, j] : ring) {
    indices.push_back(GLuint(vertices.size()));
    vertices.push_back({float(i), float(j), 1.0f, 1.0f});
    indices.push_back(GLuint(vertices.size()));
    vertices.push_back({float(i), float(j), 0.0f, 1.0f});
  }
  patch_index_count_ = GLsizei(indices.size());
  patch_triangles_ = 2 * n * n + 2 * 4 * n;
  mesh_cols_ = spec_.cols + 2;
  mesh_rows_ = spec_.rows + 2;

  // The quadtree's root: the fewest doublings of a patch that cover every
  // mesh line along both axes.
  const int lines = std::max(spec_.cols, spec_.rows) + 1;
  root_step_ = 1;
  while (root_step_ * n < lines) root_step_ *= 2;
  chunks_.reserve(4096);
  // One error per node and level (level k: step 2^k, (root_step / 2^k)^2 nodes).
  for (int step = 1; step <= root_step_; step *= 2)
    errors_.emplace_back(std::size_t(root_step_ / step) * std::size_t(root_step_ / step), 0.0f);

  upload_mesh(vbo_, ibo_, vertices, indices);
  float_attribute<PatchVertex>(0, 2, offsetof(PatchVertex, i));
  float_attribute<PatchVertex>(1, 1, offsetof(PatchVertex, top));
  float_attribute<PatchVertex>(2, 1, offsetof(PatchVertex, skirt));
  glGenBuffers(1, &instance_vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, instance_vbo_);
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, sizeof(Chunk), nullptr);
  glVertexAttribDivisor(3, 1);
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

  std::vector<BoxVertex> vertices;
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
  box_index_count_ = GLsizei(indices.size());
  triangles_ = std::int64_t(nz - 1) * (nx - 1) * 2;

  upload_mesh(vbo_, ibo_, vertices, indices);
  float_attribute<BoxVertex>(0, 2, offsetof(BoxVertex, pos_u));
  float_attribute<BoxVertex>(1, 2, offsetof(BoxVertex, sample_u));
  float_attribute<BoxVertex>(2, 1, offsetof(BoxVertex, top));
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
  // Soil can pile above every height seen so far; the chunks' boxes must hold it.
  top_m_ = std::max(top_m_, highest(heights_m, spec_.cols, r));
  if (!blocky_) update_errors(heights_m, r);
}

void TerrainRenderer::update_errors(const float* heights_m, const Rect& samples) {
  // The error of a node drawn at its step: how far its surface can be from
  // the full-detail one. Nested (Lindstrom et al. 1996): a node's error is
  // the largest distance between its own triangles and its children's
  // vertices (the lines of half its step), plus the largest of its
  // children's errors; a node of step 1 is the surface itself (error 0).
  // Only nodes whose lines reach the changed samples are recomputed, finest
  // level first.
  const int cols = spec_.cols, rows = spec_.rows;
  const int last_u = cols + 1, last_v = rows + 1;
  // The changed samples' lines (line 0 and line 1 read sample 0, line k + 1
  // sample k), one wider on each side.
  const int lu0 = std::max(samples.c0, 0), lu1 = std::min(samples.c1 + 1, last_u);
  const int lv0 = std::max(samples.r0, 0), lv1 = std::min(samples.r1 + 1, last_v);
  if (lu1 < lu0 || lv1 < lv0) return;
  const int n = kPatchQuads;
  for (std::size_t level = 1; level < errors_.size(); ++level) {
    const int step = 1 << level, half = step / 2, span = n * step;
    const int side = root_step_ / step;  // nodes per side at this level
    std::vector<float>& err = errors_[level];
    const std::vector<float>& finer = errors_[level - 1];
    // Nodes whose lines (both boundaries included) reach [lu0, lu1] x [lv0, lv1].
    const int a0 = std::max(0, lu0 / span - 1), a1 = std::min(lu1 / span, side - 1);
    const int b0 = std::max(0, lv0 / span - 1), b1 = std::min(lv1 / span, side - 1);
    for (int b = b0; b <= b1; ++b) {
      for (int a = a0; a <= a1; ++a) {
        const int u0 = a * span, v0 = b * span;
        float worst = 0.0f;
        if (u0 < last_u && v0 < last_v) {
          // Every line of half the step inside the node, against the node's
          // own triangles (split from corner (i+1, j) to (i, j+1)). Lattice
          // point p of the node is line min(start + p * half, last): its
          // sample index and, per quad, where its middle line falls (0.5,
          // or elsewhere in the narrower quads at the far edge).
          std::array<int, 2 * kPatchQuads + 1> cu{}, cv{};
          std::array<float, kPatchQuads> fx{}, fz{};
          int nu = 0, nv = 0;  // quads holding lines along X and Z
          for (int p = 0; p <= 2 * n; ++p) {
            const int lu = std::min(u0 + p * half, last_u), lv = std::min(v0 + p * half, last_v);
            cu[std::size_t(p)] = std::clamp(lu - 1, 0, cols - 1);
            cv[std::size_t(p)] = std::clamp(lv - 1, 0, rows - 1);
            if (p % 2 == 0 && p < 2 * n) {
              const int q = p / 2;
              const int ua = lu, ub = std::min(lu + step, last_u);
              const int va = lv, vb = std::min(lv + step, last_v);
              fx[std::size_t(q)] = ub > ua ? float(std::min(ua + half, ub) - ua) / float(ub - ua) : 0.0f;
              fz[std::size_t(q)] = vb > va ? float(std::min(va + half, vb) - va) / float(vb - va) : 0.0f;
              nu += ua < last_u ? 1 : 0;
              nv += va < last_v ? 1 : 0;
            }
          }
          for (int j = 0; j < nv; ++j) {
            const float* r0 = heights_m + std::int64_t(cv[std::size_t(2 * j)]) * cols;
            const float* rm = heights_m + std::int64_t(cv[std::size_t(2 * j + 1)]) * cols;
            const float* r1 = heights_m + std::int64_t(cv[std::size_t(2 * j + 2)]) * cols;
            const float z = fz[std::size_t(j)];
            for (int i = 0; i < nu; ++i) {
              const int ca = cu[std::size_t(2 * i)], cm = cu[std::size_t(2 * i + 1)],
                        cb = cu[std::size_t(2 * i + 2)];
              const float x = fx[std::size_t(i)];
              const float h00 = r0[ca], h10 = r0[cb], h01 = r1[ca], h11 = r1[cb];
              auto coarse = [&](float cx, float cz) {  // cx, cz in [0, 1] across the quad
                return cx + cz <= 1.0f ? h00 + cx * (h10 - h00) + cz * (h01 - h00)
                                       : h11 + (1.0f - cx) * (h01 - h11) + (1.0f - cz) * (h10 - h11);
              };
              // The top and left edges' middles and the centre; the right
              // and bottom edges are the next quads' left and top (on a
              // shared edge both quads interpolate the same line), except
              // at the node's last column and row.
              worst = std::max(worst, std::fabs(r0[cm] - coarse(x, 0.0f)));
              worst = std::max(worst, std::fabs(rm[ca] - coarse(0.0f, z)));
              worst = std::max(worst, std::fabs(rm[cm] - coarse(x, z)));
              if (i == nu - 1) worst = std::max(worst, std::fabs(rm[cb] - coarse(1.0f, z)));
              if (j == nv - 1) worst = std::max(worst, std::fabs(r1[cm] - coarse(x, 1.0f)));
            }
          }
          // Plus the children's own errors.
          const int fside = 2 * side;
          for (int k = 0; k < 4; ++k)
            worst = std::max(worst, finer[std::size_t(2 * b + (k >> 1)) * std::size_t(fside) +
                                          std::size_t(2 * a + (k & 1))]);
        }
        err[std::size_t(b) * std::size_t(side) + std::size_t(a)] = worst;
      }
    }
  }
}

int TerrainRenderer::finest_step() const {
  int finest = 0;
  for (const Chunk& c : chunks_) finest = finest == 0 ? int(c.step) : std::min(finest, int(c.step));
  return finest;
}

void TerrainRenderer::select_chunks(const Mat4& vp, float viewport_w, float viewport_h) {
  // Walk the quadtree from the root: a node outside the view is dropped; a
  // node too coarse for its distance (below) is split into its four
  // children, nearest first (so the nearer soil is drawn first and hides
  // what is behind it); otherwise it is drawn as one chunk. A quad of `step`
  // lines spans about step cells.
  chunks_.clear();
  const float cell = float(std::max(spec_.cell_x_m(), spec_.cell_z_m()));
  // Pixels per metre at clip w = 1, along the screen's X and Y.
  auto row_length = [&](int r) {
    return std::sqrt(vp.at(r, 0) * vp.at(r, 0) + vp.at(r, 1) * vp.at(r, 1) +
                     vp.at(r, 2) * vp.at(r, 2));
  };
  const float px_per_m = std::max(row_length(0) * 0.5f * viewport_w, row_length(1) * 0.5f * viewport_h);
  const float last_u = float(spec_.cols + 1), last_v = float(spec_.rows + 1);
  const float y0 = float(spec_.origin_m.y), y1 = float(spec_.origin_m.y) + std::max(top_m_, 1e-6f);
  auto world_x = [&](float line) {
    return float(spec_.origin_m.x) + std::clamp(line - 0.5f, 0.0f, float(spec_.cols)) * float(spec_.cell_x_m());
  };
  auto world_z = [&](float line) {
    return float(spec_.origin_m.z) + std::clamp(line - 0.5f, 0.0f, float(spec_.rows)) * float(spec_.cell_z_m());
  };

  struct Node {
    int u0, v0, step;
  };
  std::array<Node, 4 * 32> stack{};
  int top = 0;
  stack[top++] = {0, 0, root_step_};
  while (top > 0) {
    const Node node = stack[--top];
    const int span = node.step * kPatchQuads;
    const float xa = world_x(float(node.u0)), xb = world_x(float(node.u0 + span));
    const float za = world_z(float(node.v0)), zb = world_z(float(node.v0 + span));
    // The node's box in clip space: outside one clip plane at every corner = not seen.
    float w_min = std::numeric_limits<float>::max();
    int outside[6] = {0, 0, 0, 0, 0, 0};
    for (int k = 0; k < 8; ++k) {
      const float x = (k & 1) ? xb : xa, y = (k & 2) ? y1 : y0, z = (k & 4) ? zb : za;
      float clip[4];
      for (int r = 0; r < 4; ++r)
        clip[r] = vp.at(r, 0) * x + vp.at(r, 1) * y + vp.at(r, 2) * z + vp.at(r, 3);
      const float w = clip[3];
      outside[0] += clip[0] < -w;
      outside[1] += clip[0] > w;
      outside[2] += clip[1] < -w;
      outside[3] += clip[1] > w;
      outside[4] += clip[2] < -w;
      outside[5] += clip[2] > w;
      w_min = std::min(w_min, w);
    }
    if (std::any_of(std::begin(outside), std::end(outside), [](int n) { return n == 8; })) continue;
    // Split while the node's surface could be more than kLodErrorPixels
    // from the full-detail one on screen, or its quads larger than
    // kLodQuadPixels (silhouettes), at its nearest point; never into quads
    // smaller than kLodMinQuadPixels / 2 (a cut's wall smeared over a pixel
    // or so looks the same as a sharp one).
    int level = 0;
    while ((1 << level) < node.step) ++level;
    const float node_error =
        errors_[std::size_t(level)][std::size_t(node.v0 / span) * std::size_t(root_step_ / node.step) +
                                    std::size_t(node.u0 / span)];
    const float quad_px = w_min <= 1e-6f ? std::numeric_limits<float>::max()
                                         : float(node.step) * cell * px_per_m / w_min;
    const bool split = node.step > 1 && quad_px > kLodMinQuadPixels &&
                       (node_error * px_per_m / w_min > kLodErrorPixels || quad_px > kLodQuadPixels);
    if (!split) {
      chunks_.push_back({float(node.u0), float(node.v0), float(node.step)});
      continue;
    }
    // The children that hold mesh lines, farthest pushed first (popped last).
    const int half = span / 2, child_step = node.step / 2;
    Node children[4];
    float dist[4];
    int count = 0;
    for (int k = 0; k < 4; ++k) {
      const Node c{node.u0 + (k & 1) * half, node.v0 + (k >> 1) * half, child_step};
      if (float(c.u0) >= last_u || float(c.v0) >= last_v) continue;
      const float cx = 0.5f * (world_x(float(c.u0)) + world_x(float(c.u0 + half)));
      const float cz = 0.5f * (world_z(float(c.v0)) + world_z(float(c.v0 + half)));
      children[count] = c;
      dist[count] = (cx - eye_.x) * (cx - eye_.x) + (cz - eye_.z) * (cz - eye_.z);
      ++count;
    }
    for (int a = 0; a < count; ++a)
      for (int b = a + 1; b < count; ++b)
        if (dist[b] > dist[a]) {
          std::swap(dist[a], dist[b]);
          std::swap(children[a], children[b]);
        }
    if (top + count > int(stack.size())) {  // deeper than any grid a texture can hold
      chunks_.push_back({float(node.u0), float(node.v0), float(node.step)});
      continue;
    }
    for (int k = 0; k < count; ++k) stack[top++] = children[k];
  }
}

void TerrainRenderer::draw(const Mat4& view_projection, Vec3f eye, const TerrainStyle& style) {
  glUseProgram(program_);
  glUniformMatrix4fv(uniform(program_, "u_vp"), 1, GL_FALSE, view_projection.data());
  glUniform2f(uniform(program_, "u_grid"), float(spec_.cols), float(spec_.rows));
  glUniform2f(uniform(program_, "u_lines"), float(spec_.cols + 1), float(spec_.rows + 1));
  glUniform2f(uniform(program_, "u_cell"), float(spec_.cell_x_m()), float(spec_.cell_z_m()));
  glUniform3f(uniform(program_, "u_origin"), float(spec_.origin_m.x), float(spec_.origin_m.y),
              float(spec_.origin_m.z));
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
  if (blocky_) {
    glDrawElements(GL_TRIANGLE_STRIP, box_index_count_, GL_UNSIGNED_INT, nullptr);
  } else {
    GLint viewport[4] = {0, 0, 1, 1};
    glGetIntegerv(GL_VIEWPORT, viewport);
    eye_ = eye;
    select_chunks(view_projection, float(viewport[2]), float(viewport[3]));
    triangles_ = std::int64_t(chunks_.size()) * patch_triangles_;
    if (!chunks_.empty()) {
      glBindBuffer(GL_ARRAY_BUFFER, instance_vbo_);
      glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(chunks_.size() * sizeof(Chunk)), chunks_.data(),
                   GL_STREAM_DRAW);
      glDrawElementsInstanced(GL_TRIANGLE_STRIP, patch_index_count_, GL_UNSIGNED_INT, nullptr,
                              GLsizei(chunks_.size()));
    }
  }
  glBindVertexArray(0);
  glDisable(GL_PRIMITIVE_RESTART);
}

}  // namespace terracut::viewer
