// Small OpenGL helpers: shader programs with readable errors.
#pragma once

#include <epoxy/gl.h>

#include <string>

namespace terracut::viewer {

/// Compiles and links a vertex + fragment shader pair. Throws
/// std::runtime_error with the driver's log, naming `label`, on failure.
GLuint build_program(const char* label, const char* vertex_src, const char* fragment_src);

/// Location of a uniform (-1 when the driver optimised it away).
inline GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

/// Throws std::runtime_error naming `what` when glGetError reports an error.
void check_gl(const char* what);

}  // namespace terracut::viewer
