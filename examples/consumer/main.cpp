// A minimal terracut program: load a heightmap, move a blade through it and
// print the contact length and the volume cut at each 100th step.
#include <cstdio>
#include <exception>

#include <terracut/core/simulation.hpp>
#include <terracut/io/image.hpp>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s HEIGHTMAP.png\n", argv[0]);
    return 2;
  }
  try {
    // The image becomes a 1 m x 1 m terrain, 64 x 64 samples, white = 0.2 m.
    terracut::io::Image image = terracut::io::resample(terracut::io::read_png(argv[1]), 64, 64);
    terracut::SimParams params;
    params.grid.cols = image.cols;
    params.grid.rows = image.rows;
    params.grid.full_scale_m = 0.2;
    params.blade.length_m = 1.2;
    std::vector<float> heights(image.values.size());
    for (size_t i = 0; i < heights.size(); ++i) heights[i] = float(image.values[i] * 0.2);
    terracut::Simulation sim(params, heights);

    // A horizontal blade at y = 0.1 m moving along +Z over 1 s at 1 kHz.
    for (int i = 0; i <= 1000; ++i) {
      terracut::BladePose pose{{0.5, 0.1, -0.1 + 1.2 * i / 1000.0}, terracut::Quat{}};
      const terracut::StepOutput& out = sim.step(pose);
      if (i % 100 == 0) {
        std::printf("t=%.3f s  z=%.3f m  contact=%.4f m  cut=%.3g m^3\n", out.t_s, pose.position_m.z,
                    out.contact.length_m, sim.removed_volume_m3());
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
