// Loading a scenario with all its sections. See scenario.hpp.
#include "terracut/session/scenario.hpp"

#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

namespace terracut::session {

Scenario load_scenario(const std::filesystem::path& path) {
  Scenario out;
  out.base = io::load_scenario(path);
  out.haptics = out.base.haptics.value_or(HapticSettings{});
  out.bodies = out.base.bodies;
  return out;
}

Scenario heightmap_scenario(const std::filesystem::path& png, double extent_m,
                            double full_scale_m) {
  if (!(extent_m > 0.0) || !(full_scale_m > 0.0))
    throw InputError("--extent and --full-scale must be > 0");
  Scenario out;
  io::Scenario& sc = out.base;
  sc.source_path = png;
  sc.name = png.stem().string();
  sc.image_path = png;
  sc.image = io::read_png(png);
  sc.resolution = {sc.image.cols, sc.image.rows};
  sc.size_x_m = extent_m;
  sc.size_z_m = extent_m;
  sc.full_scale_m = full_scale_m;
  sc.blade.length_m = 0.5 * extent_m;
  return out;
}

}  // namespace terracut::session
