// Output files and folders. See files.hpp.
#include "terracut/io/files.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

#include "terracut/core/error.hpp"

namespace terracut::io {

void make_output_folder(const std::filesystem::path& dir) {
  if (dir.empty()) throw InputError("--out: no output folder given");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw InputError(dir.string() + ": cannot create the output folder" +
                     (ec ? ": " + ec.message() : std::string(": a file of that name exists")));
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw InputError(path.string() + ": cannot create: " + std::strerror(errno));
  f << text;
  f.close();
  if (!f) throw InputError(path.string() + ": write failed: " + std::strerror(errno));
}

}  // namespace terracut::io
