// BodySpec validation (core) and the `bodies:` list parser (io).
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <cmath>

#include "terracut/core/bodies.hpp"
#include "terracut/core/error.hpp"
#include "terracut/bullet/bodies_yaml.hpp"

namespace terracut {
namespace {

std::vector<BodySpec> parse(const std::string& text) {
  const YAML::Node root = YAML::Load(text);
  return bullet::parse_bodies(root["bodies"], "scene.yaml");
}

// The message of the InputError that parsing text throws ("" if none).
std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(BodySpec, ValidatesEveryField) {
  BodySpec b;
  EXPECT_EQ(validate(b), "");
  BodySpec bad = b;
  bad.size_m.y = 0.0;
  EXPECT_EQ(validate(bad).rfind("size_m[1] ", 0), 0u) << validate(bad);
  bad = b;
  bad.shape = BodyShape::kSphere;
  bad.radius_m = -1.0;
  EXPECT_EQ(validate(bad).rfind("radius_m ", 0), 0u);
  bad = b;
  bad.shape = BodyShape::kCylinder;
  bad.height_m = NAN;
  EXPECT_EQ(validate(bad).rfind("height_m ", 0), 0u);
  bad = b;
  bad.mass_kg = -2.0;
  EXPECT_EQ(validate(bad).rfind("mass_kg ", 0), 0u);
  bad = b;
  bad.friction = 11.0;
  EXPECT_EQ(validate(bad).rfind("friction ", 0), 0u);
  bad = b;
  bad.restitution = 1.5;
  EXPECT_EQ(validate(bad).rfind("restitution ", 0), 0u);
  bad = b;
  bad.name = "has space";
  EXPECT_EQ(validate(bad).rfind("name ", 0), 0u);
  bad = b;
  bad.position_m.x = INFINITY;
  EXPECT_EQ(validate(bad).rfind("position_m ", 0), 0u);

  BodySpec other = b;
  EXPECT_NE(validate(std::vector<BodySpec>{b, other}).find("bodies[1] (body): duplicate name"),
            std::string::npos);
}

TEST(BodySpec, HalfExtentsPerShape) {
  BodySpec b;
  b.size_m = {0.2, 0.4, 0.6};
  const Vec3 h = half_extents_m(b);
  EXPECT_DOUBLE_EQ(h.x, 0.1);
  EXPECT_DOUBLE_EQ(h.y, 0.2);
  EXPECT_DOUBLE_EQ(h.z, 0.3);
  b.shape = BodyShape::kCylinder;
  b.radius_m = 0.05;
  b.height_m = 0.3;
  EXPECT_DOUBLE_EQ(half_extents_m(b).y, 0.15);
  EXPECT_DOUBLE_EQ(half_extents_m(b).x, 0.05);
}

TEST(ParseBodies, ReadsEveryShapeAndDefault) {
  const std::vector<BodySpec> bodies = parse(R"(
bodies:
  - name: slab
    shape: box
    size_m: [0.3, 0.15, 0.2]
    mass_kg: 20
    position_m: [0.5, 0.4, 0.6]
    rotation_deg: [0, 30, 0]
    friction: 0.7
    restitution: 0.1
  - shape: sphere
    radius_m: 0.08
    mass_kg: 5
    position_m: [1, 0.4, 1]
  - name: post
    shape: cylinder
    radius_m: 0.05
    height_m: 0.2
    mass_kg: 0
    position_m: [1.5, 0.4, 0.5]
)");
  ASSERT_EQ(bodies.size(), 3u);
  EXPECT_EQ(bodies[0].name, "slab");
  EXPECT_EQ(bodies[0].shape, BodyShape::kBox);
  EXPECT_DOUBLE_EQ(bodies[0].size_m.z, 0.2);
  EXPECT_DOUBLE_EQ(bodies[0].rotation_deg.y, 30.0);
  EXPECT_DOUBLE_EQ(bodies[0].friction, 0.7);
  EXPECT_DOUBLE_EQ(bodies[0].restitution, 0.1);
  EXPECT_EQ(bodies[1].name, "body1");
  EXPECT_EQ(bodies[1].shape, BodyShape::kSphere);
  EXPECT_DOUBLE_EQ(bodies[1].radius_m, 0.08);
  EXPECT_DOUBLE_EQ(bodies[1].friction, BodySpec{}.friction);
  EXPECT_EQ(bodies[2].shape, BodyShape::kCylinder);
  EXPECT_DOUBLE_EQ(bodies[2].height_m, 0.2);
  EXPECT_DOUBLE_EQ(bodies[2].mass_kg, 0.0);
  EXPECT_EQ(validate(bodies), "");
}

TEST(ParseBodies, EmptyListIsNoBodies) {
  EXPECT_TRUE(parse("bodies: []\n").empty());
  EXPECT_TRUE(parse("bodies:\n").empty());
}

TEST(ParseBodies, ErrorsNameFileLineAndField) {
  // Line numbers are 1-based lines of the text (line 1 is "bodies:").
  EXPECT_EQ(error_of("bodies:\n  - shape: box\n    size_m: [0.1, -0.2, 0.1]\n    mass_kg: 1\n"
                     "    position_m: [0, 0, 0]\n"),
            "scene.yaml:3: bodies[0].size_m[1]: must be in (0, 1000], got -0.2");
  EXPECT_EQ(error_of("bodies:\n  - shape: cube\n"),
            "scene.yaml:2: bodies[0].shape: unknown shape 'cube'; allowed: box, sphere, cylinder");
  EXPECT_EQ(error_of("bodies:\n  - shape: sphere\n    radius_m: 0.1\n    size_m: [1, 1, 1]\n"
                     "    mass_kg: 1\n    position_m: [0, 0, 0]\n"),
            "scene.yaml:4: bodies[0].size_m: 'size_m' does not apply to a sphere");
  EXPECT_NE(error_of("bodies:\n  - shape: box\n    size_m: [1, 1, 1]\n    position_m: [0, 0, 0]\n")
                .find("scene.yaml:2: bodies[0].mass_kg: missing required field 'mass_kg'"),
            std::string::npos);
  EXPECT_NE(error_of("bodies:\n  - shape: box\n    size_m: [1, 1]\n").find(
                "scene.yaml:3: bodies[0].size_m: expected a list of 3 numbers, got a list of 2"),
            std::string::npos);
  EXPECT_NE(error_of("bodies:\n  - shape: box\n    colour: red\n")
                .find("scene.yaml:3: bodies[0].colour: unknown key 'colour'"),
            std::string::npos);
  EXPECT_NE(error_of("bodies:\n  - shape: sphere\n    radius_m: 0.1\n    mass_kg: heavy\n")
                .find("scene.yaml:4: bodies[0].mass_kg: expected a number, got 'heavy'"),
            std::string::npos);
  EXPECT_NE(error_of("bodies:\n  - shape: sphere\n    radius_m: 0.1\n    mass_kg: -1\n"
                     "    position_m: [0, 0, 0]\n")
                .find("scene.yaml:4: bodies[0].mass_kg: must be finite and >= 0"),
            std::string::npos);
  EXPECT_NE(error_of("bodies:\n  - {name: a, shape: sphere, radius_m: 1, mass_kg: 1, position_m: [0,0,0]}\n"
                     "  - {name: a, shape: sphere, radius_m: 1, mass_kg: 1, position_m: [0,0,0]}\n")
                .find("scene.yaml:3: bodies[1].name: duplicate body name 'a' (first used by "
                      "bodies[0] at line 2)"),
            std::string::npos);
  EXPECT_NE(error_of("bodies: {shape: box}\n").find("scene.yaml:1: bodies: expected a list"),
            std::string::npos);
  EXPECT_NE(error_of("bodies:\n  - 3\n").find("scene.yaml:2: bodies[0]: expected a mapping"),
            std::string::npos);
}

}  // namespace
}  // namespace terracut
