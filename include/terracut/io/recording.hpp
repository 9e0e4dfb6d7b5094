// contact.csv: the per-step record of a batch run (`terracut run`), one row
// per step:
//
//   t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,
//   max_depth,cells_visited
//
// SI units (docs/scenario-format.md); numbers printed with %.9g, so the text
// is the same on every run of the same scenario.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <string>

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

/// A CSV file written row by row through a large stdio buffer: the header
/// at creation, then rows of numbers printed with %.9g (and text cells), so
/// the text is the same on every run of the same scenario. Every error names
/// the file ("PATH: cannot create: REASON", "PATH: write failed: REASON",
/// InputError).
class CsvFile {
 public:
  CsvFile(std::filesystem::path path, const std::string& header);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;

  /// One cell of a row: a number (%.9g) or a text (as is: no quoting, so
  /// the caller gives text without commas, as cut names are).
  struct Cell {
    Cell(double v) : number(v) {}
    Cell(const std::string& t) : text(&t) {}
    double number = 0.0;
    const std::string* text = nullptr;
  };
  /// Appends one row.
  void row(std::initializer_list<Cell> cells);
  /// Flushes and closes.
  void close();
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
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
