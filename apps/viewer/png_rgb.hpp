// Writes an 8-bit RGB image as PNG (terracut::io writes only 16-bit grey).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace terracut::viewer {

/// An 8-bit RGB image, rows x cols, top row first, 3 bytes per pixel.
struct RgbImage {
  int cols = 0;
  int rows = 0;
  std::vector<std::uint8_t> pixels;  ///< rows x cols x 3, row-major, top row first
};

/// Writes image to path. Throws std::runtime_error naming the file when it
/// cannot be written (a partly written file is removed).
void write_png_rgb(const std::filesystem::path& path, const RgbImage& image);

/// Reads an 8-bit RGB or RGBA PNG (alpha dropped); for tests and tools.
/// Throws std::runtime_error naming the file on failure.
RgbImage read_png_rgb(const std::filesystem::path& path);

}  // namespace terracut::viewer
