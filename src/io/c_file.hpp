// Internal to the io layer: what the readers and writers of binary files
// (image.cpp, npy.cpp) share.
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace terracut::io::detail {

// A path in quotes, for messages.
inline std::string quoted(const std::filesystem::path& path) {
  std::string s = path.string();
  s.insert(s.begin(), '\'');
  s.push_back('\'');
  return s;
}

// A C stream closed when it goes out of scope.
struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace terracut::io::detail
