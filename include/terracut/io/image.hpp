// Heightmap images and arrays: PNG in (grey of any bit depth, colour,
// palette), PNG out (16-bit grey), resampling, and float32 NumPy .npy out and in.
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
  /// Bits per sample of the source file: 1, 2, 4, 8 or 16 for grey images,
  /// 8 or 16 for colour, 8 for palette images (their palette entries are
  /// 8-bit); 0 if made in memory. A grey value is then a multiple of
  /// 1 / (2^bit_depth - 1). resample() keeps it.
  int bit_depth = 0;
};

/// Reads a PNG as luminance in [0, 1]. Grey images are read as they are
/// (sample / (2^depth - 1), so 1-, 2- and 4-bit files too); colour and
/// palette images are converted with Y = 0.2126 R + 0.7152 G + 0.0722 B
/// (Rec. 709 weights applied to the stored values normalised to [0, 1], no
/// gamma decoding); alpha and tRNS transparency are ignored. Interlaced files
/// are read. Throws terracut::InputError naming the file and what is wrong:
/// missing, empty, not a PNG, truncated, corrupt (CRC or compressed-data
/// errors, too little image data), zero size, more than 65536 pixels per
/// side or 2^30 pixels in all, or a header claiming more image data than the
/// file can hold (its size times 1032, zlib's largest expansion) -- these
/// three refused before any image memory is allocated. Memory otherwise
/// follows the rows decoded, so a file whose data ends early (or a pipe,
/// whose size is unknown) never has the whole claimed image committed.
/// Never prints to stderr. Safe to call from several threads at once.
Image read_png(const std::filesystem::path& path);

/// Resamples to cols x rows. Each output pixel covers an equal area of the
/// source; shrinking averages the source pixels by their exact covered area
/// (a box filter), enlarging interpolates bilinearly between source pixel
/// centres (clamped at the border). Each axis is treated on its own, so one
/// can shrink while the other enlarges: along an axis of n source and m
/// output pixels, output pixel j covers source [j n/m, (j+1) n/m) when
/// m < n, and takes the linear interpolation at source coordinate
/// (j + 0.5) n/m - 0.5 (pixel i's centre being at i) when m > n. A constant
/// image stays constant and shrinking preserves the mean (to float rounding).
/// Same size returns a copy. Throws terracut::InputError when a size is not
/// in [1, 65536], cols x rows exceeds 2^30, or image.values does not hold
/// image.cols x image.rows values.
Image resample(const Image& image, int cols, int rows);

/// Writes values (rows x cols, row-major) as a 16-bit grey PNG, pixel =
/// round(clamp(value / full_scale, 0, 1) * 65535); non-finite values (NaN,
/// +-inf) become 0. cols and rows must be in [1, 65536] and full_scale finite
/// and > 0. Throws terracut::InputError naming the file when it cannot be
/// written (a partly written file is removed) or an argument is invalid.
void write_png16(const std::filesystem::path& path, const float* values, int cols, int rows,
                 double full_scale);

/// Writes values as a little-endian float32 NumPy array of shape (rows, cols),
/// C order (format version 1.0, header padded with spaces and ending in '\n'
/// so the data starts at a multiple of 64 bytes). rows, cols >= 0. Throws
/// terracut::InputError naming the file when it cannot be written.
void write_npy(const std::filesystem::path& path, const float* values, int rows, int cols);

/// Reads a float32 (rows, cols) .npy written by write_npy (or NumPy): format
/// 1.0, 2.0 or 3.0, dtype '<f4' (or '>f4', swapped), C order, two
/// dimensions, and exactly rows x cols samples after the header. Sets *rows
/// and *cols and returns the values, row-major. Throws terracut::InputError
/// naming the file on any other content (a truncated file included).
std::vector<float> read_npy(const std::filesystem::path& path, int* rows, int* cols);

}  // namespace terracut::io
