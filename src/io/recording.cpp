// contact.csv. See recording.hpp.
#include "terracut/io/recording.hpp"

#include <cerrno>
#include <cstring>

#include "terracut/core/error.hpp"

namespace terracut::io {
namespace {

[[noreturn]] void fail_file(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

}  // namespace

ContactCsvWriter::ContactCsvWriter(std::filesystem::path path) : path_(std::move(path)) {
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) fail_file(path_, std::string("cannot create: ") + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  if (std::fputs("t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,max_depth,"
                 "cells_visited\n",
                 file_) < 0)
    fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

ContactCsvWriter::~ContactCsvWriter() {
  if (file_) std::fclose(file_);
}

void ContactCsvWriter::row(const StepRecord& r, const std::string& cut_name,
                           std::int64_t cells_visited) {
  const Vec3& p = r.pose.position_m;
  const Quat& q = r.pose.orientation;
  const int n = std::fprintf(
      file_, "%.9g,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%lld\n", r.t_s,
      cut_name.c_str(), p.x, p.y, p.z, q.w, q.x, q.y, q.z, r.contact.length_m,
      r.removed_volume_m3, r.contact.section_area_m2, r.contact.max_depth_m,
      static_cast<long long>(cells_visited));
  if (n < 0) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

void ContactCsvWriter::close() {
  const bool bad = std::ferror(file_) != 0;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (bad || rc != 0) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

}  // namespace terracut::io
