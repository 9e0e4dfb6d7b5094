// The DEM section of `terracut validate`: terracut run on every bulldozing
// case of the DEM reference (validation/dem/results), with the material the
// DEM's own tests give, compared window by window against the targets of
// validation/dem.hpp; CSV files under DIR/dem and a Markdown section.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace terracut::cli {

struct DemSection {
  bool ran = false;          ///< false: no DEM results were found (the section says so)
  int runs = 0;              ///< DEM runs compared
  int targets = 0, met = 0;  ///< targets checked and met
  std::string markdown;      ///< the report's section
};

/// Runs the section: reads results_dir (material.json, bulldoze/), writes
/// out_dir/dem/{material.json, windows.csv, cases.csv, force.csv,
/// profiles.csv}. say: progress lines. Throws InputError naming a bad file.
DemSection run_dem_section(const std::filesystem::path& results_dir,
                           const std::filesystem::path& out_dir,
                           const std::function<void(const std::string&)>& say);

}  // namespace terracut::cli
