// Fuzz target: read_png, then resample to a size chosen by the input.
//
// libpng checks every chunk's CRC, so nearly every mutation would be
// refused there and go no further: the harness first writes the right CRC
// into every chunk it can walk (a last byte of the input, bit 0 set, leaves
// the CRCs as they are, so the CRC errors are fuzzed too). Every input must
// end in an image or a terracut::InputError. An image read must hold cols x
// rows values in [0, 1]; its resampling must too, keep a constant image
// constant and, shrinking both ways, keep the mean.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

#include "fuzz_file.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

namespace {

using terracut::fuzz::check;

std::uint32_t be32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | std::uint32_t(p[3]);
}

// Writes the CRC of each chunk after the 8-byte signature that fits.
void repair_crcs(std::vector<std::uint8_t>& png) {
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::uint32_t length = be32(&png[at]);
    if (length > png.size() - at - 12) break;
    const std::size_t crc_at = at + 8 + length;
    const std::uint32_t crc = std::uint32_t(::crc32(0L, &png[at + 4], uInt(length + 4)));
    png[crc_at] = std::uint8_t(crc >> 24);
    png[crc_at + 1] = std::uint8_t(crc >> 16);
    png[crc_at + 2] = std::uint8_t(crc >> 8);
    png[crc_at + 3] = std::uint8_t(crc);
    at = crc_at + 4;
  }
}

bool in_unit(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return x >= 0.0f && x <= 1.0f; });
}

double mean(const std::vector<float>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // The last two bytes choose the resampled size (and whether to repair).
  const std::uint8_t a = data[size - 2], b = data[size - 1];
  std::vector<std::uint8_t> png(data, data + size - 2);
  if ((b & 1u) == 0) repair_crcs(png);
  const auto path = terracut::fuzz::input_file(png.data(), png.size(), "png");
  terracut::io::Image image;
  try {
    image = terracut::io::read_png(path);
  } catch (const terracut::InputError&) {
    return 0;
  }
  check(image.cols >= 1 && image.rows >= 1, "fuzz_png", "an image has pixels");
  check(image.values.size() == std::size_t(image.cols) * std::size_t(image.rows), "fuzz_png", "cols x rows values");
  check(in_unit(image.values), "fuzz_png", "values in [0, 1]");
  const int cols = 1 + a % 40, rows = 1 + (b >> 1) % 40;
  const terracut::io::Image out = terracut::io::resample(image, cols, rows);
  check(out.cols == cols && out.rows == rows && out.values.size() == std::size_t(cols) * rows, "fuzz_png",
        "the resampled size");
  // Float rounding of sums over up to 2^30 pixels: a loose bound.
  const float eps = 1e-5f;
  check(std::all_of(out.values.begin(), out.values.end(), [&](float x) { return x >= -eps && x <= 1 + eps; }),
        "fuzz_png", "resampled values in [0, 1]");
  const auto range = std::minmax_element(image.values.begin(), image.values.end());
  const float lo = *range.first, hi = *range.second;
  if (lo == hi)
    check(std::all_of(out.values.begin(), out.values.end(), [&](float x) { return std::abs(x - lo) <= eps; }),
          "fuzz_png", "a constant image stays constant");
  if (cols <= image.cols && rows <= image.rows)
    check(std::abs(mean(out.values) - mean(image.values)) <= 1e-4, "fuzz_png", "shrinking keeps the mean");
  return 0;
}
