// Heightmap images and arrays: PNG in (8/16-bit grey, colour, palette), PNG
// out (16-bit grey), resampling, and float32 NumPy .npy out.
#pragma once

#include <filesystem>
#include <vector>

namespace terracut::io {

/// A single-channel image of values in [0, 1], rows x cols, row-major,
/// index = r * cols + c. Column index runs along +X, row index along +Z.
struct Image {
  int cols = 0;
  int rows = 0;
  std::vector<float> values;  ///< rows x cols, in [0, 1]
  int bit_depth = 0;          ///< bits per channel of the source file (8 or 16; 0 if made in memory)
};

/// Reads a PNG as luminance in [0, 1]. Grey images are read as they are;
/// colour and palette images are converted with Y = 0.2126 R + 0.7152 G +
/// 0.0722 B (Rec. 709 weights applied to the stored values, no gamma
/// decoding); alpha is ignored. Throws terracut::InputError naming the file
/// and what is wrong (missing, not a PNG, truncated, corrupt, zero or absurd size).
Image read_png(const std::filesystem::path& path);

/// Resamples to cols x rows. Each output pixel covers an equal area of the
/// source; shrinking averages the source pixels by their exact covered area
/// (a box filter), enlarging interpolates bilinearly between source pixel
/// centres (clamped at the border). Same size returns a copy.
/// Throws terracut::InputError when a size is not in [1, 65536].
Image resample(const Image& image, int cols, int rows);

/// Writes values (rows x cols, row-major) as a 16-bit grey PNG, pixel =
/// round(clamp(value / full_scale, 0, 1) * 65535). Throws terracut::InputError
/// naming the file when it cannot be written.
void write_png16(const std::filesystem::path& path, const float* values, int cols, int rows,
                 double full_scale);

/// Writes values as a little-endian float32 NumPy array of shape (rows, cols),
/// C order (format version 1.0). Throws terracut::InputError naming the file
/// when it cannot be written.
void write_npy(const std::filesystem::path& path, const float* values, int rows, int cols);

/// Reads a float32 (rows, cols) .npy written by write_npy (or NumPy).
/// Throws terracut::InputError naming the file on any other content.
std::vector<float> read_npy(const std::filesystem::path& path, int* rows, int* cols);

}  // namespace terracut::io
