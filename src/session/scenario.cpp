// Loading a scenario with all its sections. See scenario.hpp.
#include "terracut/session/scenario.hpp"

#include "terracut/bullet/bodies_yaml.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/settings_yaml.hpp"
#include "terracut/io/image.hpp"

namespace terracut::session {

namespace {

// Reads a scenario with each of its sections by the reader of the layer that
// owns it (bodies before haptics: the order in which their errors are found).
template <class Load>
Scenario read_with_sections(Load&& load) {
  bullet::BodiesReader bodies;
  haptics::SettingsReader settings;
  MmtReader mmt;
  io::SectionReader* const sections[] = {&bodies, &settings, &mmt};
  Scenario out;
  out.base = load(std::span<io::SectionReader* const>(sections));
  out.haptics = std::move(settings.settings);
  out.bodies = std::move(bodies.bodies);
  out.mmt = std::move(mmt.settings);
  return out;
}

}  // namespace

Scenario load_scenario(const std::filesystem::path& path) {
  return read_with_sections(
      [&](std::span<io::SectionReader* const> sections) { return io::load_scenario(path, sections); });
}

Scenario parse_scenario(const std::string& text, const std::filesystem::path& source_name) {
  return read_with_sections([&](std::span<io::SectionReader* const> sections) {
    return io::parse_scenario(text, source_name, sections);
  });
}

Scenario heightmap_scenario(const std::filesystem::path& png, double extent_m,
                            double full_scale_m) {
  if (!(extent_m > 0.0)) throw InputError(must_be("--extent", "> 0", extent_m));
  if (!(full_scale_m > 0.0)) throw InputError(must_be("--full-scale", "> 0", full_scale_m));
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
