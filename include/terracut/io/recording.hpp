// contact.csv: the per-step record of a batch run (`terracut run`), one row
// per step:
//
//   t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,
//   max_depth,cells_visited
//
// SI units (docs/scenario-format.md); numbers printed with %.9g, so the text
// is the same on every run of the same scenario. CsvFile below is the one
// CSV writer every file of terracut is written with.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "terracut/core/blade.hpp"
#include "terracut/core/contact.hpp"

namespace terracut::io {

/// One step: one row of contact.csv.
struct StepRecord {
  double t_s = 0.0;        ///< global simulation time, seconds
  int cut = 0;             ///< index into Scenario::cuts
  int sequence_index = 0;  ///< index into Scenario::sequence
  BladePose pose{};        ///< blade pose during the step
  ContactResult contact{};  ///< contact measured before the step's cut
  double removed_volume_m3 = 0.0;  ///< volume cut in this step, m^3
};

/// A CSV file written row by row through a stdio buffer: the header at
/// creation, then rows of cells, so the text is the same on every run of the
/// same scenario. Every CSV file of terracut is one (contact.csv, force.csv,
/// bodies.csv, haptics.csv, operator.csv, remote.csv). Every error names the
/// file ("PATH: cannot create: REASON", "PATH: write failed: REASON",
/// InputError). Writing a row allocates nothing.
class CsvFile {
 public:
  /// Creates (replaces) the file and writes header (the column names,
  /// comma-separated, without the line's end).
  CsvFile(std::filesystem::path path, std::string_view header);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;

  /// One cell of a row: a double printed with %.9g, a whole number (any
  /// integer or bool: 0 / 1), a number printed exactly (exact(): the shortest
  /// text that reads back to the same double or float), or a text (as is: no
  /// quoting, so the caller gives text without commas, as names are).
  class Cell {
   public:
    Cell(double v) : kind_(Kind::kNumber), number_(v) {}
    template <typename T>
      requires std::is_integral_v<T>
    Cell(T v) : kind_(Kind::kWhole), whole_(static_cast<long long>(v)) {}
    Cell(const std::string& t) : kind_(Kind::kText), text_(t) {}
    Cell(const char* t) : kind_(Kind::kText), text_(t) {}
    static Cell exact(double v) { return Cell(Kind::kExactDouble, v); }
    static Cell exact(float v) { return Cell(Kind::kExactFloat, v); }

    /// Writes the cell's text into out (at least kMaxNumberChars for a
    /// number); returns its end, or its text for a text cell.
    std::string_view print(char* out) const noexcept;
    static constexpr std::size_t kMaxNumberChars = 64;

   private:
    enum class Kind { kNumber, kWhole, kExactDouble, kExactFloat, kText };
    Cell(Kind kind, double v) : kind_(kind), number_(v) {}
    Kind kind_;
    double number_ = 0.0;
    long long whole_ = 0;
    std::string_view text_;
  };
  /// Appends one row. Throws InputError "PATH: write failed: REASON".
  void row(std::span<const Cell> cells);
  void row(std::initializer_list<Cell> cells) { row(std::span(cells.begin(), cells.size())); }
  /// Appends one row and never throws (a step listener's, in a real-time
  /// tick): false when the write failed, which close() then reports.
  bool try_row(std::initializer_list<Cell> cells) noexcept;
  /// Flushes and closes; throws InputError "PATH: write failed: REASON"
  /// when this or any try_row() failed.
  void close();
  const std::filesystem::path& path() const { return path_; }

 private:
  bool put_row(std::span<const Cell> cells) noexcept;
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  int failed_errno_ = 0;  // the first failed try_row's errno, 0: none failed
};

/// Writes contact.csv row by row (a CsvFile).
class ContactCsvWriter {
 public:
  /// Creates (replaces) the file and writes the header. Throws InputError
  /// "PATH: cannot create: REASON".
  explicit ContactCsvWriter(std::filesystem::path path);
  ~ContactCsvWriter();
  ContactCsvWriter(const ContactCsvWriter&) = delete;
  ContactCsvWriter& operator=(const ContactCsvWriter&) = delete;

  /// One row; cells_visited: cells examined by the step's contact query and cut.
  /// Throws InputError "PATH: write failed: REASON".
  void row(const StepRecord& r, const std::string& cut_name, std::int64_t cells_visited);
  /// Flushes and closes. Throws InputError "PATH: write failed: REASON".
  void close() { file_.close(); }

 private:
  CsvFile file_;
};

}  // namespace terracut::io
