// `terracut heightmap`: a built-in terrain written as a 16-bit PNG.
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/generators.hpp"
#include "terracut/io/image.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::cli {
namespace {

void require_finite(const std::vector<double>& values, const std::string& option) {
  for (double v : values)
    if (!std::isfinite(v)) throw InputError(option + ": values must be finite numbers");
}

}  // namespace

Command add_heightmap_command(CLI::App& app) {
  struct Options {
    std::string generator;
    std::string resolution;
    std::string out;
    std::vector<double> size{1.0, 1.0};
    std::vector<double> origin{0.0, 0.0, 0.0};
    double full_scale = 1.0;
    double height = std::nan("");
    std::vector<double> centre;
    double radius = std::nan("");
    std::vector<double> box_min;
    std::vector<double> box_max;
    bool quiet = false;
  };
  auto opt = std::make_shared<Options>();

  CLI::App* sub = app.add_subcommand(
      "heightmap",
      "Write a built-in terrain (mound, box or plane) as a 16-bit grey PNG, sampled at the\n"
      "cell centres of a grid. Pixel value = height / full scale (clamped to [0, 1]).");
  sub->add_option("generator", opt->generator,
                  "Terrain shape: 'mound' (dome h = H*sqrt(1-(r/R)^2) for r < R, whose horizontal\n"
                  "sections are circles), 'box' (height H inside a rectangle, 0 outside; a sample\n"
                  "is inside when its cell centre is) or 'plane' (height H everywhere)")
      ->required()
      ->check(CLI::IsMember({"mound", "box", "plane"}))
      ->type_name("GENERATOR");
  sub->add_option("--resolution", opt->resolution,
                  "Image size: N for N x N pixels, or COLSxROWS (cols along X, rows along Z),\n"
                  "each side in [1, 65536]")
      ->required()
      ->type_name("N|COLSxROWS");
  sub->add_option("--out,-o", opt->out, "PNG file to write")->required()->type_name("FILE.png");
  sub->add_option("--size", opt->size,
                  "Extent of the terrain along X and Z, metres, each > 0 (default 1,1)")
      ->expected(2)
      ->delimiter(',')
      ->type_name("X,Z");
  sub->add_option("--origin", opt->origin,
                  "World position of the terrain's origin corner, metres (default 0,0,0). The\n"
                  "shape parameters below are world coordinates")
      ->expected(3)
      ->delimiter(',')
      ->type_name("X,Y,Z");
  sub->add_option("--full-scale", opt->full_scale,
                  "Height of a white pixel, metres, > 0 (default 1). Heights above it are clipped")
      ->type_name("METRES");
  sub->add_option("--height", opt->height,
                  "Mound peak, box top or plane height, metres, > 0 for a mound, >= 0 otherwise\n"
                  "(default: the full scale, so the highest point is white)")
      ->type_name("METRES");
  sub->add_option("--centre", opt->centre,
                  "Mound only: world X,Z of the dome's axis, metres (default: the middle of the\n"
                  "extent)")
      ->expected(2)
      ->delimiter(',')
      ->type_name("X,Z");
  sub->add_option("--radius", opt->radius,
                  "Mound only: footprint radius, metres, > 0 (default 0.4 * min(size))")
      ->type_name("METRES");
  sub->add_option("--box-min", opt->box_min,
                  "Box only: world X,Z of the low corner, metres (default: the origin corner)")
      ->expected(2)
      ->delimiter(',')
      ->type_name("X,Z");
  sub->add_option("--box-max", opt->box_max,
                  "Box only: world X,Z of the high corner, metres (default: the far corner)")
      ->expected(2)
      ->delimiter(',')
      ->type_name("X,Z");
  sub->add_flag("--quiet,-q", opt->quiet, "Print nothing on success");
  sub->footer(
      "Example (the mound image of the paper's experiment 1, data/mound.png):\n"
      "  terracut heightmap mound --resolution 256 --size 1,1 --full-scale 0.2 \\\n"
      "      --out data/mound.png\n"
      "A scenario can use a generator directly instead of an image (terrain.generator).");

  return [opt, sub]() {
    const io::Resolution res = io::parse_resolution(opt->resolution);
    require_finite(opt->size, "--size");
    require_finite(opt->origin, "--origin");
    if (!(opt->size[0] > 0.0) || !(opt->size[1] > 0.0))
      throw InputError("--size: both extents must be > 0");
    if (!std::isfinite(opt->full_scale) || !(opt->full_scale > 0.0))
      throw InputError("--full-scale: " + must_be("a finite number > 0", opt->full_scale));

    GridSpec spec;
    spec.cols = res.cols;
    spec.rows = res.rows;
    spec.size_x_m = opt->size[0];
    spec.size_z_m = opt->size[1];
    spec.origin_m = {opt->origin[0], opt->origin[1], opt->origin[2]};
    spec.full_scale_m = opt->full_scale;

    const GeneratorKind kind = *parse_enum<GeneratorKind>(opt->generator);
    Generator gen = default_generator(kind, spec);

    // Shape options apply to one generator each.
    auto only_for = [&](const char* option, GeneratorKind wanted) {
      if (sub->count(option) > 0 && kind != wanted)
        throw InputError(std::string(option) + ": only valid for the " +
                         std::string(to_string(wanted)) + " generator");
    };
    only_for("--centre", GeneratorKind::kMound);
    only_for("--radius", GeneratorKind::kMound);
    only_for("--box-min", GeneratorKind::kBox);
    only_for("--box-max", GeneratorKind::kBox);

    if (sub->count("--height") > 0) {
      if (!std::isfinite(opt->height)) throw InputError("--height: must be a finite number");
      gen.mound.height_m = gen.box.height_m = gen.plane.height_m = opt->height;
    }
    if (!opt->centre.empty()) {
      require_finite(opt->centre, "--centre");
      gen.mound.centre_x_m = opt->centre[0];
      gen.mound.centre_z_m = opt->centre[1];
    }
    if (sub->count("--radius") > 0) gen.mound.radius_m = opt->radius;
    if (!opt->box_min.empty()) {
      require_finite(opt->box_min, "--box-min");
      gen.box.min_x_m = opt->box_min[0];
      gen.box.min_z_m = opt->box_min[1];
    }
    if (!opt->box_max.empty()) {
      require_finite(opt->box_max, "--box-max");
      gen.box.max_x_m = opt->box_max[0];
      gen.box.max_z_m = opt->box_max[1];
    }
    const std::string problem = validate(gen);
    if (!problem.empty()) throw InputError("heightmap " + opt->generator + ": " + problem);

    const std::vector<float> heights = generate_heights(spec, gen);
    io::write_png16(opt->out, heights.data(), spec.cols, spec.rows, spec.full_scale_m);
    if (!opt->quiet)
      std::cout << "wrote " << opt->out << " (" << spec.cols << "x" << spec.rows
                << ", 16-bit grey, pixel = height / " << spec.full_scale_m << " m)\n";
    return kExitOk;
  };
}

}  // namespace terracut::cli
