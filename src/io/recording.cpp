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

CsvFile::CsvFile(std::filesystem::path path, const std::string& header) : path_(std::move(path)) {
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) fail_file(path_, std::string("cannot create: ") + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  if (std::fputs(header.c_str(), file_) < 0 || std::fputc('\n', file_) == EOF)
    fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

CsvFile::~CsvFile() {
  if (file_) std::fclose(file_);
}

void CsvFile::row(std::initializer_list<Cell> cells) {
  bool first = true;
  int bad = 0;
  for (const Cell& c : cells) {
    if (!first) bad |= std::fputc(',', file_) == EOF;
    first = false;
    if (c.text)
      bad |= std::fputs(c.text->c_str(), file_) < 0;
    else
      bad |= std::fprintf(file_, "%.9g", c.number) < 0;
  }
  bad |= std::fputc('\n', file_) == EOF;
  if (bad) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

void CsvFile::close() {
  if (!file_) return;
  const bool bad = std::ferror(file_) != 0;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (bad || rc != 0) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

ContactCsvWriter::ContactCsvWriter(std::filesystem::path path)
    : file_(std::move(path),
            "t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,max_depth,"
            "cells_visited") {}

ContactCsvWriter::~ContactCsvWriter() = default;

void ContactCsvWriter::row(const StepRecord& r, const std::string& cut_name,
                           std::int64_t cells_visited) {
  const Vec3& p = r.pose.position_m;
  const Quat& q = r.pose.orientation;
  file_.row({r.t_s, cut_name, p.x, p.y, p.z, q.w, q.x, q.y, q.z, r.contact.length_m,
             r.removed_volume_m3, r.contact.section_area_m2, r.contact.max_depth_m,
             double(cells_visited)});
}

}  // namespace terracut::io
