// For fuzz targets of readers that take a path (read_png, read_npy): the
// input written to a file of this process's own, overwritten each time.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace terracut::fuzz {

/// Writes the bytes to $TMPDIR (or /tmp)/terracut-fuzz-<pid>.<extension> and
/// returns its path.
inline std::filesystem::path input_file(const std::uint8_t* data, std::size_t size, const char* extension) {
  const char* tmp = std::getenv("TMPDIR");
  const std::filesystem::path path = std::filesystem::path(tmp != nullptr ? tmp : "/tmp") /
                                     ("terracut-fuzz-" + std::to_string(::getpid()) + "." + extension);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

/// Aborts with the message when ok is false (a broken promise is a finding).
inline void check(bool ok, const char* target, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "%s: %s\n", target, what);
    std::abort();
  }
}

}  // namespace terracut::fuzz
