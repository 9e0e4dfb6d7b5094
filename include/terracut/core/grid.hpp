// The height grid: cols x rows samples of a soil surface over a rectangle of
// the ground plane (X-Z), with two stored layers, current height and initial
// height, and the removed material derived from them (initial - height).
//
// Sample placement (cell-centred): the terrain covers
//   x in [origin.x, origin.x + size_x_m],  z in [origin.z, origin.z + size_z_m]
// and is divided into cols x rows equal cells of cell_x_m x cell_z_m. Sample
// (c, r) describes cell c along +X and row r along +Z; its point lies at the
// cell centre (origin.x + (c + 0.5) * cell_x_m, origin.z + (r + 0.5) * cell_z_m).
// Image column index runs along +X and image row index along +Z, so the first
// pixel is the cell at the origin corner.
//
// Heights are metres above the ground level origin.y; material occupies
// origin.y <= y <= origin.y + height. Below the ground is a rigid floor that is
// neither cut nor counted as contact. A sample stands for the volume
// height * cell_x_m * cell_z_m.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "terracut/core/math.hpp"

namespace terracut {

/// Parameters of a height grid; read-only during a run.
struct GridSpec {
  int cols = 0;               ///< samples along +X, in [1, kMaxGridSide]
  int rows = 0;               ///< samples along +Z, in [1, kMaxGridSide]
  double size_x_m = 1.0;      ///< metres covered along X, > 0
  double size_z_m = 1.0;      ///< metres covered along Z, > 0
  Vec3 origin_m{};            ///< world position of the origin corner; origin_m.y is the ground level
  double full_scale_m = 1.0;  ///< height of a full-white image pixel, metres, > 0

  double cell_x_m() const { return size_x_m / cols; }
  double cell_z_m() const { return size_z_m / rows; }
  double cell_area_m2() const { return cell_x_m() * cell_z_m(); }
  std::int64_t sample_count() const { return std::int64_t(cols) * rows; }
};

/// Largest accepted grid side (65536 samples); larger grids are refused as absurd.
inline constexpr int kMaxGridSide = 65536;
/// Largest accepted sample count (2^30, 8 GiB of layers).
inline constexpr std::int64_t kMaxGridSamples = std::int64_t(1) << 30;
/// Smallest accepted cell side, metres (a micrometre): the cell coordinates
/// of any position within 1e9 m then stay finite (cells of 1e-300 m made
/// them infinite, and the traversal's conversions to int undefined).
inline constexpr double kMinCellM = 1e-6;

/// Returns an empty string when spec is valid, else a message naming the bad field.
std::string validate(const GridSpec& spec);

/// A grid of cols x rows square cells of side cell_m, metres, its origin
/// corner at origin_m, a white pixel full_scale_m high.
inline GridSpec grid_of_cells(int cols, int rows, double cell_m, Vec3 origin_m = {},
                              double full_scale_m = 1.0) {
  GridSpec s;
  s.cols = cols;
  s.rows = rows;
  s.size_x_m = cols * cell_m;
  s.size_z_m = rows * cell_m;
  s.origin_m = origin_m;
  s.full_scale_m = full_scale_m;
  return s;
}

/// A half-open rectangle of samples [c0, c1) x [r0, r1); empty when c0 >= c1 or r0 >= r1.
struct Rect {
  int c0 = 0;
  int r0 = 0;
  int c1 = 0;
  int r1 = 0;

  bool empty() const { return c0 >= c1 || r0 >= r1; }
  std::int64_t area() const { return empty() ? 0 : std::int64_t(c1 - c0) * (r1 - r0); }
  /// Grows the rectangle to include sample (c, r). (Inline: the soil's
  /// displacement calls it for every cell it writes.)
  void include(int c, int r) {
    if (empty()) {
      *this = {c, r, c + 1, r + 1};
      return;
    }
    c0 = c < c0 ? c : c0;
    r0 = r < r0 ? r : r0;
    c1 = c + 1 > c1 ? c + 1 : c1;
    r1 = r + 1 > r1 ? r + 1 : r1;
  }
  /// Grows the rectangle to include other.
  void include(const Rect& other);
  bool operator==(const Rect&) const = default;
};

namespace detail {

/// The storage of a grid's two float layers (height, initial), one block. A
/// traversal across the rows (a blade oblique or transverse to them) touches
/// the same sample column of each layer in every row, 4 * cols bytes apart:
/// with a power-of-two side those addresses agree in their low 12 bits, so
/// in separate allocations (page-aligned by the allocator) the layers' lines
/// fall into the same L1 and L2 cache sets and evict one another. Each layer
/// here starts kLayerStaggerBytes further into its page than the one before,
/// which puts them in different sets; big layers start on 2 MiB boundaries
/// and are offered transparent huge pages (Linux, madvise), so a column of
/// rows costs fewer TLB misses. Copies are deep.
class LayerBlock {
 public:
  /// Layers in the block.
  static constexpr int kLayers = 2;
  /// Offset of layer k's start within its page is k * kLayerStaggerBytes
  /// (a third of a 4 KiB page, whole cache lines).
  static constexpr std::size_t kLayerStaggerBytes = 1344;

  LayerBlock() = default;
  /// kLayers layers of samples floats each, zeroed; with zero_layers false
  /// the layers are left for the caller to fill (their pages untouched, so a
  /// big grid is built without the whole block resident at once).
  explicit LayerBlock(std::int64_t samples, bool zero_layers = true);
  LayerBlock(const LayerBlock& other);
  LayerBlock& operator=(const LayerBlock& other);
  LayerBlock(LayerBlock&&) noexcept = default;
  LayerBlock& operator=(LayerBlock&&) noexcept = default;

  /// Layer k (0 .. kLayers - 1): samples floats.
  float* layer(int k) const { return reinterpret_cast<float*>(block_.get() + std::size_t(k) * layer_stride_); }
  std::int64_t samples() const { return samples_; }

 private:
  struct Free {
    void operator()(std::byte* p) const noexcept;
  };
  std::unique_ptr<std::byte, Free> block_;
  std::int64_t samples_ = 0;
  std::size_t layer_stride_ = 0;  ///< bytes from one layer's start to the next
  std::size_t block_bytes_ = 0;
};

}  // namespace detail

/// The soil state: rows x cols float samples, row-major, index = r * cols + c,
/// metres: the current height and the initial height are stored; the
/// removed material is initial - height, computed in float on read
/// (removed_at, copy_removed), so it is exactly what a stored layer kept as
/// initial - height would hold, and a cut writes the height layer alone.
class HeightGrid {
 public:
  /// Builds a grid from initial heights (rows x cols, metres >= 0, finite).
  /// Throws std::invalid_argument naming the bad field or sample.
  HeightGrid(const GridSpec& spec, std::vector<float> initial_heights_m);

  const GridSpec& spec() const { return spec_; }
  int cols() const { return spec_.cols; }
  int rows() const { return spec_.rows; }
  std::int64_t index(int c, int r) const { return std::int64_t(r) * spec_.cols + c; }

  /// Current height above ground, rows x cols, metres. The array is stable for
  /// the grid's lifetime, so an engine (Bullet, a renderer) can read it in place.
  const float* heights() const { return height_(); }
  /// Heights at construction, rows x cols, metres.
  const float* initial() const { return initial_(); }
  /// Material removed so far at sample i, metres: initial - height (float;
  /// negative where material was put down).
  float removed_at(std::int64_t i) const { return initial_()[i] - height_()[i]; }
  /// Writes the removed layer (removed_at of every sample, rows x cols,
  /// row-major) to out, which must hold sample_count() floats.
  void copy_removed(float* out) const;

  float height(int c, int r) const { return height_()[index(c, r)]; }

  /// The layers opened for an in-place edit by a core phase (the cut, soil
  /// flow): height writable, initial read-only, each rows x cols, row-major.
  /// The removed material follows from the two. The editor must report the
  /// rectangle it changed (StepOutput), which is how everyone caching the
  /// heights (Bullet, the viewer) learns of it.
  struct EditLayers {
    float* height_m;         ///< rows x cols, metres
    const float* initial_m;  ///< rows x cols, metres
  };
  /// Opens the layers for an edit (see EditLayers): the one way to write
  /// samples besides lower() and set_heights().
  EditLayers edit_layers() { return {height_(), initial_()}; }

  /// Lowers sample i to new_height_m if that is lower than its height (and not
  /// below 0). Returns the height removed, metres (0 when nothing changed).
  float lower(std::int64_t i, float new_height_m) {
    float* height = height_();
    float old = height[i];
    float h = new_height_m > 0.0f ? new_height_m : 0.0f;
    if (!(h < old)) return 0.0f;
    height[i] = h;
    return old - h;
  }

  /// Replaces the heights of a rectangle (values rows-of-rect x cols-of-rect,
  /// row-major) and returns the rectangle that changed.
  Rect set_heights(const Rect& rect, const float* values_m);

  /// Restores every sample to its initial height.
  void reset();

  /// World X of sample column c's centre, and world Z of row r's centre.
  double sample_x(int c) const { return spec_.origin_m.x + (c + 0.5) * spec_.cell_x_m(); }
  double sample_z(int r) const { return spec_.origin_m.z + (r + 0.5) * spec_.cell_z_m(); }
  /// Continuous cell coordinates of a world point: cell c covers [c, c+1).
  double cell_u(double x) const { return (x - spec_.origin_m.x) / spec_.cell_x_m(); }
  double cell_v(double z) const { return (z - spec_.origin_m.z) / spec_.cell_z_m(); }

  /// Total material volume above ground, cubic metres (sum of height * cell area).
  double volume_m3() const;
  /// Largest |height + removed - initial| over all samples, metres (in
  /// double, removed being removed_at: what is left is the rounding of
  /// initial - height to float).
  double conservation_error_m() const;
  /// A 64-bit FNV-1a hash of the height, removed and initial layers
  /// (bitwise, in that order), for determinism checks.
  std::uint64_t state_hash() const;

 private:
  GridSpec spec_;
  detail::LayerBlock layers_;  ///< height, initial

  float* height_() const { return layers_.layer(0); }
  float* initial_() const { return layers_.layer(1); }
};

}  // namespace terracut
