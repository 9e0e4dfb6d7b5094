// Tests for terracut::io PNG reading/writing and resampling. Every PNG used
// here is written at run time, by write_png16 or directly with libpng, into a
// fresh temporary folder.
#include "terracut/io/image.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "terracut/core/error.hpp"

#include "../support/peak_memory.hpp"

namespace terracut::io {
namespace {

namespace fs = std::filesystem;

// Float tolerance for values in [0, 1] computed in double and rounded once.
constexpr float kUnitTol = 1e-6F;

// A fresh folder per test, removed afterwards.
class ImageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("terracut_image_test_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path file(const std::string& name) const { return dir_ / name; }

  fs::path dir_;
};

// ---------------------------------------------------------------------------
// Writing arbitrary PNGs with libpng.

// A PNG to write: samples are per channel, row-major, each in [0, 2^bit_depth - 1]
// (palette indices for palette images).
struct RawPng {
  int width = 0;
  int height = 0;
  int bit_depth = 8;
  int color_type = PNG_COLOR_TYPE_GRAY;
  bool interlaced = false;
  std::vector<std::uint16_t> samples;
  std::vector<png_color> palette;
  std::vector<png_byte> palette_alpha;  // tRNS for palette images
  int zlib_level = -1;                  // libpng's default when < 0
};

RawPng raw_png(int width, int height, int bit_depth, int color_type, bool interlaced = false) {
  RawPng p;
  p.width = width;
  p.height = height;
  p.bit_depth = bit_depth;
  p.color_type = color_type;
  p.interlaced = interlaced;
  return p;
}

int channels_of(int color_type) {
  switch (color_type) {
    case PNG_COLOR_TYPE_GRAY: return 1;
    case PNG_COLOR_TYPE_GRAY_ALPHA: return 2;
    case PNG_COLOR_TYPE_RGB: return 3;
    case PNG_COLOR_TYPE_RGB_ALPHA: return 4;
    default: return 1;  // palette index
  }
}

// The libpng part, kept free of C++ objects because of setjmp/longjmp.
bool write_png_c(std::FILE* fp, const RawPng* png_desc, png_bytepp rows) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, fp);
  if (png_desc->zlib_level >= 0) png_set_compression_level(png, png_desc->zlib_level);
  png_set_IHDR(png, info, static_cast<png_uint_32>(png_desc->width), static_cast<png_uint_32>(png_desc->height),
               png_desc->bit_depth, png_desc->color_type,
               png_desc->interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (!png_desc->palette.empty()) {
    png_set_PLTE(png, info, png_desc->palette.data(), static_cast<int>(png_desc->palette.size()));
  }
  if (!png_desc->palette_alpha.empty()) {
    png_set_tRNS(png, info, png_desc->palette_alpha.data(), static_cast<int>(png_desc->palette_alpha.size()),
                 nullptr);
  }
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

// Packs the samples (MSB first below 8 bits, big-endian at 16) and writes the file.
void write_raw_png(const fs::path& path, const RawPng& desc) {
  const int channels = channels_of(desc.color_type);
  const std::size_t row_bits = static_cast<std::size_t>(desc.width) * channels * desc.bit_depth;
  std::vector<std::vector<png_byte>> rows(static_cast<std::size_t>(desc.height),
                                          std::vector<png_byte>((row_bits + 7) / 8, 0));
  ASSERT_EQ(desc.samples.size(), static_cast<std::size_t>(desc.width) * desc.height * channels);
  for (int r = 0; r < desc.height; ++r) {
    for (int i = 0; i < desc.width * channels; ++i) {
      const std::uint16_t s = desc.samples[static_cast<std::size_t>(r) * desc.width * channels + i];
      ASSERT_LT(s, 1U << desc.bit_depth);
      auto& row = rows[static_cast<std::size_t>(r)];
      if (desc.bit_depth == 16) {
        row[2 * i] = static_cast<png_byte>(s >> 8);
        row[2 * i + 1] = static_cast<png_byte>(s & 0xff);
      } else if (desc.bit_depth == 8) {
        row[i] = static_cast<png_byte>(s);
      } else {
        const std::size_t bit = static_cast<std::size_t>(i) * desc.bit_depth;
        const int shift = 8 - desc.bit_depth - static_cast<int>(bit % 8);
        row[bit / 8] = static_cast<png_byte>(row[bit / 8] | (s << shift));
      }
    }
  }
  std::vector<png_bytep> pointers;
  for (auto& row : rows) pointers.push_back(row.data());
  std::FILE* fp = std::fopen(path.c_str(), "wb");
  ASSERT_NE(fp, nullptr);
  const bool ok = write_png_c(fp, &desc, pointers.data());
  std::fclose(fp);
  ASSERT_TRUE(ok) << "libpng could not write " << path;
}

std::vector<std::uint16_t> random_samples(std::size_t n, int bit_depth, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> dist(0, (1 << bit_depth) - 1);
  std::vector<std::uint16_t> s(n);
  for (auto& v : s) v = static_cast<std::uint16_t>(dist(rng));
  return s;
}

double luma(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }

// ---------------------------------------------------------------------------
// Raw byte helpers for damaged files.

std::vector<char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::uint32_t be32(const std::vector<char>& b, std::size_t at) {
  return (static_cast<std::uint32_t>(static_cast<unsigned char>(b[at])) << 24) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 1])) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 2])) << 8) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 3]));
}

void put_be32(std::vector<char>* b, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) b->push_back(static_cast<char>((v >> shift) & 0xff));
}

struct Chunk {
  std::string type;
  std::size_t offset = 0;  // of the length field
  std::size_t length = 0;  // of the data
};

std::vector<Chunk> chunks_of(const std::vector<char>& b) {
  std::vector<Chunk> chunks;
  std::size_t at = 8;
  while (at + 12 <= b.size()) {
    Chunk c;
    c.offset = at;
    c.length = be32(b, at);
    c.type.assign(b.begin() + static_cast<std::ptrdiff_t>(at + 4), b.begin() + static_cast<std::ptrdiff_t>(at + 8));
    chunks.push_back(c);
    at += 12 + c.length;
  }
  return chunks;
}

// Appends a chunk with a correct CRC.
void add_chunk(std::vector<char>* b, const std::string& type, const std::vector<char>& data) {
  put_be32(b, static_cast<std::uint32_t>(data.size()));
  const std::size_t type_at = b->size();
  b->insert(b->end(), type.begin(), type.end());
  b->insert(b->end(), data.begin(), data.end());
  const auto* p = reinterpret_cast<const Bytef*>(b->data() + type_at);
  put_be32(b, static_cast<std::uint32_t>(crc32(0L, p, static_cast<uInt>(4 + data.size()))));
}

// A hand-made PNG with the given IHDR (size, bit depth, colour type,
// interlace method) and a small IDAT.
std::vector<char> png_with_header(std::uint32_t width, std::uint32_t height, char bit_depth, char color_type,
                                  char interlace) {
  std::vector<char> b = {'\x89', 'P', 'N', 'G', '\r', '\n', '\x1a', '\n'};
  std::vector<char> ihdr;
  put_be32(&ihdr, width);
  put_be32(&ihdr, height);
  ihdr.insert(ihdr.end(), {bit_depth, color_type, 0, 0, interlace});  // deflate, adaptive filters
  add_chunk(&b, "IHDR", ihdr);
  // A valid zlib stream of a few zero bytes.
  std::vector<Bytef> raw(64, 0);
  uLongf packed_size = compressBound(raw.size());
  std::vector<Bytef> packed(packed_size);
  compress(packed.data(), &packed_size, raw.data(), raw.size());
  add_chunk(&b, "IDAT", std::vector<char>(packed.begin(), packed.begin() + static_cast<std::ptrdiff_t>(packed_size)));
  add_chunk(&b, "IEND", {});
  return b;
}

// A hand-made PNG with the given IHDR size (8-bit grey, not interlaced) and a small IDAT.
std::vector<char> png_with_size(std::uint32_t width, std::uint32_t height) {
  return png_with_header(width, height, 8, 0, 0);
}

// Expects read_png to throw InputError whose message names the file; returns the message.
std::string expect_input_error(const fs::path& path) {
  try {
    (void)read_png(path);
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path.filename().string()), std::string::npos) << message;
    return message;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError for " << path << ", got another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected InputError for " << path << ", but it was read";
  return {};
}

// A 16-bit grey noise image (incompressible, so its IDAT is large) written by write_png16.
fs::path write_noise_png(const fs::path& path, int cols, int rows) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> dist(0.0F, 1.0F);
  std::vector<float> v(static_cast<std::size_t>(cols) * rows);
  for (auto& x : v) x = dist(rng);
  write_png16(path, v.data(), cols, rows, 1.0);
  return path;
}

// ---------------------------------------------------------------------------
// write_png16 / read_png round trips.

TEST_F(ImageTest, Png16RoundTripWithinHalfStep) {
  const int cols = 37;
  const int rows = 23;
  const double full_scale = 2.5;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> dist(0.0F, static_cast<float>(full_scale));
  std::vector<float> v(static_cast<std::size_t>(cols) * rows);
  for (auto& x : v) x = dist(rng);
  const fs::path path = file("round.png");
  write_png16(path, v.data(), cols, rows, full_scale);

  const Image image = read_png(path);
  ASSERT_EQ(image.cols, cols);
  ASSERT_EQ(image.rows, rows);
  EXPECT_EQ(image.bit_depth, 16);
  ASSERT_EQ(image.values.size(), v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    // Half a quantisation step, plus float rounding of the value and of v/full_scale.
    const double expected = v[i] / full_scale;
    EXPECT_NEAR(image.values[i], expected, 0.5 / 65535.0 + 2e-7) << "at " << i;
    // The value read is an exact multiple of 1/65535.
    const double steps = image.values[i] * 65535.0;
    EXPECT_NEAR(steps, std::round(steps), 1e-2) << "at " << i;
  }
}

TEST_F(ImageTest, Png16ClampsAndZeroesNonFinite) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> v = {-1.0F, 0.0F, 2.0F, 4.0F, 9.0F, std::nanf(""), inf, -inf};
  const fs::path path = file("clamp.png");
  write_png16(path, v.data(), 4, 2, 4.0);
  const Image image = read_png(path);
  ASSERT_EQ(image.values.size(), v.size());
  const std::vector<float> expected = {0.0F, 0.0F, 32768.0F / 65535.0F, 1.0F, 1.0F, 0.0F, 0.0F, 0.0F};
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_FLOAT_EQ(image.values[i], expected[i]) << "at " << i;
}

TEST_F(ImageTest, Png16RowMajorOrientation) {
  // Distinct values so a transposition or flip would show: v(c, r) = r * cols + c.
  const int cols = 5;
  const int rows = 3;
  std::vector<float> v(cols * rows);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) v[r * cols + c] = static_cast<float>(r * cols + c);
  }
  const fs::path path = file("orient.png");
  write_png16(path, v.data(), cols, rows, 100.0);
  const Image image = read_png(path);
  ASSERT_EQ(image.cols, cols);
  ASSERT_EQ(image.rows, rows);
  for (int i = 0; i < cols * rows; ++i) EXPECT_NEAR(image.values[i] * 100.0, i, 100.0 / 65535.0);
}

TEST_F(ImageTest, WritePng16ErrorsNameTheFile) {
  const std::vector<float> v(4, 0.5F);
  const fs::path missing_dir = file("no_such_dir") / "out.png";
  try {
    write_png16(missing_dir, v.data(), 2, 2, 1.0);
    ADD_FAILURE() << "writing into a missing folder succeeded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing_dir.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_png16(file("a.png"), v.data(), 2, 2, 0.0), InputError);
  EXPECT_THROW(write_png16(file("a.png"), v.data(), 2, 2, std::nan("")), InputError);
  EXPECT_THROW(write_png16(file("a.png"), v.data(), 0, 2, 1.0), InputError);
  EXPECT_THROW(write_png16(file("a.png"), nullptr, 2, 2, 1.0), InputError);
}

// ---------------------------------------------------------------------------
// Reading every PNG colour type and bit depth.

TEST_F(ImageTest, Grey8) {
  RawPng p = raw_png(16, 16, 8, PNG_COLOR_TYPE_GRAY);
  for (int i = 0; i < 256; ++i) p.samples.push_back(static_cast<std::uint16_t>(i));
  const fs::path path = file("grey8.png");
  write_raw_png(path, p);
  const Image image = read_png(path);
  ASSERT_EQ(image.cols, 16);
  ASSERT_EQ(image.rows, 16);
  EXPECT_EQ(image.bit_depth, 8);
  for (int i = 0; i < 256; ++i) EXPECT_NEAR(image.values[i], i / 255.0, kUnitTol);
  EXPECT_EQ(image.values[0], 0.0F);
  EXPECT_EQ(image.values[255], 1.0F);
}

TEST_F(ImageTest, Grey16) {
  RawPng p = raw_png(9, 7, 16, PNG_COLOR_TYPE_GRAY);
  p.samples = random_samples(9 * 7, 16, 1);
  p.samples[0] = 0;
  p.samples[1] = 65535;
  const fs::path path = file("grey16.png");
  write_raw_png(path, p);
  const Image image = read_png(path);
  EXPECT_EQ(image.bit_depth, 16);
  for (std::size_t i = 0; i < p.samples.size(); ++i) EXPECT_NEAR(image.values[i], p.samples[i] / 65535.0, kUnitTol);
  EXPECT_EQ(image.values[1], 1.0F);
}

TEST_F(ImageTest, GreyLowBitDepths) {
  // 1, 2 and 4 bits: sample s reads as s / (2^depth - 1). Odd widths test
  // the partial last byte of each row.
  for (int depth : {1, 2, 4}) {
    RawPng p = raw_png(11, 5, depth, PNG_COLOR_TYPE_GRAY);
    p.samples = random_samples(11 * 5, depth, static_cast<unsigned>(depth));
    const fs::path path = file("grey" + std::to_string(depth) + ".png");
    write_raw_png(path, p);
    const Image image = read_png(path);
    ASSERT_EQ(image.cols, 11);
    ASSERT_EQ(image.rows, 5);
    EXPECT_EQ(image.bit_depth, depth);
    const double max = (1 << depth) - 1;
    for (std::size_t i = 0; i < p.samples.size(); ++i) {
      EXPECT_NEAR(image.values[i], p.samples[i] / max, kUnitTol) << "depth " << depth << " at " << i;
    }
  }
}

TEST_F(ImageTest, GreyAlphaIgnoresAlpha) {
  for (int depth : {8, 16}) {
    RawPng p = raw_png(6, 4, depth, PNG_COLOR_TYPE_GRAY_ALPHA);
    p.samples = random_samples(6 * 4 * 2, depth, 3);
    const fs::path path = file("ga" + std::to_string(depth) + ".png");
    write_raw_png(path, p);
    const Image image = read_png(path);
    EXPECT_EQ(image.bit_depth, depth);
    const double max = (1 << depth) - 1;
    for (int i = 0; i < 6 * 4; ++i) EXPECT_NEAR(image.values[i], p.samples[2 * i] / max, kUnitTol) << "at " << i;
  }
}

TEST_F(ImageTest, RgbAndRgbaUseRec709Luminance) {
  for (int type : {PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA}) {
    for (int depth : {8, 16}) {
      const int ch = channels_of(type);
      RawPng p = raw_png(8, 5, depth, type);
      p.samples = random_samples(8 * 5 * static_cast<std::size_t>(ch), depth, static_cast<unsigned>(type + depth));
      // Pure primaries and white in the first pixels: Y = weight, or 1.
      const std::uint16_t max = static_cast<std::uint16_t>((1 << depth) - 1);
      for (int px = 0; px < 4; ++px) {
        for (int k = 0; k < 3; ++k) p.samples[px * ch + k] = (px == 3 || px == k) ? max : 0;
      }
      const fs::path path = file("rgb" + std::to_string(type) + "_" + std::to_string(depth) + ".png");
      write_raw_png(path, p);
      const Image image = read_png(path);
      EXPECT_EQ(image.bit_depth, depth);
      EXPECT_NEAR(image.values[0], 0.2126, kUnitTol);
      EXPECT_NEAR(image.values[1], 0.7152, kUnitTol);
      EXPECT_NEAR(image.values[2], 0.0722, kUnitTol);
      EXPECT_NEAR(image.values[3], 1.0, kUnitTol);
      EXPECT_LE(image.values[3], 1.0F);
      for (int i = 0; i < 8 * 5; ++i) {
        const auto* s = &p.samples[static_cast<std::size_t>(i) * ch];
        EXPECT_NEAR(image.values[i], luma(s[0], s[1], s[2]) / max, kUnitTol)
            << "type " << type << " depth " << depth << " at " << i;
      }
    }
  }
}

TEST_F(ImageTest, PaletteWithAndWithoutTransparency) {
  std::vector<png_color> palette;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 16; ++i) {
    palette.push_back(png_color{static_cast<png_byte>(byte(rng)), static_cast<png_byte>(byte(rng)),
                                static_cast<png_byte>(byte(rng))});
  }
  for (int depth : {4, 8}) {
    for (bool trns : {false, true}) {
      RawPng p = raw_png(7, 6, depth, PNG_COLOR_TYPE_PALETTE);
      p.palette = palette;
      if (trns) p.palette_alpha = {0, 128, 255, 10, 20};
      p.samples = random_samples(7 * 6, 4, static_cast<unsigned>(depth + trns));
      const fs::path path = file("pal" + std::to_string(depth) + (trns ? "t" : "") + ".png");
      write_raw_png(path, p);
      const Image image = read_png(path);
      ASSERT_EQ(image.cols, 7);
      ASSERT_EQ(image.rows, 6);
      EXPECT_EQ(image.bit_depth, 8);
      for (int i = 0; i < 7 * 6; ++i) {
        const png_color& c = palette[p.samples[static_cast<std::size_t>(i)]];
        EXPECT_NEAR(image.values[i], luma(c.red, c.green, c.blue) / 255.0, kUnitTol)
            << "depth " << depth << " tRNS " << trns << " at " << i;
      }
    }
  }
}

TEST_F(ImageTest, InterlacedFiles) {
  // Adam7 needs the whole image in memory across passes: a separate code path.
  RawPng grey = raw_png(13, 11, 16, PNG_COLOR_TYPE_GRAY, true);
  grey.samples = random_samples(13 * 11, 16, 11);
  write_raw_png(file("i16.png"), grey);
  const Image g = read_png(file("i16.png"));
  for (std::size_t i = 0; i < grey.samples.size(); ++i) EXPECT_NEAR(g.values[i], grey.samples[i] / 65535.0, kUnitTol);

  RawPng rgba = raw_png(10, 9, 8, PNG_COLOR_TYPE_RGB_ALPHA, true);
  rgba.samples = random_samples(10 * 9 * 4, 8, 12);
  write_raw_png(file("i8rgba.png"), rgba);
  const Image c = read_png(file("i8rgba.png"));
  for (int i = 0; i < 10 * 9; ++i) {
    const auto* s = &rgba.samples[static_cast<std::size_t>(i) * 4];
    EXPECT_NEAR(c.values[i], luma(s[0], s[1], s[2]) / 255.0, kUnitTol) << "at " << i;
  }
}

// ---------------------------------------------------------------------------
// Bad input: every case throws InputError naming the file.

TEST_F(ImageTest, MissingEmptyAndNotPng) {
  EXPECT_NE(expect_input_error(file("missing.png")).find("does not exist"), std::string::npos);

  write_bytes(file("empty.png"), {});
  EXPECT_NE(expect_input_error(file("empty.png")).find("empty"), std::string::npos);

  const std::string text = "This is a text file, not an image.\n";
  write_bytes(file("text.png"), std::vector<char>(text.begin(), text.end()));
  EXPECT_NE(expect_input_error(file("text.png")).find("not a PNG"), std::string::npos);

  write_bytes(file("short.png"), {'\x89', 'P'});
  expect_input_error(file("short.png"));

  fs::create_directories(file("folder.png"));
  expect_input_error(file("folder.png"));
}

TEST_F(ImageTest, TruncatedAtManyOffsets) {
  const fs::path good = write_noise_png(file("good.png"), 64, 48);
  const std::vector<char> bytes = read_bytes(good);
  const std::vector<Chunk> chunks = chunks_of(bytes);
  ASSERT_GE(chunks.size(), 3U);
  ASSERT_EQ(chunks.front().type, "IHDR");
  ASSERT_EQ(chunks.back().type, "IEND");
  const auto idat = std::find_if(chunks.begin(), chunks.end(), [](const Chunk& c) { return c.type == "IDAT"; });
  ASSERT_NE(idat, chunks.end());
  ASSERT_GT(idat->length, 1000U);  // noise does not compress
  ASSERT_NO_THROW((void)read_png(good));

  const std::vector<std::size_t> cuts = {
      4,                                    // inside the signature
      8,                                    // right after the signature
      20,                                   // inside IHDR
      chunks[1].offset,                     // after IHDR, before the next chunk
      idat->offset + 6,                     // inside the IDAT chunk header
      idat->offset + 8 + idat->length / 2,  // middle of the IDAT data
      idat->offset + 8 + idat->length,      // IDAT data complete, its CRC missing
      chunks.back().offset,                 // everything but IEND
      bytes.size() - 1,                     // last byte of IEND's CRC missing
  };
  for (const std::size_t cut : cuts) {
    ASSERT_LT(cut, bytes.size());
    const fs::path path = file("cut_" + std::to_string(cut) + ".png");
    write_bytes(path, std::vector<char>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut)));
    SCOPED_TRACE("truncated at byte " + std::to_string(cut));
    expect_input_error(path);
  }
}

TEST_F(ImageTest, FlippedIdatBytesFailCrc) {
  // 128 x 96 x 2 bytes of noise: libpng writes several IDAT chunks. Flip
  // bytes in the first, so its CRC check fails before zlib reaches the end.
  const fs::path good = write_noise_png(file("good.png"), 128, 96);
  std::vector<char> bytes = read_bytes(good);
  const std::vector<Chunk> chunks = chunks_of(bytes);
  const auto idat_count = std::count_if(chunks.begin(), chunks.end(), [](const Chunk& c) { return c.type == "IDAT"; });
  ASSERT_GE(idat_count, 2);
  const auto idat = std::find_if(chunks.begin(), chunks.end(), [](const Chunk& c) { return c.type == "IDAT"; });
  const std::size_t at = idat->offset + 8 + idat->length / 3;
  for (std::size_t i = at; i < at + 4; ++i) bytes[i] = static_cast<char>(~bytes[i]);
  const fs::path path = file("flipped.png");
  write_bytes(path, bytes);
  const std::string message = expect_input_error(path);
  EXPECT_NE(message.find("CRC"), std::string::npos) << message;

  // A flip in the last IDAT chunk of a small image: whichever check fires
  // first (CRC or zlib's Adler-32), the read fails.
  const fs::path small = write_noise_png(file("small.png"), 16, 16);
  std::vector<char> small_bytes = read_bytes(small);
  const std::vector<Chunk> small_chunks = chunks_of(small_bytes);
  const auto last_idat = std::find_if(small_chunks.rbegin(), small_chunks.rend(),
                                      [](const Chunk& c) { return c.type == "IDAT"; });
  ASSERT_NE(last_idat, small_chunks.rend());
  const std::size_t mid = last_idat->offset + 8 + last_idat->length / 2;
  small_bytes[mid] = static_cast<char>(~small_bytes[mid]);
  write_bytes(file("flipped_small.png"), small_bytes);
  expect_input_error(file("flipped_small.png"));
}

TEST_F(ImageTest, CorruptDeflateStreamWithValidCrc) {
  // Damage the compressed data but fix the CRC, so zlib (not the CRC check)
  // must notice: in a smooth image (Huffman-coded, decoding goes wrong) and
  // in noise (stored blocks, only the Adler-32 check can tell).
  for (const bool smooth : {true, false}) {
    const fs::path good = file(smooth ? "smooth.png" : "noise.png");
    if (smooth) {
      std::vector<float> v(64 * 48);
      for (int i = 0; i < 64 * 48; ++i) v[static_cast<std::size_t>(i)] = 0.5F + 0.4F * std::sin(i * 0.05F);
      write_png16(good, v.data(), 64, 48, 1.0);
    } else {
      write_noise_png(good, 64, 48);
    }
    const std::vector<char> original = read_bytes(good);
    const std::vector<Chunk> chunks = chunks_of(original);
    const auto idat = std::find_if(chunks.begin(), chunks.end(), [](const Chunk& c) { return c.type == "IDAT"; });
    ASSERT_NE(idat, chunks.end());
    ASSERT_GT(idat->length, 40U);
    for (int part = 1; part <= 4; ++part) {
      std::vector<char> bytes = original;
      const std::size_t data = idat->offset + 8;
      const std::size_t at = data + idat->length * static_cast<std::size_t>(part) / 5;
      for (std::size_t i = at; i < at + 8; ++i) bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
      const auto* p = reinterpret_cast<const Bytef*>(bytes.data() + idat->offset + 4);
      const auto crc = static_cast<std::uint32_t>(crc32(0L, p, static_cast<uInt>(4 + idat->length)));
      for (int k = 0; k < 4; ++k) bytes[data + idat->length + k] = static_cast<char>((crc >> (24 - 8 * k)) & 0xff);
      const fs::path path = file(std::string(smooth ? "smooth" : "noise") + "_damaged_" + std::to_string(part) + ".png");
      write_bytes(path, bytes);
      SCOPED_TRACE(path.filename().string() + " damaged at byte " + std::to_string(at));
      expect_input_error(path);
    }
  }
}

TEST_F(ImageTest, RandomDamageGivesImageOrInputError) {
  // Random byte damage anywhere (with and without repairing the chunk CRCs,
  // so both the CRC checks and the decoders are exercised): each file must
  // either read as a well-formed image or throw InputError, never crash or
  // throw anything else.
  RawPng p = raw_png(24, 17, 8, PNG_COLOR_TYPE_RGB_ALPHA);
  p.samples = random_samples(24 * 17 * 4, 8, 77);
  write_raw_png(file("base.png"), p);
  const std::vector<char> original = read_bytes(file("base.png"));
  std::mt19937 rng(2024);
  std::uniform_int_distribution<std::size_t> where(8, original.size() - 1);
  std::uniform_int_distribution<int> byte(0, 255);
  int errors = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<char> bytes = original;
    const int flips = 1 + trial % 4;
    for (int k = 0; k < flips; ++k) bytes[where(rng)] = static_cast<char>(byte(rng));
    if (trial % 2 == 1) {
      // Repair every chunk's CRC whose length still fits the file.
      for (const Chunk& c : chunks_of(bytes)) {
        if (c.offset + 12 + c.length > bytes.size()) break;
        const auto* d = reinterpret_cast<const Bytef*>(bytes.data() + c.offset + 4);
        const auto crc = static_cast<std::uint32_t>(crc32(0L, d, static_cast<uInt>(4 + c.length)));
        for (int k = 0; k < 4; ++k) bytes[c.offset + 8 + c.length + k] = static_cast<char>((crc >> (24 - 8 * k)) & 0xff);
      }
    }
    const fs::path path = file("damaged.png");
    write_bytes(path, bytes);
    try {
      const Image image = read_png(path);
      ASSERT_EQ(image.values.size(), static_cast<std::size_t>(image.cols) * image.rows) << "trial " << trial;
      for (float v : image.values) ASSERT_TRUE(v >= 0.0F && v <= 1.0F) << "trial " << trial;
    } catch (const InputError& e) {
      ++errors;
      ASSERT_NE(std::string(e.what()).find("damaged.png"), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(errors, 100);  // most damage is detected
}

TEST_F(ImageTest, AbsurdAndZeroSizesRefused) {
  const struct {
    std::uint32_t width, height;
  } sizes[] = {{70000, 16}, {16, 65537}, {40000, 40000}, {0, 16}, {16, 0}};
  for (const auto& s : sizes) {
    const fs::path path = file("size_" + std::to_string(s.width) + "x" + std::to_string(s.height) + ".png");
    write_bytes(path, png_with_size(s.width, s.height));
    SCOPED_TRACE(path.filename().string());
    const std::string message = expect_input_error(path);
    if (s.width > 0 && s.height > 0) {
      EXPECT_NE(message.find("65536"), std::string::npos) << message;
    }
  }
  // The same hand-made file at a sane size is read (all zero): the files
  // above failed because of their size alone.
  write_bytes(file("sane.png"), png_with_size(7, 8));
  const Image sane = read_png(file("sane.png"));
  EXPECT_EQ(sane.cols, 7);
  EXPECT_EQ(sane.rows, 8);
  for (float v : sane.values) EXPECT_EQ(v, 0.0F);
}

TEST_F(ImageTest, TooLittleImageData) {
  // A well-formed file (valid CRCs, complete zlib stream, IEND) whose IDAT
  // holds 64 bytes: enough for 7 x 8 8-bit grey (8 rows of 1 + 7 bytes), not
  // for 16 x 16.
  write_bytes(file("enough.png"), png_with_size(7, 8));
  EXPECT_NO_THROW((void)read_png(file("enough.png")));
  write_bytes(file("too_little.png"), png_with_size(16, 16));
  expect_input_error(file("too_little.png"));
}

using test::peak_rss_bytes;
using test::small_growth;

// A header claiming far more pixels than its few bytes of data can hold
// (the review's 69-byte file claiming 65536 x 16384, and a 16-bit
// interlaced one claiming 32768^2) is refused from its file size alone,
// before any image memory is committed: the message names the file, the
// claim and zlib's limit, and the peak memory of the process barely moves.
TEST_F(ImageTest, LyingHeaderRefusedBeforeAllocating) {
  const struct {
    std::uint32_t width, height;
    char bit_depth, color_type, interlace;
    const char* name;
  } cases[] = {
      {65536, 16384, 8, 0, 0, "grey8_65536x16384.png"},        // 2^30 pixels, 1 GiB of data, 4 GiB of floats
      {32768, 32768, 16, 0, 1, "grey16_interlaced_32768.png"},  // 2 GiB of data held raw while interlaced
      {16384, 16384, 16, 6, 0, "rgba16_16384.png"},             // 8 bytes a pixel
      {32768, 32768, 1, 0, 0, "grey1_32768.png"},               // 1 bit a pixel still needs 128 MiB of data
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::vector<char> bytes = png_with_header(c.width, c.height, c.bit_depth, c.color_type, c.interlace);
    ASSERT_LT(bytes.size(), 100U);
    write_bytes(file(c.name), bytes);
    const std::int64_t before = peak_rss_bytes();
    const std::string message = expect_input_error(file(c.name));
    const std::int64_t grew = peak_rss_bytes() - before;
    EXPECT_NE(message.find("claims " + std::to_string(c.width) + " x " + std::to_string(c.height) + " pixels"),
              std::string::npos) << message;
    EXPECT_NE(message.find("only " + std::to_string(bytes.size()) + " bytes"), std::string::npos) << message;
    EXPECT_NE(message.find("at most 1032"), std::string::npos) << message;
    EXPECT_LT(grew, small_growth(16)) << "peak memory grew by " << grew << " bytes";
  }
  // 2^31 pixels: refused by the size limit, before reading on.
  write_bytes(file("huge.png"), png_with_size(65536, 32768));
  const std::int64_t before = peak_rss_bytes();
  const std::string message = expect_input_error(file("huge.png"));
  EXPECT_NE(message.find("2^30 pixels"), std::string::npos) << message;
  EXPECT_LT(peak_rss_bytes() - before, small_growth(16));
}

// Through a pipe the file size is not known in advance, so the claim cannot
// be checked against it: memory then follows the rows actually decoded, and
// the lying file still fails (too little image data) without committing the
// image it claims.
TEST_F(ImageTest, LyingHeaderThroughAPipeCommitsOnlyWhatIsDecoded) {
  const struct {
    std::uint32_t width, height;
    char bit_depth, interlace;
  } cases[] = {{65536, 16384, 8, 0}, {32768, 32768, 16, 1}};
  for (const auto& c : cases) {
    const fs::path fifo = file("pipe_" + std::to_string(c.width) + ".png");
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
    const std::vector<char> bytes = png_with_header(c.width, c.height, c.bit_depth, 0, c.interlace);
    std::thread writer([&] {
      std::FILE* out = std::fopen(fifo.c_str(), "wb");
      if (out == nullptr) return;
      std::fwrite(bytes.data(), 1, bytes.size(), out);
      std::fclose(out);
    });
    const std::int64_t before = peak_rss_bytes();
    const std::string message = expect_input_error(fifo);
    writer.join();
    const std::int64_t grew = peak_rss_bytes() - before;
    EXPECT_NE(message.find("image data"), std::string::npos) << message;
    EXPECT_LT(grew, small_growth(64)) << "peak memory grew by " << grew << " bytes";
  }
}

// A real file near zlib's best ratio (a constant image at level 9) is not
// mistaken for a lying one.
TEST_F(ImageTest, MaximallyCompressedImageIsRead) {
  const int n = 2048;
  RawPng p = raw_png(n, n, 8, PNG_COLOR_TYPE_GRAY);
  p.samples.assign(static_cast<std::size_t>(n) * n, 0);
  p.zlib_level = 9;
  write_raw_png(file("zeros.png"), p);
  const auto bytes = fs::file_size(file("zeros.png"));
  EXPECT_LT(bytes, static_cast<std::uintmax_t>(n) * n / 500) << "not compressed near zlib's limit";
  const Image image = read_png(file("zeros.png"));
  ASSERT_EQ(image.cols, n);
  ASSERT_EQ(image.rows, n);
  EXPECT_EQ(*std::max_element(image.values.begin(), image.values.end()), 0.0F);
}

// ---------------------------------------------------------------------------
// Resampling.

Image make_image(int cols, int rows, const std::vector<float>& values) {
  Image image;
  image.cols = cols;
  image.rows = rows;
  image.values = values;
  return image;
}

Image random_image(int cols, int rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(0.0F, 1.0F);
  std::vector<float> v(static_cast<std::size_t>(cols) * rows);
  for (auto& x : v) x = dist(rng);
  return make_image(cols, rows, v);
}

double mean_of(const Image& image) {
  double sum = 0.0;
  for (float v : image.values) sum += v;
  return sum / static_cast<double>(image.values.size());
}

// Reference box filter, computed directly in 2-D: output (j, i) covers the
// source rectangle [j*sx, (j+1)*sx) x [i*sy, (i+1)*sy) and averages the
// source pixels by overlap area.
Image box_reference(const Image& in, int cols, int rows) {
  const double sx = static_cast<double>(in.cols) / cols;
  const double sy = static_cast<double>(in.rows) / rows;
  Image out = make_image(cols, rows, std::vector<float>(static_cast<std::size_t>(cols) * rows));
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      double sum = 0.0;
      for (int r = 0; r < in.rows; ++r) {
        const double oy = std::min((i + 1) * sy, r + 1.0) - std::max(i * sy, static_cast<double>(r));
        if (oy <= 0.0) continue;
        for (int c = 0; c < in.cols; ++c) {
          const double ox = std::min((j + 1) * sx, c + 1.0) - std::max(j * sx, static_cast<double>(c));
          if (ox > 0.0) sum += ox * oy * in.values[static_cast<std::size_t>(r) * in.cols + c];
        }
      }
      out.values[static_cast<std::size_t>(i) * cols + j] = static_cast<float>(sum / (sx * sy));
    }
  }
  return out;
}

TEST(Resample, ConstantStaysConstant) {
  const float value = 0.3717F;
  const struct {
    int cols_in, rows_in, cols, rows;
  } cases[] = {{64, 48, 32, 24}, {64, 48, 7, 5},  {7, 5, 64, 48}, {10, 10, 3, 3},
               {9, 13, 20, 4},   {1, 1, 5, 3},    {50, 1, 3, 9},  {3, 3, 3, 3}};
  for (const auto& k : cases) {
    const Image in = make_image(k.cols_in, k.rows_in, std::vector<float>(static_cast<std::size_t>(k.cols_in) * k.rows_in, value));
    const Image out = resample(in, k.cols, k.rows);
    ASSERT_EQ(out.cols, k.cols);
    ASSERT_EQ(out.rows, k.rows);
    ASSERT_EQ(out.values.size(), static_cast<std::size_t>(k.cols) * k.rows);
    for (float v : out.values) {
      ASSERT_NEAR(v, value, 2.0F * std::numeric_limits<float>::epsilon() * value)
          << k.cols_in << "x" << k.rows_in << " -> " << k.cols << "x" << k.rows;
    }
  }
}

TEST(Resample, HalvingAveragesBlocks) {
  const Image in = random_image(8, 6, 21);
  const Image out = resample(in, 4, 3);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      const auto at = [&](int r, int c) { return static_cast<double>(in.values[static_cast<std::size_t>(r) * 8 + c]); };
      const double block = (at(2 * i, 2 * j) + at(2 * i, 2 * j + 1) + at(2 * i + 1, 2 * j) + at(2 * i + 1, 2 * j + 1)) / 4;
      EXPECT_NEAR(out.values[static_cast<std::size_t>(i) * 4 + j], block, kUnitTol);
    }
  }
  EXPECT_NEAR(mean_of(out), mean_of(in), 1e-6);
}

TEST(Resample, NonIntegerShrinkMatchesAreaReference) {
  const struct {
    int cols_in, rows_in, cols, rows;
  } cases[] = {{7, 7, 3, 3}, {13, 9, 5, 4}, {100, 37, 33, 10}, {7, 1, 3, 1}, {11, 6, 1, 1}};
  for (const auto& k : cases) {
    const Image in = random_image(k.cols_in, k.rows_in, static_cast<unsigned>(k.cols_in * 31 + k.rows_in));
    const Image out = resample(in, k.cols, k.rows);
    const Image ref = box_reference(in, k.cols, k.rows);
    for (std::size_t i = 0; i < ref.values.size(); ++i) {
      ASSERT_NEAR(out.values[i], ref.values[i], kUnitTol) << k.cols_in << "x" << k.rows_in << " at " << i;
    }
    // Equal-area outputs tiling the source: the mean is preserved.
    EXPECT_NEAR(mean_of(out), mean_of(in), 1e-6);
  }
}

TEST(Resample, BilinearEnlargeReproducesRamp) {
  // v = a*x + b*y + d at source pixel centres (x = c, y = r in pixel units).
  const int cols_in = 8;
  const int rows_in = 5;
  const double a = 0.05;
  const double b = -0.07;
  const double d = 0.4;
  std::vector<float> v;
  for (int r = 0; r < rows_in; ++r) {
    for (int c = 0; c < cols_in; ++c) v.push_back(static_cast<float>(a * c + b * r + d));
  }
  const Image in = make_image(cols_in, rows_in, v);
  const int cols = 29;
  const int rows = 17;
  const Image out = resample(in, cols, rows);
  int interior = 0;
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      // Output centre in source pixel coordinates, clamped to the outermost centres.
      const double x = std::clamp((j + 0.5) * cols_in / cols - 0.5, 0.0, cols_in - 1.0);
      const double y = std::clamp((i + 0.5) * rows_in / rows - 0.5, 0.0, rows_in - 1.0);
      EXPECT_NEAR(out.values[static_cast<std::size_t>(i) * cols + j], a * x + b * y + d, 1e-6)
          << "at col " << j << " row " << i;
      if (x > 0.0 && x < cols_in - 1.0 && y > 0.0 && y < rows_in - 1.0) ++interior;
    }
  }
  EXPECT_GE(interior, (cols - 4) * (rows - 4));
}

TEST(Resample, MixedShrinkAndEnlarge) {
  // v(c, r) = g(c) + h(r) with random g and linear h: shrinking columns
  // 12 -> 4 averages g over triples, enlarging rows 4 -> 10 interpolates h.
  const int cols_in = 12;
  const int rows_in = 4;
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> dist(0.0, 0.5);
  std::vector<double> g(cols_in);
  for (auto& x : g) x = dist(rng);
  const auto h = [](double y) { return 0.1 * y + 0.05; };
  std::vector<float> v;
  for (int r = 0; r < rows_in; ++r) {
    for (int c = 0; c < cols_in; ++c) v.push_back(static_cast<float>(g[c] + h(r)));
  }
  const Image out = resample(make_image(cols_in, rows_in, v), 4, 10);
  ASSERT_EQ(out.cols, 4);
  ASSERT_EQ(out.rows, 10);
  for (int i = 0; i < 10; ++i) {
    const double y = std::clamp((i + 0.5) * rows_in / 10.0 - 0.5, 0.0, rows_in - 1.0);
    for (int j = 0; j < 4; ++j) {
      const double g_mean = (g[3 * j] + g[3 * j + 1] + g[3 * j + 2]) / 3.0;
      EXPECT_NEAR(out.values[static_cast<std::size_t>(i) * 4 + j], g_mean + h(y), 1e-6) << j << "," << i;
    }
  }
  // And the other way round: enlarge columns, shrink rows.
  const Image in2 = random_image(3, 20, 5);
  const Image out2 = resample(in2, 9, 4);
  const Image back = resample(resample(in2, 3, 4), 9, 4);  // shrink rows first, then enlarge columns
  for (std::size_t i = 0; i < out2.values.size(); ++i) EXPECT_NEAR(out2.values[i], back.values[i], kUnitTol);
}

TEST(Resample, OneByOneAndToOneByOne) {
  const Image one = make_image(1, 1, {0.625F});
  const Image big = resample(one, 5, 3);
  ASSERT_EQ(big.values.size(), 15U);
  for (float v : big.values) EXPECT_EQ(v, 0.625F);

  const Image in = random_image(7, 4, 8);
  const Image mean = resample(in, 1, 1);
  ASSERT_EQ(mean.values.size(), 1U);
  EXPECT_NEAR(mean.values[0], mean_of(in), kUnitTol);
}

TEST(Resample, SameSizeIsCopyAndBitDepthKept) {
  Image in = random_image(6, 4, 3);
  in.bit_depth = 16;
  const Image same = resample(in, 6, 4);
  EXPECT_EQ(same.values, in.values);
  EXPECT_EQ(resample(in, 3, 2).bit_depth, 16);
}

TEST(Resample, RefusesBadSizes) {
  const Image in = random_image(4, 4, 1);
  EXPECT_THROW(resample(in, 0, 4), InputError);
  EXPECT_THROW(resample(in, 4, -1), InputError);
  EXPECT_THROW(resample(in, 65537, 4), InputError);
  EXPECT_THROW(resample(in, 65536, 65536), InputError);  // 2^32 pixels
  Image broken = in;
  broken.values.pop_back();
  EXPECT_THROW(resample(broken, 2, 2), InputError);
  EXPECT_THROW(resample(Image{}, 2, 2), InputError);
}

// ---------------------------------------------------------------------------
// A large height map, read back and resampled: every run, at a size CI can
// afford (2048^2, 16-bit, two files: one from write_png16, one written with
// libpng's default settings, zlib level 6 and adaptive filters, as other
// tools write them). The speed at 8192^2 is measured by the benchmark
// (bench/image_bench.cpp, scripts/bench.sh), not by a timed test.

TEST_F(ImageTest, LargePng16ReadsBackAndResamplesConservingTheMean) {
  const int n = 2048;
  // A smooth terrain with some fine noise, like a scanned height map.
  std::vector<float> v(static_cast<std::size_t>(n) * n);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> noise(0.0F, 0.002F);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      v[static_cast<std::size_t>(r) * n + c] =
          0.5F + 0.3F * std::sin(c * 0.012F) * std::cos(r * 0.008F) + 0.1F * std::sin((c + r) * 0.08F) + noise(rng);
    }
  }
  for (const bool ours : {true, false}) {
    const fs::path path = file(ours ? "large_ours.png" : "large_libpng_defaults.png");
    if (ours) {
      write_png16(path, v.data(), n, n, 1.0);
    } else {
      RawPng p = raw_png(n, n, 16, PNG_COLOR_TYPE_GRAY);
      p.samples.resize(v.size());
      for (std::size_t i = 0; i < v.size(); ++i) {
        p.samples[i] = static_cast<std::uint16_t>(std::lround(std::clamp(v[i], 0.0F, 1.0F) * 65535.0F));
      }
      write_raw_png(path, p);
    }
    const Image image = read_png(path);
    ASSERT_EQ(image.cols, n);
    ASSERT_EQ(image.rows, n);
    // Every sample within half a 16-bit step (plus float rounding).
    for (std::size_t i = 0; i < v.size(); i += 997) EXPECT_NEAR(image.values[i], v[i], 0.5 / 65535.0 + 2e-7);
    // Shrinking by 2 (exact box filter) and by a non-integer factor keep the
    // mean (area averaging conserves the volume).
    const Image half = resample(image, n / 2, n / 2);
    const Image small = resample(image, 1000, 1000);
    EXPECT_NEAR(mean_of(half), mean_of(image), 1e-5);
    EXPECT_NEAR(mean_of(small), mean_of(image), 1e-5);
    fs::remove(path);
  }
}

}  // namespace
}  // namespace terracut::io
