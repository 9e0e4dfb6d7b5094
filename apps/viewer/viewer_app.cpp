// The viewer application's glue: loading the input, construction, opening
// and closing a session (and its reset and its rebuild from the panel),
// taking the newest frame from the loop, one rendered frame (background,
// scene, ImGui) and the window's main loop. The rest of ViewerApp is in
// viewer_input.cpp (mouse and keys), viewer_panel.cpp (ImGui),
// viewer_scene.cpp (the 3D scene) and viewer_headless.cpp (screenshots and
// the benchmark).
#include "viewer_app.hpp"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <thread>

#include "gl_context.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"
#include "viewer_app_internal.hpp"

namespace terracut::viewer {
namespace {

std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  for (char& ch : e) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return e;
}

}  // namespace

// ---------------------------------------------------------------------------
// Input
// ---------------------------------------------------------------------------

session::Scenario load_input(const ViewerOptions& options) {
  // A bare heightmap (the given extent and full scale, no scripted cuts), or
  // the scenario with its sections (haptics defaults when absent).
  session::Scenario input =
      lower_extension(options.input) == ".png"
          ? session::heightmap_scenario(options.input, options.heightmap_size_m,
                                        options.heightmap_full_scale_m)
          : session::load_scenario(options.input);
  io::apply_overrides(input.base, options.resolution, options.representation, std::nullopt);
  return input;
}

// ---------------------------------------------------------------------------
// Construction and sessions
// ---------------------------------------------------------------------------

ViewerApp::ViewerApp(ViewerOptions options, session::Scenario scenario)
    : options_(std::move(options)),
      base_scenario_(std::move(scenario)),
      scenario_(base_scenario_),
      haptics_(viewer_settings(base_scenario_.haptics)),
      live_(std::make_unique<Live>()) {
  pending_representation_ = base_scenario_.base.representation;
  pending_resolution_[0] = base_scenario_.base.resolution.cols;
  pending_resolution_[1] = base_scenario_.base.resolution.rows;
  pending_haptics_ = haptics_;
  style_.color = options_.color;
  camera_.mode = options_.camera;
}

ViewerApp::~ViewerApp() { close_session(); }

void ViewerApp::open_session(const DriverOptions& driver_options) {
  driver_options_ = driver_options;
  driver_ = std::make_unique<LoopDriver>(scenario_, haptics_, driver_options, &timing_);
  const GridSpec& spec = driver_->spec();
  const std::vector<float>& initial = driver_->initial_heights();
  max_initial_height_m_ = 0.0f;
  for (float h : initial) max_initial_height_m_ = std::max(max_initial_height_m_, h);
  if (!(max_initial_height_m_ > 0.0f)) max_initial_height_m_ = float(spec.full_scale_m);
  style_.height_scale_m = max_initial_height_m_;
  style_.removed_scale_m = 0.5f * max_initial_height_m_;
  style_.contour_step_m = options_.contours ? max_initial_height_m_ / 10.0f : 0.0f;
  terrain_ = std::make_unique<TerrainRenderer>(spec, driver_->representation(), initial.data(),
                                               driver_->exchange().front().heights.data(),
                                               options_.mesh_max);
  // Frame the camera on the first session; a reset or an Apply on the same
  // extent keeps the user's view.
  const bool same_extent = camera_framed_ && framed_size_[0] == spec.size_x_m &&
                           framed_size_[1] == spec.size_z_m;
  if (!same_extent) {
    CameraMode mode = camera_.mode;
    float yaw = camera_.yaw_rad, pitch = camera_.pitch_rad;
    camera_.frame_terrain(spec, max_initial_height_m_);
    camera_.mode = mode;
    camera_.yaw_rad = yaw;
    camera_.pitch_rad = pitch;
    if (!camera_framed_ && options_.orbit) {
      camera_.yaw_rad = float((*options_.orbit)[0] * kDegToRad);
      camera_.pitch_rad = float((*options_.orbit)[1] * kDegToRad);
      camera_.distance_m *= (*options_.orbit)[2];
    }
    if (!camera_framed_ && options_.look_at) camera_.target = to_f(*options_.look_at);
    camera_framed_ = true;
    framed_size_[0] = spec.size_x_m;
    framed_size_[1] = spec.size_z_m;
  }
  float extent = float(std::max(spec.size_x_m, spec.size_z_m));
  arrow_length_m_ = 0.25f * extent;
  *live_ = Live{};
  consume_frame();  // the starting frame: tool pose
  device_target_ = live_->pose;
  driver_->device().set_target(device_target_);
  driver_->start();
}

void ViewerApp::close_session() {
  if (driver_) driver_->stop();
  driver_.reset();
  terrain_.reset();
}

bool ViewerApp::consume_frame() {
  const haptics::ViewFrame* f = driver_->exchange().acquire();
  if (!f) {
    live_->uploaded_last = 0;
    return false;
  }
  std::int64_t before = terrain_->uploaded_samples();
  terrain_->upload(f->heights.data(), f->dirty);
  Live& l = *live_;
  l.uploaded_last = terrain_->uploaded_samples() - before;
  l.have_frame = true;
  l.sequence = f->sequence;
  l.t_s = f->t_s;
  l.step = f->step;
  l.pose = f->pose;
  l.edge = f->edge;
  l.contact = f->contact;
  l.device_m = f->device_position_m;
  l.proxy_m = f->proxy_position_m;
  l.force_world_n = f->force_world_n;
  l.force_device_n = f->force_device_n;
  l.body_force_n = f->body_force_world_n;
  l.body_count = f->body_count;
  l.body_total = f->body_total;
  std::copy_n(f->bodies.begin(), f->body_count, l.bodies.begin());
  l.step_time_s = f->step_time_s;
  l.period_s = f->period_s;
  return true;
}

void ViewerApp::push_history() {
  Live& l = *live_;
  l.contact_hist[std::size_t(l.hist_next)] = float(l.contact.length_m);
  l.force_hist[std::size_t(l.hist_next)] = magnitude(l.force_world_n);
  l.jitter_hist[std::size_t(l.hist_next)] = float(timing_.take_worst_jitter_s() * 1e6);
  l.hist_next = (l.hist_next + 1) % kHistory;
}

void ViewerApp::reset_session() {
  // The haptic loop has no reset: a new session starts from the initial
  // terrain, with the same tool source and speed.
  reset_requested_ = false;
  DriverOptions o = driver_options_;
  o.source = driver_->device().source();
  o.speed = driver_->device().speed();
  o.playing = true;
  close_session();
  open_session(o);
}

void ViewerApp::apply_model_changes() {
  session::Scenario sc = base_scenario_;
  try {
    io::Resolution res{pending_resolution_[0], pending_resolution_[1]};
    io::apply_overrides(sc.base, res, pending_representation_, std::nullopt);
    // The loop's own check (InputError naming the field, or a refused rendering).
    const haptics::LoopParams check(pending_haptics_, sc.base.blade);
    close_session();
    scenario_ = sc;
    haptics_ = check.settings();
    panel_error_.clear();
  } catch (const std::exception& e) {
    panel_error_ = e.what();
    return;
  }
  open_session(driver_options_);
}

// ---------------------------------------------------------------------------
// Drawing
// ---------------------------------------------------------------------------

void ViewerApp::render(int fb_width, int fb_height, bool draw_imgui) {
  panel_width_ = options_.panel ? std::min(390, fb_width / 2) : 0;
  scene_x_ = panel_width_;
  scene_y_ = 0;
  scene_w_ = std::max(fb_width - panel_width_, 1);
  scene_h_ = std::max(fb_height, 1);

  draw_background(fb_width, fb_height);

  draw_scene(scene_x_, scene_y_, scene_w_, scene_h_);

  if (draw_imgui) {
    ImGui::NewFrame();
    if (options_.panel) {
      draw_panel(fb_width, fb_height);
      if (show_labels_) draw_labels(scene_x_, scene_y_, scene_w_, scene_h_);
    }
    ImGui::Render();
    glViewport(0, 0, fb_width, fb_height);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }
}

// ---------------------------------------------------------------------------
// Window
// ---------------------------------------------------------------------------

GLFWwindow* ViewerApp::open_window() {
  if (!glfwInit()) {
    std::cerr << "terracut-viewer: cannot open a window (no display?). Use --screenshot for "
                 "headless rendering, or run under xvfb-run.\n";
    return nullptr;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, 4);
  std::string title = "terracut viewer - " + base_scenario_.base.name;
  GLFWwindow* window = glfwCreateWindow(options_.width, options_.height, title.c_str(), nullptr, nullptr);
  if (!window) {
    std::cerr << "terracut-viewer: cannot create an OpenGL 3.3 core window.\n";
    glfwTerminate();
    return nullptr;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  glfwSetWindowUserPointer(window, this);
  glfwSetScrollCallback(window, scroll_callback);  // ImGui chains to it
  // Sticky keys and buttons: a tap shorter than a frame is still seen once.
  glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
  glfwSetInputMode(window, GLFW_STICKY_MOUSE_BUTTONS, GLFW_TRUE);
  return window;
}

int ViewerApp::run_window() {
  GLFWwindow* window = open_window();
  if (!window) return kExitNoContext;
  glEnable(GL_MULTISAMPLE);
  init_gl_objects();
  init_imgui(true, window);

  DriverOptions dopt;
  dopt.paced = true;
  dopt.source = options_.tool_from_script ? ToolSource::kScript : ToolSource::kMouse;
  dopt.realtime = options_.realtime;
  dopt.playing = true;
  open_session(dopt);
  std::cerr << "terracut-viewer: " << describe_current_context() << "\n";

  Clock::time_point last = Clock::now();
  while (!glfwWindowShouldClose(window)) {
    glfwPollEvents();
    Clock::time_point now = Clock::now();
    double dt = std::chrono::duration<double>(now - last).count();
    last = now;
    window_frame(window, dt);
    if (options_.max_fps > 0) {
      // Pace by wall clock (no vsync under a virtual X server).
      std::this_thread::sleep_until(now + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(1.0 / options_.max_fps)));
    }
  }
  close_session();
  shutdown_imgui(true);
  shapes_.reset();
  glfwDestroyWindow(window);
  glfwTerminate();
  return 0;
}

void ViewerApp::window_frame(GLFWwindow* window, double dt_s) {
  // One frame of the window: a pending reset, the input, the newest frame, the drawing.
  if (reset_requested_) reset_session();
  // Slow drawing posts sparse targets: let the tool glide between them.
  driver_->device().set_lag_s(1.5 * dt_s);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  handle_window_input(window, dt_s);
  consume_frame();
  push_history();
  int fb_w = 1, fb_h = 1;
  glfwGetFramebufferSize(window, &fb_w, &fb_h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  render(fb_w, fb_h, true);
  glfwSwapBuffers(window);
}

}  // namespace terracut::viewer
