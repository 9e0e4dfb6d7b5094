// bodies.csv: header, one row per body per written step, values that read
// back exactly, identical files for identical runs.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "terracut/bullet/bodies_csv.hpp"
#include "terracut/core/error.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  for (std::string cell; std::getline(s, cell, ',');) out.push_back(cell);
  return out;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::filesystem::path temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("terracut_bullet_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

// Runs the test scene for `steps`, writing every `every`-th step.
void write_run(const std::filesystem::path& file, int steps, int every) {
  test::Scene scene;
  BodiesCsvWriter csv(file, every);
  for (int i = 0; i < steps; ++i) {
    scene.step(i);
    csv.write_step(scene.world);
  }
  csv.close();
}

TEST(BodiesCsv, HeaderRowsAndExactValues) {
  const auto dir = temp_dir("rows");
  test::Scene scene;
  BodiesCsvWriter csv(dir / "bodies.csv");
  const int steps = 300;
  std::vector<BodyState> last(std::size_t(scene.world.body_count()));
  for (int i = 0; i < steps; ++i) {
    scene.step(i);
    csv.write_step(scene.world);
  }
  for (int b = 0; b < scene.world.body_count(); ++b) last[std::size_t(b)] = scene.world.body_state(b);
  csv.close();
  EXPECT_EQ(csv.rows_written(), std::int64_t(steps) * scene.world.body_count());

  std::ifstream in(dir / "bodies.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, kBodiesCsvColumns);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) rows.push_back(split(line));
  ASSERT_EQ(rows.size(), std::size_t(steps) * std::size_t(scene.world.body_count()));
  for (const auto& row : rows) ASSERT_EQ(row.size(), 13u);
  // The last step's rows: time, index, name, and Bullet's float state exactly.
  const int n = scene.world.body_count();
  for (int b = 0; b < n; ++b) {
    const auto& row = rows[rows.size() - std::size_t(n) + std::size_t(b)];
    EXPECT_DOUBLE_EQ(std::strtod(row[0].c_str(), nullptr), steps / 1000.0);
    EXPECT_EQ(row[1], std::to_string(b));
    EXPECT_EQ(row[2], scene.world.body_spec(b).name);
    const BodyState& s = last[std::size_t(b)];
    EXPECT_EQ(std::strtof(row[3].c_str(), nullptr), float(s.position_m.x));
    EXPECT_EQ(std::strtof(row[4].c_str(), nullptr), float(s.position_m.y));
    EXPECT_EQ(std::strtof(row[5].c_str(), nullptr), float(s.position_m.z));
    EXPECT_EQ(std::strtof(row[6].c_str(), nullptr), float(s.orientation.w));
    EXPECT_EQ(std::strtof(row[9].c_str(), nullptr), float(s.orientation.z));
    EXPECT_EQ(std::strtof(row[11].c_str(), nullptr), float(s.velocity_m_s.y));
  }
  std::filesystem::remove_all(dir);
}

TEST(BodiesCsv, DecimationAndIdenticalRuns) {
  const auto dir = temp_dir("runs");
  write_run(dir / "a.csv", 400, 10);
  write_run(dir / "b.csv", 400, 10);
  const std::string a = read_file(dir / "a.csv");
  EXPECT_EQ(a, read_file(dir / "b.csv"));
  // 40 written steps (calls 0, 10, ..., 390) x 4 bodies + the header.
  EXPECT_EQ(std::count(a.begin(), a.end(), '\n'), 40 * 4 + 1);
  std::filesystem::remove_all(dir);
}

TEST(BodiesCsv, UnwritablePathIsAnInputError) {
  EXPECT_THROW(BodiesCsvWriter("/nonexistent_dir_terracut/bodies.csv"), InputError);
  EXPECT_THROW(BodiesCsvWriter(std::filesystem::temp_directory_path() / "x.csv", 0), InputError);
}

}  // namespace
}  // namespace terracut::bullet
