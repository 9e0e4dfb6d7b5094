// Output files and folders: the one way terracut's programs create an output
// folder and write a text file, with one error grammar ("PATH: what").
#pragma once

#include <filesystem>
#include <string>

namespace terracut::io {

/// Creates the folder (with parents) when missing. Throws InputError
/// "--out: no output folder given" for an empty path, or "DIR: cannot create
/// the output folder: REASON" (a file of that name exists, permissions, ...).
void make_output_folder(const std::filesystem::path& dir);

/// Writes text to the file (created or replaced). Throws InputError
/// "PATH: cannot create: REASON" or "PATH: write failed: REASON".
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace terracut::io
