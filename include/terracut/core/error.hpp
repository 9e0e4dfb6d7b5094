// The one exception type for bad input (files, fields, values). Its message
// names what was wrong: the file, the line, the field or the sample.
#pragma once

#include <stdexcept>
#include <string>

namespace terracut {

class InputError : public std::invalid_argument {
 public:
  explicit InputError(const std::string& message) : std::invalid_argument(message) {}
};

}  // namespace terracut
