// Body poses per step: DIR/bodies.csv of a run with rigid bodies.
//
//   t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz
//
// One row per body per written step: t = simulated time after the step,
// seconds; body = index in the scenario's `bodies:` list; name = its name;
// x, y, z = world position of its centre, metres; qw..qz = unit quaternion,
// body frame -> world; vx, vy, vz = linear velocity, m/s. Numbers are the
// shortest text that reads back to the same value (Bullet's floats are
// printed as floats, time as a double), so two identical runs give identical
// files.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

#include "terracut/bullet/terrain_world.hpp"

namespace terracut::bullet {

/// The header line, with its trailing newline.
std::string_view bodies_csv_header();

/// Appends one row per body of `world` at time t_s to `out`. Allocates only
/// when `out` must grow (reserve it: about 160 bytes per body).
void append_rows(const TerrainWorld& world, double t_s, std::string& out);

/// Writes bodies.csv: the header at open, rows on write_step, buffered.
class BodiesCsvWriter {
 public:
  /// Creates (replaces) the file. Throws terracut::InputError naming the path
  /// when it cannot be opened. every_n_steps >= 1 keeps one step in n.
  explicit BodiesCsvWriter(const std::filesystem::path& path, int every_n_steps = 1);
  ~BodiesCsvWriter();
  BodiesCsvWriter(const BodiesCsvWriter&) = delete;
  BodiesCsvWriter& operator=(const BodiesCsvWriter&) = delete;

  /// Writes the rows of the world's last step (at world.time_s()), keeping
  /// one call in every_n_steps (the first call is always written). Never
  /// throws; a write error is remembered and reported by close().
  void write_step(const TerrainWorld& world);
  /// Flushes and closes; throws terracut::InputError naming the path when any
  /// write failed.
  void close();

  std::int64_t rows_written() const { return rows_; }

 private:
  void flush();

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
  int every_n_ = 1;
  std::int64_t calls_ = 0;
  std::int64_t rows_ = 0;
  bool failed_ = false;
};

}  // namespace terracut::bullet
