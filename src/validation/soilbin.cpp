// terracut against published soil-bin measurements. See soilbin.hpp.
#include "terracut/validation/soilbin.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "terracut/core/earthmoving.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/io/soil_yaml.hpp"
#include "terracut/io/yaml_reader.hpp"

namespace terracut::validation {

namespace fs = std::filesystem;

namespace {

constexpr const char* kHeader =
    "point_id,blade_width_m,rake_angle_deg,depth_m,speed_m_per_s,horizontal_force_n,vertical_force_n,"
    "source_location,reading";

// One CSV line's cells: commas split; a cell that starts with a double
// quote runs to the closing one ("" inside is a quote). Throws InputError
// at where for a quote inside an unquoted cell or an unterminated one.
std::vector<std::string> cells_of(const std::string& line, const std::string& where) {
  std::vector<std::string> out(1);
  bool quoted = false, closed = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
        closed = true;
      } else {
        out.back() += c;
      }
    } else if (c == ',') {
      out.emplace_back();
      closed = false;
    } else if (c == '\r') {
      continue;
    } else if (closed) {
      throw InputError(where + ": text after a quoted cell's closing quote (cell " + std::to_string(out.size()) + ")");
    } else if (c == '"') {
      if (!out.back().empty())
        throw InputError(where + ": a quote inside an unquoted cell (cell " + std::to_string(out.size()) + ")");
      quoted = true;
    } else {
      out.back() += c;
    }
  }
  if (quoted) throw InputError(where + ": unterminated quote (cell " + std::to_string(out.size()) + ")");
  return out;
}

// A number in [lo, hi].
double number_in(const std::string& cell, const std::string& where, const char* column, double lo, double hi) {
  double v = 0.0;
  try {
    std::size_t used = 0;
    v = std::stod(cell, &used);
    if (used != cell.size()) throw std::invalid_argument("");
  } catch (const std::exception&) {
    throw InputError(where + ": " + column + ": '" + cell + "' is not a number");
  }
  if (!(std::isfinite(v) && v >= lo && v <= hi))
    throw InputError(where + ": " + column + ": " + cell + " is outside [" + format_number(lo) + ", " +
                     format_number(hi) + "]");
  return v;
}

std::vector<SoilBinPoint> read_points(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) throw InputError(csv.string() + ": cannot be read");
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != kHeader) throw InputError(csv.string() + ":1: expected the header " + std::string(kHeader));
  std::vector<SoilBinPoint> points;
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty() || line == "\r") continue;
    const std::string where = csv.string() + ":" + std::to_string(row);
    const std::vector<std::string> c = cells_of(line, where);
    if (c.size() != 9) throw InputError(where + ": 9 columns expected, got " + std::to_string(c.size()));
    SoilBinPoint p;
    p.id = c[0];
    if (p.id.empty()) throw InputError(where + ": point_id: empty");
    // Soil-bin blades: millimetres to metres wide and deep, at 1 mm/s to
    // 20 m/s (a prediction steps 0.3 m at 1 kHz: at most 3e5 steps).
    p.blade_width_m = number_in(c[1], where, "blade_width_m", 1e-3, 20.0);
    p.rake_deg = number_in(c[2], where, "rake_angle_deg", 1.0, 179.0);
    p.depth_m = number_in(c[3], where, "depth_m", 1e-3, 5.0);
    p.speed_m_per_s = number_in(c[4], where, "speed_m_per_s", 1e-3, 20.0);
    p.horizontal_n = number_in(c[5], where, "horizontal_force_n", 1e-6, 1e9);
    if (!c[6].empty()) p.vertical_n = number_in(c[6], where, "vertical_force_n", -1e9, 1e9);
    p.source_location = c[7];
    p.reading = c[8];
    if (p.reading.empty()) throw InputError(where + ": reading: say how the value was read (table, digitized figure)");
    points.push_back(p);
  }
  if (points.empty()) throw InputError(csv.string() + ": no points");
  return points;
}

}  // namespace

std::vector<SoilBinSet> read_soilbin_sets(const fs::path& dir) {
  std::vector<SoilBinSet> sets;
  if (!fs::is_directory(dir)) return sets;
  std::vector<fs::path> jsons;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".json") jsons.push_back(e.path());
  std::sort(jsons.begin(), jsons.end());
  for (const fs::path& json : jsons) {
    std::ifstream in(json);
    if (!in) throw InputError(json.string() + ": cannot be read");
    std::stringstream text;
    text << in.rdbuf();
    // JSON is YAML: the scenario's reader reads the material with the
    // scenario's messages (FILE:LINE: terracut_soil.FIELD: what).
    const io::yaml::Context ctx(json.string());
    const YAML::Node root = io::yaml::parse_text(ctx, text.str(), "malformed JSON");
    if (!root.IsMap() || !root["terracut_soil"]) continue;  // a candidate without a material: not a data set
    SoilBinSet set;
    set.name = json.stem().string();
    // The citation as written: a text, or an object shown in flow style.
    const auto text_of = [](const YAML::Node& n) {
      if (n.IsScalar()) return n.as<std::string>();
      YAML::Emitter e;
      e << YAML::Flow << n;
      return std::string(e.c_str());
    };
    if (root["citation"]) set.citation = text_of(root["citation"]);
    if (root["how_read"]) set.how_read = text_of(root["how_read"]);
    const io::yaml::Field soil(ctx, root["terracut_soil"], "terracut_soil", YAML::Mark());
    const io::yaml::Map fields(soil, io::soil_material_keys());
    io::read_soil_material(fields, set.material);
    // The published properties, all of them: a default must not stand in
    // for one (a preset names where the values come from).
    if (!fields.has("preset")) {
      if (!fields.has("density_kg_per_m3") && !fields.has("unit_weight_n_per_m3"))
        soil.fail("give the soil's density_kg_per_m3 or unit_weight_n_per_m3 (or a preset)");
      for (const char* key : {"internal_friction_deg", "cohesion_pa", "soil_tool_friction_deg", "adhesion_pa"})
        if (!fields.has(key)) soil.fail(std::string("give the soil's ") + key + " (0 where it has none), or a preset");
    }
    if (std::string e = validate(set.material); !e.empty())
      throw InputError(json.string() + ": terracut_soil." + e);
    const fs::path csv = fs::path(json).replace_extension(".csv");
    if (fs::exists(csv)) set.points = read_points(csv);
    // Every point's blade must make a failure wedge in this soil.
    for (const SoilBinPoint& p : set.points) {
      EarthmovingParams ep;
      ep.soil = set.material;
      ep.rake_angle_deg = p.rake_deg;
      if (std::string e = validate(ep); !e.empty())
        throw InputError(csv.string() + ": point " + p.id + ": " + e);
    }
    sets.push_back(std::move(set));
  }
  return sets;
}

SoilBinPrediction predict_soilbin(const SoilBinPoint& pt, const SoilMaterial& material) {
  const double cell = std::min(0.01, pt.depth_m / 5.0);
  const double layer = std::max(0.1, 3.0 * pt.depth_m);
  const double travel = 0.3, lead = 0.05;
  SimParams p;
  const int cols = int(std::ceil((pt.blade_width_m + 0.1) / cell));
  const int rows = int(std::ceil((travel + 2.0 * lead) / cell));
  p.grid = grid_of_cells(cols, rows, cell);
  p.grid.full_scale_m = 2.0 * layer;
  p.blade.length_m = pt.blade_width_m;
  p.blade.rake_angle_deg = pt.rake_deg;
  p.soil.model = SoilModel::kVanish;
  p.soil.material = material;
  Simulation sim(p, std::vector<float>(std::size_t(cols) * std::size_t(rows), float(layer)));
  // The edge along X, centred across the grid, pushed along +Z.
  const double x = 0.5 * cols * cell, y = layer - pt.depth_m;
  const std::int64_t steps = std::llround(travel / pt.speed_m_per_s * p.rate_hz);
  double h = 0.0, v = 0.0;
  std::int64_t n = 0;
  for (std::int64_t i = 0; i <= steps; ++i) {
    const double z = lead + travel * double(i) / double(steps);
    const StepOutput& o = sim.step({{x, y, z}, Quat{}});
    if (z - lead >= travel - 0.1) {
      h += -o.force.total_n.z;
      v += -o.force.total_n.y;
      ++n;
    }
  }
  return {h / double(std::max<std::int64_t>(n, 1)), v / double(std::max<std::int64_t>(n, 1))};
}

SoilBinComparison compare_soilbin(const SoilBinSet& set) {
  SoilBinComparison c;
  c.name = set.name;
  double sum = 0.0;
  for (const SoilBinPoint& pt : set.points) {
    SoilBinPrediction pr;
    try {
      pr = predict_soilbin(pt, set.material);
    } catch (const InputError& e) {
      throw InputError(set.name + ": point " + pt.id + ": " + e.what());
    }
    c.predicted.push_back(pr);
    const double e = (pr.horizontal_n - pt.horizontal_n) / pt.horizontal_n;
    c.error.push_back(e);
    sum += std::abs(e);
    const double ratio = pr.horizontal_n / pt.horizontal_n;
    c.worst_factor = std::max(c.worst_factor, ratio > 0.0 ? std::max(ratio, 1.0 / ratio) : INFINITY);
  }
  c.mare = set.points.empty() ? 0.0 : sum / double(set.points.size());
  c.mare_met = !set.points.empty() && c.mare <= kSoilBinMareTarget;
  c.factor_met = !set.points.empty() && c.worst_factor <= kSoilBinFactorTarget;
  return c;
}

}  // namespace terracut::validation
