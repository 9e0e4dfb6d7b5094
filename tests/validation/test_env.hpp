// What the validation tests read from the environment: how many random
// cases to draw, and from which seed.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>

namespace terracut::validation {

// The environment variable `name` as a whole number in [0, most], or
// fallback when it is not set. A variable set to anything else is an error
// (the test fails naming it), not a quiet default.
inline long whole_from_env(const char* name, long fallback, long most) {
  const char* text = std::getenv(name);
  if (text == nullptr) return fallback;
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || value < 0 || value > most) {
    ADD_FAILURE() << name << "=" << text << " is not a whole number in [0, " << most << "]";
    return fallback;
  }
  return value;
}

}  // namespace terracut::validation
