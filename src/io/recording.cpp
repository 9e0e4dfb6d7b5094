// contact.csv. See recording.hpp.
#include "terracut/io/recording.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>

#include "terracut/core/error.hpp"

namespace terracut::io {
namespace {

[[noreturn]] void fail_file(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

}  // namespace

std::string_view CsvFile::Cell::print(char* out) const noexcept {
  char* const end = out + kMaxNumberChars;
  std::to_chars_result r{out, std::errc()};
  switch (kind_) {
    case Kind::kText:
      return text_;
    case Kind::kNumber:  // as printf's %.9g
      r = std::to_chars(out, end, number_, std::chars_format::general, 9);
      break;
    case Kind::kWhole:
      r = std::to_chars(out, end, whole_);
      break;
    case Kind::kExactDouble:
      r = std::to_chars(out, end, number_);
      break;
    case Kind::kExactFloat:
      r = std::to_chars(out, end, float(number_));
      break;
  }
  return {out, std::size_t(r.ptr - out)};
}

CsvFile::CsvFile(std::filesystem::path path, std::string_view header) : path_(std::move(path)) {
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) fail_file(path_, std::string("cannot create: ") + std::strerror(errno));
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  if (std::fwrite(header.data(), 1, header.size(), file_) != header.size() ||
      std::fputc('\n', file_) == EOF)
    fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

CsvFile::~CsvFile() {
  if (file_) std::fclose(file_);
}

bool CsvFile::put_row(std::span<const Cell> cells) noexcept {
  if (!file_) return false;
  char number[Cell::kMaxNumberChars];
  bool first = true;
  bool bad = false;
  for (const Cell& c : cells) {
    if (!first) bad |= std::fputc(',', file_) == EOF;
    first = false;
    const std::string_view text = c.print(number);
    bad |= std::fwrite(text.data(), 1, text.size(), file_) != text.size();
  }
  bad |= std::fputc('\n', file_) == EOF;
  return !bad;
}

void CsvFile::row(std::span<const Cell> cells) {
  if (!put_row(cells)) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
}

bool CsvFile::try_row(std::initializer_list<Cell> cells) noexcept {
  if (put_row(std::span(cells.begin(), cells.size()))) return true;
  if (failed_errno_ == 0) failed_errno_ = errno != 0 ? errno : EIO;
  return false;
}

void CsvFile::close() {
  if (!file_) return;
  const bool bad = std::ferror(file_) != 0;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (failed_errno_ != 0)
    fail_file(path_, std::string("write failed: ") + std::strerror(failed_errno_));
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
