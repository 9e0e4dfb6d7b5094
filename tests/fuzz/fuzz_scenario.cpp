// Fuzz target: a whole scenario document, read as the programs read it (the
// io reader with the `bodies:` and `haptics:` section readers, the `soil:`
// section its own), then, when it is accepted and small, its terrain built
// and a few steps of each cut simulated.
//
// Every input must end in an accepted scenario or a terracut::InputError;
// any other exception, a crash, a hang or a sanitizer report is a finding.
// An accepted scenario must keep the promises of scenario.hpp (resolution
// within its caps, keyframe times strictly increasing, finite values).
//
// The structure-aware mutator (LLVMFuzzerCustomMutator) keeps the YAML well
// formed: it parses the input and changes one value to NaN, +-inf, a
// negative number, 1e300, 0, ..., or one key to a near miss ("rate_h",
// "Rate_hz", "rate_hz_"), or drops or repeats an entry; input that is not
// YAML goes to libFuzzer's own byte mutator.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "terracut/bullet/bodies_yaml.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/haptics/settings_yaml.hpp"
#include "terracut/io/scenario.hpp"

namespace {

using namespace terracut;

// Terrains up to this many samples are built and stepped (a fuzzer
// execution must stay fast; the size caps themselves are checked above it).
constexpr std::int64_t kMaxSteppedSamples = 4096;
constexpr int kStepsPerCut = 8;

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_scenario: accepted scenario breaks a promise: %s\n", what);
    std::abort();
  }
}

void exercise(const io::Scenario& sc) {
  check(sc.resolution.cols >= 1 && sc.resolution.rows >= 1, "resolution >= 1");
  check(std::int64_t(sc.resolution.cols) * sc.resolution.rows <= io::kMaxScenarioSamples, "sample cap");
  check(std::isfinite(sc.rate_hz) && sc.rate_hz > 0.0, "rate_hz finite and > 0");
  check(std::isfinite(sc.blade.length_m) && sc.blade.length_m > 0.0, "blade length finite and > 0");
  check(!sc.cuts.empty() && !sc.sequence.empty(), "cuts and sequence");
  for (const Motion& m : sc.cuts) {
    check(!m.keyframes.empty(), "a keyframe per cut");
    for (std::size_t i = 1; i < m.keyframes.size(); ++i)
      check(m.keyframes[i].t_s > m.keyframes[i - 1].t_s, "keyframe times increase");
  }
  if (std::int64_t(sc.resolution.cols) * sc.resolution.rows > kMaxSteppedSamples) return;
  std::vector<float> heights = io::build_initial_heights(sc);
  for (float h : heights) check(std::isfinite(h), "initial heights finite");
  const SimParams params = io::sim_params(sc);
  if (!validate(params).empty()) return;  // refused later by the programs, with this message
  Simulation sim(params, std::move(heights));
  for (int index : sc.sequence) {
    const Motion& m = sc.cuts[std::size_t(index)];
    for (int k = 0; k <= kStepsPerCut; ++k) sim.step(m.sample(m.duration_s() * k / kStepsPerCut));
    sim.lift();
  }
  for (std::int64_t i = 0; i < sim.grid().spec().sample_count(); ++i)
    check(std::isfinite(sim.grid().heights()[i]), "heights stay finite");
}

// ---------------------------------------------------------------------------
// The structure-aware mutator.

const char* const kOddNumbers[] = {".nan", ".inf", "-.inf", "-1", "-0.0", "0", "1e300", "-1e300",
                                   "1e-300", "1e9", "1000000001", "2147483648", "65536", "65537",
                                   "268435457", "0x10", "1e", "nan", "+5", "3.5", "~", "[]", "{}"};

std::string near_miss(std::string key, std::mt19937& rng) {
  if (key.empty()) return "x";
  switch (rng() % 6) {
    case 0: key.pop_back(); break;                                      // rate_h
    case 1: key += '_'; break;                                          // rate_hz_
    case 2: key[0] = char(std::toupper(static_cast<unsigned char>(key[0]))); break;  // Rate_hz
    case 3: key.insert(key.begin() + std::ptrdiff_t(rng() % key.size()), 's'); break;
    case 4:
      if (key.size() > 1) std::swap(key[0], key[1]);
      break;
    default: key += "s"; break;
  }
  return key;
}

// Walks the tree; the target-th value or key met is changed. Returns the
// node to put in place of node (itself, changed or not).
struct Mutation {
  std::mt19937 rng;
  long target = 0;
  long seen = 0;
  bool done = false;

  YAML::Node visit(YAML::Node node) {
    if (done) return node;
    if (node.IsScalar() || node.IsNull()) {
      if (seen++ == target) {
        done = true;
        return YAML::Node(std::string(kOddNumbers[rng() % std::size(kOddNumbers)]));
      }
      return node;
    }
    if (node.IsSequence()) {
      YAML::Node out(YAML::NodeType::Sequence);
      for (std::size_t i = 0; i < node.size(); ++i) {
        const bool mine = !done && seen++ == target;
        if (mine) {
          done = true;
          const unsigned what = rng() % 3;
          if (what == 0) continue;                         // drop the element
          out.push_back(YAML::Clone(node[i]));
          if (what == 1) out.push_back(YAML::Clone(node[i]));  // repeat it
          if (what == 2) out.push_back(YAML::Node(std::string(kOddNumbers[rng() % std::size(kOddNumbers)])));
          continue;
        }
        out.push_back(visit(node[i]));
      }
      return out;
    }
    if (node.IsMap()) {
      YAML::Node out(YAML::NodeType::Map);
      for (auto it = node.begin(); it != node.end(); ++it) {
        std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
        if (!done && seen++ == target) {
          done = true;
          const unsigned what = rng() % 4;
          if (what == 0) continue;  // drop the entry
          if (what == 1) key = near_miss(key, rng);
          out[key] = YAML::Clone(it->second);
          continue;
        }
        out[key] = visit(it->second);
      }
      return out;
    }
    return node;
  }
};

long count_nodes(const YAML::Node& node) {
  if (node.IsSequence() || node.IsMap()) {
    long n = 0;
    for (auto it = node.begin(); it != node.end(); ++it)
      n += 1 + count_nodes(node.IsMap() ? it->second : *it);
    return n;
  }
  return 1;
}

}  // namespace

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned int seed) {
  std::mt19937 rng(seed);
  // One time in eight (or when the input is not YAML), libFuzzer's bytes.
  if (rng() % 8 == 0) return LLVMFuzzerMutate(data, size, max_size);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const YAML::Exception&) {
    return LLVMFuzzerMutate(data, size, max_size);
  }
  if (!root.IsMap()) return LLVMFuzzerMutate(data, size, max_size);
  const long nodes = count_nodes(root);
  if (nodes == 0) return LLVMFuzzerMutate(data, size, max_size);  // {}: nothing to change
  Mutation m{rng, 0, 0, false};
  m.target = long(rng() % std::uint32_t(nodes));
  YAML::Emitter out;
  try {
    out << m.visit(root);
  } catch (const YAML::Exception&) {
    return LLVMFuzzerMutate(data, size, max_size);
  }
  if (!out.good() || out.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
  std::memcpy(data, out.c_str(), out.size());
  return out.size();
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  bullet::BodiesReader bodies;
  haptics::SettingsReader settings;
  io::SectionReader* const sections[] = {&bodies, &settings};
  io::Scenario sc;
  try {
    // Relative image paths resolve against the working folder's scenarios/.
    sc = io::parse_scenario(text, "scenarios/fuzz.yaml", sections);
  } catch (const InputError&) {
    return 0;
  }
  try {
    exercise(sc);
  } catch (const InputError&) {
    // Refusals after the reader (e.g. a terrain too small for the blade).
  }
  return 0;
}
