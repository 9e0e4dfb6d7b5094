// The normal suite's driver of a fuzz target (built with any compiler, without
// libFuzzer): runs every file of the folders (or files) given through
// LLVMFuzzerTestOneInput, so the checked-in corpus and every crash found
// before stay regression tests. A target with a structure-aware mutator
// (LLVMFuzzerCustomMutator) also gets, for each file, a fixed series of its
// mutations, so the mutator's output is run through the target too (the
// byte-level LLVMFuzzerMutate it may call is a seeded bit flipper here).
//
//   fuzz_scenario_replay tests/fuzz/corpus/scenario [more folders or files]
//
// Exit status 0 when every input ran (a crash or a failed check aborts).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
extern "C" __attribute__((weak)) std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                                                     std::size_t max_size, unsigned int seed);

namespace {

std::mt19937 flipper(12345);

}  // namespace

// libFuzzer's byte-level mutator, for a custom mutator to call: flips a few
// bits (the real one, when linked with libFuzzer, does far more).
extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size) {
  if (size == 0 && max_size > 0) {
    data[0] = std::uint8_t(flipper());
    return 1;
  }
  const int flips = 1 + int(flipper() % 4);
  for (int i = 0; i < flips && size > 0; ++i) data[flipper() % size] ^= std::uint8_t(1u << (flipper() % 8));
  return size;
}

namespace {

constexpr int kMutationsPerFile = 24;

int run_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "%s: cannot open\n", path.c_str());
    return 1;
  }
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  if (LLVMFuzzerCustomMutator != nullptr) {
    const std::size_t max_size = bytes.size() * 2 + 4096;
    for (int k = 0; k < kMutationsPerFile; ++k) {
      std::vector<std::uint8_t> mutated = bytes;
      mutated.resize(max_size);
      const std::size_t size = LLVMFuzzerCustomMutator(mutated.data(), bytes.size(), max_size, unsigned(k));
      if (size > max_size) {
        std::fprintf(stderr, "%s: the mutator returned %zu bytes, more than %zu\n", path.c_str(), size, max_size);
        return 1;
      }
      LLVMFuzzerTestOneInput(mutated.data(), size);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FOLDER_OR_FILE...\n", argv[0]);
    return 2;
  }
  int files = 0;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path arg = argv[i];
    std::vector<std::filesystem::path> paths;
    if (std::filesystem::is_directory(arg)) {
      for (const auto& entry : std::filesystem::recursive_directory_iterator(arg))
        if (entry.is_regular_file()) paths.push_back(entry.path());
      std::sort(paths.begin(), paths.end());
    } else {
      paths.push_back(arg);
    }
    for (const auto& p : paths) {
      if (run_file(p) != 0) return 1;
      ++files;
    }
  }
  if (files == 0) {
    std::fprintf(stderr, "no input files\n");
    return 1;
  }
  std::printf("%d inputs ran\n", files);
  return 0;
}
