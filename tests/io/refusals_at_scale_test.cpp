// Refusals at scale: inputs whose size claims would take gigabytes or write
// terabytes are refused before any large allocation, with an error naming
// the limit -- a terrain past the sample cap (scenario, command-line
// override, core grid), an image whose header claims 2^31 pixels, cuts and
// sequences that would write terabytes of output. Each test runs in its own
// process (gtest_discover_tests), so the peak resident memory measures it alone.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../support/peak_memory.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/generators.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::io {
namespace {

using test::peak_rss_bytes;
using test::small_growth;

std::string scenario_text(const std::string& terrain, const std::string& cuts = "", const std::string& extra = "") {
  return "rate_hz: 1000\nblade: {length_m: 0.5}\nterrain:\n" + terrain + "cuts:\n" +
         (cuts.empty() ? "  - name: a\n    keyframes:\n      - {t_s: 0, position_m: [0.1, 0.2, 0.4]}\n"
                             "      - {t_s: 1, position_m: [0.9, 0.2, 0.4]}\n"
                       : cuts) +
         extra;
}
const std::string kPlane = "  generator: plane\n  size_m: [1, 1]\n  full_scale_m: 0.4\n";

// The message of the InputError that parsing text throws ("" if none), and
// the growth of the peak resident memory meanwhile.
std::string refusal(const std::string& text, std::int64_t* grew) {
  const std::int64_t before = peak_rss_bytes();
  std::string message;
  try {
    parse_scenario(text, "big.yaml");
  } catch (const InputError& e) {
    message = e.what();
  }
  *grew = peak_rss_bytes() - before;
  return message;
}

TEST(RefusalsAtScale, ATerrainPastTheSampleCapIsRefusedBeforeItIsBuilt) {
  std::int64_t grew = 0;
  // 16385 x 16384 = 2^28 + 16384 samples: 3 GiB of float layers.
  const std::string m = refusal(scenario_text(kPlane + "  resolution: [16385, 16384]\n"), &grew);
  EXPECT_NE(m.find("big.yaml:"), std::string::npos) << m;
  EXPECT_NE(m.find("terrain.resolution"), std::string::npos) << m;
  EXPECT_NE(m.find("2^28 samples"), std::string::npos) << m;
  EXPECT_LT(grew, small_growth(16));
}

TEST(RefusalsAtScale, ATerrainAtTheCapIsReadWithoutCommittingItsMemory) {
  // Exactly 2^28 samples is allowed; reading the scenario builds nothing
  // (the heights are built by build_initial_heights, when a run starts).
  const std::int64_t before = peak_rss_bytes();
  const Scenario sc = parse_scenario(scenario_text(kPlane + "  resolution: 16384\n"), "cap.yaml");
  EXPECT_EQ(std::int64_t(sc.resolution.cols) * sc.resolution.rows, kMaxScenarioSamples);
  EXPECT_LT(peak_rss_bytes() - before, small_growth(16));
}

TEST(RefusalsAtScale, AResolutionOverridePastTheCapIsRefused) {
  Scenario sc = parse_scenario(scenario_text(kPlane + "  resolution: 8\n"), "small.yaml");
  const std::int64_t before = peak_rss_bytes();
  try {
    apply_overrides(sc, Resolution{65536, 65536}, std::nullopt, std::nullopt);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--resolution"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2^28"), std::string::npos) << e.what();
  }
  try {
    parse_resolution("65536x65536");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2^28 samples"), std::string::npos) << e.what();
  }
  EXPECT_LT(peak_rss_bytes() - before, small_growth(16));
}

TEST(RefusalsAtScale, CoreGridsPastTheirCapAreRefusedBeforeAllocating) {
  // 65536 x 32768 = 2^31 samples: 8 GiB of floats for one layer.
  GridSpec spec;
  spec.cols = 65536;
  spec.rows = 32768;
  const std::int64_t before = peak_rss_bytes();
  try {
    (void)generate_heights(spec, default_generator(GeneratorKind::kPlane, spec));
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(format_number(kMaxGridSamples)), std::string::npos) << e.what();
  }
  // A negative side would make the sample count wrap to an absurd size.
  spec.cols = -4;
  spec.rows = 3;
  EXPECT_THROW((void)generate_heights(spec, default_generator(GeneratorKind::kPlane, grid_of_cells(4, 3, 0.1))),
               InputError);
  EXPECT_LT(peak_rss_bytes() - before, small_growth(16));
}

// Cells of 1e-300 m made every cell coordinate infinite (undefined
// conversions to int in the traversal; found by the scenario fuzz target):
// a cell must be at least kMinCellM, in the scenario and in core.
TEST(RefusalsAtScale, AbsurdlySmallCellsAreRefusedNamingTheLimit) {
  std::int64_t grew = 0;
  const std::string m = refusal(
      scenario_text("  generator: plane\n  size_m: [1e-300, 1]\n  full_scale_m: 0.4\n  resolution: 8\n"), &grew);
  EXPECT_NE(m.find("big.yaml:5: terrain.size_m:"), std::string::npos) << m;
  EXPECT_NE(m.find("at least 1e-6 m"), std::string::npos) << m;
  EXPECT_NO_THROW(parse_scenario(scenario_text("  generator: plane\n  size_m: [8e-6, 1]\n  full_scale_m: 0.4\n"
                                               "  resolution: 8\n"),
                                 "micro.yaml"));  // cells of exactly 1e-6 m
  GridSpec spec = grid_of_cells(4, 4, 1e-7);
  EXPECT_NE(validate(spec).find(">= 1e-6 m"), std::string::npos) << validate(spec);
  spec = grid_of_cells(4, 4, kMinCellM);
  EXPECT_EQ(validate(spec), "");
}

std::vector<std::uint8_t> chunk(const char* type, const std::vector<std::uint8_t>& data) {
  std::vector<std::uint8_t> out;
  auto be32 = [&](std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(std::uint8_t(v >> s));
  };
  be32(std::uint32_t(data.size()));
  for (int i = 0; i < 4; ++i) out.push_back(std::uint8_t(type[i]));
  for (std::uint8_t b : data) out.push_back(b);
  const std::uint32_t crc =
      std::uint32_t(::crc32(::crc32(0L, reinterpret_cast<const Bytef*>(type), 4), data.data(), uInt(data.size())));
  be32(crc);
  return out;
}

TEST(RefusalsAtScale, AnImageWhoseHeaderClaims2To31PixelsIsRefusedBeforeAllocating) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "terracut_scale";
  std::filesystem::create_directories(dir);
  // 65536 x 32768 grey pixels claimed by a file of a hundred bytes.
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const std::vector<std::uint8_t> ihdr = {0, 1, 0, 0, 0, 0, 0x80, 0, 8, 0, 0, 0, 0};
  for (const auto& c : {chunk("IHDR", ihdr), chunk("IDAT", {0x78, 0x9c, 0x03, 0, 0, 0, 0, 1}), chunk("IEND", {})})
    for (std::uint8_t b : c) png.push_back(b);
  std::ofstream(dir / "liar.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  std::ofstream(dir / "liar.yaml") << scenario_text("  image: liar.png\n  size_m: [1, 1]\n  full_scale_m: 0.4\n");
  const std::int64_t before = peak_rss_bytes();
  try {
    load_scenario(dir / "liar.yaml");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("terrain.image"), std::string::npos) << m;
    EXPECT_NE(m.find("2^30 pixels"), std::string::npos) << m;
  }
  EXPECT_LT(peak_rss_bytes() - before, small_growth(16));
}

TEST(RefusalsAtScale, CutsThatWouldWriteTerabytesAreRefused) {
  std::int64_t grew = 0;
  // A cut of 1e9 s at 1 MHz: 1e15 steps, a contact.csv of about 200 PB.
  const std::string one = refusal(
      "rate_hz: 1000000\nblade: {length_m: 0.5}\nterrain:\n" + kPlane + "  resolution: 8\ncuts:\n" +
          "  - name: long\n    keyframes:\n      - {t_s: 0, position_m: [0.1, 0.2, 0.4]}\n"
          "      - {t_s: 1000000000, position_m: [0.9, 0.2, 0.4]}\n",
      &grew);
  EXPECT_NE(one.find("cuts[0].keyframes[1].t_s"), std::string::npos) << one;
  EXPECT_NE(one.find("more than 1e8 steps"), std::string::npos) << one;
  EXPECT_LT(grew, small_growth(16));

  // Each cut within the cap, the sequence far beyond it: 5000 runs of a
  // 1e5-step cut (5e8 steps, about 100 GB of contact.csv).
  std::string sequence = "sequence: [";
  for (int i = 0; i < 5000; ++i) sequence += i == 0 ? "a" : ", a";
  sequence += "]\n";
  const std::string many = refusal(
      scenario_text(kPlane + "  resolution: 8\n",
                    "  - name: a\n    keyframes:\n      - {t_s: 0, position_m: [0.1, 0.2, 0.4]}\n"
                    "      - {t_s: 100, position_m: [0.9, 0.2, 0.4]}\n",
                    sequence),
      &grew);
  EXPECT_NE(many.find(": sequence:"), std::string::npos) << many;
  EXPECT_NE(many.find("more than 1e8 steps"), std::string::npos) << many;
  EXPECT_LT(grew, small_growth(16));

  // The same through the command line's --sequence.
  Scenario sc = parse_scenario(scenario_text(kPlane + "  resolution: 8\n",
                                             "  - name: a\n    keyframes:\n      - {t_s: 0, position_m: [0.1, 0.2, 0.4]}\n"
                                             "      - {t_s: 100, position_m: [0.9, 0.2, 0.4]}\n"),
                               "seq.yaml");
  try {
    apply_overrides(sc, std::nullopt, std::nullopt, std::vector<std::string>(5000, "a"));
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--sequence"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1e8 steps"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace terracut::io
