// Fuzz target: read_npy. Every input must end in an array or a
// terracut::InputError; an array read holds exactly rows x cols values.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_file.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = terracut::fuzz::input_file(data, size, "npy");
  int rows = -1, cols = -1;
  std::vector<float> values;
  try {
    values = terracut::io::read_npy(path, &rows, &cols);
  } catch (const terracut::InputError&) {
    return 0;
  }
  terracut::fuzz::check(rows >= 0 && cols >= 0, "fuzz_npy", "a shape of two sizes >= 0");
  terracut::fuzz::check(values.size() == std::size_t(rows) * std::size_t(cols), "fuzz_npy", "rows x cols values");
  terracut::fuzz::check(size >= values.size() * sizeof(float), "fuzz_npy", "no more values than the file holds");
  return 0;
}
