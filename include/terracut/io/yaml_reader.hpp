// The one toolkit every YAML section reader is written with (the scenario,
// its `bodies:` list and its `haptics:` section), in the spirit of MuJoCo's
// xml_util: the same helpers read every section, so every section refuses
// the same mistakes with the same messages and the same limits.
//
// Every error is a terracut::InputError reading
//
//   FILE:LINE: field.path: what is wrong
//
// (LINE 1-based; "FILE: ..." when the place has no line, and no "field.path: "
// for errors about the document as a whole). Numbers in messages are written
// by core's format_number, range errors by its must_be (terracut/core/format.hpp).
//
//   const yaml::Context ctx("scene.yaml");
//   const yaml::Field root(ctx, document, "", YAML::Mark());
//   const yaml::Map top(root, {"blade", "rate_hz"});   // unknown, repeated keys refused here
//   const double rate = top.require("rate_hz").positive();
//   if (const auto f = top.get("blade")) ... ;         // absent: nullopt
//
// The toolkit is for section readers of any layer (io, haptics, bullet), so
// it exposes yaml-cpp's types.
#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/format.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/ranges.hpp"

namespace terracut::io::yaml {

/// Largest magnitude of any number or whole number read: 1e9. No length,
/// time, rate, force or stiffness of a scenario comes near it in SI units,
/// and larger values would overflow float heights or volumes. It also keeps
/// every whole number inside an int.
inline constexpr double kMaxMagnitude = kRangeMax;

/// A node for messages: "'text'" for a scalar, "a list", "a mapping",
/// "nothing" for null, "an undefined value" otherwise.
std::string describe(const YAML::Node& node);

/// The items separated by sep ("a, b, c"): the form of every list of names
/// in messages (allowed keys, allowed values).
std::string join(const std::vector<std::string>& items, std::string_view sep = ", ");

/// "parent.key", or "key" when parent is empty.
std::string child_path(std::string_view parent, std::string_view key);

/// A problem found after reading, by one of core's validate() functions,
/// whose messages read "field.path what is wrong".
struct Problem {
  std::string path;  ///< "field.path", relative to the section validated
  std::string what;  ///< "what is wrong" (the whole message when it has no space)
};
/// Splits a validate() message at its first space.
Problem split_problem(std::string_view message);

namespace detail {
/// A YAML::Node whose assignment rebinds it to the other node. YAML::Node's
/// own assignment instead writes the other node's content into the document
/// (so assigning a kept Field would corrupt the tree it came from).
class NodeRef {
 public:
  NodeRef(YAML::Node node) : node_(std::move(node)) {}  // NOLINT: implicit by design
  NodeRef(const NodeRef&) = default;
  NodeRef& operator=(const NodeRef& other) {
    node_.reset(other.node_);
    return *this;
  }
  const YAML::Node& get() const { return node_; }

 private:
  YAML::Node node_;
};
}  // namespace detail

/// The file that errors name. Cheap to copy (the name is shared), so Fields
/// and Maps hold their own copy and can outlive the Context they came from.
class Context {
 public:
  /// file: the name written at the start of every error (a path, as given).
  explicit Context(std::string file);

  const std::string& file() const { return *file_; }
  /// "FILE:LINE" (LINE 1-based) for a mark with a line, else "FILE".
  std::string where(const YAML::Mark& mark) const;
  /// Throws InputError "FILE:LINE: path: what" ("FILE:LINE: what" when path is
  /// empty, "FILE: ..." for YAML::Mark::null_mark()).
  [[noreturn]] void fail(const YAML::Mark& mark, std::string_view path, std::string_view what) const;

 private:
  std::shared_ptr<const std::string> file_;
};

/// Parses YAML text (a whole document). Malformed text throws InputError
/// "FILE:LINE: <malformed>: what yaml-cpp says", where <malformed> is the
/// phrase given (each reader keeps the phrase its users already see).
YAML::Node parse_text(const Context& ctx, const std::string& text,
                      std::string_view malformed = "malformed YAML");

/// An entry of a table of ranges (core/ranges.hpp).
using Range = terracut::Range;

/// One value of the document with its field path (e.g. "cuts[0].keyframes[1].t_s")
/// and the line errors about it report: its own mark, or the mark of the key
/// (or list) that introduced it when it has none. Safe to keep and copy.
class Field {
 public:
  /// fallback: the mark of the key that introduced node (or of the list
  /// holding it), used when node has no mark of its own and for errors about
  /// fields missing inside it. A document's root: path "" (or the section's
  /// name) and YAML::Mark() (line 1; YAML::Mark::null_mark() has no line).
  Field(Context ctx, YAML::Node node, std::string path, YAML::Mark fallback);

  const YAML::Node& node() const { return node_.get(); }
  const std::string& path() const { return path_; }
  const Context& context() const { return ctx_; }
  /// The line reported for the value: its own mark, else the fallback.
  YAML::Mark mark() const;
  /// Where the field is introduced: its key's line for a mapping value.
  YAML::Mark key_mark() const;
  /// Throws InputError "FILE:LINE: path: what" at mark().
  [[noreturn]] void fail(std::string_view what) const;
  /// Reports a problem about sub_path ("a.b[1]", relative to this field) at
  /// the line of the deepest part of it the file gives (this field's own
  /// line when none): "FILE:LINE: path.sub_path: what". For problems found
  /// after reading, such as those of a validate() function.
  [[noreturn]] void fail_at(std::string_view sub_path, std::string_view what) const;

  bool is_null() const { return node().IsNull(); }
  bool is_scalar() const { return node().IsScalar(); }
  bool is_sequence() const { return node().IsSequence(); }
  bool is_map() const { return node().IsMap(); }

  /// The value of key in this mapping, looked up without checking the other
  /// keys (for a reader that owns only one key of a document); nullopt when
  /// the key is absent or this is not a mapping. Prefer Map.
  std::optional<Field> lookup(std::string_view key) const;

  /// A scalar, as written.
  std::string text() const;
  /// true or false (also YAML's yes/no, on/off).
  bool boolean() const;
  /// A finite number within +-kMaxMagnitude (1e9).
  double number() const;
  /// number(), > 0.
  double positive() const;
  /// number(), >= 0.
  double non_negative() const;
  /// Whether the ends of a range belong to it.
  using Ends = RangeEnds;
  /// number() in the range from lo to hi: [lo, hi] (kClosed), (lo, hi]
  /// (kOpenLow), [lo, hi) (kOpenHigh) or (lo, hi) (kOpen). The error writes
  /// the range that way: "must be in (0, 1000], got 1500".
  double in_range(double lo, double hi, Ends ends = Ends::kClosed) const;
  /// A whole number written as one ("+5", "-3"; not "5.0" or "1e3"), within
  /// +-kMaxMagnitude (1e9), so it fits an int.
  long long integer() const;
  /// integer() in [lo, hi].
  long long integer_in(long long lo, long long hi) const;
  /// The number as its entry of a reader's table of ranges says (see Range).
  double in(const Range& range) const;

  /// The elements of a list, each with its path "path[i]".
  std::vector<Field> elements() const;
  /// A list of exactly n numbers, each number().
  std::vector<double> numbers(std::size_t n) const;
  /// A list of 3 numbers, each number().
  Vec3 vec3() const;

  /// The index in names of the scalar's text; else the error "unknown NOUN
  /// 'text'; allowed: a, b, c".
  std::size_t choose(const std::vector<std::string_view>& names,
                     std::string_view noun = "value") const;
  /// The value among values whose to_string (found by argument-dependent
  /// lookup, as for core's enums) is the scalar's text; else choose's error,
  /// listing the names of values in their order.
  template <typename T>
  T choice(std::initializer_list<T> values, std::string_view noun = "value") const {
    std::vector<std::string_view> names;
    for (const T& v : values) names.push_back(to_string(v));
    return values.begin()[choose(names, noun)];
  }

 private:
  Context ctx_;
  detail::NodeRef node_;
  std::string path_;
  YAML::Mark fallback_;
};

// A Range (core/ranges.hpp) read from a file: the reader reads the field with
// Field::in(range), and the boundary tests are generated from the same table
// (each end, and just beyond it). Reading follows the toolkit's own checks,
// so the messages are theirs: whole numbers by integer_in, (0, 1e9] by
// positive ("must be > 0"), [0, 1e9] by non_negative, anything else by
// in_range ("must be in (0, 1e6]").

/// The entry of table for path (core's find_range).
using terracut::find_range;

/// A mapping with a fixed set of allowed keys. Unknown keys (the error lists
/// the allowed ones), repeated keys (the error names the first one's line)
/// and keys that are not plain names are refused at construction, before
/// anything is read. Values are looked up without yaml-cpp's operator[],
/// which would invent missing nodes. Safe to keep and copy.
class Map {
 public:
  /// field must be a mapping whose keys are all in allowed.
  Map(const Field& field, std::vector<std::string_view> allowed);

  const Field& field() const { return field_; }
  bool has(std::string_view key) const { return find(key) != nullptr; }

  /// The value of key, or nullopt when absent. A key given with no value
  /// ("key:") is an error.
  std::optional<Field> get(std::string_view key) const;
  /// The value of key; absent is the error "missing required field 'key'",
  /// at the line that introduces this mapping.
  Field require(std::string_view key) const;
  /// The mapping under key with its own allowed keys; an empty one (every
  /// get() nullopt) when key is absent, for sections whose fields all have
  /// defaults.
  Map section(std::string_view key, std::vector<std::string_view> allowed) const;

  // Read-if-given: when key is present, set out to its value (read as the
  // Field function of the same name) and return true; else leave out as it
  // is (its default) and return false.
  bool read_number(std::string_view key, double& out) const;
  bool read_integer(std::string_view key, int& out) const;
  bool read_boolean(std::string_view key, bool& out) const;
  bool read_text(std::string_view key, std::string& out) const;
  bool read_vec3(std::string_view key, Vec3& out) const;

 private:
  struct Entry {
    std::string name;
    YAML::Mark key_mark;
    detail::NodeRef value;
  };
  struct Absent {};
  Map(Field field, std::vector<std::string_view> allowed, Absent);

  const Entry* find(std::string_view key) const;
  std::string allowed_list() const;

  Field field_;
  std::vector<std::string> allowed_;  // copies: the Map may outlive the caller's names
  std::vector<Entry> entries_;
};

}  // namespace terracut::io::yaml
