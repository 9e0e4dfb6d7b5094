// The `bodies:` list of a scenario file: rigid bodies resting on the terrain.
//
//   bodies:
//     - name: block_a              # optional, default "body<i>"; letters, digits, _ - .
//       shape: box                 # box | sphere | cylinder (required)
//       size_m: [0.3, 0.2, 0.3]    # box: FULL edge lengths along local X, Y, Z (required for box)
//       radius_m: 0.1              # sphere, cylinder (required for them)
//       height_m: 0.2              # cylinder: full height along its local Y (required)
//       mass_kg: 20                # required, >= 0; 0 = static
//       position_m: [1.0, 0.4, 0.6]  # centre, world metres (required)
//       rotation_deg: [0, 30, 0]   # optional, extrinsic X-Y-Z degrees like keyframes
//       friction: 0.6              # optional, [0, 10]
//       restitution: 0.0           # optional, [0, 1]
//       buried: false              # optional: covered by the soil, held until the blade reaches it
//
// A field that does not belong to the shape (radius_m on a box, size_m on a
// sphere) is refused, as are unknown keys and repeated names.
#pragma once

#include <string>
#include <vector>

#include "terracut/core/bodies.hpp"
#include "terracut/io/scenario.hpp"

namespace YAML {
class Node;
}

namespace terracut::bullet {

/// Parses the value of a scenario's `bodies:` key (a list of mappings, may be
/// empty). `file` names the scenario in error messages. Every error is a
/// terracut::InputError reading "FILE:LINE: bodies[i].field: what is wrong"
/// (LINE 1-based). The returned list passes terracut::validate(bodies).
/// buried_where, when given, gets per body "FILE:LINE: bodies[i].buried" for
/// a buried one (empty for the others): whether the soil covers it is
/// checked once the terrain is known (session::load_scenario), and the
/// error points there.
std::vector<BodySpec> parse_bodies(const YAML::Node& node, const std::string& file,
                                   std::vector<std::string>* buried_where = nullptr);

/// The `bodies:` section's reader for io::load_scenario: after the load,
/// bodies holds the section's list (parse_bodies), empty when the file has
/// none. Needs no Bullet (terracut::bodies), so a build without Bullet can
/// still read a scenario and say why its bodies cannot be simulated.
class BodiesReader final : public io::SectionReader {
 public:
  std::string_view key() const override { return "bodies"; }
  void read(const YAML::Node& value, const std::string& file) override {
    bodies = parse_bodies(value, file, &buried_where);
  }
  std::vector<BodySpec> bodies;
  std::vector<std::string> buried_where;  ///< parse_bodies' buried_where
};

}  // namespace terracut::bullet
