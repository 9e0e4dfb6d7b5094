// The table of ranges of the scenario reader (io/scenario.hpp): every number
// of a scenario file that has a range beyond the toolkit's +-1e9, declared
// once. The reader reads each of them through its entry, and
// tests/io/scenario_ranges_test.cpp tests each entry at both ends and just
// beyond them, so the table, the reader and the tests cannot drift apart.
#pragma once

#include <span>

#include "terracut/io/yaml_reader.hpp"

namespace terracut::io {

/// The scenario's ranges, paths relative to the file's top level.
std::span<const yaml::Range> scenario_ranges();

}  // namespace terracut::io
