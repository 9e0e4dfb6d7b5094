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
  pending_material_ = base_scenario_.base.soil.material;
  pending_rake_deg_ = base_scenario_.base.blade.rake_angle_deg;
  style_.color = options_.color;
  camera_.mode = options_.camera;
}

ViewerApp::~ViewerApp() { close_session(true); }

void ViewerApp::open_session(const DriverOptions& driver_options) {
  driver_options_ = driver_options;
  driver_options_.mmt = options_.mmt;
  driver_options_.remote = options_.remote;
  driver_options_.key = options_.key;
  driver_ = std::make_unique<LoopDriver>(scenario_, haptics_, driver_options_, &timing_);
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
    if (!camera_framed_) frame_on_tool_path();
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
  frame_gate_.reset();
  redraw_.changed();
  mouse_placed_ = false;
  consume_frame();  // the starting frame: tool pose
  device_target_ = live_->pose;
  driver_->device().set_target(device_target_);
  driver_->start();
}

void ViewerApp::frame_on_tool_path() {
  // The orbit camera turns about the middle of the terrain and of the tool's
  // scripted path (the blade's ends included), far enough back that a blade
  // passing near the terrain's edge does not fill the view.
  const Tour& tour = driver_->tour();
  if (tour.empty()) return;
  const GridSpec& spec = driver_->spec();
  Vec3 lo{spec.origin_m.x, spec.origin_m.y, spec.origin_m.z};
  Vec3 hi{spec.origin_m.x + spec.size_x_m, spec.origin_m.y + max_initial_height_m_,
          spec.origin_m.z + spec.size_z_m};
  const BladeSpec& blade = scenario_.base.blade;
  constexpr int kSamples = 64;
  for (int i = 0; i <= kSamples; ++i) {
    const Segment e = blade_segment(blade, tour.sample(tour.duration_s() * i / kSamples));
    for (const Vec3& p : {e.a, e.b}) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
  }
  const Vec3 size = hi - lo;
  const float radius = 0.5f * float(length(size));
  camera_.target = to_f((lo + hi) * 0.5);
  camera_.target.y = float(spec.origin_m.y) + 0.25f * max_initial_height_m_;
  camera_.scene_radius_m = std::max(camera_.scene_radius_m, radius);
  camera_.distance_m = std::max(camera_.distance_m, 3.0f * radius);
}

void ViewerApp::print_realtime_line() {
  // The loop thread's scheduling, in the words `terracut haptics` uses.
  std::cerr << "terracut-viewer: " << driver_->realtime_line() << "\n";
}

void ViewerApp::close_session(bool end_remote) {
  if (driver_) driver_->stop();
  if (driver_ && end_remote) driver_->end_session();
  driver_.reset();
  terrain_.reset();
}

void ViewerApp::release_gl(bool with_glfw) {
  close_session();
  window_fb_.reset();
  shutdown_imgui(with_glfw);
  shapes_.reset();
}

bool ViewerApp::take_frame() {
  ViewerDevice& dev = driver_->device();
  if (!frame_gate_.take(dev.playing() || dev.stepping(), dev.clock_s())) {
    live_->uploaded_last = 0;
    return false;
  }
  return consume_frame();
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
  // Does the picture change? A still tool over an unchanged terrain does not
  // need drawing again.
  auto same = [](Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
  bool changed = !l.have_frame || !f->dirty.empty() || !same(l.pose.position_m, f->pose.position_m) ||
                 l.pose.orientation.w != f->pose.orientation.w ||
                 l.pose.orientation.x != f->pose.orientation.x ||
                 l.pose.orientation.y != f->pose.orientation.y ||
                 l.pose.orientation.z != f->pose.orientation.z ||
                 l.contact.length_m != f->contact.length_m ||
                 !same(l.force_world_n, f->force_world_n) ||
                 f->window.force_max_n != l.window.force_max_n || l.body_count != f->body_count;
  for (int i = 0; !changed && i < f->body_count; ++i) {
    const haptics::ViewBody& a = l.bodies[std::size_t(i)];
    const haptics::ViewBody& b = f->bodies[std::size_t(i)];
    changed = !same(a.position_m, b.position_m) || a.orientation.w != b.orientation.w ||
              a.orientation.x != b.orientation.x || a.orientation.y != b.orientation.y;
  }
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
  l.penetration_n = f->penetration_force_n;
  l.bucket_load_m3 = f->bucket_load_m3;
  l.twist_torque_n_m = f->twist_torque_n_m;
  l.yaw_rate_rad_per_s = f->yaw_rate_rad_per_s;
  l.window = f->window;
  l.force_max_n = std::max(l.force_max_n, f->window.force_max_n);
  l.body_force_max_n = std::max(l.body_force_max_n, f->window.body_force_max_n);
  l.readout = tool_readout(f->pose, driver_->spec(), f->heights.data(), driver_->representation());
  if (changed) redraw_.changed();
  return changed;
}

void ViewerApp::push_history() {
  Live& l = *live_;
  l.contact_hist[std::size_t(l.hist_next)] = float(l.contact.length_m);
  l.force_hist[std::size_t(l.hist_next)] = float(l.window.force_max_n);
  l.body_hist[std::size_t(l.hist_next)] = float(l.window.body_force_max_n);
  l.jitter_hist[std::size_t(l.hist_next)] = float(timing_.take_worst_jitter_s() * 1e6);
  l.hist_next = (l.hist_next + 1) % kHistory;
}

void ViewerApp::reset_session() {
  // The haptic loop has no reset: a new session starts from the initial
  // terrain, with the same tool source and speed.
  reset_requested_ = false;
  const DriverOptions o = reset_options(driver_options_, driver_->device());
  close_session();
  timing_.clear();  // the timing statistics and the maxima start afresh
  open_session(o);
}

void ViewerApp::apply_model_changes() {
  session::Scenario sc = base_scenario_;
  try {
    io::Resolution res{pending_resolution_[0], pending_resolution_[1]};
    io::apply_overrides(sc.base, res, pending_representation_, std::nullopt);
    sc.base.soil.material = pending_material_;
    sc.base.blade.rake_angle_deg = pending_rake_deg_;
    // The simulation's check (the material with the rake) and the loop's own
    // (InputError naming the field, or a refused rendering).
    if (const std::string e = validate(io::sim_params(sc.base)); !e.empty()) throw InputError(e);
    const haptics::LoopParams check(pending_haptics_, sc.base.blade, sc.base.rate_hz);
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
  glfwWindowHint(GLFW_SAMPLES, 0);  // multisampled offscreen instead (window_frame)
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
  glfwSetScrollCallback(window, scroll_callback);  // ImGui chains to these
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double, double) { event_callback(w); });
  glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int, int, int) { event_callback(w); });
  glfwSetKeyCallback(window, [](GLFWwindow* w, int, int, int, int) { event_callback(w); });
  glfwSetCharCallback(window, [](GLFWwindow* w, unsigned) { event_callback(w); });
  glfwSetWindowFocusCallback(window, [](GLFWwindow* w, int) { event_callback(w); });
  glfwSetCursorEnterCallback(window, [](GLFWwindow* w, int) { event_callback(w); });
  glfwSetFramebufferSizeCallback(window, [](GLFWwindow* w, int, int) { event_callback(w); });
  glfwSetWindowRefreshCallback(window, [](GLFWwindow* w) { event_callback(w); });
  // Sticky keys and buttons: a tap shorter than a frame is still seen once.
  glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
  glfwSetInputMode(window, GLFW_STICKY_MOUSE_BUTTONS, GLFW_TRUE);
  return window;
}

int ViewerApp::run_window() {
  GLFWwindow* window = open_window();
  if (!window) return kExitNoContext;
  // The window and its context outlive everything drawn with it, on every
  // way out (an error that opening a session throws included).
  struct WindowScope {
    GLFWwindow* window;
    ~WindowScope() {
      glfwDestroyWindow(window);
      glfwTerminate();
    }
  } window_scope{window};
  const GLScope gl_scope{*this, true};
  init_gl_objects();
  init_imgui(true, window);

  DriverOptions dopt;
  dopt.paced = true;
  dopt.source = options_.tool_from_script ? ToolSource::kScript : ToolSource::kMouse;
  dopt.realtime = options_.realtime;
  dopt.playing = true;
  dopt.speed = options_.play_speed;
  open_session(dopt);
  const std::string renderer = describe_current_context();
  std::cerr << "terracut-viewer: " << renderer << "\n";
  if (options_.msaa > 0 && (renderer.find("llvmpipe") != std::string::npos ||
                            renderer.find("softpipe") != std::string::npos))
    std::cerr << "terracut-viewer: a software renderer: multisampling (--msaa " << options_.msaa
              << ") takes about 3x the frame time; --msaa 0 draws faster, with jagged edges\n";
  print_realtime_line();

  // Event-driven: sleep until an event or the next frame time, draw only
  // when something changed (RedrawGate), and count the frames drawn.
  const double frame_period = options_.max_fps > 0 ? 1.0 / options_.max_fps : 0.0;
  const Clock::time_point opened = Clock::now();
  Clock::time_point last = opened;
  std::int64_t drawn = 0, iterations = 0;
  double drawing_s = 0.0;  // wall time of the iterations that drew
  while (!glfwWindowShouldClose(window)) {
    const Clock::time_point begin = Clock::now();
    double dt = std::chrono::duration<double>(begin - last).count();
    last = begin;
    ++iterations;
    const bool drew = window_frame(window, dt);
    if (drew) ++drawn;
    const double elapsed = std::chrono::duration<double>(Clock::now() - opened).count();
    if (options_.window_seconds > 0.0 && elapsed >= options_.window_seconds)
      glfwSetWindowShouldClose(window, GLFW_TRUE);
    // Pace by wall clock (no vsync under a virtual X server): wait for
    // events until the next frame is due.
    const double spent = std::chrono::duration<double>(Clock::now() - begin).count();
    const double wait = std::max(frame_period - spent, 0.0);
    if (drew) drawing_s += std::max(spent, frame_period);
    if (wait > 0.0) glfwWaitEventsTimeout(wait); else glfwPollEvents();
  }
  const double open_s = std::chrono::duration<double>(Clock::now() - opened).count();
  std::fprintf(stderr,
               "terracut-viewer: window: %lld frames drawn in %.1f s open (%lld iterations); "
               "%.1f frames/s while drawing\n",
               static_cast<long long>(drawn), open_s, static_cast<long long>(iterations),
               drawing_s > 0.0 ? double(drawn) / drawing_s : 0.0);
  // The end of the session, told to a remote in another process; the GL
  // objects and the window go with gl_scope.
  close_session(true);
  return apps::kExitOk;
}

bool ViewerApp::window_frame(GLFWwindow* window, double dt_s) {
  // One iteration of the window: a pending reset (or the script's replay),
  // the input, the newest frame, and the drawing when something changed.
  if (options_.loop_script && driver_->device().source() == ToolSource::kScript &&
      driver_->device().script_finished())
    reset_requested_ = true;
  if (reset_requested_) {
    reset_session();
    if (options_.loop_script) driver_->device().set_playing(true);
  }
  // Targets come once a frame: the device ramps to each over one frame
  // interval, so the tool moves at a steady speed between them.
  driver_->device().set_frame_interval_s(dt_s);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  handle_window_input(window, dt_s);
  if (take_frame()) push_history();
  int fb_w = 1, fb_h = 1;
  glfwGetFramebufferSize(window, &fb_w, &fb_h);
  if (!redraw_.draw()) {
    // Nothing changed: ImGui's frame is begun and ended without drawing.
    ImGui::NewFrame();
    ImGui::EndFrame();
    return false;
  }
  // Multisampling in a window too: draw into a multisampled framebuffer of
  // the window's size and resolve it into the window (a virtual X server's
  // visual has no samples of its own).
  if (options_.msaa > 0 && (!window_fb_ || window_fb_->width() != fb_w || window_fb_->height() != fb_h))
    window_fb_ = std::make_unique<Framebuffer>(fb_w, fb_h, options_.msaa);
  if (window_fb_) {
    window_fb_->bind();
    glEnable(GL_MULTISAMPLE);
  } else {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  render(fb_w, fb_h, true);
  if (window_fb_) window_fb_->blit_to_default();
  glfwSwapBuffers(window);
  return true;
}

}  // namespace terracut::viewer
