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
// files. Written with io::CsvFile, terracut's one CSV writer.
#pragma once

#include <cstdint>
#include <filesystem>

#include "terracut/bullet/terrain_world.hpp"
#include "terracut/io/recording.hpp"

namespace terracut::bullet {

/// The columns of bodies.csv, in order.
inline constexpr const char* kBodiesCsvColumns = "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz";

/// Writes bodies.csv: the header at open, rows on write_step, buffered.
class BodiesCsvWriter {
 public:
  /// Creates (replaces) the file. Throws terracut::InputError naming the path
  /// when it cannot be created. every_n_steps >= 1 keeps one step in n.
  explicit BodiesCsvWriter(const std::filesystem::path& path, int every_n_steps = 1);

  /// Writes the rows of the world's last step (at world.time_s()), keeping
  /// one call in every_n_steps (the first call is always written). Never
  /// throws and allocates nothing; a write error is remembered and reported
  /// by close().
  void write_step(const TerrainWorld& world) noexcept;
  /// Flushes and closes; throws terracut::InputError naming the path when any
  /// write failed.
  void close() { file_.close(); }

  std::int64_t rows_written() const { return rows_; }

 private:
  int every_n_ = 1;
  io::CsvFile file_;
  std::int64_t calls_ = 0;
  std::int64_t rows_ = 0;
};

}  // namespace terracut::bullet
