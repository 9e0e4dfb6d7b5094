// The `bodies:` list of a scenario file -> validated BodySpec list.
#include "terracut/io/bodies_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string_view>

#include "terracut/core/error.hpp"
#include "yaml_util.hpp"

namespace terracut::io {
namespace {

using detail::describe;
using detail::mark_or;

// Reports errors as "FILE:LINE: PATH: what", the line taken from the value's
// own mark or, when it has none, the nearest enclosing one.
class Reporter {
 public:
  explicit Reporter(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& path,
                         const std::string& what) const {
    std::string where = file_;
    if (!mark.is_null() && mark.line >= 0) where += ":" + std::to_string(mark.line + 1);
    throw InputError(where + ": " + path + ": " + what);
  }

 private:
  std::string file_;
};

// One body mapping: its keys (each checked against the allowed set, no
// repeats), with typed getters that name the field on error.
class BodyMap {
 public:
  BodyMap(const Reporter& rep, const YAML::Node& node, std::string path, YAML::Mark mark)
      : rep_(rep), path_(std::move(path)), mark_(mark) {
    if (!node.IsMap())
      rep_.fail(mark_, path_, "expected a mapping with keys " + allowed_list() + ", got " +
                                  describe(node));
    for (const auto& kv : node) {
      const YAML::Mark key_mark = mark_or(kv.first, mark_);
      if (!kv.first.IsScalar())
        rep_.fail(key_mark, path_, "keys must be plain names, got " + describe(kv.first));
      const std::string key = kv.first.Scalar();
      if (std::find(kAllowed.begin(), kAllowed.end(), key) == kAllowed.end())
        rep_.fail(key_mark, path_ + "." + key,
                  "unknown key '" + key + "'; allowed keys here: " + allowed_list());
      for (const Entry& e : entries_)
        if (e.key == key)
          rep_.fail(key_mark, path_ + "." + key,
                    "key given twice (first at line " + std::to_string(e.mark.line + 1) + ")");
      entries_.push_back({key, key_mark, kv.second});
    }
  }

  const YAML::Mark& mark() const { return mark_; }
  bool has(std::string_view key) const { return find(key) != nullptr; }

  // The mark of key's value (or of the key), for errors found after parsing.
  YAML::Mark mark_of(std::string_view key) const {
    const Entry* e = find(key);
    return e ? mark_or(e->value, e->mark) : mark_;
  }
  std::string path_of(std::string_view key) const { return path_ + "." + std::string(key); }

  [[noreturn]] void fail(std::string_view key, const std::string& what) const {
    rep_.fail(mark_of(key), path_of(key), what);
  }
  // As fail, with a sub-path under the body such as "size_m[1]".
  [[noreturn]] void fail_at(std::string_view key, const std::string& sub_path,
                            const std::string& what) const {
    rep_.fail(mark_of(key), path_ + "." + sub_path, what);
  }

  // The value of a present key; a key with no value is an error.
  const YAML::Node& value(std::string_view key) const {
    const Entry* e = find(key);
    if (!e)
      rep_.fail(mark_, path_of(key), "missing required field '" + std::string(key) + "' in '" +
                                         path_ + "'");
    if (e->value.IsNull()) rep_.fail(e->mark, path_of(key), "no value given");
    return e->value;
  }

  std::string text(std::string_view key) const {
    const YAML::Node& v = value(key);
    if (!v.IsScalar()) fail(key, "expected a text value, got " + describe(v));
    return v.Scalar();
  }

  double number(std::string_view key) const { return number_of(value(key), key, path_of(key)); }

  std::vector<double> numbers(std::string_view key, std::size_t n) const {
    const YAML::Node& v = value(key);
    const std::string want = "expected a list of " + std::to_string(n) + " numbers, got ";
    if (!v.IsSequence()) fail(key, want + describe(v));
    if (v.size() != n) fail(key, want + "a list of " + std::to_string(v.size()));
    std::vector<double> out;
    for (std::size_t i = 0; i < n; ++i)
      out.push_back(number_of(v[i], key, path_of(key) + "[" + std::to_string(i) + "]"));
    return out;
  }

  Vec3 vec3(std::string_view key) const {
    const std::vector<double> v = numbers(key, 3);
    return {v[0], v[1], v[2]};
  }

 private:
  struct Entry {
    std::string key;
    YAML::Mark mark;
    YAML::Node value;
  };
  static constexpr std::array<std::string_view, 10> kAllowed = {
      "name",     "shape",      "size_m",       "radius_m", "height_m",
      "mass_kg", "position_m", "rotation_deg", "friction", "restitution"};

  const Entry* find(std::string_view key) const {
    for (const Entry& e : entries_)
      if (e.key == key) return &e;
    return nullptr;
  }

  double number_of(const YAML::Node& v, std::string_view key, const std::string& path) const {
    const YAML::Mark m = mark_or(v, mark_of(key));
    if (!v.IsScalar()) rep_.fail(m, path, "expected a number, got " + describe(v));
    double out = 0.0;
    try {
      out = v.as<double>();
    } catch (const YAML::Exception&) {
      rep_.fail(m, path, "expected a number, got " + describe(v));
    }
    if (!std::isfinite(out)) rep_.fail(m, path, "must be a finite number, got " + describe(v));
    return out;
  }

  static std::string allowed_list() {
    std::string out;
    for (std::string_view k : kAllowed) {
      if (!out.empty()) out += ", ";
      out += k;
    }
    return out;
  }

  const Reporter& rep_;
  std::string path_;
  YAML::Mark mark_;
  std::vector<Entry> entries_;
};

// Fields that belong to each shape; any other dimension field is refused.
bool field_belongs(BodyShape shape, std::string_view key) {
  if (key == "size_m") return shape == BodyShape::kBox;
  if (key == "radius_m") return shape == BodyShape::kSphere || shape == BodyShape::kCylinder;
  if (key == "height_m") return shape == BodyShape::kCylinder;
  return true;
}

BodySpec parse_body(const BodyMap& map, std::size_t index) {
  BodySpec spec;
  spec.name = map.has("name") ? map.text("name") : "body" + std::to_string(index);

  const std::string shape_name = map.text("shape");
  const std::optional<BodyShape> shape = parse_body_shape(shape_name);
  if (!shape) map.fail("shape", "unknown shape '" + shape_name + "'; allowed: box, sphere, cylinder");
  spec.shape = *shape;
  for (std::string_view key : {"size_m", "radius_m", "height_m"})
    if (map.has(key) && !field_belongs(spec.shape, key))
      map.fail(key, "'" + std::string(key) + "' does not apply to a " + shape_name);

  switch (spec.shape) {
    case BodyShape::kBox:
      spec.size_m = map.vec3("size_m");
      break;
    case BodyShape::kSphere:
      spec.radius_m = map.number("radius_m");
      break;
    case BodyShape::kCylinder:
      spec.radius_m = map.number("radius_m");
      spec.height_m = map.number("height_m");
      break;
  }
  spec.mass_kg = map.number("mass_kg");
  spec.position_m = map.vec3("position_m");
  if (map.has("rotation_deg")) spec.rotation_deg = map.vec3("rotation_deg");
  if (map.has("friction")) spec.friction = map.number("friction");
  if (map.has("restitution")) spec.restitution = map.number("restitution");

  // Range checks, reported against the field they concern: validate's
  // messages start with the field ("size_m[1] must be ...").
  const std::string problem = validate(spec);
  if (!problem.empty()) {
    const std::size_t space = problem.find(' ');
    const std::string sub_path = problem.substr(0, space);
    const std::string key = sub_path.substr(0, sub_path.find('['));
    const std::string what = space == std::string::npos ? problem : problem.substr(space + 1);
    if (map.has(key)) map.fail_at(key, sub_path, what);
    map.fail("shape", problem);
  }
  return spec;
}

}  // namespace

std::vector<BodySpec> parse_bodies(const YAML::Node& node, const std::string& file) {
  const Reporter rep(file);
  const YAML::Mark list_mark = node.Mark();
  if (node.IsNull()) return {};
  if (!node.IsSequence())
    rep.fail(list_mark, "bodies", "expected a list of bodies, got " + describe(node));

  std::vector<BodySpec> bodies;
  std::vector<YAML::Mark> name_marks;
  std::size_t i = 0;
  for (const auto& item : node) {
    const std::string path = "bodies[" + std::to_string(i) + "]";
    const BodyMap map(rep, item, path, mark_or(item, list_mark));
    BodySpec spec = parse_body(map, i);
    for (std::size_t j = 0; j < bodies.size(); ++j)
      if (bodies[j].name == spec.name)
        rep.fail(map.has("name") ? map.mark_of("name") : map.mark(), path + ".name",
                 "duplicate body name '" + spec.name + "' (first used by bodies[" +
                     std::to_string(j) + "] at line " + std::to_string(name_marks[j].line + 1) +
                     ")");
    name_marks.push_back(map.has("name") ? map.mark_of("name") : map.mark());
    bodies.push_back(std::move(spec));
    ++i;
  }
  return bodies;
}

}  // namespace terracut::io
