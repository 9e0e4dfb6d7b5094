#include "terracut/core/grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut {

std::string validate(const GridSpec& spec) {
  const std::string sides = "in [1, " + format_number(kMaxGridSide) + "]";
  if (spec.cols < 1 || spec.cols > kMaxGridSide) return must_be("grid.cols", sides, spec.cols);
  if (spec.rows < 1 || spec.rows > kMaxGridSide) return must_be("grid.rows", sides, spec.rows);
  if (spec.sample_count() > kMaxGridSamples)
    return "grid has " + format_number(spec.sample_count()) + " samples, more than the limit " +
           format_number(kMaxGridSamples);
  if (!(std::isfinite(spec.size_x_m) && spec.size_x_m > 0.0))
    return must_be("grid.size_x_m", "finite and > 0", spec.size_x_m);
  if (!(std::isfinite(spec.size_z_m) && spec.size_z_m > 0.0))
    return must_be("grid.size_z_m", "finite and > 0", spec.size_z_m);
  if (!(spec.cell_x_m() >= kMinCellM))
    return must_be("grid.size_x_m / grid.cols (the cell side along x)", ">= 1e-6 m", spec.cell_x_m());
  if (!(spec.cell_z_m() >= kMinCellM))
    return must_be("grid.size_z_m / grid.rows (the cell side along z)", ">= 1e-6 m", spec.cell_z_m());
  if (!is_finite(spec.origin_m)) return "grid.origin_m must be finite";
  if (!(std::isfinite(spec.full_scale_m) && spec.full_scale_m > 0.0))
    return must_be("grid.full_scale_m", "finite and > 0", spec.full_scale_m);
  return {};
}

void Rect::include(const Rect& other) {
  if (other.empty()) return;
  if (empty()) {
    *this = other;
    return;
  }
  c0 = std::min(c0, other.c0);
  r0 = std::min(r0, other.r0);
  c1 = std::max(c1, other.c1);
  r1 = std::max(r1, other.r1);
}

namespace detail {

namespace {

constexpr std::size_t kPageBytes = 4096;
constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;

std::size_t round_up(std::size_t n, std::size_t to) { return (n + to - 1) / to * to; }

}  // namespace

LayerBlock::LayerBlock(std::int64_t samples, bool zero_layers) : samples_(samples) {
  const std::size_t bytes = std::size_t(samples) * sizeof(float);
  // Layers of a huge page or more start on huge-page boundaries (plus their
  // stagger); smaller ones on pages, so small grids waste little.
  const std::size_t align = bytes >= kHugePageBytes ? kHugePageBytes : kPageBytes;
  layer_stride_ = round_up(bytes, align) + kLayerStaggerBytes;
  block_bytes_ = round_up((kLayers - 1) * layer_stride_ + bytes, align);
  block_.reset(static_cast<std::byte*>(std::aligned_alloc(align, block_bytes_)));
  if (!block_) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // A hint (THP in madvise mode); refused or unsupported, nothing changes.
  if (align == kHugePageBytes) (void)madvise(block_.get(), block_bytes_, MADV_HUGEPAGE);
#endif
  if (zero_layers) {
    std::memset(block_.get(), 0, block_bytes_);
  } else {
    // Only what lies between and after the layers (copies read it).
    for (int k = 0; k < kLayers; ++k) {
      std::byte* end = block_.get() + std::size_t(k) * layer_stride_ + bytes;
      std::byte* next =
          k < kLayers - 1 ? block_.get() + std::size_t(k + 1) * layer_stride_ : block_.get() + block_bytes_;
      std::memset(end, 0, std::size_t(next - end));
    }
  }
}

LayerBlock::LayerBlock(const LayerBlock& other) : LayerBlock() { *this = other; }

LayerBlock& LayerBlock::operator=(const LayerBlock& other) {
  if (this == &other) return *this;
  if (other.block_ == nullptr) {
    *this = LayerBlock();
    return *this;
  }
  if (samples_ != other.samples_ || block_ == nullptr) *this = LayerBlock(other.samples_);
  std::memcpy(block_.get(), other.block_.get(), block_bytes_);
  return *this;
}

void LayerBlock::Free::operator()(std::byte* p) const noexcept { std::free(p); }

}  // namespace detail

HeightGrid::HeightGrid(const GridSpec& spec, std::vector<float> initial_heights_m) : spec_(spec) {
  if (std::string error = validate(spec); !error.empty()) throw InputError(error);
  if (std::int64_t(initial_heights_m.size()) != spec.sample_count()) {
    throw InputError("initial heights have " + format_number(initial_heights_m.size()) +
                     " values, expected cols x rows = " + format_number(spec.cols) + " x " +
                     format_number(spec.rows) + " = " + format_number(spec.sample_count()));
  }
  for (std::int64_t i = 0; i < spec.sample_count(); ++i) {
    float h = initial_heights_m[size_t(i)];
    if (!std::isfinite(h) || h < 0.0f) {
      throw InputError(must_be("initial height at sample (col " + format_number(i % spec.cols) +
                                   ", row " + format_number(i / spec.cols) + ")",
                               "finite and >= 0", h));
    }
  }
  // Filled layer by layer, the caller's heights released as soon as they are
  // copied: the peak is the heights plus one layer, not plus two.
  layers_ = detail::LayerBlock(spec.sample_count(), false);
  const std::size_t bytes = initial_heights_m.size() * sizeof(float);
  std::memcpy(initial_(), initial_heights_m.data(), bytes);
  std::vector<float>().swap(initial_heights_m);
  std::memcpy(height_(), initial_(), bytes);
}

void HeightGrid::copy_removed(float* out) const {
  const float *height = height_(), *initial = initial_();
  for (std::int64_t i = 0; i < spec_.sample_count(); ++i) out[i] = initial[i] - height[i];
}

Rect HeightGrid::set_heights(const Rect& rect, const float* values_m) {
  Rect clipped{std::max(rect.c0, 0), std::max(rect.r0, 0), std::min(rect.c1, cols()),
               std::min(rect.r1, rows())};
  if (clipped.empty()) return {};
  int width = rect.c1 - rect.c0;
  for (int r = clipped.r0; r < clipped.r1; ++r) {
    for (int c = clipped.c0; c < clipped.c1; ++c) {
      float h = values_m[std::int64_t(r - rect.r0) * width + (c - rect.c0)];
      if (!std::isfinite(h) || h < 0.0f) h = 0.0f;
      height_()[index(c, r)] = h;
    }
  }
  return clipped;
}

void HeightGrid::reset() {
  const std::size_t n = std::size_t(spec_.sample_count());
  std::memcpy(height_(), initial_(), n * sizeof(float));
}

double HeightGrid::volume_m3() const {
  double sum = 0.0;
  const float* height = height_();
  for (std::int64_t i = 0; i < spec_.sample_count(); ++i) sum += height[i];
  return sum * spec_.cell_area_m2();
}

double HeightGrid::conservation_error_m() const {
  double worst = 0.0;
  const float *height = height_(), *initial = initial_();
  for (std::int64_t i = 0; i < spec_.sample_count(); ++i) {
    const float removed = initial[i] - height[i];  // removed_at(i)
    double e = std::abs(double(height[i]) + double(removed) - double(initial[i]));
    worst = std::max(worst, e);
  }
  return worst;
}

std::uint64_t HeightGrid::state_hash() const {
  std::uint64_t hash = 1469598103934665603ull;
  const std::int64_t n = spec_.sample_count();
  auto mix = [&hash](float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    for (int k = 0; k < 4; ++k) {
      hash ^= (bits >> (8 * k)) & 0xffu;
      hash *= 1099511628211ull;
    }
  };
  // The derived removed layer is hashed as the stored one was, so a state
  // hashes as it did when all three were stored.
  const float *height = height_(), *initial = initial_();
  for (std::int64_t i = 0; i < n; ++i) mix(height[i]);
  for (std::int64_t i = 0; i < n; ++i) mix(initial[i] - height[i]);
  for (std::int64_t i = 0; i < n; ++i) mix(initial[i]);
  return hash;
}

}  // namespace terracut
