// Draws the terrain from a height texture, with a mesh whose detail follows
// the screen.
//
// Two R32F textures hold the heights (rows x cols texels, texel (c, r) =
// sample (c, r)): the current heights, updated each frame with only the
// rectangle that changed (glTexSubImage2D with GL_UNPACK_ROW_LENGTH), and the
// initial heights, uploaded once, so the removed depth (initial - height) is
// computed per fragment. The mesh holds no heights, only sample coordinates:
//
//  - surface representation: a chunked quadtree (level of detail). Every
//    chunk draws the same patch of kPatchQuads x kPatchQuads quads (one
//    instanced draw call), over mesh lines that run from the terrain's outer
//    edge through every sample centre to the far edge (the half-cell border
//    is flat, as in core/surface.hpp's surface_height_m). Each frame the tree
//    is walked from the root: nodes outside the view are dropped, and a node
//    is split while, at its nearest point, its surface could be more than
//    kLodErrorPixels from the full-detail one on screen (each node keeps
//    that distance in metres, updated over the uploaded rectangle) or its
//    quads larger than kLodQuadPixels, down to one quad per cell but never
//    to quads under a pixel. A cut's
//    wall near the camera is drawn cell by cell; flat or smooth soil and
//    distant soil with few quads, so the triangles drawn follow what the
//    screen can show, not the terrain's size. Every chunk hangs a skirt down
//    to the ground from its edges: on the terrain's outer edge it is the
//    terrain's wall (the terrain reads as a solid slab), inside it fills the
//    cracks where chunks of different detail meet. Normals and colours are
//    computed per fragment from the texture (central differences over one
//    cell), so lighting keeps every texel's detail even where the mesh is
//    coarser.
//  - columns representation: when 2 * cols and 2 * rows fit in mesh_max, a
//    mesh with a vertex pair at each cell edge, heights sampled per cell
//    (texelFetch), so every column has a flat top and vertical walls, as the
//    paper's boxes. Larger grids take the surface's quadtree with blocky top
//    shading (colour and normal constant over each cell; no walls).
#pragma once

#include <epoxy/gl.h>

#include <cstdint>
#include <vector>

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

/// Default largest columns grid drawn as boxes: 2 x cols and 2 x rows at most
/// this many vertices (256 x 256 columns).
inline constexpr int kDefaultMeshMax = 512;

/// Quads per side of a level-of-detail chunk.
inline constexpr int kPatchQuads = 32;
/// Largest distance on screen between a chunk's surface and the full-detail
/// surface, pixels, before the chunk is split.
inline constexpr float kLodErrorPixels = 4.0f;
/// Largest size of a chunk's quad on screen, pixels, before it is split
/// (keeps silhouettes and the per-vertex height of smooth soil close).
inline constexpr float kLodQuadPixels = 24.0f;
/// Chunks whose quads are this small on screen, pixels, are never split.
inline constexpr float kLodMinQuadPixels = 1.5f;

class TerrainRenderer {
 public:
  /// Creates the textures (initial_m and heights_m: rows x cols, row-major,
  /// metres) and the mesh. Needs a current OpenGL 3.3 core context. Throws
  /// std::runtime_error when the grid is larger than GL_MAX_TEXTURE_SIZE or a
  /// shader fails. mesh_max: the largest columns mesh drawn as boxes (above).
  TerrainRenderer(const GridSpec& spec, Representation representation, const float* initial_m,
                  const float* heights_m, int mesh_max = kDefaultMeshMax);
  ~TerrainRenderer();
  TerrainRenderer(const TerrainRenderer&) = delete;
  TerrainRenderer& operator=(const TerrainRenderer&) = delete;

  /// Uploads the samples of rect from heights_m (rows x cols of the grid,
  /// row-major). An empty rect uploads nothing.
  void upload(const float* heights_m, const Rect& rect);
  /// Draws the terrain with the given view-projection matrix into the current
  /// viewport (its size sets the level of detail); eye: camera position,
  /// world metres (for specular light and the chunks' order).
  void draw(const Mat4& view_projection, Vec3f eye, const TerrainStyle& style);

  /// Mesh vertices along X and Z at full detail (including the border).
  int mesh_cols() const { return mesh_cols_; }
  int mesh_rows() const { return mesh_rows_; }
  /// Whether the columns are drawn as boxes (false: blocky top shading).
  bool blocky_mesh() const { return blocky_; }
  /// Triangles of the last draw (the boxes' mesh: all of it).
  std::int64_t triangle_count() const { return triangles_; }
  /// Level-of-detail chunks of the last draw (0 for the boxes' mesh).
  int chunk_count() const { return int(chunks_.size()); }
  /// Cells per quad in the finest chunk of the last draw (1: one quad per
  /// cell; 0 when no chunk was drawn).
  int finest_step() const;
  /// Samples uploaded by upload() since construction.
  std::int64_t uploaded_samples() const { return uploaded_samples_; }

 private:
  struct Chunk {
    float u0, v0, step;  ///< first mesh lines along X and Z, mesh lines per quad
  };

  void build_lod_patch();
  void build_blocky_mesh();
  // Recomputes the nodes' errors over the changed samples (heights_m: the grid).
  void update_errors(const float* heights_m, const Rect& samples);
  // Fills chunks_ with the quadtree's chunks for this view (viewport in pixels).
  void select_chunks(const Mat4& vp, float viewport_w, float viewport_h);

  GridSpec spec_;
  Representation representation_;
  bool blocky_ = false;
  GLuint program_ = 0;
  GLuint vao_ = 0, vbo_ = 0, ibo_ = 0, instance_vbo_ = 0;
  GLuint heights_tex_ = 0, initial_tex_ = 0;
  GLsizei box_index_count_ = 0;    // the boxes' strips
  GLsizei patch_index_count_ = 0;  // the patch's strips and its skirt
  std::int64_t patch_triangles_ = 0;
  int root_step_ = 1;              // mesh lines per quad at the quadtree's root
  float top_m_ = 0.0f;             // highest height seen, metres above ground
  Vec3f eye_{};
  std::vector<Chunk> chunks_;      // the last draw's chunks, reused
  // Per level k (step 2^k), per node (row-major, root_step / 2^k a side): the
  // largest height distance between the node drawn at its step and the
  // full-detail surface, metres.
  std::vector<std::vector<float>> errors_;
  int mesh_cols_ = 0, mesh_rows_ = 0;
  std::int64_t triangles_ = 0;
  std::int64_t uploaded_samples_ = 0;
};

}  // namespace terracut::viewer
