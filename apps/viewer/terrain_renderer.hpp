// Draws the terrain as one mesh displaced by a height texture.
//
// Two R32F textures hold the heights (rows x cols texels, texel (c, r) =
// sample (c, r)): the current heights, updated each frame with only the
// rectangle that changed (glTexSubImage2D with GL_UNPACK_ROW_LENGTH), and the
// initial heights, uploaded once, so the removed depth (initial - height) is
// computed per fragment. The mesh holds no heights, only sample coordinates:
//
//  - surface representation: a regular grid of at most mesh_max x mesh_max
//    vertices whose interior vertices run from the first to the last sample
//    centre (so a 4096^2 terrain is drawn with a 1024^2 mesh sampling the
//    texture bilinearly), plus a ring on the terrain's outer edge (the
//    half-cell border is flat, as in core/surface.hpp's surface_height_m) and a
//    skirt down to the ground, so the terrain reads as a solid slab. Normals
//    and colours are computed per fragment from the texture (central
//    differences over one cell), so lighting keeps the texture's detail even
//    where the mesh is coarser.
//  - columns representation: when 2 * cols and 2 * rows fit in mesh_max, a
//    mesh with a vertex pair at each cell edge, heights sampled per cell
//    (texelFetch), so every column has a flat top and vertical walls, as the
//    paper's boxes. Larger grids fall back to the surface mesh with blocky
//    top shading (colour and normal constant over each cell; no walls).
#pragma once

#include <epoxy/gl.h>

#include <cstdint>

#include "gfx_math.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/grid.hpp"

namespace terracut::viewer {

/// What the terrain's colour shows.
enum class ColorMode {
  kHeight,   ///< height above ground, scaled by height_scale_m
  kRemoved,  ///< removed depth (initial - height), scaled by removed_scale_m; untouched soil is sand
};

/// Look of the terrain (changeable every frame).
struct TerrainStyle {
  ColorMode color = ColorMode::kHeight;
  float height_scale_m = 1.0f;   ///< height at the top of the height colour ramp, metres, > 0
  float removed_scale_m = 0.1f;  ///< removed depth at the top of the removed ramp, metres, > 0
  float contour_step_m = 0.0f;   ///< spacing of height contour lines, metres; 0 = none
  Vec3f light_dir{0.45f, 0.8f, 0.35f};  ///< direction towards the light (any length)
};

/// Default largest mesh side, vertices. 512 keeps a software renderer
/// (llvmpipe) interactive; per-fragment normals and colours still read every
/// texel, so a finer grid keeps its detail in the shading.
inline constexpr int kDefaultMeshMax = 512;

class TerrainRenderer {
 public:
  /// Creates the textures (initial_m and heights_m: rows x cols, row-major,
  /// metres) and the mesh. Needs a current OpenGL 3.3 core context. Throws
  /// std::runtime_error when the grid is larger than GL_MAX_TEXTURE_SIZE or a
  /// shader fails. mesh_max >= 2.
  TerrainRenderer(const GridSpec& spec, Representation representation, const float* initial_m,
                  const float* heights_m, int mesh_max = kDefaultMeshMax);
  ~TerrainRenderer();
  TerrainRenderer(const TerrainRenderer&) = delete;
  TerrainRenderer& operator=(const TerrainRenderer&) = delete;

  /// Uploads the samples of rect from heights_m (rows x cols of the grid,
  /// row-major). An empty rect uploads nothing.
  void upload(const float* heights_m, const Rect& rect);
  /// Draws the terrain with the given view-projection matrix; eye: camera
  /// position, world metres (for specular light).
  void draw(const Mat4& view_projection, Vec3f eye, const TerrainStyle& style);

  /// Mesh vertices along X and Z (including the border ring).
  int mesh_cols() const { return mesh_cols_; }
  int mesh_rows() const { return mesh_rows_; }
  /// Whether the columns are drawn as boxes (false: blocky top shading).
  bool blocky_mesh() const { return blocky_; }
  std::int64_t triangle_count() const { return triangles_; }
  /// Samples uploaded by upload() since construction.
  std::int64_t uploaded_samples() const { return uploaded_samples_; }

 private:
  void build_surface_mesh(int mesh_max);
  void build_blocky_mesh();

  GridSpec spec_;
  Representation representation_;
  bool blocky_ = false;
  GLuint program_ = 0;
  GLuint vao_ = 0, vbo_ = 0, ibo_ = 0;
  GLuint heights_tex_ = 0, initial_tex_ = 0;
  GLsizei top_index_count_ = 0;    // strips of the top surface
  GLsizei skirt_index_count_ = 0;  // the skirt strip, after the top indices
  int mesh_cols_ = 0, mesh_rows_ = 0;
  std::int64_t triangles_ = 0;
  std::int64_t uploaded_samples_ = 0;
};

}  // namespace terracut::viewer
