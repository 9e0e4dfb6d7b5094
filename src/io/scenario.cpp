// Scenario files: YAML -> validated Scenario. See scenario.hpp and
// docs/scenario-format.md.
#include "terracut/io/scenario.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <system_error>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/io/scenario_ranges.hpp"
#include "terracut/io/soil_yaml.hpp"
#include "terracut/io/yaml_reader.hpp"

namespace terracut::io {
namespace {

using yaml::child_path;
using yaml::Context;
using yaml::Field;
using yaml::join;
using yaml::Map;

// Largest scenario file read (a scenario is a few kilobytes; this only stops a
// wrong path to a huge file from being read into memory).
constexpr std::uintmax_t kMaxScenarioFileBytes = 64u << 20;
// Largest number of steps one cut may take (duration * rate); a longer cut
// would write a contact.csv of more than ~10 GB.
constexpr double kMaxStepsPerCut = 1e8;
/// Largest number of steps of a whole run (the sequence); each step is a row
/// of contact.csv (about 200 bytes), so 1e8 steps is about 20 GB.
constexpr double kMaxStepsPerRun = 1e8;

// Steps of the whole sequence: each cut runs round(duration * rate) + 1 steps.
double sequence_steps(const Scenario& sc) {
  double total = 0.0;
  for (int index : sc.sequence)
    total += std::round(sc.cuts[std::size_t(index)].duration_s() * sc.rate_hz) + 1.0;
  return total;
}
using Ends = yaml::Field::Ends;
constexpr double kMax = yaml::kMaxMagnitude;

// Every number of the file with a range of its own (scenario_ranges.hpp).
// The simulation's and the soil's are their structs' entries
// (kSimParamsRanges, kSoilFlowRanges), read here through the same entry.
constexpr yaml::Range kRanges[] = {
    find_range(kSimParamsRanges, "rate_hz"),
    find_range(kSimParamsRanges, "blade.length_m"),
    find_range(kSimParamsRanges, "blade.rake_angle_deg"),
    find_range(kSimParamsRanges, "blade.edge_thickness_m"),
    find_range(kSimParamsRanges, "blade.height_m"),
    // The file's own: a bucket: section is a bucket (the struct's depth 0 is none).
    {"blade.bucket.depth_m", 0.0, kMax, Ends::kOpenLow},
    find_range(kSimParamsRanges, "blade.bucket.height_m"),
    {"terrain.size_m[0]", 0.0, kMax, Ends::kOpenLow},
    {"terrain.size_m[1]", 0.0, kMax, Ends::kOpenLow},
    {"terrain.full_scale_m", 0.0, kMax, Ends::kOpenLow},
    // Each side, of N or [cols, rows]; the total is capped too (kMaxScenarioSamples).
    {"terrain.resolution", 1, kMaxGridSide, Ends::kClosed, true},
    {"terrain.mound.radius_m", 0.0, kMax, Ends::kOpenLow},
    {"terrain.plane.height_m", 0.0, kMax, Ends::kClosed},
    {"cuts[].keyframes[].t_s", 0.0, kMax, Ends::kClosed},
    at_path(find_range(kSoilFlowRanges, "max_pair_checks_per_step"), "soil.max_pair_checks_per_step"),
    {"reference.mound.radius_m", 0.0, kMax, Ends::kOpenLow},
    {"reference.mound.height_m", 0.0, kMax, Ends::kOpenLow},
};

const yaml::Range& range(std::string_view path) { return yaml::find_range(kRanges, path); }

void check_resolution(const Field& f, long long cols, long long rows) {
  const yaml::Range& side = range("terrain.resolution");
  if (cols < side.lo || rows < side.lo)
    f.fail("resolution must be at least 1 sample per side, got " + std::to_string(cols) + "x" +
           std::to_string(rows));
  if (cols > side.hi || rows > side.hi)
    f.fail("resolution " + std::to_string(cols) + "x" + std::to_string(rows) +
           " is absurd: each side must be at most " + format_number(side.hi) + " samples");
  if (cols * rows > kMaxScenarioSamples)
    f.fail("resolution " + std::to_string(cols) + "x" + std::to_string(rows) +
           " is absurd: more than 2^28 samples in total");
}

Resolution parse_resolution_field(const Field& f) {
  long long cols = 0;
  long long rows = 0;
  if (f.is_sequence()) {
    const std::vector<Field> items = f.elements();
    if (items.size() != 2)
      f.fail("expected N or [cols, rows], got a list of " + std::to_string(items.size()));
    cols = items[0].integer();
    rows = items[1].integer();
  } else {
    cols = rows = f.integer();
  }
  check_resolution(f, cols, rows);
  return {int(cols), int(rows)};
}

// A point [x, z] of the ground plane, read when key is given.
void read_xz(const Map& map, std::string_view key, double& x_m, double& z_m) {
  if (const auto f = map.get(key)) {
    const std::vector<double> v = f->numbers(2);
    x_m = v[0];
    z_m = v[1];
  }
}

bool valid_cut_name(const std::string& name) {
  if (name.empty()) return false;
  for (char ch : name) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
  }
  return true;
}

// The caps on keyframes, in the words of both checks (the scan of the text
// and the check of the parsed document, which also sees aliased lists).
std::string too_many_keyframes_in_cut() {
  return "more than " + format_number(kMaxKeyframesPerCut) + " keyframes; a cut may have at most " +
         format_number(kMaxKeyframesPerCut);
}
std::string too_many_keyframes_in_all() {
  return "the cuts have more than " + format_number(kMaxKeyframes) +
         " keyframes in all; a scenario may have at most " + format_number(kMaxKeyframes);
}

// The top-level keys: the scenario's own and those of the section readers.
std::vector<std::string_view> top_level_keys(std::span<SectionReader* const> sections) {
  std::vector<std::string_view> keys = {"name",     "description", "terrain",  "representation",
                                        "rate_hz",  "blade",       "cuts",     "sequence",
                                        "reference", "soil"};
  for (const SectionReader* reader : sections) keys.push_back(reader->key());
  return keys;
}

// A scan of the scenario text by yaml-cpp's event parser, before the
// document is built (yaml-cpp's YAML::Load holds the whole document, a few
// hundred bytes per value): it refuses, while reading and with memory
// bounded by the nesting depth, what would make the document absurdly large
// or deep -- more keyframes than kMaxKeyframesPerCut in a cut or
// kMaxKeyframes in all, nesting deeper than kMaxScenarioDepth -- and an
// unknown or repeated top-level key, with the messages the document's checks
// would give. Everything else is left to those checks.
class ScenarioScan : public YAML::EventHandler {
 public:
  ScenarioScan(const Context& ctx, std::vector<std::string_view> top_keys)
      : ctx_(ctx), top_keys_(std::move(top_keys)) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { leaf(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { leaf(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string& value) override {
    leaf(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    open(mark, false);
  }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    open(mark, true);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapEnd() override { close(); }

 private:
  // What a collection is in a scenario, as far as the scan cares.
  enum class Role { kOther, kTop, kCuts, kCut, kKeyframes };
  struct Frame {
    bool map = false;
    Role role = Role::kOther;
    bool is_key = false;       // this collection is itself a mapping's key
    bool expect_key = true;    // (mapping) the next node is a key
    bool key_plain = false;    // (mapping) the last key was a scalar; its text in key
    std::string key;
    YAML::Mark key_mark;
    std::size_t count = 0;     // (list) elements so far
    std::string component;     // this node's part of the field path: "key" or "[i]"
    YAML::Mark mark;           // where it starts; for a mapping's value, its key's mark
  };

  // The field path of the node about to start in the innermost collection.
  std::string path_of_next() const {
    std::string path;
    for (const Frame& f : stack_) path = child_path(path, f.component);
    if (!stack_.empty()) path = child_path(path, next_component());
    return path;
  }
  // (called once the node has begun: a list's count includes it)
  std::string next_component() const {
    const Frame& parent = stack_.back();
    if (parent.map) return parent.key_plain ? parent.key : "?";
    return "[" + std::to_string(parent.count - 1) + "]";
  }

  // A node begins in the innermost collection: a mapping key, a mapping
  // value or a list element. Returns whether it is a key.
  bool begin_node() {
    if (stack_.empty()) return false;
    Frame& parent = stack_.back();
    if (parent.map) return parent.expect_key;
    ++parent.count;
    if (parent.role == Role::kKeyframes) {
      if (parent.count > kMaxKeyframesPerCut) fail_keyframes(parent, too_many_keyframes_in_cut());
      if (++keyframes_ > kMaxKeyframes) fail_keyframes(parent, too_many_keyframes_in_all());
    }
    return false;
  }
  // A node ended in the innermost collection.
  void end_node() {
    if (stack_.empty()) return;
    Frame& parent = stack_.back();
    if (parent.map) parent.expect_key = !parent.expect_key;
  }

  void leaf(const YAML::Mark& mark, const std::string* scalar) {
    if (begin_node()) {
      Frame& parent = stack_.back();
      parent.key_plain = scalar != nullptr;
      parent.key = scalar != nullptr ? *scalar : std::string();
      parent.key_mark = mark;
      if (parent.role == Role::kTop) check_top_key(scalar, mark);
    }
    end_node();
  }

  void open(const YAML::Mark& mark, bool map) {
    Frame frame;
    frame.map = map;
    frame.mark = mark;
    if (stack_.empty()) {
      frame.role = map ? Role::kTop : Role::kOther;
    } else {
      const bool is_key = begin_node();
      Frame& parent = stack_.back();
      frame.is_key = is_key || parent.is_key;
      frame.component = next_component();
      if (parent.map && !is_key) frame.mark = parent.key_mark;
      if (is_key) {
        // A collection as a key: not a plain name (the document's check says so).
        parent.key_plain = false;
        parent.key.clear();
        if (parent.role == Role::kTop) top_checked_ = true;
      } else if (!frame.is_key && parent.key_plain) {
        if (parent.role == Role::kTop && !map && parent.key == "cuts") frame.role = Role::kCuts;
        if (parent.role == Role::kCut && !map && parent.key == "keyframes") frame.role = Role::kKeyframes;
      }
      if (parent.role == Role::kCuts && !frame.is_key && map) frame.role = Role::kCut;
    }
    if (int(stack_.size()) + 1 > kMaxScenarioDepth) {
      std::string path = path_of_next();
      if (path.size() > 120) path = path.substr(0, 120) + "...";
      ctx_.fail(mark, path, "lists and mappings are nested more than " + std::to_string(kMaxScenarioDepth) +
                                " levels deep (a scenario needs a handful)");
    }
    stack_.push_back(std::move(frame));
  }

  void close() {
    stack_.pop_back();
    end_node();
  }

  // An unknown or repeated top-level key, as the document's Map would say it.
  void check_top_key(const std::string* name, const YAML::Mark& mark) {
    if (top_checked_) return;
    if (name == nullptr) {  // not a plain name: left to the document's check
      top_checked_ = true;
      return;
    }
    if (std::find(top_keys_.begin(), top_keys_.end(), *name) == top_keys_.end()) {
      std::vector<std::string> allowed(top_keys_.begin(), top_keys_.end());
      ctx_.fail(mark, *name, "unknown key '" + *name + "'; allowed keys here: " + join(allowed));
    }
    for (const auto& [seen, seen_mark] : seen_top_keys_)
      if (seen == *name)
        ctx_.fail(mark, *name, "key given twice (first at line " + std::to_string(seen_mark.line + 1) + ")");
    seen_top_keys_.emplace_back(*name, mark);
  }

  [[noreturn]] void fail_keyframes(const Frame& keyframes, const std::string& what) const {
    std::string path;
    for (const Frame& f : stack_) path = child_path(path, f.component);
    ctx_.fail(keyframes.mark, path, what);
  }

  const Context& ctx_;
  std::vector<std::string_view> top_keys_;
  std::vector<Frame> stack_;
  std::size_t keyframes_ = 0;
  bool top_checked_ = false;
  std::vector<std::pair<std::string, YAML::Mark>> seen_top_keys_;
};

// Reads a string in place (std::istringstream would copy it).
class StringViewBuf : public std::streambuf {
 public:
  explicit StringViewBuf(const std::string& text) {
    char* begin = const_cast<char*>(text.data());  // only read: the get area
    setg(begin, begin, begin + text.size());
  }
};

// Runs the scan over the text; malformed YAML gets parse_text's message.
void scan_scenario(const Context& ctx, const std::string& text, std::span<SectionReader* const> sections) {
  ScenarioScan scan(ctx, top_level_keys(sections));
  StringViewBuf buffer(text);
  std::istream in(&buffer);
  try {
    YAML::Parser parser(in);
    parser.HandleNextDocument(scan);
  } catch (const YAML::Exception&) {
    // Malformed text: reported by parse_text, which meets the same error.
  }
}

// An image terrain whose file is read once the rest of the document is
// checked (a mistake anywhere is reported before a large image is decoded).
struct PendingImage {
  Field image;
  Field size;
  std::optional<Resolution> resolution;
};

// Cells of at least kMinCellM (core/grid.hpp), reported at size_m once the
// resolution is known.
void check_cells(const Field& size, const Scenario& sc) {
  const double cell = std::min(sc.size_x_m / sc.resolution.cols, sc.size_z_m / sc.resolution.rows);
  if (!(cell >= kMinCellM))
    size.fail("the cells would be " + format_number(cell) +
              " m (size_m / resolution); a cell must be at least 1e-6 m");
}

// The terrain block; a generator terrain is complete on return, an image
// terrain is returned to read_terrain_image.
std::optional<PendingImage> parse_terrain(const Context& ctx, const Field& field, Scenario& sc) {
  const Map terrain(field, {"image", "generator", "resolution", "size_m", "origin_m",
                            "full_scale_m", "mound", "box", "plane"});
  const std::optional<Field> image = terrain.get("image");
  const std::optional<Field> generator = terrain.get("generator");
  if (image && generator)
    ctx.fail(field.key_mark(), field.path(), "give either 'image' or 'generator', not both");
  if (!image && !generator)
    ctx.fail(field.key_mark(), field.path(),
             "missing 'image' or 'generator' (one of them is required)");

  // Extent, origin and full scale.
  const Field size = terrain.require("size_m");
  size.numbers(2);  // the shape first: a list of two numbers
  const std::vector<Field> sides = size.elements();
  sc.size_x_m = sides[0].in(range("terrain.size_m[0]"));
  sc.size_z_m = sides[1].in(range("terrain.size_m[1]"));
  if (const auto origin = terrain.get("origin_m")) sc.origin_m = origin->vec3();
  sc.full_scale_m = terrain.require("full_scale_m").in(range("terrain.full_scale_m"));

  std::optional<Resolution> resolution;
  if (const auto res = terrain.get("resolution")) resolution = parse_resolution_field(*res);

  std::optional<GeneratorKind> kind;
  if (generator)
    kind = generator->choice({GeneratorKind::kMound, GeneratorKind::kBox, GeneratorKind::kPlane},
                             "generator");

  // Generator parameter blocks are only accepted with their generator.
  for (std::string_view block : {"mound", "box", "plane"}) {
    if (!terrain.has(block)) continue;
    const Field f = *terrain.get(block);
    if (!kind || to_string(*kind) != block)
      ctx.fail(f.key_mark(), f.path(),
               "the '" + std::string(block) + "' block is only allowed with 'generator: " +
                   std::string(block) + "'");
  }

  if (generator) {
    if (!resolution)
      ctx.fail(field.key_mark(), child_path(field.path(), "resolution"),
               "missing required field 'resolution' (required with a generator)");
    sc.resolution = *resolution;
    check_cells(size, sc);
    Generator gen = default_generator(*kind, grid_spec(sc));
    if (const auto m = terrain.get("mound")) {
      const Map mound(*m, {"centre_m", "radius_m"});
      read_xz(mound, "centre_m", gen.mound.centre_x_m, gen.mound.centre_z_m);
      if (const auto r = mound.get("radius_m")) gen.mound.radius_m = r->in(range("terrain.mound.radius_m"));
    }
    if (const auto b = terrain.get("box")) {
      const Map box(*b, {"min_m", "max_m"});
      read_xz(box, "min_m", gen.box.min_x_m, gen.box.min_z_m);
      read_xz(box, "max_m", gen.box.max_x_m, gen.box.max_z_m);
      if (!(gen.box.min_x_m <= gen.box.max_x_m) || !(gen.box.min_z_m <= gen.box.max_z_m))
        b->fail("min_m must be <= max_m in X and in Z");
    }
    if (const auto p = terrain.get("plane")) {
      const Map plane(*p, {"height_m"});
      if (const auto h = plane.get("height_m")) gen.plane.height_m = h->in(range("terrain.plane.height_m"));
    }
    const std::string problem = validate(gen);
    if (!problem.empty()) generator->fail(problem);
    sc.generator = gen;
    return std::nullopt;
  }
  return PendingImage{*image, size, resolution};
}

// Why a path's status cannot be read (exists() failed with ec): a
// symbolic link loop, or the system's reason.
std::string unresolvable(const std::error_code& ec) {
  if (ec == std::errc::too_many_symbolic_link_levels)
    return "cannot be resolved: it is a symbolic link loop (or a chain of more links than the system "
           "follows)";
  return "cannot be resolved: " + ec.message();
}

// For a path that does not exist: ", a symbolic link to 'TARGET', which does
// not exist" when it is a dangling link, else nothing.
std::string dangling_link(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_symlink(path, ec)) return {};
  const std::filesystem::path target = std::filesystem::read_symlink(path, ec);
  if (ec) return {};
  return " (a symbolic link to '" + target.string() + "', which does not exist)";
}

// Image terrain: the path is relative to the scenario's folder.
void read_terrain_image(const PendingImage& pending, const std::filesystem::path& base_dir,
                        Scenario& sc) {
  const Field& image = pending.image;
  const std::string relative = image.text();
  if (relative.empty()) image.fail("the image path is empty");
  std::filesystem::path path(relative);
  if (path.is_relative()) path = base_dir / path;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    if (ec) image.fail("image file '" + path.string() + "' " + unresolvable(ec));
    image.fail("image file '" + path.string() + "' not found" + dangling_link(path) +
               " (relative paths are read from the scenario file's folder)");
  }
  if (!std::filesystem::is_regular_file(path, ec))
    image.fail("image '" + path.string() + "' is not a regular file");
  try {
    sc.image = read_png(path);
  } catch (const InputError& e) {
    image.fail(std::string("cannot read image: ") + e.what());
  }
  sc.image_path = path;
  if (pending.resolution) {
    sc.resolution = *pending.resolution;
  } else {
    check_resolution(image, sc.image.cols, sc.image.rows);
    sc.resolution = {sc.image.cols, sc.image.rows};
  }
  check_cells(pending.size, sc);
}

// One parsed cut, with the fields that later checks report against.
struct ParsedCut {
  Motion motion;
  Field name;
  Field last_t;
};

ParsedCut parse_cut(const Field& field) {
  const Map cut(field, {"name", "keyframes"});
  Motion motion;
  const Field name = cut.require("name");
  motion.name = name.text();
  if (!valid_cut_name(motion.name))
    name.fail("cut name '" + motion.name +
              "' must be non-empty and use only letters, digits, '_', '-' and '.'");

  const Field frames = cut.require("keyframes");
  if (frames.is_sequence() && frames.node().size() > kMaxKeyframesPerCut)
    frames.context().fail(frames.key_mark(), frames.path(), too_many_keyframes_in_cut());
  const std::vector<Field> items = frames.elements();
  if (items.empty()) frames.fail("a cut needs at least one keyframe");
  std::optional<Field> last_t;
  for (const Field& item : items) {
    const Map kf(item, {"t_s", "position_m", "rotation_deg"});
    Keyframe k;
    const Field t = kf.require("t_s");
    k.t_s = t.in(range("cuts[].keyframes[].t_s"));
    if (!motion.keyframes.empty() && !(k.t_s > motion.keyframes.back().t_s))
      t.fail("t_s " + format_number(k.t_s) + " is not after the previous keyframe's " +
             format_number(motion.keyframes.back().t_s) + " (times must strictly increase)");
    k.pose.position_m = kf.require("position_m").vec3();
    Vec3 euler{};
    kf.read_vec3("rotation_deg", euler);
    k.pose.orientation = quat_from_euler_deg(euler);
    motion.keyframes.push_back(k);
    last_t = t;
  }
  return {std::move(motion), name, *last_t};
}

Scenario parse_document(const Context& ctx, const YAML::Node& root,
                        const std::filesystem::path& source_name,
                        std::span<SectionReader* const> sections) {
  Scenario sc;
  sc.source_path = source_name;
  sc.name = source_name.stem().string();

  const Field top_field(ctx, root, "", YAML::Mark());
  if (root.IsNull() || !root.IsDefined())
    ctx.fail(YAML::Mark(), "", "the scenario is empty; expected a mapping with 'terrain', "
                                      "'blade' and 'cuts'");
  const Map top(top_field, top_level_keys(sections));

  if (const auto f = top.get("name")) {
    sc.name = f->text();
    if (sc.name.empty()) f->fail("the name is empty");
  }
  if (const auto f = top.get("description")) sc.description = f->text();

  if (const auto f = top.get("representation"))
    sc.representation =
        f->choice({Representation::kSurface, Representation::kColumns}, "representation");
  if (const auto f = top.get("rate_hz")) {
    sc.rate_hz = f->in(range("rate_hz"));
  }

  const Map blade(top.require("blade"), {"length_m", "rake_angle_deg", "edge_thickness_m", "height_m", "bucket"});
  sc.blade.length_m = blade.require("length_m").in(range("blade.length_m"));
  if (const auto f = blade.get("rake_angle_deg")) sc.blade.rake_angle_deg = f->in(range("blade.rake_angle_deg"));
  if (const auto f = blade.get("edge_thickness_m"))
    sc.blade.edge_thickness_m = f->in(range("blade.edge_thickness_m"));
  const std::optional<Field> height_field = blade.get("height_m");
  if (height_field) sc.blade.height_m = height_field->in(range("blade.height_m"));
  const std::optional<Field> bucket_field = blade.get("bucket");
  if (const auto& b = bucket_field) {
    // A bucket behind the edge (blade.hpp, BucketSpec): its floor and back.
    const Map bucket(*b, {"depth_m", "height_m"});
    sc.blade.bucket.depth_m = bucket.require("depth_m").in(range("blade.bucket.depth_m"));
    sc.blade.bucket.height_m = bucket.require("height_m").in(range("blade.bucket.height_m"));
    if (height_field)
      height_field->fail("a bucket's height is its own (blade.bucket.height_m): leave blade.height_m out with a bucket");
  }

  const std::optional<PendingImage> image = parse_terrain(ctx, top.require("terrain"), sc);

  // Cuts: unique names, and a bounded number of steps each.
  const Field cuts = top.require("cuts");
  const std::vector<Field> cut_fields = cuts.elements();
  if (cut_fields.empty()) cuts.fail("the list of cuts is empty; give at least one cut");
  // The keyframe caps before any keyframe is read (the scan of the text saw
  // the lists written out; this also counts lists given by alias).
  std::size_t keyframes = 0;
  for (const Field& cf : cut_fields) {
    const std::optional<Field> frames = cf.lookup("keyframes");
    if (!frames || !frames->is_sequence()) continue;
    // At the key's line, as the scan reports it (an aliased list's own line is elsewhere).
    if (frames->node().size() > kMaxKeyframesPerCut)
      ctx.fail(frames->key_mark(), frames->path(), too_many_keyframes_in_cut());
    keyframes += frames->node().size();
    if (keyframes > kMaxKeyframes) ctx.fail(frames->key_mark(), frames->path(), too_many_keyframes_in_all());
  }
  std::vector<YAML::Mark> name_marks;
  for (const Field& cf : cut_fields) {
    ParsedCut cut = parse_cut(cf);
    const int existing = sc.find_cut(cut.motion.name);
    if (existing >= 0)
      cut.name.fail("duplicate cut name '" + cut.motion.name + "' (first defined at line " +
                    std::to_string(name_marks[std::size_t(existing)].line + 1) + ")");
    const double steps = std::round(cut.motion.duration_s() * sc.rate_hz);
    if (steps > kMaxStepsPerCut)
      cut.last_t.fail("the cut lasts " + format_number(cut.motion.duration_s()) + " s, " +
                      format_number(steps) + " steps at rate_hz; more than 1e8 steps is absurd");
    name_marks.push_back(cut.name.mark());
    sc.cuts.push_back(std::move(cut.motion));
  }

  if (const auto f = top.get("sequence")) {
    const std::vector<Field> items = f->elements();
    if (items.empty()) f->fail("the sequence is empty; leave it out to run the cuts as listed");
    for (const Field& item : items) {
      const std::string name = item.text();
      const int index = sc.find_cut(name);
      if (index < 0) {
        std::vector<std::string> names;
        for (const Motion& m : sc.cuts) names.push_back(m.name);
        item.fail("unknown cut '" + name + "'; cuts defined: " + join(names));
      }
      sc.sequence.push_back(index);
    }
  } else {
    for (std::size_t i = 0; i < sc.cuts.size(); ++i) sc.sequence.push_back(int(i));
  }
  if (const double total = sequence_steps(sc); total > kMaxStepsPerRun) {
    const std::string what = "the sequence runs " + format_number(total) +
                             " steps at rate_hz in total; more than 1e8 steps is absurd";
    if (const auto f = top.get("sequence")) f->fail(what);
    top_field.fail(what);
  }

  // The soil: its material (material.hpp: a preset, then fields replacing
  // its values) and what happens to the cut soil (soil.hpp): vanish, or flow
  // to the repose angle.
  if (const auto f = top.get("soil")) {
    std::vector<std::string_view> keys = soil_material_keys();
    keys.insert(keys.end(), {"model", "max_pair_checks_per_step", "edge", "settle"});
    const Map soil(*f, keys);
    if (const auto m = soil.get("model"))
      sc.soil.model = m->choice({SoilModel::kVanish, SoilModel::kFlow}, "soil model");
    read_soil_material(soil, sc.soil.material);
    if (const auto w = soil.get("max_pair_checks_per_step"))
      sc.soil.max_pair_checks_per_step =
          static_cast<std::int64_t>(w->in(range("soil.max_pair_checks_per_step")));
    if (const auto e = soil.get("edge"))
      sc.soil.edge = e->choice({SoilEdge::kWall, SoilEdge::kOpen}, "soil edge");
    if (const auto e = soil.get("settle"))
      sc.soil.settle = e->choice({SoilSettle::kPatches, SoilSettle::kPasses, SoilSettle::kFans}, "soil settle");
    // The flow's settings without a model: the model defaults to vanish,
    // where they do nothing, which is surely not what was meant (an
    // explicit 'model: vanish' keeps them, to compare the two).
    if (!soil.get("model"))
      for (const char* key : {"repose_deg", "max_pair_checks_per_step", "edge", "settle"})
        if (const auto g = soil.get(key))
          g->fail(std::string("given without 'model', which defaults to vanish (the cut soil is deleted, nothing "
                              "slides): add 'model: flow', or 'model: vanish' to keep the soil vanishing"));
  }
  if (bucket_field && sc.soil.model != SoilModel::kFlow)
    bucket_field->fail("a bucket carries the soil it digs, so it needs soil that flows: add 'soil: {model: flow}'");

  // The other layers' sections (e.g. bodies:, haptics:), by their readers.
  for (SectionReader* reader : sections)
    if (const auto f = top.get(reader->key())) reader->read(f->node(), ctx.file());

  if (const auto f = top.get("reference")) {
    const Map reference(*f, {"mound"});
    const Map mound(reference.require("mound"), {"centre_m", "radius_m", "height_m"});
    MoundShape shape;
    const std::vector<double> c = mound.require("centre_m").numbers(2);
    shape.centre_x_m = c[0];
    shape.centre_z_m = c[1];
    shape.radius_m = mound.require("radius_m").in(range("reference.mound.radius_m"));
    shape.height_m = mound.require("height_m").in(range("reference.mound.height_m"));
    sc.reference_mound = shape;
  }

  // Last, once everything else is known to be valid: the (possibly large) image.
  if (image) read_terrain_image(*image, source_name.parent_path(), sc);
  return sc;
}

[[noreturn]] void fail_option(std::string_view option, const std::string& what) {
  throw InputError(std::string(option) + ": " + what);
}

}  // namespace

std::span<const yaml::Range> scenario_ranges() { return kRanges; }

int Scenario::find_cut(std::string_view cut_name) const {
  for (std::size_t i = 0; i < cuts.size(); ++i)
    if (cuts[i].name == cut_name) return int(i);
  return -1;
}

std::vector<std::string> Scenario::sequence_names() const {
  std::vector<std::string> names;
  for (int i : sequence) names.push_back(cuts[std::size_t(i)].name);
  return names;
}

Scenario parse_scenario(const std::string& text, const std::filesystem::path& source_name,
                        std::span<SectionReader* const> sections) {
  const Context ctx(source_name.string());
  scan_scenario(ctx, text, sections);
  const YAML::Node root = yaml::parse_text(ctx, text);
  try {
    return parse_document(ctx, root, source_name, sections);
  } catch (const YAML::Exception& e) {
    // Any yaml-cpp error not caught field by field (not expected) still names the place.
    ctx.fail(e.mark, "", "invalid scenario: " + e.msg);
  }
}

Scenario load_scenario(const std::filesystem::path& path,
                       std::span<SectionReader* const> sections) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    if (ec) throw InputError(path.string() + ": " + unresolvable(ec));
    throw InputError(path.string() + ": scenario file not found" + dangling_link(path));
  }
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path.string() + ": not a regular file");
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path.string() + ": cannot read the file size: " + ec.message());
  if (bytes > kMaxScenarioFileBytes)
    throw InputError(path.string() + ": the file is " + std::to_string(bytes) +
                     " bytes; a scenario file is at most 64 MiB");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": error while reading the scenario file");
  return parse_scenario(text.str(), path, sections);
}

Resolution parse_resolution(std::string_view text, std::string_view option_name) {
  auto parse_side = [&](std::string_view s) -> long long {
    long long v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || ptr != s.data() + s.size())
      fail_option(option_name, "expected N or COLSxROWS (e.g. 50 or 64x32), got '" +
                                   std::string(text) + "'");
    return v;
  };
  const std::size_t x = text.find_first_of("xX");
  const long long cols = parse_side(x == std::string_view::npos ? text : text.substr(0, x));
  const long long rows = x == std::string_view::npos ? cols : parse_side(text.substr(x + 1));
  if (cols < 1 || rows < 1)
    fail_option(option_name, "each side must be at least 1, got '" + std::string(text) + "'");
  if (cols > kMaxGridSide || rows > kMaxGridSide)
    fail_option(option_name, "'" + std::string(text) + "' is absurd: at most " +
                                 std::to_string(kMaxGridSide) + " samples per side");
  if (cols * rows > kMaxScenarioSamples)
    fail_option(option_name, "'" + std::string(text) + "' is absurd: more than 2^28 samples");
  return {int(cols), int(rows)};
}

std::vector<std::string> parse_name_list(std::string_view text, std::string_view option_name) {
  std::vector<std::string> names;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string_view item =
        text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    while (!item.empty() && std::isspace(static_cast<unsigned char>(item.front()))) item.remove_prefix(1);
    while (!item.empty() && std::isspace(static_cast<unsigned char>(item.back()))) item.remove_suffix(1);
    if (item.empty())
      fail_option(option_name, "empty name in '" + std::string(text) +
                                   "'; expected names separated by commas, e.g. A,B,C");
    names.emplace_back(item);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return names;
}

void apply_overrides(Scenario& scenario, std::optional<Resolution> resolution,
                     std::optional<Representation> representation,
                     std::optional<std::vector<std::string>> sequence) {
  if (resolution) {
    const long long cols = resolution->cols;
    const long long rows = resolution->rows;
    if (cols < 1 || rows < 1 || cols > kMaxGridSide || rows > kMaxGridSide ||
        cols * rows > kMaxScenarioSamples)
      fail_option("--resolution", std::to_string(cols) + "x" + std::to_string(rows) +
                                      " is outside [1, 65536] per side or 2^28 in total");
    scenario.resolution = *resolution;
  }
  if (representation) scenario.representation = *representation;
  if (sequence) {
    if (sequence->empty()) fail_option("--sequence", "the sequence is empty");
    std::vector<int> indices;
    for (const std::string& name : *sequence) {
      const int index = scenario.find_cut(name);
      if (index < 0) {
        std::vector<std::string> names;
        for (const Motion& m : scenario.cuts) names.push_back(m.name);
        fail_option("--sequence", "unknown cut '" + name + "' (scenario " +
                                      scenario.source_path.string() + " defines: " + join(names) +
                                      ")");
      }
      indices.push_back(index);
    }
    scenario.sequence = std::move(indices);
    if (const double total = sequence_steps(scenario); total > kMaxStepsPerRun)
      fail_option("--sequence", "the sequence runs " + format_number(total) +
                                    " steps in total; more than 1e8 steps is absurd");
  }
}

SimParams sim_params(const Scenario& scenario, std::optional<double> rate_hz) {
  SimParams params;
  params.grid = grid_spec(scenario);
  params.representation = scenario.representation;
  params.rate_hz = rate_hz.value_or(scenario.rate_hz);
  params.blade = scenario.blade;
  params.soil = scenario.soil;
  return params;
}

GridSpec grid_spec(const Scenario& scenario) {
  GridSpec spec;
  spec.cols = scenario.resolution.cols;
  spec.rows = scenario.resolution.rows;
  spec.size_x_m = scenario.size_x_m;
  spec.size_z_m = scenario.size_z_m;
  spec.origin_m = scenario.origin_m;
  spec.full_scale_m = scenario.full_scale_m;
  return spec;
}

std::vector<float> build_initial_heights(const Scenario& scenario) {
  const GridSpec spec = grid_spec(scenario);
  if (scenario.generator) return generate_heights(spec, *scenario.generator);

  // Image terrain: resample to the grid, then scale brightness to metres.
  const Image& source = scenario.image;
  const Image resized = (source.cols == spec.cols && source.rows == spec.rows)
                            ? source
                            : resample(source, spec.cols, spec.rows);
  std::vector<float> heights(resized.values.size());
  const float scale = static_cast<float>(scenario.full_scale_m);
  for (std::size_t i = 0; i < heights.size(); ++i) heights[i] = resized.values[i] * scale;
  return heights;
}

}  // namespace terracut::io
