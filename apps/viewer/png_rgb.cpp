#include "png_rgb.hpp"

#include <png.h>

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

namespace terracut::viewer {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};

}  // namespace

void write_png_rgb(const std::filesystem::path& path, const RgbImage& image) {
  const std::string name = path.string();
  if (image.cols <= 0 || image.rows <= 0 ||
      image.pixels.size() != std::size_t(image.cols) * std::size_t(image.rows) * 3u)
    throw std::runtime_error(name + ": image size does not match its pixels");
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(name.c_str(), "wb"));
  if (!file) throw std::runtime_error(name + ": cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error(name + ": out of memory for the PNG writer");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    file.reset();
    std::error_code ec;
    std::filesystem::remove(path, ec);
    throw std::runtime_error(name + ": error while writing the PNG");
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, png_uint_32(image.cols), png_uint_32(image.rows), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int r = 0; r < image.rows; ++r) {
    png_write_row(png, image.pixels.data() + std::size_t(r) * std::size_t(image.cols) * 3u);
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(file.get()) != 0) {
    file.reset();
    std::error_code ec;
    std::filesystem::remove(path, ec);
    throw std::runtime_error(name + ": error while writing the PNG");
  }
}

RgbImage read_png_rgb(const std::filesystem::path& path) {
  const std::string name = path.string();
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, name.c_str()))
    throw std::runtime_error(name + ": " + img.message);
  img.format = PNG_FORMAT_RGB;
  RgbImage out;
  out.cols = int(img.width);
  out.rows = int(img.height);
  out.pixels.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.pixels.data(), 0, nullptr)) {
    std::string message = img.message;
    png_image_free(&img);
    throw std::runtime_error(name + ": " + message);
  }
  return out;
}

}  // namespace terracut::viewer
