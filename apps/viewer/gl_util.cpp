#include "gl_util.hpp"

#include <cstdio>
#include <stdexcept>
#include <vector>

namespace terracut::viewer {
namespace {

GLuint compile(const char* label, GLenum type, const char* src) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(std::size_t(n > 0 ? n : 1), '\0');
    glGetShaderInfoLog(s, n, nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error(std::string(label) +
                             (type == GL_VERTEX_SHADER ? " vertex" : " fragment") +
                             " shader: " + log.data());
  }
  return s;
}

}  // namespace

GLuint build_program(const char* label, const char* vertex_src, const char* fragment_src) {
  GLuint vs = compile(label, GL_VERTEX_SHADER, vertex_src);
  GLuint fs = compile(label, GL_FRAGMENT_SHADER, fragment_src);
  GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(std::size_t(n > 0 ? n : 1), '\0');
    glGetProgramInfoLog(p, n, nullptr, log.data());
    glDeleteProgram(p);
    throw std::runtime_error(std::string(label) + " program link: " + log.data());
  }
  return p;
}

void check_gl(const char* what) {
  GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "OpenGL error 0x%04x after ", unsigned(e));
    throw std::runtime_error(std::string(buf) + what);
  }
}

}  // namespace terracut::viewer
