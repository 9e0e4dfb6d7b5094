// The YAML section-reader toolkit. See yaml_reader.hpp.
#include "terracut/io/yaml_reader.hpp"

#if __has_include(<yaml-cpp/depthguard.h>)
#include <yaml-cpp/depthguard.h>  // YAML::DeepRecursion (yaml-cpp >= 0.7)
#define TERRACUT_YAML_HAS_DEPTH_GUARD 1
#endif

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <system_error>

#include "terracut/core/error.hpp"

namespace terracut::io::yaml {
namespace {

// kMaxMagnitude as a whole number, for integer().
constexpr long long kMaxWhole = 1'000'000'000;
static_assert(double(kMaxWhole) == kMaxMagnitude);

// The body of Map's read_* functions: out = read(value) when key is given.
template <typename T, typename Read>
bool read_if_given(const Map& map, std::string_view key, T& out, Read read) {
  const std::optional<Field> f = map.get(key);
  if (f) out = read(*f);
  return f.has_value();
}

}  // namespace

std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    default:
      return "an undefined value";
  }
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i) out += sep;
    out += items[i];
  }
  return out;
}

std::string child_path(std::string_view parent, std::string_view key) {
  if (parent.empty()) return std::string(key);
  // An index ("[1]") follows its list without a dot.
  if (!key.empty() && key.front() == '[') return std::string(parent) + std::string(key);
  return std::string(parent) + "." + std::string(key);
}

Problem split_problem(std::string_view message) {
  const std::size_t space = message.find(' ');
  if (space == std::string_view::npos) return {std::string(message), std::string(message)};
  return {std::string(message.substr(0, space)), std::string(message.substr(space + 1))};
}

// ---------------------------------------------------------------------------
// Context

Context::Context(std::string file) : file_(std::make_shared<const std::string>(std::move(file))) {}

std::string Context::where(const YAML::Mark& mark) const {
  if (mark.is_null() || mark.line < 0) return *file_;
  return *file_ + ":" + std::to_string(mark.line + 1);
}

void Context::fail(const YAML::Mark& mark, std::string_view path, std::string_view what) const {
  std::string message = where(mark) + ": ";
  if (!path.empty()) message += std::string(path) + ": ";
  throw InputError(message + std::string(what));
}

YAML::Node parse_text(const Context& ctx, const std::string& text, std::string_view malformed) {
  try {
    return YAML::Load(text);
#if defined(TERRACUT_YAML_HAS_DEPTH_GUARD)
  } catch (const YAML::DeepRecursion& e) {
    // yaml-cpp's own message for this is "bad file".
    ctx.fail(e.mark, "", std::string(malformed) + ": lists and mappings are nested more than " +
                             std::to_string(e.depth() - 1) + " levels deep");
#endif
  } catch (const YAML::Exception& e) {
    ctx.fail(e.mark, "", std::string(malformed) + ": " + e.msg);
  }
}

// ---------------------------------------------------------------------------
// Field

Field::Field(Context ctx, YAML::Node node, std::string path, YAML::Mark fallback)
    : ctx_(std::move(ctx)), node_(std::move(node)), path_(std::move(path)), fallback_(fallback) {}

YAML::Mark Field::mark() const {
  const YAML::Mark m = node().Mark();
  return m.is_null() ? fallback_ : m;
}

YAML::Mark Field::key_mark() const { return fallback_.is_null() ? mark() : fallback_; }

void Field::fail(std::string_view what) const { ctx_.fail(mark(), path_, what); }

void Field::fail_at(std::string_view sub_path, std::string_view what) const {
  // Walk "a.b[1].c" down the document as far as the file gives it.
  Field at = *this;
  std::size_t i = 0;
  while (i < sub_path.size()) {
    if (sub_path[i] == '.') ++i;
    if (i < sub_path.size() && sub_path[i] == '[') {
      const std::size_t close = sub_path.find(']', i);
      if (close == std::string_view::npos) break;
      std::size_t index = 0;
      const auto [ptr, ec] = std::from_chars(sub_path.data() + i + 1, sub_path.data() + close, index);
      if (ec != std::errc() || ptr != sub_path.data() + close) break;
      if (!at.is_sequence() || index >= at.node().size()) break;
      at = at.elements()[index];  // rebinds (detail::NodeRef)
      i = close + 1;
    } else {
      const std::size_t end = std::min(sub_path.find_first_of(".[", i), sub_path.size());
      const std::optional<Field> child = at.lookup(sub_path.substr(i, end - i));
      if (!child) break;
      at = *child;
      i = end;
    }
  }
  ctx_.fail(at.mark(), child_path(path_, sub_path), what);
}

std::optional<Field> Field::lookup(std::string_view key) const {
  if (!node().IsMap()) return std::nullopt;
  for (const auto& kv : node())
    if (kv.first.IsScalar() && kv.first.Scalar() == key) {
      const YAML::Mark key_mark = kv.first.Mark().is_null() ? mark() : kv.first.Mark();
      return Field(ctx_, kv.second, child_path(path_, key), key_mark);
    }
  return std::nullopt;
}

std::string Field::text() const {
  if (!node().IsScalar()) fail("expected a text value, got " + describe(node()));
  return node().Scalar();
}

bool Field::boolean() const {
  bool value = false;
  if (!node().IsScalar() || !YAML::convert<bool>::decode(node(), value))
    fail("expected true or false, got " + describe(node()));
  return value;
}

double Field::number() const {
  if (!node().IsScalar()) fail("expected a number, got " + describe(node()));
  double v = 0.0;
  try {
    v = node().as<double>();
  } catch (const YAML::Exception&) {
    fail("expected a number, got " + describe(node()));
  }
  if (!std::isfinite(v)) fail("must be a finite number, got " + describe(node()));
  if (std::abs(v) > kMaxMagnitude) fail("must be within +-1e9 (SI units), got " + describe(node()));
  return v;
}

double Field::positive() const {
  const double v = number();
  if (!(v > 0.0)) fail(must_be("> 0", v));
  return v;
}

double Field::non_negative() const {
  const double v = number();
  if (!(v >= 0.0)) fail(must_be(">= 0", v));
  return v;
}

double Field::in_range(double lo, double hi, Ends ends) const {
  const double v = number();
  const bool above_low = (ends == Ends::kOpenLow || ends == Ends::kOpen) ? v > lo : v >= lo;
  const bool below_high = (ends == Ends::kOpenHigh || ends == Ends::kOpen) ? v < hi : v <= hi;
  if (!above_low || !below_high)
    fail(must_be("in " + range_text(lo, hi, ends), v));
  return v;
}

long long Field::integer() const {
  if (!node().IsScalar()) fail("expected a whole number, got " + describe(node()));
  // std::from_chars, not as<long long>(): yaml-cpp's conversion accepts
  // forms such as "0x10" and differs between versions.
  const std::string& s = node().Scalar();
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (first != last && *first == '+') ++first;  // "+5", as numbers may be written
  long long v = 0;
  const auto [ptr, ec] = std::from_chars(first, last, v);
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && std::llabs(v) > kMaxWhole))
    fail("whole number " + describe(node()) + " is out of range: must be within +-1e9");
  if (ec != std::errc() || ptr != last || first == last)
    fail("expected a whole number, got " + describe(node()));
  return v;
}

long long Field::integer_in(long long lo, long long hi) const {
  const long long v = integer();
  if (v < lo || v > hi)
    fail(must_be("in [" + format_number(lo) + ", " + format_number(hi) + "]", v));
  return v;
}

double Field::in(const Range& range) const {
  if (range.whole) return double(integer_in(std::llround(range.lo), std::llround(range.hi)));
  if (range.hi == kMaxMagnitude && range.lo == 0.0 && range.ends == Ends::kOpenLow) return positive();
  if (range.hi == kMaxMagnitude && range.lo == 0.0 && range.ends == Ends::kClosed) return non_negative();
  if (range.hi == kMaxMagnitude && range.lo == -kMaxMagnitude) return number();
  return in_range(range.lo, range.hi, range.ends);
}

std::vector<Field> Field::elements() const {
  if (!node().IsSequence()) fail("expected a list, got " + describe(node()));
  std::vector<Field> out;
  std::size_t i = 0;
  for (const auto& element : node()) {
    // An element's own mark, when it has one, is also where fields missing
    // inside it are reported.
    const YAML::Mark m = element.Mark().is_null() ? mark() : element.Mark();
    out.emplace_back(ctx_, element, path_ + "[" + std::to_string(i) + "]", m);
    ++i;
  }
  return out;
}

std::vector<double> Field::numbers(std::size_t n) const {
  const std::string want = "expected a list of " + std::to_string(n) + " numbers, got ";
  if (!node().IsSequence()) fail(want + describe(node()));
  if (node().size() != n) fail(want + "a list of " + std::to_string(node().size()));
  std::vector<double> out;
  for (const Field& f : elements()) out.push_back(f.number());
  return out;
}

Vec3 Field::vec3() const {
  const std::vector<double> v = numbers(3);
  return {v[0], v[1], v[2]};
}

std::size_t Field::choose(const std::vector<std::string_view>& names, std::string_view noun) const {
  const std::string name = text();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end())
    fail("unknown " + std::string(noun) + " '" + name +
         "'; allowed: " + join(std::vector<std::string>(names.begin(), names.end())));
  return std::size_t(it - names.begin());
}

// ---------------------------------------------------------------------------
// Map

Map::Map(const Field& field, std::vector<std::string_view> allowed)
    : field_(field), allowed_(allowed.begin(), allowed.end()) {
  const YAML::Node& node = field.node();
  if (!node.IsMap())
    field.fail("expected a mapping with keys " + allowed_list() + ", got " + describe(node));
  const Context& ctx = field.context();
  for (const auto& kv : node) {
    const YAML::Node& key = kv.first;
    const YAML::Mark key_mark = key.Mark().is_null() ? field.mark() : key.Mark();
    if (!key.IsScalar())
      ctx.fail(key_mark, field.path(), "keys must be plain names, got " + describe(key));
    const std::string name = key.Scalar();
    const std::string path = child_path(field.path(), name);
    if (std::find(allowed_.begin(), allowed_.end(), name) == allowed_.end())
      ctx.fail(key_mark, path, "unknown key '" + name + "'; allowed keys here: " + allowed_list());
    if (const Entry* first = find(name))
      ctx.fail(key_mark, path,
               "key given twice (first at line " + std::to_string(first->key_mark.line + 1) + ")");
    entries_.push_back({name, key_mark, kv.second});
  }
}

Map::Map(Field field, std::vector<std::string_view> allowed, Absent)
    : field_(std::move(field)), allowed_(allowed.begin(), allowed.end()) {}

std::optional<Field> Map::get(std::string_view key) const {
  const Entry* e = find(key);
  if (!e) return std::nullopt;
  const std::string path = child_path(field_.path(), key);
  if (e->value.get().IsNull()) field_.context().fail(e->key_mark, path, "no value given");
  return Field(field_.context(), e->value.get(), path, e->key_mark);
}

Field Map::require(std::string_view key) const {
  std::optional<Field> f = get(key);
  if (!f)
    field_.context().fail(field_.key_mark(), child_path(field_.path(), key),
                          "missing required field '" + std::string(key) + "'" +
                              (field_.path().empty() ? std::string()
                                                     : " in '" + field_.path() + "'"));
  return *f;
}

Map Map::section(std::string_view key, std::vector<std::string_view> allowed) const {
  if (const std::optional<Field> f = get(key)) return Map(*f, std::move(allowed));
  // Absent: errors about it (from fail_at) report the line of this mapping.
  return Map(Field(field_.context(), YAML::Node(), child_path(field_.path(), key), field_.mark()),
             std::move(allowed), Absent{});
}

bool Map::read_number(std::string_view key, double& out) const {
  return read_if_given(*this, key, out, [](const Field& f) { return f.number(); });
}
bool Map::read_integer(std::string_view key, int& out) const {
  // integer() is within +-1e9, so it fits an int.
  return read_if_given(*this, key, out, [](const Field& f) { return int(f.integer()); });
}
bool Map::read_boolean(std::string_view key, bool& out) const {
  return read_if_given(*this, key, out, [](const Field& f) { return f.boolean(); });
}
bool Map::read_text(std::string_view key, std::string& out) const {
  return read_if_given(*this, key, out, [](const Field& f) { return f.text(); });
}
bool Map::read_vec3(std::string_view key, Vec3& out) const {
  return read_if_given(*this, key, out, [](const Field& f) { return f.vec3(); });
}

const Map::Entry* Map::find(std::string_view key) const {
  for (const Entry& e : entries_)
    if (e.name == key) return &e;
  return nullptr;
}

std::string Map::allowed_list() const { return join(allowed_); }

}  // namespace terracut::io::yaml
