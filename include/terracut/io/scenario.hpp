// Scenario files: a YAML description of one experiment (terrain, terrain
// representation, step rate, blade, and an ordered list of named cuts). The
// full format is documented in docs/scenario-format.md.
//
// Everything is validated at load: every error is a terracut::InputError whose
// message reads "FILE:LINE: field.path: what is wrong" (LINE is 1-based).
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/blade.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/generators.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/io/image.hpp"

namespace YAML {
class Node;
}

namespace terracut::io {

/// A reader of one top-level section of a scenario file that belongs to
/// another layer (`haptics:` to the haptic loop, `bodies:` to the rigid-body
/// engine): the layer that owns the section provides the reader, and the
/// scenario loader hands it the section's value while it reads the file, so
/// its errors carry the file's line numbers. Built with the one YAML
/// toolkit (io/yaml_reader.hpp), so every section has the same errors and
/// limits.
class SectionReader {
 public:
  virtual ~SectionReader() = default;
  /// The section's top-level key, e.g. "haptics".
  virtual std::string_view key() const = 0;
  /// Reads the section's value (called at most once, only when the key is
  /// in the file). file names the scenario in messages. Throws InputError
  /// "FILE:LINE: key.field: what".
  virtual void read(const YAML::Node& value, const std::string& file) = 0;
};

/// Largest accepted total sample count in a scenario (2^28 samples, 3 GiB of
/// float layers); more is refused as absurd.
inline constexpr std::int64_t kMaxScenarioSamples = std::int64_t(1) << 28;

/// Largest number of keyframes in one cut: a keyframe a millisecond for 100 s.
/// yaml-cpp holds the whole document in memory, about 6 kB per keyframe, so
/// the caps bound what a scenario file can make the reader allocate; they
/// are checked while the text is scanned, before the document is built.
inline constexpr std::size_t kMaxKeyframesPerCut = 100'000;
/// Largest number of keyframes in all the cuts of a scenario together.
inline constexpr std::size_t kMaxKeyframes = 200'000;
/// Deepest nesting of lists and mappings in a scenario file (a scenario
/// needs a handful of levels; deeper is refused while the text is scanned).
inline constexpr int kMaxScenarioDepth = 64;

/// A grid resolution: samples along X (cols) and along Z (rows).
struct Resolution {
  int cols = 0;  ///< samples along +X, in [1, 65536]
  int rows = 0;  ///< samples along +Z, in [1, 65536]
  bool operator==(const Resolution&) const = default;
};

/// A loaded, validated scenario.
struct Scenario {
  /// The file it was read from (as given to load_scenario), or the source
  /// name given to parse_scenario.
  std::filesystem::path source_path;
  /// Name of the experiment: the `name` field, or the file's stem.
  std::string name;
  /// Free-text description (`description` field), may be empty.
  std::string description;

  // --- Terrain -------------------------------------------------------------
  /// Image terrain: the PNG's path, resolved against the scenario's folder.
  /// Empty when the terrain comes from a generator.
  std::filesystem::path image_path;
  /// Image terrain: the PNG as read at load (values in [0, 1]); empty otherwise.
  Image image;
  /// Generator terrain: the shape; nullopt for image terrain.
  std::optional<Generator> generator;
  /// Grid resolution (the `resolution` field; for an image without one, the
  /// image's own size).
  Resolution resolution{};
  double size_x_m = 1.0;      ///< terrain extent along X, metres, > 0
  double size_z_m = 1.0;      ///< terrain extent along Z, metres, > 0
  Vec3 origin_m{};            ///< world position of the origin corner; y = ground level, metres
  double full_scale_m = 1.0;  ///< height of a white pixel (or generator height), metres, > 0

  // --- Simulation ----------------------------------------------------------
  Representation representation = Representation::kSurface;
  /// The one rate of every run of the scenario (SimParams::rate_hz): steps
  /// per second, Hz, in (0, 1e6]; a haptic loop's too (in [10, 10000]).
  double rate_hz = 1000.0;
  BladeSpec blade{};

  /// The cuts in the order listed; each has >= 1 keyframe with strictly
  /// increasing t_s >= 0 (seconds from the cut's start) and a unique name.
  std::vector<Motion> cuts;
  /// Order in which cuts are run: indices into `cuts` (names may repeat).
  std::vector<int> sequence;

  /// What happens to the soil the blade cuts (`soil:`; docs/scenario-format.md):
  /// vanish (the paper's, the default) or flow.
  SoilFlowParams soil{};

  /// The exact shape the terrain was made from, for error reports
  /// (`reference: mound:`); nullopt when not given.
  std::optional<MoundShape> reference_mound;

  /// Index of the cut with the given name, or -1.
  int find_cut(std::string_view cut_name) const;
  /// The names of the cuts in `sequence`, in order.
  std::vector<std::string> sequence_names() const;
};

/// Reads and validates a scenario file: its own keys, and the sections of
/// `sections` (each read by its reader, after the cuts and the sequence; a
/// top-level key that is neither is refused). Throws terracut::InputError
/// ("FILE:LINE: field: what") on any problem, including a missing file,
/// malformed YAML and a missing or unreadable terrain image.
Scenario load_scenario(const std::filesystem::path& path,
                       std::span<SectionReader* const> sections = {});

/// Parses scenario text as if it were the file `source_name` (used in error
/// messages; relative image paths are resolved against its parent folder).
Scenario parse_scenario(const std::string& text, const std::filesystem::path& source_name,
                        std::span<SectionReader* const> sections = {});

/// Command-line overrides: each given value replaces the scenario's. The
/// sequence is a list of cut names. Throws terracut::InputError naming the
/// option ("--resolution", "--sequence") when a value is invalid.
void apply_overrides(Scenario& scenario, std::optional<Resolution> resolution,
                     std::optional<Representation> representation,
                     std::optional<std::vector<std::string>> sequence);

/// Parses "N" (N x N) or "COLSxROWS" (e.g. "64x32"). Throws
/// terracut::InputError naming option_name when the text is not that, or a
/// side is outside [1, 65536] or the total exceeds kMaxScenarioSamples.
Resolution parse_resolution(std::string_view text, std::string_view option_name = "--resolution");

/// Splits "A,B,C" into names (surrounding spaces trimmed). Throws
/// terracut::InputError naming option_name on an empty name.
std::vector<std::string> parse_name_list(std::string_view text,
                                         std::string_view option_name = "--sequence");

/// The grid parameters of the scenario (resolution, extent, origin, full scale).
GridSpec grid_spec(const Scenario& scenario);

/// The simulation parameters of the scenario (grid, representation, blade)
/// at its rate_hz, or at rate_hz when given (a program's override of the
/// rate for its haptic loop, `terracut haptics --rate`).
SimParams sim_params(const Scenario& scenario, std::optional<double> rate_hz = std::nullopt);

/// The initial heights, rows x cols, row-major, metres: the generator sampled
/// at cell centres, or the image resampled to the resolution (area average when
/// shrinking, bilinear when enlarging) times full_scale_m.
std::vector<float> build_initial_heights(const Scenario& scenario);

}  // namespace terracut::io
