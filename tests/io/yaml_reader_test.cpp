// The YAML section-reader toolkit: the error grammar "FILE:LINE: path: what"
// at the right line, key checks, the one magnitude cap, the one integer
// parser, finite numbers, ranges, choices, lists, and the one number format.
#include "terracut/io/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "../support/input_error.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/contact.hpp"

namespace terracut::io::yaml {
namespace {

// The root field of text read as "doc.yaml".
Field root_of(const std::string& text) {
  const Context ctx("doc.yaml");
  return Field(ctx, parse_text(ctx, text), "", YAML::Mark());
}

// The value of key in text ("key: value").
Field value_of(const std::string& text, std::string_view key = "v") {
  return Map(root_of(text), {key}).require(key);
}

template <typename F>
std::string error_of(F&& f) {
  return terracut::test::input_error_of(std::forward<F>(f));
}

TEST(YamlReader, ErrorsReadFileLinePathWhat) {
  const std::string text = "a: 1\nsection:\n  inner: 2\n  x: word\n";
  const Map top(root_of(text), {"a", "section"});
  const Map section(top.require("section"), {"inner", "x"});
  EXPECT_EQ(error_of([&] { section.require("x").number(); }),
            "doc.yaml:4: section.x: expected a number, got 'word'");
  EXPECT_EQ(error_of([&] { top.require("a").fail("what is wrong"); }),
            "doc.yaml:1: a: what is wrong");
  // Errors about the whole document have no path.
  EXPECT_EQ(error_of([] { Context("doc.yaml").fail(YAML::Mark::null_mark(), "", "empty"); }), "doc.yaml: empty");
}

TEST(YamlReader, FieldsAreSafeToKeepAndAssign) {
  std::optional<Field> kept;
  {
    const Context ctx("gone.yaml");
    kept = Field(ctx, YAML::Load("v: 1\n"), "", YAML::Mark());
  }
  EXPECT_EQ(error_of([&] { kept->fail("still named"); }), "gone.yaml:1: still named");
  // Assigning a Field rebinds it; the value it held is left as it was.
  const Map map(root_of("a: 1\nb: 2\n"), {"a", "b"});
  Field f = map.require("a");
  f = map.require("b");
  EXPECT_EQ(f.number(), 2.0);
  EXPECT_EQ(map.require("a").number(), 1.0);
}

TEST(YamlReader, MalformedTextNamesTheLine) {
  const std::string m = error_of([] { root_of("a: 1\nb: [1, 2\n"); });
  EXPECT_EQ(m.rfind("doc.yaml:", 0), 0u) << m;
  EXPECT_NE(m.find("malformed YAML: "), std::string::npos) << m;
  const Context ctx("x.yaml");
  EXPECT_NE(error_of([&] { parse_text(ctx, "[", "not valid YAML"); }).find("not valid YAML"),
            std::string::npos);
}

// Nesting deeper than yaml-cpp allows: said so, not yaml-cpp's "bad file".
TEST(YamlReader, DeepNestingSaysSo) {
  const std::string m = error_of([] { root_of("a: 1\nb: " + std::string(5000, '[') + std::string(5000, ']') + "\n"); });
  EXPECT_EQ(m.rfind("doc.yaml:2: malformed YAML: lists and mappings are nested more than ", 0), 0u) << m;
  EXPECT_NE(m.find(" levels deep"), std::string::npos) << m;
  EXPECT_EQ(m.find("bad file"), std::string::npos) << m;
}

TEST(YamlReader, UnknownKeyListsTheAllowedKeys) {
  EXPECT_EQ(error_of([] { Map(root_of("alpha: 1\ngamma: 2\n"), {"alpha", "beta"}); }),
            "doc.yaml:2: gamma: unknown key 'gamma'; allowed keys here: alpha, beta");
  EXPECT_EQ(error_of([] { Map(root_of("m: 3\n"), {"m"}).section("m", {"k"}); }),
            "doc.yaml:1: m: expected a mapping with keys k, got '3'");
  EXPECT_EQ(error_of([] { Map(root_of("? [1, 2]\n: 3\n"), {"a"}); }),
            "doc.yaml:1: keys must be plain names, got a list");
}

TEST(YamlReader, RepeatedKeyNamesTheFirstLine) {
  EXPECT_EQ(error_of([] { Map(root_of("a: 1\nb: 2\na: 3\n"), {"a", "b"}); }),
            "doc.yaml:3: a: key given twice (first at line 1)");
}

TEST(YamlReader, MissingAndEmptyValues) {
  const Map top(root_of("top:\n  a: 1\nempty:\n"), {"top", "empty"});
  const Map inner(top.require("top"), {"a", "b"});
  EXPECT_EQ(error_of([&] { inner.require("b"); }),
            "doc.yaml:1: top.b: missing required field 'b' in 'top'");
  EXPECT_EQ(error_of([&] { top.get("empty"); }), "doc.yaml:3: empty: no value given");
  EXPECT_FALSE(inner.get("b").has_value());
  // No lookup invents a node (yaml-cpp's operator[] would).
  EXPECT_EQ(inner.field().node().size(), 1u);
  // An absent section is an empty one; its errors report the parent's line.
  const Map absent = top.section("missing", {"k"});
  EXPECT_FALSE(absent.get("k").has_value());
  double kept = 7.0;
  EXPECT_FALSE(absent.read_number("k", kept));
  EXPECT_EQ(kept, 7.0);
  EXPECT_EQ(error_of([&] { absent.field().fail_at("k", "bad"); }), "doc.yaml:1: missing.k: bad");
}

TEST(YamlReader, MagnitudeCapIsExactly1e9) {
  EXPECT_EQ(value_of("v: 1e9").number(), 1e9);
  EXPECT_EQ(value_of("v: -1000000000").number(), -1e9);
  // The next double above 1e9 is refused.
  const std::string beyond = format_number(std::nextafter(1e9, 2e9));
  EXPECT_EQ(error_of([&] { value_of("v: " + beyond).number(); }),
            "doc.yaml:1: v: must be within +-1e9 (SI units), got '" + beyond + "'");
  EXPECT_NE(error_of([] { value_of("v: -1e300").number(); }).find("+-1e9"), std::string::npos);
}

TEST(YamlReader, NanAndInfinityAreRefused) {
  for (const char* bad : {".nan", ".NaN", ".inf", "-.inf", ".Inf"})
    EXPECT_EQ(error_of([&] { value_of(std::string("v: ") + bad).number(); }),
              std::string("doc.yaml:1: v: must be a finite number, got '") + bad + "'");
  EXPECT_EQ(error_of([] { value_of("v: [1]").number(); }),
            "doc.yaml:1: v: expected a number, got a list");
}

TEST(YamlReader, SignsAndRanges) {
  EXPECT_EQ(value_of("v: 0").non_negative(), 0.0);
  EXPECT_EQ(error_of([] { value_of("v: 0").positive(); }), "doc.yaml:1: v: must be > 0, got 0");
  EXPECT_EQ(error_of([] { value_of("v: -0.5").non_negative(); }),
            "doc.yaml:1: v: must be >= 0, got -0.5");
  EXPECT_EQ(value_of("v: 0").in_range(0, 1), 0.0);
  EXPECT_EQ(value_of("v: 1").in_range(0, 1, Field::Ends::kOpenLow), 1.0);
  EXPECT_EQ(error_of([] { value_of("v: 0").in_range(0, 1000, Field::Ends::kOpenLow); }),
            "doc.yaml:1: v: must be in (0, 1000], got 0");
  EXPECT_EQ(error_of([] { value_of("v: 1").in_range(0, 1, Field::Ends::kOpenHigh); }),
            "doc.yaml:1: v: must be in [0, 1), got 1");
  EXPECT_EQ(error_of([] { value_of("v: 2e6").in_range(-1, 1e6, Field::Ends::kOpen); }),
            "doc.yaml:1: v: must be in (-1, 1e+06), got 2e+06");
}

TEST(YamlReader, OneIntegerParser) {
  EXPECT_EQ(value_of("v: +5").integer(), 5);
  EXPECT_EQ(value_of("v: -3").integer(), -3);
  EXPECT_EQ(value_of("v: 1000000000").integer(), 1000000000);
  for (const char* bad : {"5.0", "1e3", "0x10", "five", "5 apples", "+"})
    EXPECT_EQ(error_of([&] { value_of(std::string("v: ") + bad).integer(); }),
              std::string("doc.yaml:1: v: expected a whole number, got '") + bad + "'")
        << bad;
  for (const char* big : {"1000000001", "-1000000001", "99999999999999999999"})
    EXPECT_EQ(error_of([&] { value_of(std::string("v: ") + big).integer(); }),
              std::string("doc.yaml:1: v: whole number '") + big +
                  "' is out of range: must be within +-1e9")
        << big;
  EXPECT_EQ(error_of([] { value_of("v: 0").integer_in(1, 65535); }),
            "doc.yaml:1: v: must be in [1, 65535], got 0");
  int port = 1;
  EXPECT_TRUE(Map(root_of("port: 47000\n"), {"port"}).read_integer("port", port));
  EXPECT_EQ(port, 47000);
}

TEST(YamlReader, TextAndBooleans) {
  EXPECT_EQ(value_of("v: hello").text(), "hello");
  EXPECT_EQ(error_of([] { value_of("v: {a: 1}").text(); }),
            "doc.yaml:1: v: expected a text value, got a mapping");
  EXPECT_TRUE(value_of("v: true").boolean());
  EXPECT_FALSE(value_of("v: no").boolean());
  EXPECT_EQ(error_of([] { value_of("v: maybe").boolean(); }),
            "doc.yaml:1: v: expected true or false, got 'maybe'");
}

TEST(YamlReader, ChoicesListTheAllowedNames) {
  EXPECT_EQ(value_of("v: columns").choice({Representation::kSurface, Representation::kColumns}),
            Representation::kColumns);
  EXPECT_EQ(error_of([] {
              value_of("v: voxels").choice({Representation::kSurface, Representation::kColumns},
                                           "representation");
            }),
            "doc.yaml:1: v: unknown representation 'voxels'; allowed: surface, columns");
  EXPECT_EQ(value_of("v: b").choose({"a", "b"}), 1u);
  EXPECT_EQ(error_of([] { value_of("v: c").choose({"a", "b"}); }),
            "doc.yaml:1: v: unknown value 'c'; allowed: a, b");
}

TEST(YamlReader, ListsOfNumbers) {
  const Vec3 v = value_of("v: [1, -2.5, 3e2]").vec3();
  EXPECT_EQ(v.x, 1.0);
  EXPECT_EQ(v.y, -2.5);
  EXPECT_EQ(v.z, 300.0);
  EXPECT_EQ(error_of([] { value_of("v: [1, 2]").vec3(); }),
            "doc.yaml:1: v: expected a list of 3 numbers, got a list of 2");
  EXPECT_EQ(error_of([] { value_of("v: [1, 2, 3, 4]").vec3(); }),
            "doc.yaml:1: v: expected a list of 3 numbers, got a list of 4");
  EXPECT_EQ(error_of([] { value_of("v: 3").vec3(); }),
            "doc.yaml:1: v: expected a list of 3 numbers, got '3'");
  // Each element is named and reported at its own line.
  EXPECT_EQ(error_of([] { value_of("v:\n  - 1\n  - .inf\n  - 3\n").vec3(); }),
            "doc.yaml:3: v[1]: must be a finite number, got '.inf'");
  EXPECT_EQ(value_of("v: [4, 5]").numbers(2), (std::vector<double>{4, 5}));
  EXPECT_EQ(error_of([] { value_of("v: 1").elements(); }), "doc.yaml:1: v: expected a list, got '1'");
}

TEST(YamlReader, FailAtReportsTheDeepestGivenPart) {
  const Field body = value_of("v:\n  size_m:\n    - 1\n    - -2\n  mass_kg: 3\n");
  EXPECT_EQ(error_of([&] { body.fail_at("size_m[1]", "must be > 0"); }),
            "doc.yaml:4: v.size_m[1]: must be > 0");
  EXPECT_EQ(error_of([&] { body.fail_at("size_m[7]", "too short"); }),
            "doc.yaml:3: v.size_m[7]: too short");
  EXPECT_EQ(error_of([&] { body.fail_at("friction", "out of range"); }),
            "doc.yaml:2: v.friction: out of range");
  // Reporting never changes the document (YAML::Node's assignment would).
  EXPECT_EQ(body.node()["mass_kg"].as<int>(), 3);
  EXPECT_EQ(body.node()["size_m"].size(), 2u);
  const Problem p = split_problem("hand.mass_kg must be finite and > 0 (got -1)");
  EXPECT_EQ(p.path, "hand.mass_kg");
  EXPECT_EQ(p.what, "must be finite and > 0 (got -1)");
}

TEST(YamlReader, OneNumberFormat) {
  // Shortest text that reads back as the same double.
  EXPECT_EQ(format_number(0.5), "0.5");
  EXPECT_EQ(format_number(0.1), "0.1");
  EXPECT_EQ(format_number(-0.2), "-0.2");
  EXPECT_EQ(format_number(250), "250");
  EXPECT_EQ(format_number(1e10), "1e+10");
  EXPECT_EQ(format_number(1e-7), "1e-07");
  EXPECT_EQ(format_number(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(std::stod(format_number(1.0 / 3.0)), 1.0 / 3.0);
  EXPECT_EQ(format_number(std::numeric_limits<double>::infinity()), "inf");
}

}  // namespace
}  // namespace terracut::io::yaml
