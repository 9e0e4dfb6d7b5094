// OpenGL contexts for the viewer: a headless one (EGL, surfaceless Mesa
// platform: no X display needed) and an offscreen framebuffer to draw into
// and read back.
#pragma once

#include <epoxy/gl.h>

#include <stdexcept>
#include <string>

#include "../exit_codes.hpp"
#include "png_rgb.hpp"

namespace terracut::viewer {

/// Thrown when no OpenGL 3.3 core context can be made (no EGL, no Mesa
/// surfaceless platform, no display); the message says which step failed.
class ContextUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Exit status of terracut-viewer when no OpenGL context can be made (tests
/// skip on it instead of failing): the programs' table, exit_codes.hpp.
inline constexpr int kExitNoContext = apps::kExitNoContext;

/// An OpenGL 3.3 core context without any window or display: EGL on
/// EGL_PLATFORM_SURFACELESS_MESA, made current with no surface. Draw into a
/// Framebuffer.
class HeadlessContext {
 public:
  /// Throws ContextUnavailable naming the EGL step that failed.
  HeadlessContext();
  ~HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
};

/// GL_RENDERER and GL_VERSION of the current context, e.g. "llvmpipe (...) | 4.5 (Core Profile) Mesa".
std::string describe_current_context();

/// An offscreen colour + depth target of a fixed size, optionally
/// multisampled (resolved into a single-sample target on read-back).
class Framebuffer {
 public:
  /// samples: 0 or 1 for none, else the MSAA sample count (clamped to GL_MAX_SAMPLES).
  Framebuffer(int width, int height, int samples);
  ~Framebuffer();
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  /// Binds the framebuffer to draw into.
  void bind() const;
  /// Resolves and reads the pixels back, top row first.
  RgbImage read() const;
  /// Resolves (when multisampled) and copies the picture into the window's
  /// default framebuffer of the same size: multisampling in a window whose
  /// visual has none (a virtual X server).
  void blit_to_default() const;

 private:
  int width_, height_, samples_;
  GLuint fbo_ = 0, color_ = 0, depth_ = 0;
  GLuint resolve_fbo_ = 0, resolve_color_ = 0;
};

}  // namespace terracut::viewer
