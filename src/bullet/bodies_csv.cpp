// bodies.csv. See bodies_csv.hpp.
#include "terracut/bullet/bodies_csv.hpp"

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut::bullet {

namespace {

int checked_every_n(int every_n_steps) {
  if (every_n_steps < 1)
    throw InputError(must_be("bodies.csv: every_n_steps", ">= 1", every_n_steps));
  return every_n_steps;
}

}  // namespace

BodiesCsvWriter::BodiesCsvWriter(const std::filesystem::path& path, int every_n_steps)
    : every_n_(checked_every_n(every_n_steps)), file_(path, kBodiesCsvColumns) {}

void BodiesCsvWriter::write_step(const TerrainWorld& world) noexcept {
  const bool keep = calls_ % every_n_ == 0;
  ++calls_;
  if (!keep) return;
  using Cell = io::CsvFile::Cell;
  const double t_s = world.time_s();
  for (int i = 0; i < world.body_count(); ++i) {
    // Bullet's state is single precision: print it as floats, exactly.
    const BodyState s = world.body_state(i);
    file_.try_row({Cell::exact(t_s), i, world.body_spec(i).name,
                   Cell::exact(float(s.position_m.x)), Cell::exact(float(s.position_m.y)),
                   Cell::exact(float(s.position_m.z)), Cell::exact(float(s.orientation.w)),
                   Cell::exact(float(s.orientation.x)), Cell::exact(float(s.orientation.y)),
                   Cell::exact(float(s.orientation.z)), Cell::exact(float(s.velocity_m_s.x)),
                   Cell::exact(float(s.velocity_m_s.y)), Cell::exact(float(s.velocity_m_s.z))});
  }
  rows_ += world.body_count();
}

}  // namespace terracut::bullet
