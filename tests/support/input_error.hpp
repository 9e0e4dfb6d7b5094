// The message of the InputError a call throws: the tests of bad input check
// that the message names the file, the line and the field.
#pragma once

#include <string>

#include "terracut/core/error.hpp"

namespace terracut::test {

/// The message of the InputError that f() throws; "" when it throws none.
template <typename F>
std::string input_error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace terracut::test
