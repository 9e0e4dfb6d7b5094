// Tests for terracut::io .npy writing and reading, checked against the
// format specification byte by byte and, where /usr/bin/python3 has NumPy,
// against NumPy itself in both directions.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

namespace terracut::io {
namespace {

namespace fs = std::filesystem;

class NpyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("terracut_npy_test_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
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

std::vector<char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::uint32_t bits_of(float v) {
  std::uint32_t b = 0;
  std::memcpy(&b, &v, 4);
  return b;
}

// A version 1.0 file with the given header dict (padded as NumPy does) and raw data.
std::string npy_v1(const std::string& dict, const std::string& data) {
  std::string header = dict;
  while ((10 + header.size() + 1) % 64 != 0) header.push_back(' ');
  header.push_back('\n');
  std::string b = std::string("\x93NUMPY", 6) + '\x01' + '\x00';
  b.push_back(static_cast<char>(header.size() & 0xff));
  b.push_back(static_cast<char>(header.size() >> 8));
  return b + header + data;
}

std::string float_bytes(const std::vector<float>& v) {
  std::string s(v.size() * 4, '\0');
  std::memcpy(s.data(), v.data(), s.size());
  return s;
}

// Expects read_npy to throw InputError naming the file; returns the message.
std::string expect_input_error(const fs::path& path) {
  int rows = -1;
  int cols = -1;
  try {
    (void)read_npy(path, &rows, &cols);
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

bool python_has_numpy() {
  return std::system("/usr/bin/python3 -c 'import numpy' >/dev/null 2>&1") == 0;
}

TEST_F(NpyTest, RoundTripIsBitExact) {
  const int rows = 7;
  const int cols = 5;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> dist(-1e3F, 1e3F);
  std::vector<float> v(rows * cols);
  for (auto& x : v) x = dist(rng);
  v[0] = -0.0F;
  v[1] = std::numeric_limits<float>::infinity();
  v[2] = std::numeric_limits<float>::quiet_NaN();
  v[3] = std::numeric_limits<float>::denorm_min();
  const fs::path path = file("a.npy");
  write_npy(path, v.data(), rows, cols);
  int r = 0;
  int c = 0;
  const std::vector<float> back = read_npy(path, &r, &c);
  EXPECT_EQ(r, rows);
  EXPECT_EQ(c, cols);
  ASSERT_EQ(back.size(), v.size());
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(bits_of(back[i]), bits_of(v[i])) << "at " << i;
}

TEST_F(NpyTest, HeaderFollowsFormat10) {
  const int rows = 3;
  const int cols = 11;
  std::vector<float> v(rows * cols);
  for (int i = 0; i < rows * cols; ++i) v[i] = static_cast<float>(i) * 0.5F;
  const fs::path path = file("h.npy");
  write_npy(path, v.data(), rows, cols);
  const std::vector<char> b = read_bytes(path);
  ASSERT_GE(b.size(), 10U);
  EXPECT_EQ(std::string(b.begin(), b.begin() + 6), std::string("\x93NUMPY", 6));
  EXPECT_EQ(b[6], 1);  // major version
  EXPECT_EQ(b[7], 0);  // minor version
  const std::size_t header_len = static_cast<unsigned char>(b[8]) | (static_cast<unsigned char>(b[9]) << 8);
  const std::size_t data_start = 10 + header_len;
  EXPECT_EQ(data_start % 64, 0U);
  ASSERT_EQ(b.size(), data_start + 4U * rows * cols);
  EXPECT_EQ(b[data_start - 1], '\n');
  const std::string header(b.begin() + 10, b.begin() + static_cast<std::ptrdiff_t>(data_start));
  EXPECT_NE(header.find("'descr': '<f4'"), std::string::npos) << header;
  EXPECT_NE(header.find("'fortran_order': False"), std::string::npos) << header;
  EXPECT_NE(header.find("'shape': (3, 11)"), std::string::npos) << header;
  // Samples are little-endian float32 in C order: sample (r, c) at r * cols + c.
  for (int i = 0; i < rows * cols; ++i) {
    std::uint32_t u = 0;
    for (int k = 3; k >= 0; --k) u = (u << 8) | static_cast<unsigned char>(b[data_start + 4 * i + k]);
    EXPECT_EQ(u, bits_of(v[i])) << "at " << i;
  }
}

TEST_F(NpyTest, NumpyReadsOurFile) {
  if (!python_has_numpy()) GTEST_SKIP() << "/usr/bin/python3 has no numpy";
  const int rows = 4;
  const int cols = 6;
  std::vector<float> v(rows * cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) v[r * cols + c] = static_cast<float>(r * 10 + c) + 0.25F;
  }
  const fs::path path = file("ours.npy");
  write_npy(path, v.data(), rows, cols);
  // NumPy checks shape, dtype and every value (rows along axis 0).
  const std::string script =
      "import numpy, sys; a = numpy.load(sys.argv[1]); "
      "e = (numpy.arange(4)[:, None] * 10 + numpy.arange(6)[None, :] + 0.25).astype(numpy.float32); "
      "sys.exit(0 if a.shape == (4, 6) and a.dtype == numpy.float32 and a.flags['C_CONTIGUOUS'] "
      "and numpy.array_equal(a, e) else 3)";
  const std::string command = "/usr/bin/python3 -c \"" + script + "\" '" + path.string() + "'";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
}

TEST_F(NpyTest, WeReadNumpyFiles) {
  if (!python_has_numpy()) GTEST_SKIP() << "/usr/bin/python3 has no numpy";
  // numpy.save (format 1.0), a big-endian array and a format 2.0 file.
  const std::string script =
      "import numpy, sys; d = sys.argv[1]; "
      "a = (numpy.arange(12, dtype=numpy.float32).reshape(3, 4) * 0.5 - 1); "
      "numpy.save(d + '/le.npy', a); "
      "numpy.save(d + '/be.npy', a.astype('>f4')); "
      "f = open(d + '/v2.npy', 'wb'); numpy.lib.format.write_array(f, a, version=(2, 0)); f.close()";
  const std::string command = "/usr/bin/python3 -c \"" + script + "\" '" + dir_.string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  for (const char* name : {"le.npy", "be.npy", "v2.npy"}) {
    int rows = 0;
    int cols = 0;
    const std::vector<float> a = read_npy(file(name), &rows, &cols);
    EXPECT_EQ(rows, 3) << name;
    EXPECT_EQ(cols, 4) << name;
    ASSERT_EQ(a.size(), 12U) << name;
    for (int i = 0; i < 12; ++i) EXPECT_EQ(a[i], static_cast<float>(i) * 0.5F - 1.0F) << name << " at " << i;
  }
}

TEST_F(NpyTest, ZeroSizedArray) {
  const fs::path path = file("empty_array.npy");
  write_npy(path, nullptr, 0, 3);
  int rows = -1;
  int cols = -1;
  EXPECT_TRUE(read_npy(path, &rows, &cols).empty());
  EXPECT_EQ(rows, 0);
  EXPECT_EQ(cols, 3);
}

TEST_F(NpyTest, TruncatedFilesFail) {
  std::vector<float> v(16);
  for (int i = 0; i < 16; ++i) v[i] = static_cast<float>(i);
  const fs::path good = file("good.npy");
  write_npy(good, v.data(), 4, 4);
  const std::vector<char> b = read_bytes(good);
  // The header dict is longer than 64 - 10 bytes: data starts at byte 128.
  ASSERT_EQ(b.size(), 128U + 64U);
  // Inside the magic, the version, the header length, the header (twice),
  // right at the data, in the middle of the data, one byte short.
  for (const std::size_t cut : {3UL, 7UL, 9UL, 30UL, 100UL, 128UL, 160UL, 191UL}) {
    const fs::path path = file("cut_" + std::to_string(cut) + ".npy");
    write_bytes(path, std::string(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(cut)));
    SCOPED_TRACE("truncated at byte " + std::to_string(cut));
    expect_input_error(path);
  }
  // One byte too many is also not a (4, 4) float32 array.
  write_bytes(file("long.npy"), std::string(b.begin(), b.end()) + "x");
  expect_input_error(file("long.npy"));
}

TEST_F(NpyTest, WrongContentFails) {
  const std::string data16 = float_bytes(std::vector<float>(16, 1.0F));
  const struct {
    const char* name;
    std::string bytes;
    const char* says;  // part of the message
  } cases[] = {
      {"f8.npy", npy_v1("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 4), }", data16), "<f8"},
      {"i4.npy", npy_v1("{'descr': '<i4', 'fortran_order': False, 'shape': (4, 4), }", data16), "<i4"},
      {"fortran.npy", npy_v1("{'descr': '<f4', 'fortran_order': True, 'shape': (4, 4), }", data16), "Fortran"},
      {"1d.npy", npy_v1("{'descr': '<f4', 'fortran_order': False, 'shape': (16,), }", data16), "dimensions"},
      {"3d.npy", npy_v1("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2, 4), }", data16), "dimensions"},
      {"noshape.npy", npy_v1("{'descr': '<f4', 'fortran_order': False, }", data16), "shape"},
      {"garbled.npy", npy_v1("{'descr': '<f4', 'fortran_order': Maybe, 'shape': (4, 4), }", data16), "True or False"},
      {"badmagic.npy", "\x93NUMPX" + npy_v1("{}", "").substr(6), "magic"},
      {"version4.npy", std::string("\x93NUMPY\x04\x00", 8) + npy_v1("{}", "").substr(8), "version"},
      {"text.npy", "just some text, long enough to look like a header", "magic"},
      {"empty.npy", "", "empty"},
  };
  for (const auto& k : cases) {
    const fs::path path = file(k.name);
    write_bytes(path, k.bytes);
    SCOPED_TRACE(k.name);
    const std::string message = expect_input_error(path);
    EXPECT_NE(message.find(k.says), std::string::npos) << message;
  }
  // The same data with a correct header is accepted: the cases above failed
  // only because of what they changed.
  write_bytes(file("right.npy"), npy_v1("{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4), }", data16));
  int rows = 0;
  int cols = 0;
  EXPECT_EQ(read_npy(file("right.npy"), &rows, &cols), std::vector<float>(16, 1.0F));
}

TEST_F(NpyTest, RandomDamageGivesArrayOrInputError) {
  // Random bytes changed in the header or the first data bytes, and random
  // lengths: each file either reads as a consistent array or throws
  // InputError, never crashes or throws anything else.
  std::vector<float> v(12);
  for (int i = 0; i < 12; ++i) v[i] = static_cast<float>(i);
  write_npy(file("base.npy"), v.data(), 3, 4);
  const std::vector<char> original = read_bytes(file("base.npy"));
  std::mt19937 rng(31);
  std::uniform_int_distribution<std::size_t> where(0, 140);
  std::uniform_int_distribution<int> byte(0, 255);
  int errors = 0;
  for (int trial = 0; trial < 500; ++trial) {
    std::string bytes(original.begin(), original.end());
    for (int k = 0; k <= trial % 3; ++k) bytes[where(rng)] = static_cast<char>(byte(rng));
    if (trial % 5 == 0) bytes.resize(where(rng));
    const fs::path path = file("damaged.npy");
    write_bytes(path, bytes);
    int rows = -1;
    int cols = -1;
    try {
      const std::vector<float> a = read_npy(path, &rows, &cols);
      ASSERT_EQ(a.size(), static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols)) << "trial " << trial;
    } catch (const InputError& e) {
      ++errors;
      ASSERT_NE(std::string(e.what()).find("damaged.npy"), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(errors, 100);
}

TEST_F(NpyTest, MissingFileAndUnwritablePath) {
  EXPECT_NE(expect_input_error(file("missing.npy")).find("does not exist"), std::string::npos);
  const std::vector<float> v(4, 1.0F);
  const fs::path bad = file("no_such_dir") / "out.npy";
  try {
    write_npy(bad, v.data(), 2, 2);
    ADD_FAILURE() << "writing into a missing folder succeeded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_npy(file("neg.npy"), v.data(), -1, 2), InputError);
  EXPECT_THROW(write_npy(file("null.npy"), nullptr, 2, 2), InputError);
}

}  // namespace
}  // namespace terracut::io
