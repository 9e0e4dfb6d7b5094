#include "terracut/bullet/bodies_csv.hpp"

#include <charconv>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut::bullet {

namespace {

// Buffered bytes before a write to the file.
constexpr std::size_t kFlushBytes = 1 << 16;

// Appends the shortest round-trip text of v (float or double) and a separator.
template <typename T>
void put(std::string& out, T v, char sep) {
  char text[40];
  const auto result = std::to_chars(text, text + sizeof text, v);
  out.append(text, result.ptr);
  out.push_back(sep);
}

}  // namespace

std::string_view bodies_csv_header() { return "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz\n"; }

void append_rows(const TerrainWorld& world, double t_s, std::string& out) {
  for (int i = 0; i < world.body_count(); ++i) {
    // Bullet's state is single precision: print it as floats, exactly.
    const BodyState s = world.body_state(i);
    put(out, t_s, ',');
    put(out, i, ',');
    out.append(world.body_spec(i).name);
    out.push_back(',');
    put(out, float(s.position_m.x), ',');
    put(out, float(s.position_m.y), ',');
    put(out, float(s.position_m.z), ',');
    put(out, float(s.orientation.w), ',');
    put(out, float(s.orientation.x), ',');
    put(out, float(s.orientation.y), ',');
    put(out, float(s.orientation.z), ',');
    put(out, float(s.velocity_m_s.x), ',');
    put(out, float(s.velocity_m_s.y), ',');
    put(out, float(s.velocity_m_s.z), '\n');
  }
}

BodiesCsvWriter::BodiesCsvWriter(const std::filesystem::path& path, int every_n_steps)
    : path_(path), every_n_(every_n_steps) {
  if (every_n_steps < 1)
    throw InputError(must_be("bodies.csv: every_n_steps", ">= 1", every_n_steps));
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw InputError(path.string() + ": cannot open for writing");
  buffer_.reserve(2 * kFlushBytes);
  buffer_.append(bodies_csv_header());
}

BodiesCsvWriter::~BodiesCsvWriter() {
  if (file_) {
    flush();
    std::fclose(file_);
  }
}

void BodiesCsvWriter::write_step(const TerrainWorld& world) {
  const bool keep = calls_ % every_n_ == 0;
  ++calls_;
  if (!keep || !file_) return;
  append_rows(world, world.time_s(), buffer_);
  rows_ += world.body_count();
  if (buffer_.size() >= kFlushBytes) flush();
}

void BodiesCsvWriter::flush() {
  if (!file_ || buffer_.empty()) return;
  if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) failed_ = true;
  buffer_.clear();
}

void BodiesCsvWriter::close() {
  if (!file_) return;
  flush();
  if (std::fclose(file_) != 0) failed_ = true;
  file_ = nullptr;
  if (failed_) throw InputError(path_.string() + ": error while writing");
}

}  // namespace terracut::bullet
