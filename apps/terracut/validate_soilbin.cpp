// The soil-bin section of `terracut validate`. See validate_soilbin.hpp and
// docs/validation.md, "Against soil-bin measurements".
#include "validate_soilbin.hpp"

#include <fstream>
#include <sstream>

#include "report_files.hpp"
#include "terracut/core/error.hpp"
#include "terracut/validation/soilbin.hpp"

namespace terracut::cli {

namespace fs = std::filesystem;
using namespace terracut::validation;

SoilBinSection run_soilbin_section(const fs::path& data_dir, const fs::path& out_dir,
                                   const std::function<void(const std::string&)>& say) {
  SoilBinSection section;
  std::ostringstream md;
  md << "## Against soil-bin measurements\n\n";
  const std::vector<SoilBinSet> sets = read_soilbin_sets(data_dir);
  std::vector<const SoilBinSet*> with_forces;
  std::string without;
  for (const SoilBinSet& s : sets) {
    if (!s.points.empty()) with_forces.push_back(&s);
    else without += (without.empty() ? "`" : ", `") + s.name + "`";
  }
  if (!without.empty())
    md << "Data sets whose soil is stored but whose forces are not (" << data_dir.string()
       << "/README.md says why): " << without << ".\n\n";
  if (with_forces.empty()) {
    md << "No published soil-bin data set with forces is stored in `" << data_dir.string()
       << "`: nothing is compared.\n";
    section.markdown = md.str();
    return section;
  }
  const fs::path dir = out_dir / "soilbin";
  create_output_folder(dir);
  std::ofstream points(dir / "points.csv");
  if (!points) throw InputError((dir / "points.csv").string() + ": cannot be written");
  points << "set,point_id,blade_width_m,rake_angle_deg,depth_m,speed_m_per_s,measured_horizontal_n,"
            "terracut_horizontal_n,error,measured_vertical_n,terracut_vertical_n\n";
  md << "Each point predicted by terracut from its data set's published soil properties alone (no fitting), "
        "the blade pushed 0.3 m through a flat layer with the cut soil leaving it (a soil bin's steady "
        "draft), the mean over the last 0.1 m. Targets: the mean absolute relative error of the horizontal "
        "force at most " << fmt("%.0f", 100 * kSoilBinMareTarget) << " %, every point within a factor "
     << fmt("%.1f", kSoilBinFactorTarget) << ".\n\n";
  for (const SoilBinSet* s : with_forces) {
    const SoilBinComparison c = compare_soilbin(*s);
    ++section.sets;
    section.targets += 2;
    section.met += int(c.mare_met) + int(c.factor_met);
    say("soil bin " + s->name + ": " + std::to_string(s->points.size()) + " points, mean |error| " +
        fmt("%.1f", 100 * c.mare) + " %, worst factor " + fmt("%.2f", c.worst_factor));
    md << "### " << s->name << "\n\n" << s->citation << (s->how_read.empty() ? "" : " (" + s->how_read + ")")
       << "\n\n| point | width (m) | rake (deg) | depth (m) | speed (m/s) | measured (N) | terracut (N) | error |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (std::size_t i = 0; i < s->points.size(); ++i) {
      const SoilBinPoint& p = s->points[i];
      md << "| " << p.id << " | " << fmt("%.3f", p.blade_width_m) << " | " << fmt("%.0f", p.rake_deg) << " | "
         << fmt("%.3f", p.depth_m) << " | " << fmt("%.2f", p.speed_m_per_s) << " | " << fmt("%.1f", p.horizontal_n)
         << " | " << fmt("%.1f", c.predicted[i].horizontal_n) << " | " << fmt("%+.0f %%", 100 * c.error[i]) << " |\n";
      points << s->name << "," << p.id << "," << p.blade_width_m << "," << p.rake_deg << "," << p.depth_m << ","
             << p.speed_m_per_s << "," << p.horizontal_n << "," << c.predicted[i].horizontal_n << "," << c.error[i]
             << "," << (p.vertical_n ? std::to_string(*p.vertical_n) : std::string()) << ","
             << c.predicted[i].vertical_n << "\n";
    }
    md << "\nMean absolute relative error " << fmt("%.1f", 100 * c.mare) << " % ("
       << (c.mare_met ? "met" : "**missed**") << "), worst factor " << fmt("%.2f", c.worst_factor) << " ("
       << (c.factor_met ? "met" : "**missed**") << ").\n\n";
  }
  section.markdown = md.str();
  return section;
}

}  // namespace terracut::cli
