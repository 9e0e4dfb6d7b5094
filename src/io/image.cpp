// PNG reading (any bit depth and colour type, as luminance), resampling
// (box filter down, bilinear up, separable) and 16-bit grey PNG writing.
//
// libpng reports errors through a callback that must not return. Throwing a
// C++ exception through libpng's C frames is not safe, so every libpng call
// sits in a small function that arms setjmp() first; the error callback
// copies the message into a plain buffer and longjmp()s back, and the caller
// turns it into terracut::InputError. Those functions and the callbacks hold
// only trivially destructible locals, so the jump skips no destructor.
#include "terracut/io/image.hpp"

#include <png.h>

#include <sys/stat.h>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <system_error>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "c_file.hpp"

namespace terracut::io {
namespace {

using detail::FilePtr;
using detail::quoted;

// Largest accepted image: per side and in total (checked before allocating).
constexpr std::uint64_t kMaxSide = 65536;
constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 30;

// The most bytes zlib's deflate can expand one compressed byte to: a
// dynamic-Huffman block can code a 258-byte match in 2 bits, so 258 * 8 / 2
// = 1032 (less in practice, after the block headers). A PNG's image data is
// deflated, so a file of N bytes holds at most 1032 N bytes of it: a header
// claiming more pixels than that is refused before any image memory is
// allocated, whatever it claims.
constexpr std::uint64_t kMaxDeflateRatio = 1032;

// Rows of a non-interlaced image decoded per growth of the output buffer, so
// that memory follows the rows actually decoded: a file whose data ends early
// (or a pipe, whose size is not known in advance) never has the whole image
// committed.
constexpr int kRowsPerBlock = 64;

// Rec. 709 luminance weights applied to stored (not linearised) values.
constexpr double kLumaR = 0.2126;
constexpr double kLumaG = 0.7152;
constexpr double kLumaB = 0.0722;

// Reserves (address space only: nothing is touched, so nothing is committed)
// a buffer of n floats for a large image. On Linux a buffer of 8 MiB or more
// is advised to use transparent huge pages before it is touched: where each
// page fault is expensive, as in virtual machines, faulting in 4 KiB pages
// costs more than decoding the image (measured: 256 MiB took 0.7-1.0 s with
// 4 KiB pages, 0.03 s with 2 MiB pages). The advice is only a hint; the
// result is the same either way.
void reserve_image_buffer(std::vector<float>& buffer, std::size_t n) {
  if (buffer.capacity() >= n) return;
  buffer.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::size_t kHugePage = std::size_t{2} << 20U;
  constexpr std::size_t kMinBytes = std::size_t{8} << 20U;
  if (n * sizeof(float) >= kMinBytes) {
    const auto begin = reinterpret_cast<std::uintptr_t>(buffer.data());
    const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
    const std::uintptr_t last = (begin + n * sizeof(float)) & ~(kHugePage - 1);
    if (last > first) {
      (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
    }
  }
#endif
}

// Sizes a buffer of n floats for a large image (see reserve_image_buffer).
void resize_image_buffer(std::vector<float>& buffer, std::size_t n) {
  reserve_image_buffer(buffer, n);
  buffer.resize(n);
}

// State shared with the libpng callbacks. Plain data only: libpng longjmps
// out of the callbacks.
struct PngIo {
  std::FILE* file = nullptr;
  std::uint64_t offset = 0;   // bytes read or written so far
  bool io_failed = false;     // a short read or failed write, as opposed to bad data
  char message[512] = {};     // the libpng error message, or our I/O message
};

[[noreturn]] void on_png_error(png_structp png, png_const_charp message) {
  auto* io = static_cast<PngIo*>(png_get_error_ptr(png));
  // Keep our own I/O message when the failure came from a read/write callback.
  if (io != nullptr && !io->io_failed) {
    std::snprintf(io->message, sizeof io->message, "%s", message != nullptr ? message : "libpng error");
  }
  png_longjmp(png, 1);
}

// Warnings (unknown chunks, bad ancillary CRCs, ...) do not stop the read and
// must not reach stderr from inside a library.
void on_png_warning(png_structp, png_const_charp) {}

void on_png_read(png_structp png, png_bytep data, std::size_t length) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  const std::size_t got = std::fread(data, 1, length, io->file);
  if (got != length) {
    io->io_failed = true;
    if (std::ferror(io->file) != 0) {
      std::snprintf(io->message, sizeof io->message, "read error at byte %llu",
                    static_cast<unsigned long long>(io->offset + got));
    } else {
      std::snprintf(io->message, sizeof io->message,
                    "file is truncated: unexpected end of file at byte %llu",
                    static_cast<unsigned long long>(io->offset + got));
    }
    png_error(png, io->message);
  }
  io->offset += length;
}

void on_png_write(png_structp png, png_bytep data, std::size_t length) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  if (std::fwrite(data, 1, length, io->file) != length) {
    io->io_failed = true;
    std::snprintf(io->message, sizeof io->message, "write failed at byte %llu: %s",
                  static_cast<unsigned long long>(io->offset), std::strerror(errno));
    png_error(png, io->message);
  }
  io->offset += length;
}

void on_png_flush(png_structp png) {
  auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
  std::fflush(io->file);
}

// Owns the libpng read structures.
class PngReadHandle {
 public:
  explicit PngReadHandle(PngIo* io) {
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, io, on_png_error, on_png_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
  }
  ~PngReadHandle() { png_destroy_read_struct(&png_, info_ != nullptr ? &info_ : nullptr, nullptr); }
  PngReadHandle(const PngReadHandle&) = delete;
  PngReadHandle& operator=(const PngReadHandle&) = delete;
  bool ok() const { return png_ != nullptr && info_ != nullptr; }
  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

// Owns the libpng write structures.
class PngWriteHandle {
 public:
  explicit PngWriteHandle(PngIo* io) {
    png_ = png_create_write_struct(PNG_LIBPNG_VER_STRING, io, on_png_error, on_png_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
  }
  ~PngWriteHandle() { png_destroy_write_struct(&png_, info_ != nullptr ? &info_ : nullptr); }
  PngWriteHandle(const PngWriteHandle&) = delete;
  PngWriteHandle& operator=(const PngWriteHandle&) = delete;
  bool ok() const { return png_ != nullptr && info_ != nullptr; }
  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

// The file's header as stored, before any transformation.
struct PngHeader {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  int bit_depth = 0;
  int color_type = 0;
};

// The row layout libpng delivers after our transformations.
struct PngLayout {
  int channels = 0;       // 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA
  int bit_depth = 0;      // 8 or 16
  int passes = 1;         // > 1 for interlaced files
  std::size_t row_bytes = 0;
};

// Reads chunks up to the first IDAT. Returns false on a libpng error.
bool png_read_header(png_structp png, png_infop info, PngHeader* header) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_sig_bytes(png, 8);
  // Let our own size limit (with its clearer message) apply instead of libpng's.
  png_set_user_limits(png, 0x7fffffffU, 0x7fffffffU);
  png_read_info(png, info);
  header->width = png_get_image_width(png, info);
  header->height = png_get_image_height(png, info);
  header->bit_depth = png_get_bit_depth(png, info);
  header->color_type = png_get_color_type(png, info);
  return true;
}

// Asks libpng for 8- or 16-bit grey or RGB samples: alpha channels stripped,
// palettes expanded to RGB, grey below 8 bits scaled up to 0..255. A palette
// with tRNS may still arrive as RGBA; row_to_luminance skips any alpha.
// Returns false on a libpng error.
bool png_set_layout(png_structp png, png_infop info, const PngHeader& header, PngLayout* layout) {
  if (setjmp(png_jmpbuf(png))) return false;
  if (header.color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (header.color_type == PNG_COLOR_TYPE_GRAY && header.bit_depth < 8) {
    png_set_expand_gray_1_2_4_to_8(png);
  }
  if ((header.color_type & PNG_COLOR_MASK_ALPHA) != 0) png_set_strip_alpha(png);
  layout->passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  layout->channels = png_get_channels(png, info);
  layout->bit_depth = png_get_bit_depth(png, info);
  layout->row_bytes = png_get_rowbytes(png, info);
  return true;
}

// Converts one row of 8/16-bit samples with 1..4 channels to luminance in [0, 1].
void row_to_luminance(const std::uint8_t* row, int cols, const PngLayout& layout, float* out) {
  const int channels = layout.channels;
  if (layout.bit_depth == 8) {
    constexpr float kScale8 = 255.0F;
    if (channels <= 2) {
      for (int c = 0; c < cols; ++c) out[c] = static_cast<float>(row[c * channels]) / kScale8;
    } else {
      for (int c = 0; c < cols; ++c) {
        const std::uint8_t* p = row + static_cast<std::ptrdiff_t>(c) * channels;
        const double y = (kLumaR * p[0] + kLumaG * p[1] + kLumaB * p[2]) / 255.0;
        out[c] = std::min(static_cast<float>(y), 1.0F);
      }
    }
  } else {
    constexpr float kScale16 = 65535.0F;
    const auto sample = [row](std::ptrdiff_t i) {
      return static_cast<unsigned>(row[2 * i] << 8U) | static_cast<unsigned>(row[2 * i + 1]);
    };
    if (channels <= 2) {
      for (int c = 0; c < cols; ++c) {
        out[c] = static_cast<float>(sample(static_cast<std::ptrdiff_t>(c) * channels)) / kScale16;
      }
    } else {
      for (int c = 0; c < cols; ++c) {
        const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(c) * channels;
        const double y = (kLumaR * sample(i) + kLumaG * sample(i + 1) + kLumaB * sample(i + 2)) / 65535.0;
        out[c] = std::min(static_cast<float>(y), 1.0F);
      }
    }
  }
}

// Non-interlaced: decode `rows` rows, one at a time into `row`, converting
// each straight away into out (rows x cols), so memory stays at one row of
// raw samples. Returns false on a libpng error.
bool png_read_rows_into(png_structp png, const PngLayout& layout, int cols, int rows, std::uint8_t* row,
                        float* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  for (int r = 0; r < rows; ++r) {
    png_read_row(png, row, nullptr);
    row_to_luminance(row, cols, layout, out + static_cast<std::ptrdiff_t>(r) * cols);
  }
  return true;
}

// The chunks after the image data. Returns false on a libpng error.
bool png_read_tail(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_end(png, info);
  return true;
}

// Interlaced: libpng needs every row in memory across its passes.
bool png_read_whole(png_structp png, png_infop info, png_bytepp row_pointers) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, row_pointers);
  png_read_end(png, info);
  return true;
}

// Bits per pixel as stored in the file (before any transformation).
std::uint64_t stored_bits_per_pixel(const PngHeader& header) {
  std::uint64_t channels = 1;  // grey, or a palette index
  if (header.color_type == PNG_COLOR_TYPE_GRAY_ALPHA) channels = 2;
  if (header.color_type == PNG_COLOR_TYPE_RGB) channels = 3;
  if (header.color_type == PNG_COLOR_TYPE_RGB_ALPHA) channels = 4;
  return channels * static_cast<std::uint64_t>(header.bit_depth);
}

// The size of an open file in bytes; nullopt when it is not a regular file
// (a pipe, a device) and so has no size known in advance.
std::optional<std::uint64_t> regular_file_size(std::FILE* file) {
  struct stat st {};
  if (fstat(fileno(file), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  return static_cast<std::uint64_t>(st.st_size);
}

// An uninitialised byte buffer: unlike std::vector it does not write its
// bytes, so pages the decoder never reaches are never committed.
struct RawBuffer {
  std::unique_ptr<std::uint8_t[]> bytes;
  explicit RawBuffer(std::size_t n) : bytes(new std::uint8_t[n]) {}
};

std::string describe_size(std::uint64_t cols, std::uint64_t rows) {
  return std::to_string(cols) + " x " + std::to_string(rows) + " pixels";
}

// One output sample of a 1-D resampling: a run of consecutive source samples
// and their weights.
struct Taps {
  std::vector<int> first;          // first source index per output, size n_out
  std::vector<int> count;          // number of taps per output, size n_out
  std::vector<std::size_t> start;  // offset of each output's weights in weights, size n_out
  std::vector<double> weights;     // concatenated weights, each output's summing to 1
  int max_count = 0;
};

// Weights for resampling n_in samples to n_out along one axis, both >= 1.
Taps make_taps(int n_in, int n_out) {
  Taps taps;
  taps.first.resize(static_cast<std::size_t>(n_out));
  taps.count.resize(static_cast<std::size_t>(n_out));
  taps.start.resize(static_cast<std::size_t>(n_out));
  const double scale = static_cast<double>(n_in) / n_out;  // source samples per output sample
  if (n_out == n_in) {
    // Identity.
    for (int j = 0; j < n_out; ++j) {
      taps.first[j] = j;
      taps.count[j] = 1;
      taps.start[j] = taps.weights.size();
      taps.weights.push_back(1.0);
    }
  } else if (n_out < n_in) {
    // Box filter: output j covers source [j*scale, (j+1)*scale); each source
    // sample weighs by the length of its overlap with that interval.
    for (int j = 0; j < n_out; ++j) {
      // Interval ends as exact rationals j*n_in/n_out, so neighbours share ends.
      const double lo = static_cast<double>(static_cast<std::int64_t>(j) * n_in) / n_out;
      const double hi = static_cast<double>(static_cast<std::int64_t>(j + 1) * n_in) / n_out;
      int i0 = static_cast<int>(std::floor(lo));
      int i1 = static_cast<int>(std::ceil(hi));  // exclusive
      i0 = std::clamp(i0, 0, n_in - 1);
      i1 = std::clamp(i1, i0 + 1, n_in);
      taps.first[j] = i0;
      taps.start[j] = taps.weights.size();
      double sum = 0.0;
      for (int i = i0; i < i1; ++i) {
        const double w = std::min(hi, i + 1.0) - std::max(lo, static_cast<double>(i));
        taps.weights.push_back(std::max(w, 0.0));
        sum += std::max(w, 0.0);
      }
      // Normalise so a constant input stays constant despite rounding.
      for (std::size_t k = taps.start[j]; k < taps.weights.size(); ++k) taps.weights[k] /= sum;
      taps.count[j] = i1 - i0;
    }
  } else {
    // Bilinear: output centre j+0.5 maps to source coordinate (j+0.5)*scale;
    // source sample i has its centre at i+0.5. Clamp at the border.
    for (int j = 0; j < n_out; ++j) {
      const double x = std::clamp((j + 0.5) * scale - 0.5, 0.0, static_cast<double>(n_in - 1));
      const int i0 = std::min(static_cast<int>(std::floor(x)), n_in - 1);
      const double f = x - i0;
      taps.first[j] = i0;
      taps.start[j] = taps.weights.size();
      if (i0 + 1 < n_in && f > 0.0) {
        taps.weights.push_back(1.0 - f);
        taps.weights.push_back(f);
        taps.count[j] = 2;
      } else {
        taps.weights.push_back(1.0);
        taps.count[j] = 1;
      }
    }
  }
  for (int c : taps.count) taps.max_count = std::max(taps.max_count, c);
  return taps;
}

// Resamples image to out (cols x rows, already sized). Output row by output
// row: first the source rows it covers are combined column-wise into one row
// (a vertical pass over contiguous memory), then that row is resampled
// along x. No intermediate image, so memory stays at one row; sums are in
// double so wide box filters and constants keep float precision.
void resample_separable(const Image& image, const Taps& taps_x, const Taps& taps_y, Image* out) {
  const int cols_in = image.cols;
  const int cols = out->cols;
  std::vector<double> line(static_cast<std::size_t>(cols_in));
  for (int i = 0; i < out->rows; ++i) {
    // Vertical: line = sum_k w_k * source row (first + k).
    const double* wy = taps_y.weights.data() + taps_y.start[i];
    const float* src0 = image.values.data() + static_cast<std::ptrdiff_t>(taps_y.first[i]) * cols_in;
    for (int c = 0; c < cols_in; ++c) line[c] = wy[0] * src0[c];
    for (int k = 1; k < taps_y.count[i]; ++k) {
      const float* src = src0 + static_cast<std::ptrdiff_t>(k) * cols_in;
      const double w = wy[k];
      for (int c = 0; c < cols_in; ++c) line[c] += w * src[c];
    }
    // Horizontal: each output sample is a weighted sum of a run of line.
    float* dst = out->values.data() + static_cast<std::ptrdiff_t>(i) * cols;
    for (int j = 0; j < cols; ++j) {
      const double* s = line.data() + taps_x.first[j];
      const double* w = taps_x.weights.data() + taps_x.start[j];
      double acc = 0.0;
      for (int k = 0; k < taps_x.count[j]; ++k) acc += w[k] * s[k];
      dst[j] = static_cast<float>(acc);
    }
  }
}

// Writes a 16-bit grey PNG of prepared big-endian rows. Returns false on a libpng error.
bool png_write_rows(png_structp png, png_infop info, const float* values, int cols, int rows,
                    double full_scale, std::uint8_t* row) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, static_cast<png_uint_32>(cols), static_cast<png_uint_32>(rows), 16,
               PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  const double inv_scale = 1.0 / full_scale;
  for (int r = 0; r < rows; ++r) {
    const float* in = values + static_cast<std::ptrdiff_t>(r) * cols;
    for (int c = 0; c < cols; ++c) {
      const double v = static_cast<double>(in[c]) * inv_scale;
      // Non-finite -> 0; clamp, then round half away from zero (v >= 0).
      const double q = std::isfinite(v) ? std::clamp(v, 0.0, 1.0) * 65535.0 + 0.5 : 0.0;
      const auto pixel = static_cast<unsigned>(q);
      row[2 * c] = static_cast<std::uint8_t>(pixel >> 8U);
      row[2 * c + 1] = static_cast<std::uint8_t>(pixel & 0xffU);
    }
    png_write_row(png, row);
  }
  png_write_end(png, info);
  return true;
}

}  // namespace

Image read_png(const std::filesystem::path& path) {
  const std::string name = quoted(path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) && !ec) throw InputError("PNG file " + name + " does not exist");
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError("PNG file " + name + " is a directory, not a file");
  }
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) throw InputError("cannot open PNG file " + name + ": " + std::strerror(errno));

  // Signature first, so a text file or an empty file gets a plain message.
  png_byte signature[8] = {};
  const std::size_t got = std::fread(signature, 1, sizeof signature, file.get());
  if (got == 0) throw InputError("PNG file " + name + " is empty");
  if (got < sizeof signature || png_sig_cmp(signature, 0, sizeof signature) != 0) {
    if (got < sizeof signature && png_sig_cmp(signature, 0, got) == 0) {
      throw InputError("PNG file " + name + " is truncated: only " + std::to_string(got) +
                       " bytes, inside the PNG signature");
    }
    if (got == sizeof signature && png_sig_cmp(signature, 0, 4) == 0) {
      throw InputError("PNG file " + name + " has a damaged PNG signature (converted line endings?)");
    }
    throw InputError("file " + name + " is not a PNG (no PNG signature)");
  }

  PngIo io;
  io.file = file.get();
  io.offset = sizeof signature;
  PngReadHandle handle(&io);
  if (!handle.ok()) throw InputError("cannot read PNG file " + name + ": out of memory for libpng");
  png_set_read_fn(handle.png(), &io, on_png_read);
  const auto fail = [&](const char* stage) {
    return InputError("cannot read PNG file " + name + " (" + stage + "): " + io.message);
  };

  PngHeader header;
  if (!png_read_header(handle.png(), handle.info(), &header)) throw fail("header");
  // Refuse sizes we will not allocate, before allocating anything.
  const std::uint64_t cols64 = header.width;
  const std::uint64_t rows64 = header.height;
  if (cols64 == 0 || rows64 == 0) {
    throw InputError("PNG file " + name + " has zero size (" + describe_size(cols64, rows64) + ")");
  }
  if (cols64 > kMaxSide || rows64 > kMaxSide || cols64 * rows64 > kMaxPixels) {
    throw InputError("PNG file " + name + " is " + describe_size(cols64, rows64) +
                     "; at most 65536 pixels per side and 2^30 pixels in all are supported");
  }

  PngLayout layout;
  if (!png_set_layout(handle.png(), handle.info(), header, &layout)) throw fail("header");
  if ((layout.bit_depth != 8 && layout.bit_depth != 16) || layout.channels < 1 || layout.channels > 4) {
    throw InputError("PNG file " + name + " has an unsupported sample layout (" +
                     std::to_string(layout.channels) + " channels of " + std::to_string(layout.bit_depth) +
                     " bits)");
  }

  // Refuse a header claiming more image data than the file can hold, before
  // allocating: every pixel is stored (each row of each interlace pass adds
  // a filter byte on top), deflated at most kMaxDeflateRatio to 1.
  const std::uint64_t min_data_bytes = cols64 * rows64 * stored_bits_per_pixel(header) / 8;
  const std::optional<std::uint64_t> file_bytes = regular_file_size(file.get());
  if (file_bytes && min_data_bytes > *file_bytes * kMaxDeflateRatio) {
    throw InputError("PNG file " + name + " claims " + describe_size(cols64, rows64) + ", at least " +
                     std::to_string(min_data_bytes) + " bytes of image data, but the file is only " +
                     std::to_string(*file_bytes) + " bytes and zlib expands a byte to at most " +
                     std::to_string(kMaxDeflateRatio) + ": its header is wrong or the file is truncated");
  }

  Image image;
  image.cols = static_cast<int>(cols64);
  image.rows = static_cast<int>(rows64);
  image.bit_depth = header.color_type == PNG_COLOR_TYPE_PALETTE ? 8 : header.bit_depth;
  const std::size_t pixels = static_cast<std::size_t>(cols64 * rows64);
  try {
    if (layout.passes == 1) {
      // The output grows block by block as rows are decoded. With a known
      // file size (the check above passed) the whole image is reserved up
      // front, as address space only; from a pipe it grows geometrically.
      if (file_bytes) reserve_image_buffer(image.values, pixels);
      std::vector<std::uint8_t> row(layout.row_bytes);
      for (int r0 = 0; r0 < image.rows; r0 += kRowsPerBlock) {
        const int n = std::min(kRowsPerBlock, image.rows - r0);
        const std::size_t offset = static_cast<std::size_t>(r0) * static_cast<std::size_t>(image.cols);
        image.values.resize(offset + static_cast<std::size_t>(n) * static_cast<std::size_t>(image.cols));
        if (!png_read_rows_into(handle.png(), layout, image.cols, n, row.data(), image.values.data() + offset)) {
          throw fail("image data");
        }
      }
      if (!png_read_tail(handle.png(), handle.info())) throw fail("image data");
    } else {
      // The raw rows are not initialised, so only the rows the passes reach
      // are committed; the output is allocated once they are all decoded.
      RawBuffer raw(layout.row_bytes * static_cast<std::size_t>(rows64));
      std::vector<png_bytep> row_pointers(static_cast<std::size_t>(rows64));
      for (std::size_t r = 0; r < row_pointers.size(); ++r) row_pointers[r] = raw.bytes.get() + r * layout.row_bytes;
      if (!png_read_whole(handle.png(), handle.info(), row_pointers.data())) throw fail("image data");
      resize_image_buffer(image.values, pixels);
      for (int r = 0; r < image.rows; ++r) {
        row_to_luminance(row_pointers[static_cast<std::size_t>(r)], image.cols, layout,
                         image.values.data() + static_cast<std::ptrdiff_t>(r) * image.cols);
      }
    }
  } catch (const std::bad_alloc&) {
    throw InputError("PNG file " + name + " (" + describe_size(cols64, rows64) + ") does not fit in memory");
  }
  return image;
}

Image resample(const Image& image, int cols, int rows) {
  const auto in_range = [](int n) { return n >= 1 && static_cast<std::uint64_t>(n) <= kMaxSide; };
  if (!in_range(cols) || !in_range(rows) ||
      static_cast<std::uint64_t>(cols) * static_cast<std::uint64_t>(rows) > kMaxPixels) {
    throw InputError("resample: target size " + std::to_string(cols) + " x " + std::to_string(rows) +
                     " is outside [1, 65536] per side or has more than 2^30 pixels");
  }
  if (!in_range(image.cols) || !in_range(image.rows) ||
      image.values.size() != static_cast<std::size_t>(image.cols) * static_cast<std::size_t>(image.rows)) {
    throw InputError("resample: the source image must be 1 to 65536 pixels per side with cols x rows values; "
                     "it is " + std::to_string(image.cols) + " x " + std::to_string(image.rows) + " with " +
                     std::to_string(image.values.size()) + " values");
  }
  if (cols == image.cols && rows == image.rows) return image;

  const Taps taps_x = make_taps(image.cols, cols);
  const Taps taps_y = make_taps(image.rows, rows);
  Image out;
  out.cols = cols;
  out.rows = rows;
  out.bit_depth = image.bit_depth;
  resize_image_buffer(out.values, static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows));

  resample_separable(image, taps_x, taps_y, &out);
  return out;
}

void write_png16(const std::filesystem::path& path, const float* values, int cols, int rows,
                 double full_scale) {
  const std::string name = quoted(path);
  if (cols < 1 || rows < 1 || static_cast<std::uint64_t>(cols) > kMaxSide ||
      static_cast<std::uint64_t>(rows) > kMaxSide) {
    throw InputError("cannot write PNG file " + name + ": size " + std::to_string(cols) + " x " +
                     std::to_string(rows) + " is outside [1, 65536] per side");
  }
  if (values == nullptr) throw InputError("cannot write PNG file " + name + ": no values given");
  if (!std::isfinite(full_scale) || full_scale <= 0.0) {
    throw InputError("cannot write PNG file " + name + ": " +
                     must_be("full_scale", "finite and > 0", full_scale));
  }
  FilePtr file(std::fopen(path.c_str(), "wb"));
  if (!file) throw InputError("cannot open PNG file " + name + " for writing: " + std::strerror(errno));

  PngIo io;
  io.file = file.get();
  bool ok = false;
  {
    PngWriteHandle handle(&io);
    if (handle.ok()) {
      png_set_write_fn(handle.png(), &io, on_png_write, on_png_flush);
      // Height maps are smooth, so the "up" filter alone does about as well
      // as libpng's adaptive choice. Measured on 8192 x 8192 maps (smooth, and
      // smooth plus noise): with zlib level 1 the write is 5-8x faster than
      // libpng's defaults (level 6, adaptive filters), the read is faster too,
      // and the file is at most 3% larger (smaller for the smooth map).
      png_set_filter(handle.png(), PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
      png_set_compression_level(handle.png(), 1);
      std::vector<std::uint8_t> row(static_cast<std::size_t>(cols) * 2);
      ok = png_write_rows(handle.png(), handle.info(), values, cols, rows, full_scale, row.data());
    } else {
      std::snprintf(io.message, sizeof io.message, "out of memory for libpng");
    }
  }
  // fclose flushes: a full disk shows up here.
  const bool closed = std::fclose(file.release()) == 0;
  if (ok && !closed) std::snprintf(io.message, sizeof io.message, "closing failed: %s", std::strerror(errno));
  if (!ok || !closed) {
    std::error_code ec;
    std::filesystem::remove(path, ec);  // leave no half-written file behind
    throw InputError("cannot write PNG file " + name + ": " + io.message);
  }
}

}  // namespace terracut::io
