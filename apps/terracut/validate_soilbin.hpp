// The soil-bin section of `terracut validate`: terracut's force against
// published soil-bin measurements (data/soilbin), each point predicted from
// its data set's published soil properties (validation/soilbin.hpp).
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace terracut::cli {

struct SoilBinSection {
  int sets = 0;              ///< data sets with forces compared
  int targets = 0, met = 0;  ///< targets checked and met
  std::string markdown;      ///< the report's section
};

/// Reads data_dir's data sets, writes out_dir/soilbin/points.csv (one row per
/// point: set, point_id, the point, measured and predicted forces, error)
/// and returns the section. Throws InputError naming a bad file.
SoilBinSection run_soilbin_section(const std::filesystem::path& data_dir, const std::filesystem::path& out_dir,
                                   const std::function<void(const std::string&)>& say);

}  // namespace terracut::cli
