// Loading a scenario with all its sections. See scenario.hpp.
#include "terracut/session/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>

#include "terracut/bullet/bodies_yaml.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/settings_yaml.hpp"
#include "terracut/io/image.hpp"
#include "terracut/io/scenario_ranges.hpp"
#include "terracut/net/emulator.hpp"

namespace terracut::session {

namespace {

// A buried body must be under the soil of the initial terrain, which is
// known only once the whole file is read: checked here, the error pointing
// at the body's `buried:` line.
void check_buried(const Scenario& sc, const std::vector<std::string>& where) {
  const auto buried = [](const BodySpec& b) { return b.buried; };
  if (std::none_of(sc.bodies.begin(), sc.bodies.end(), buried)) return;
  const GridSpec grid = io::grid_spec(sc.base);
  const std::vector<float> heights = io::build_initial_heights(sc.base);
  for (std::size_t i = 0; i < sc.bodies.size(); ++i) {
    if (!sc.bodies[i].buried) continue;
    // Soil that flows would have to flow around a held body and over it:
    // not modelled (docs/bullet.md, "Buried bodies").
    if (sc.base.soil.model == SoilModel::kFlow)
      throw InputError(where[i] + ": a buried body needs soil.model vanish (flowing soil around a "
                                  "held body is not modelled)");
    std::string problem = buried_problem(sc.bodies[i], grid, heights.data());
    if (!problem.empty())
      throw InputError(where[i] + ": " + problem.substr(std::string_view("buried: ").size()));
  }
}

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
  check_buried(out, bodies.buried_where);
  return out;
}

// The gathered table: its paths are owned here (a deque keeps them in place).
struct RangeTable {
  std::deque<std::string> paths;
  std::vector<Range> entries;

  // The entries of a struct's table under prefix. Angles, radians in the
  // structs ("_rad"), are degrees in the file ("_deg").
  void add(std::string_view prefix, std::span<const Range> table) {
    for (Range r : table) {
      std::string path = std::string(prefix) + std::string(r.path);
      if (path.ends_with("_rad")) {
        path.replace(path.size() - 4, 4, "_deg");
        // Degrees as written (90, not 90.00000000000001); the struct's check,
        // in radians, keeps the ends open or closed as declared.
        const auto degrees = [](double rad) { return std::round(rad * 180.0 / std::numbers::pi * 1e9) / 1e9; };
        r.lo = degrees(r.lo);
        r.hi = degrees(r.hi);
      }
      r.path = paths.emplace_back(std::move(path));
      entries.push_back(r);
    }
  }
};

}  // namespace

std::span<const Range> scenario_ranges() {
  static const RangeTable table = [] {
    RangeTable t;
    t.add("", io::scenario_ranges());
    t.add("soil.", material_ranges());
    t.add("haptics.", haptics::haptic_settings_ranges());
    t.add("haptics.forces.", force_ranges());
    t.add("haptics.safety.", safety_ranges());
    t.add("bodies[].", body_ranges());
    t.add("mmt.", mmt_ranges());
    t.add("mmt.link.", net::link_ranges());
    return t;
  }();
  return table.entries;
}

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
