#include "gl_context.hpp"

#include <epoxy/egl.h>

#include <algorithm>
#include <cstring>

#include "gl_util.hpp"

namespace terracut::viewer {
namespace {

std::string egl_error(const char* step) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "EGL: %s failed (error 0x%04x)", step, unsigned(eglGetError()));
  return buf;
}

}  // namespace

HeadlessContext::HeadlessContext() {
  // The surfaceless platform needs EGL_MESA_platform_surfaceless (client extension).
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!client_ext || !std::strstr(client_ext, "EGL_MESA_platform_surfaceless"))
    throw ContextUnavailable("EGL: the Mesa surfaceless platform (EGL_MESA_platform_surfaceless) "
                             "is not available; install libegl-mesa0 and libgl1-mesa-dri");
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_platform_display) throw ContextUnavailable("EGL: no eglGetPlatformDisplayEXT");
  EGLDisplay display =
      get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY) throw ContextUnavailable(egl_error("eglGetPlatformDisplayEXT"));
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor))
    throw ContextUnavailable(egl_error("eglInitialize"));
  display_ = display;
  if (!eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(display);
    throw ContextUnavailable(egl_error("eglBindAPI(EGL_OPENGL_API)"));
  }
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  eglChooseConfig(display, config_attribs, &config, 1, &count);
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3,
                                    EGL_CONTEXT_MINOR_VERSION, 3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  EGLContext context = eglCreateContext(display, count > 0 ? config : EGL_NO_CONFIG_KHR,
                                        EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT) {
    std::string m = egl_error("eglCreateContext (OpenGL 3.3 core)");
    eglTerminate(display);
    throw ContextUnavailable(m);
  }
  context_ = context;
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    std::string m = egl_error("eglMakeCurrent without a surface");
    eglDestroyContext(display, context);
    eglTerminate(display);
    throw ContextUnavailable(m);
  }
}

HeadlessContext::~HeadlessContext() {
  EGLDisplay display = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, static_cast<EGLContext>(context_));
  eglTerminate(display);
}

std::string describe_current_context() {
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(renderer ? renderer : "?") + " | " + (version ? version : "?");
}

Framebuffer::Framebuffer(int width, int height, int samples)
    : width_(width), height_(height), samples_(samples) {
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples_ = samples > 1 ? std::min(samples, int(max_samples)) : 0;
  glGenFramebuffers(1, &fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glGenRenderbuffers(1, &color_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  glGenRenderbuffers(1, &depth_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH_COMPONENT24, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("OpenGL: the offscreen framebuffer is incomplete");
  if (samples_ > 0) {
    glGenFramebuffers(1, &resolve_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
    glGenRenderbuffers(1, &resolve_color_);
    glBindRenderbuffer(GL_RENDERBUFFER, resolve_color_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              resolve_color_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("OpenGL: the resolve framebuffer is incomplete");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  check_gl("creating the offscreen framebuffer");
}

Framebuffer::~Framebuffer() {
  glDeleteFramebuffers(1, &fbo_);
  glDeleteRenderbuffers(1, &color_);
  glDeleteRenderbuffers(1, &depth_);
  if (resolve_fbo_) glDeleteFramebuffers(1, &resolve_fbo_);
  if (resolve_color_) glDeleteRenderbuffers(1, &resolve_color_);
}

void Framebuffer::bind() const { glBindFramebuffer(GL_FRAMEBUFFER, fbo_); }

void Framebuffer::blit_to_default() const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
}

RgbImage Framebuffer::read() const {
  GLuint source = fbo_;
  if (samples_ > 0) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
    glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT,
                      GL_NEAREST);
    source = resolve_fbo_;
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, source);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  std::vector<std::uint8_t> bottom_up(std::size_t(width_) * std::size_t(height_) * 3u);
  glReadPixels(0, 0, width_, height_, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data());
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  check_gl("reading the framebuffer back");
  // OpenGL's first row is the bottom one; images start at the top.
  RgbImage image;
  image.cols = width_;
  image.rows = height_;
  image.pixels.resize(bottom_up.size());
  const std::size_t row_bytes = std::size_t(width_) * 3u;
  for (int r = 0; r < height_; ++r)
    std::memcpy(image.pixels.data() + std::size_t(r) * row_bytes,
                bottom_up.data() + std::size_t(height_ - 1 - r) * row_bytes, row_bytes);
  return image;
}

}  // namespace terracut::viewer
