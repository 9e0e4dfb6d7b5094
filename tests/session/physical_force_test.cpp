// The physical force is one result whatever runs the path: `terracut run`
// (force.csv), `terracut haptics --device script` (haptics.csv's fp_*
// columns, the loop's record), with any device settings: force scale,
// workspace scale, device limits and the low-speed damper change what the
// device is sent, never the physical force. Every cut of a sequence runs in
// both (the script device plays them, lifted between them, as the run does).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "terracut/session/batch.hpp"
#include "terracut/session/haptic.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

const fs::path kScenarios = fs::path(TERRACUT_SOURCE_DIR) / "scenarios";

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("terracut_physical_force_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The numeric columns named of a CSV with a header line (text columns skipped).
std::vector<std::vector<double>> columns(const fs::path& csv, const std::vector<std::string>& names) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) header.push_back(cell);
  }
  std::vector<std::size_t> at;
  for (const std::string& n : names) {
    const auto it = std::find(header.begin(), header.end(), n);
    EXPECT_NE(it, header.end()) << n << " in " << csv;
    at.push_back(std::size_t(it - header.begin()));
  }
  std::vector<std::vector<double>> out(names.size());
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    for (std::size_t k = 0; k < at.size(); ++k) out[k].push_back(std::stod(cells[at[k]]));
  }
  return out;
}

struct Forces {
  std::vector<double> fx, fy, fz;
};

Forces run_forces(const Scenario& sc, const std::string& name) {
  const fs::path dir = fresh_dir(name + "_run");
  RunOptions o;
  o.out_dir = dir;
  run_scenario(sc, o);
  auto c = columns(dir / "force.csv", {"fx", "fy", "fz"});
  return {c[0], c[1], c[2]};
}

Forces haptic_forces(const Scenario& sc, const std::string& name) {
  SessionOptions o;
  o.device = haptics::DeviceKind::kScript;
  HapticSession session(sc, o);
  session.run();
  const fs::path dir = fresh_dir(name + "_haptics");
  session.write_outputs(dir);
  auto c = columns(dir / "haptics.csv", {"fp_x", "fp_y", "fp_z"});
  return {c[0], c[1], c[2]};
}

// Device settings far from the scenario's: a tenth of the force scale, a
// damper that caps everything, another workspace scale, a weaker device.
Scenario with_other_device(Scenario sc) {
  sc.haptics.forces.force_scale *= 0.1;
  sc.haptics.forces.low_speed_damping_n_s_per_m = 5.0;
  sc.haptics.workspace.scale *= 1.7;
  sc.haptics.forces.device.max_force_n = 3.0;
  sc.haptics.safety.max_force_n = 3.0;
  sc.haptics.forces.cutting = CuttingModel::kContactDrag;
  return sc;
}

void expect_same(const Forces& run, const Forces& loop, const std::string& what) {
  ASSERT_GE(loop.fx.size(), run.fx.size()) << what;  // the session settles after the path
  double largest = 0.0;
  for (double f : run.fz) largest = std::max(largest, std::abs(f));
  for (double f : run.fx) largest = std::max(largest, std::abs(f));
  ASSERT_GT(largest, 10.0) << what << ": the path must cut";
  // Float rounding: the device's workspace mapping turns each pose through
  // the device frame and back (a few ulps of metres), so a depth read from
  // float32 heights may differ at 1e-7 relative.
  const double tol = 1e-6 * largest;
  std::size_t worst = 0;
  double worst_d = 0.0;
  for (std::size_t i = 0; i < run.fx.size(); ++i) {
    const double d = std::max({std::abs(run.fx[i] - loop.fx[i]), std::abs(run.fy[i] - loop.fy[i]),
                               std::abs(run.fz[i] - loop.fz[i])});
    if (d > worst_d) {
      worst_d = d;
      worst = i;
    }
  }
  EXPECT_LE(worst_d, tol) << what << ": step " << worst << " run (" << run.fx[worst] << ", "
                          << run.fy[worst] << ", " << run.fz[worst] << ") haptics ("
                          << loop.fx[worst] << ", " << loop.fy[worst] << ", " << loop.fz[worst] << ")";
}

TEST(PhysicalForce, RunAndHapticsGiveTheSameForceWhateverTheDevice) {
  // Soil that flows (a pile, its surcharge) and a sequence of two cuts of a
  // cube with the soil vanishing (every cut of the sequence, lifted between).
  for (const char* file : {"push_pile.yaml", "paper_experiment2.yaml"}) {
    SCOPED_TRACE(file);
    Scenario sc = load_scenario(kScenarios / file);
    const Forces run = run_forces(sc, file);
    expect_same(run, haptic_forces(sc, file), std::string(file) + ", its own device settings");
    expect_same(run, haptic_forces(with_other_device(sc), std::string(file) + "_other"),
                std::string(file) + ", other device settings");
  }
}

}  // namespace
}  // namespace terracut::session
