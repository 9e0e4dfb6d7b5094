// The `bodies:` list of a scenario file -> validated BodySpec list.
// Written with the section-reader toolkit (yaml_reader.hpp) alone, so that it
// refuses what the scenario reader refuses, with the same messages.
#include "terracut/bullet/bodies_yaml.hpp"

#include <string_view>

#include "terracut/io/yaml_reader.hpp"

namespace terracut::bullet {

namespace yaml = io::yaml;
namespace {

// Fields that belong to each shape; any other dimension field is refused.
bool field_belongs(BodyShape shape, std::string_view key) {
  if (key == "size_m") return shape == BodyShape::kBox;
  if (key == "radius_m") return shape == BodyShape::kSphere || shape == BodyShape::kCylinder;
  if (key == "height_m") return shape == BodyShape::kCylinder;
  return true;
}

BodySpec parse_body(const yaml::Field& field, std::size_t index, std::string& buried_where) {
  const yaml::Map map(field, {"name", "shape", "size_m", "radius_m", "height_m", "mass_kg",
                              "position_m", "rotation_deg", "friction", "restitution", "buried"});
  BodySpec spec;
  spec.name = "body" + std::to_string(index);
  map.read_text("name", spec.name);

  const yaml::Field shape = map.require("shape");
  spec.shape = shape.choice({BodyShape::kBox, BodyShape::kSphere, BodyShape::kCylinder}, "shape");
  for (std::string_view key : {"size_m", "radius_m", "height_m"})
    if (map.has(key) && !field_belongs(spec.shape, key))
      map.get(key)->fail("'" + std::string(key) + "' does not apply to a " + shape.text());

  switch (spec.shape) {
    case BodyShape::kBox:
      spec.size_m = map.require("size_m").vec3();
      break;
    case BodyShape::kSphere:
      spec.radius_m = map.require("radius_m").number();
      break;
    case BodyShape::kCylinder:
      spec.radius_m = map.require("radius_m").number();
      spec.height_m = map.require("height_m").number();
      break;
  }
  spec.mass_kg = map.require("mass_kg").number();
  spec.position_m = map.require("position_m").vec3();
  map.read_vec3("rotation_deg", spec.rotation_deg);
  map.read_number("friction", spec.friction);
  map.read_number("restitution", spec.restitution);
  if (map.read_boolean("buried", spec.buried) && spec.buried)
    buried_where = field.context().where(map.get("buried")->mark()) + ": " + field.path() + ".buried";

  // Range checks, reported against the field they concern: validate's
  // messages start with the field ("size_m[1] must be ...").
  if (const std::string problem = validate(spec); !problem.empty()) {
    const yaml::Problem p = yaml::split_problem(problem);
    field.fail_at(p.path, p.what);
  }
  return spec;
}

}  // namespace

std::vector<BodySpec> parse_bodies(const YAML::Node& node, const std::string& file,
                                   std::vector<std::string>* buried_where) {
  if (buried_where) buried_where->clear();
  if (node.IsNull()) return {};  // "bodies:" with nothing under it: no bodies
  const yaml::Field list(yaml::Context(file), node, "bodies", node.Mark());
  if (!list.is_sequence()) list.fail("expected a list of bodies, got " + yaml::describe(node));

  std::vector<BodySpec> bodies;
  std::vector<yaml::Field> names;  // where each body's name is given (or the body itself)
  const std::vector<yaml::Field> items = list.elements();
  for (std::size_t i = 0; i < items.size(); ++i) {
    std::string where;
    BodySpec spec = parse_body(items[i], i, where);
    if (buried_where) buried_where->push_back(std::move(where));
    const yaml::Field name = items[i].lookup("name").value_or(items[i]);
    for (std::size_t j = 0; j < bodies.size(); ++j)
      if (bodies[j].name == spec.name)
        name.context().fail(name.mark(), items[i].path() + ".name",
                            "duplicate body name '" + spec.name + "' (first used by bodies[" +
                                std::to_string(j) + "] at line " +
                                std::to_string(names[j].mark().line + 1) + ")");
    names.push_back(name);
    bodies.push_back(std::move(spec));
  }
  return bodies;
}

}  // namespace terracut::bullet
