// NumPy .npy files of float32 (rows, cols) arrays: writing format 1.0, and
// reading format 1.0/2.0/3.0 with every header field checked.
//
// Layout: magic "\x93NUMPY", major and minor version bytes, header length
// (uint16 little-endian for 1.x, uint32 for 2.x/3.x), then an ASCII Python
// dict literal padded with spaces and ending in '\n' so the data starts at a
// multiple of 64 bytes, then the raw little-endian samples in C order.
#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <system_error>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

#include "c_file.hpp"

namespace terracut::io {
namespace {

using detail::FilePtr;
using detail::quoted;

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicSize = 6;
constexpr std::size_t kAlignment = 64;

std::uint32_t byteswap32(std::uint32_t v) {
  return (v >> 24U) | ((v >> 8U) & 0xff00U) | ((v << 8U) & 0xff0000U) | (v << 24U);
}

// Swaps the bytes of n 4-byte samples in place.
void swap_samples(float* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, values + i, 4);
    bits = byteswap32(bits);
    std::memcpy(values + i, &bits, 4);
  }
}

// A parser for the small subset of Python literals a .npy header uses:
// a dict of string keys to strings, True/False and tuples of integers.
class HeaderParser {
 public:
  HeaderParser(const std::string& text, const std::string& file) : text_(text), file_(file) {}

  void parse(std::string* descr, bool* fortran_order, std::vector<std::int64_t>* shape) {
    bool have_descr = false;
    bool have_order = false;
    bool have_shape = false;
    expect('{');
    skip_space();
    while (peek() != '}') {
      const std::string key = parse_string();
      expect(':');
      if (key == "descr") {
        *descr = parse_string();
        have_descr = true;
      } else if (key == "fortran_order") {
        *fortran_order = parse_bool();
        have_order = true;
      } else if (key == "shape") {
        *shape = parse_tuple();
        have_shape = true;
      } else {
        fail("unexpected key '" + key + "'");
      }
      skip_space();
      if (peek() == ',') {
        ++pos_;
        skip_space();
      } else if (peek() != '}') {
        fail("expected ',' or '}'");
      }
    }
    ++pos_;
    skip_space();
    if (pos_ != text_.size()) fail("unexpected text after the closing '}'");
    if (!have_descr) fail("missing key 'descr'");
    if (!have_order) fail("missing key 'fortran_order'");
    if (!have_shape) fail("missing key 'shape'");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError("NumPy file " + file_ + ": bad header at character " + std::to_string(pos_) + ": " +
                     what + " in \"" + text_ + "\"");
  }
  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_])) != 0) ++pos_;
  }
  char peek() {
    if (pos_ >= text_.size()) fail("unexpected end of header");
    return text_[pos_];
  }
  void expect(char c) {
    skip_space();
    if (peek() != c) fail(std::string("expected '") + c + "'");
    ++pos_;
  }
  std::string parse_string() {
    skip_space();
    const char quote = peek();
    if (quote != '\'' && quote != '"') fail("expected a quoted string");
    const std::size_t end = text_.find(quote, pos_ + 1);
    if (end == std::string::npos) fail("unterminated string");
    std::string s = text_.substr(pos_ + 1, end - pos_ - 1);
    pos_ = end + 1;
    return s;
  }
  bool parse_bool() {
    skip_space();
    if (text_.compare(pos_, 4, "True") == 0) {
      pos_ += 4;
      return true;
    }
    if (text_.compare(pos_, 5, "False") == 0) {
      pos_ += 5;
      return false;
    }
    fail("expected True or False");
  }
  std::vector<std::int64_t> parse_tuple() {
    std::vector<std::int64_t> dims;
    expect('(');
    skip_space();
    while (peek() != ')') {
      if (std::isdigit(static_cast<unsigned char>(peek())) == 0) fail("expected a non-negative integer");
      std::int64_t v = 0;
      while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_])) != 0) {
        if (v > (std::numeric_limits<std::int64_t>::max() - 9) / 10) fail("dimension too large");
        v = v * 10 + (text_[pos_] - '0');
        ++pos_;
      }
      // Python 2 era files may write 3L.
      if (pos_ < text_.size() && text_[pos_] == 'L') ++pos_;
      dims.push_back(v);
      skip_space();
      if (peek() == ',') {
        ++pos_;
        skip_space();
      } else if (peek() != ')') {
        fail("expected ',' or ')' in shape");
      }
    }
    ++pos_;
    return dims;
  }

  const std::string& text_;
  const std::string& file_;
  std::size_t pos_ = 0;
};

}  // namespace

void write_npy(const std::filesystem::path& path, const float* values, int rows, int cols) {
  const std::string name = quoted(path);
  if (rows < 0 || cols < 0) {
    throw InputError("cannot write NumPy file " + name + ": negative shape (" + std::to_string(rows) + ", " +
                     std::to_string(cols) + ")");
  }
  const std::size_t count = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  if (values == nullptr && count > 0) throw InputError("cannot write NumPy file " + name + ": no values given");

  // Header dict, padded with spaces so magic + version + length + header is
  // a multiple of 64 bytes, the last byte being '\n'.
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", " +
                       std::to_string(cols) + "), }";
  const std::size_t prefix = kMagicSize + 2 + 2;
  const std::size_t total = (prefix + header.size() + 1 + kAlignment - 1) / kAlignment * kAlignment;
  header.append(total - prefix - header.size() - 1, ' ');
  header.push_back('\n');

  std::string bytes(kMagic, kMagicSize);
  bytes.push_back('\x01');
  bytes.push_back('\x00');
  bytes.push_back(static_cast<char>(header.size() & 0xffU));
  bytes.push_back(static_cast<char>((header.size() >> 8U) & 0xffU));
  bytes += header;

  FilePtr file(std::fopen(path.c_str(), "wb"));
  if (!file) throw InputError("cannot open NumPy file " + name + " for writing: " + std::strerror(errno));
  bool ok = std::fwrite(bytes.data(), 1, bytes.size(), file.get()) == bytes.size();
  if (ok && count > 0) {
    if constexpr (std::endian::native == std::endian::little) {
      ok = std::fwrite(values, sizeof(float), count, file.get()) == count;
    } else {
      // Swap a block at a time to keep memory small.
      constexpr std::size_t kBlock = 4096;
      float block[kBlock];
      for (std::size_t i = 0; ok && i < count; i += kBlock) {
        const std::size_t n = std::min(kBlock, count - i);
        std::memcpy(block, values + i, n * sizeof(float));
        swap_samples(block, n);
        ok = std::fwrite(block, sizeof(float), n, file.get()) == n;
      }
    }
  }
  const int write_errno = errno;
  const bool closed = std::fclose(file.release()) == 0;
  if (!ok || !closed) {
    const int err = ok ? errno : write_errno;
    std::error_code ec;
    std::filesystem::remove(path, ec);  // leave no half-written file behind
    throw InputError("cannot write NumPy file " + name + ": " + std::strerror(err));
  }
}

std::vector<float> read_npy(const std::filesystem::path& path, int* rows, int* cols) {
  const std::string name = quoted(path);
  if (rows == nullptr || cols == nullptr) {
    throw InputError("read_npy " + name + ": rows and cols must not be null");
  }
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) && !ec) throw InputError("NumPy file " + name + " does not exist");
  if (std::filesystem::is_directory(path, ec)) throw InputError("NumPy file " + name + " is a directory");
  const std::uintmax_t file_size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError("cannot read NumPy file " + name + ": " + ec.message());
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) throw InputError("cannot open NumPy file " + name + ": " + std::strerror(errno));
  const auto fail = [&](const std::string& what) { return InputError("NumPy file " + name + ": " + what); };

  // Magic and version.
  unsigned char prefix[kMagicSize + 2] = {};
  const std::size_t got = std::fread(prefix, 1, sizeof prefix, file.get());
  if (got == 0) throw fail("file is empty");
  if (got < kMagicSize || std::memcmp(prefix, kMagic, kMagicSize) != 0) throw fail("not a .npy file (bad magic)");
  if (got < sizeof prefix) throw fail("file is truncated in the version bytes");
  const int major = prefix[kMagicSize];
  const int minor = prefix[kMagicSize + 1];
  if (major < 1 || major > 3 || minor != 0) {
    throw fail("unsupported format version " + std::to_string(major) + "." + std::to_string(minor) +
               " (1.0, 2.0 and 3.0 are read)");
  }

  // Header length: 2 bytes in 1.x, 4 bytes in 2.x/3.x, little-endian.
  const std::size_t length_bytes = major == 1 ? 2 : 4;
  unsigned char length_raw[4] = {};
  if (std::fread(length_raw, 1, length_bytes, file.get()) != length_bytes) {
    throw fail("file is truncated in the header length");
  }
  std::uint64_t header_size = 0;
  for (std::size_t i = length_bytes; i-- > 0;) header_size = (header_size << 8U) | length_raw[i];
  const std::uint64_t data_offset = sizeof prefix + length_bytes + header_size;
  if (data_offset > file_size) {
    throw fail("file is truncated: header claims " + std::to_string(header_size) + " bytes but the file has " +
               std::to_string(file_size) + " bytes in all");
  }
  std::string header(static_cast<std::size_t>(header_size), '\0');
  if (header_size > 0 && std::fread(header.data(), 1, header.size(), file.get()) != header.size()) {
    throw fail("file is truncated in the header");
  }

  std::string descr;
  bool fortran_order = true;
  std::vector<std::int64_t> shape;
  HeaderParser(header, name).parse(&descr, &fortran_order, &shape);

  // Only float32 in C order with two dimensions.
  bool swap = false;
  if (descr == "<f4") {
    swap = std::endian::native != std::endian::little;
  } else if (descr == ">f4") {
    swap = std::endian::native != std::endian::big;
  } else {
    throw fail("dtype '" + descr + "' is not float32 ('<f4')");
  }
  if (fortran_order) throw fail("array is in Fortran order; only C order is read");
  if (shape.size() != 2) {
    throw fail("array has " + std::to_string(shape.size()) + " dimensions; a 2-D (rows, cols) array is needed");
  }
  constexpr std::int64_t kMaxDim = std::numeric_limits<int>::max();
  if (shape[0] > kMaxDim || shape[1] > kMaxDim) {
    throw fail("shape (" + std::to_string(shape[0]) + ", " + std::to_string(shape[1]) + ") is too large");
  }

  // The data must be exactly rows * cols samples.
  const std::uint64_t count = static_cast<std::uint64_t>(shape[0]) * static_cast<std::uint64_t>(shape[1]);
  const std::uint64_t data_bytes = count * sizeof(float);
  const std::uint64_t have = file_size - data_offset;
  if (have < data_bytes) {
    throw fail("file is truncated: shape (" + std::to_string(shape[0]) + ", " + std::to_string(shape[1]) +
               ") needs " + std::to_string(data_bytes) + " bytes of data but only " + std::to_string(have) +
               " follow the header");
  }
  if (have > data_bytes) {
    throw fail(std::to_string(have - data_bytes) + " unexpected bytes after the data of shape (" +
               std::to_string(shape[0]) + ", " + std::to_string(shape[1]) + ")");
  }
  std::vector<float> values;
  try {
    values.resize(static_cast<std::size_t>(count));
  } catch (const std::bad_alloc&) {
    throw fail("array of " + std::to_string(count) + " samples does not fit in memory");
  }
  if (count > 0 && std::fread(values.data(), sizeof(float), values.size(), file.get()) != values.size()) {
    throw fail("read error or file truncated while reading the data");
  }
  if (swap) swap_samples(values.data(), values.size());
  *rows = static_cast<int>(shape[0]);
  *cols = static_cast<int>(shape[1]);
  return values;
}

}  // namespace terracut::io
