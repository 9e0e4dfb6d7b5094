#include "viewer_app.hpp"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numbers>
#include <thread>

#include "gl_context.hpp"
#include "gl_util.hpp"
#include "png_rgb.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

namespace terracut::viewer {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kHistory = 240;  // plot samples (4 s at 60 frames/s)
constexpr double kDegToRad = std::numbers::pi / 180.0;

const char* kBackgroundVertex = R"(#version 330 core
out float v_t;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  v_t = 0.5 * (p.y + 1.0);
  gl_Position = vec4(p, 0.999, 1.0);
}
)";
const char* kBackgroundFragment = R"(#version 330 core
in float v_t;
out vec4 o_color;
void main() {
  vec3 bottom = vec3(0.80, 0.84, 0.88), top = vec3(0.42, 0.55, 0.70);
  o_color = vec4(mix(bottom, top, clamp(v_t, 0.0, 1.0)), 1.0);
}
)";

std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  for (char& ch : e) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return e;
}

float magnitude(Vec3 v) { return float(length(v)); }

// A titled separator (ImGui 1.86 has no SeparatorText).
void section(const char* title) {
  ImGui::Spacing();
  ImGui::TextColored(ImVec4(0.55f, 0.75f, 1.0f, 1.0f), "%s", title);
  ImGui::Separator();
}

}  // namespace

// The latest frame's scalar fields, plot histories and frame timing.
struct ViewerApp::Live {
  bool have_frame = false;
  std::uint64_t sequence = 0;
  double t_s = 0.0;
  std::int64_t step = 0;
  BladePose pose{};
  Segment edge{};
  ContactResult contact{};
  Vec3 device_m{}, proxy_m{}, force_world_n{}, force_device_n{}, body_force_n{};
  double step_time_s = 0.0, period_s = 0.0;
  // Rigid bodies of the frame (the first body_count are valid).
  int body_count = 0, body_total = 0;
  std::array<haptics::ViewBody, haptics::kMaxViewBodies> bodies{};
  std::int64_t uploaded_last = 0;

  std::vector<float> contact_hist = std::vector<float>(kHistory, 0.0f);
  std::vector<float> force_hist = std::vector<float>(kHistory, 0.0f);
  std::vector<float> jitter_hist = std::vector<float>(kHistory, 0.0f);
  int hist_next = 0;

  Clock::time_point last_frame = Clock::now();
  double frame_ms = 0.0;  // smoothed wall time between rendered frames
  LoopTimingSnapshot stats{};
  Clock::time_point last_stats = Clock::now();
};

// ---------------------------------------------------------------------------
// Input
// ---------------------------------------------------------------------------

haptics::HapticScenario load_input(const ViewerOptions& options) {
  haptics::HapticScenario input;
  io::Scenario& sc = input.scenario;
  std::string ext = lower_extension(options.input);
  if (ext == ".png") {
    // A bare heightmap: the given extent and full scale, no scripted cuts.
    if (!(options.heightmap_size_m > 0.0) || !(options.heightmap_full_scale_m > 0.0))
      throw InputError("--extent and --full-scale must be > 0");
    sc.source_path = options.input;
    sc.name = options.input.stem().string();
    sc.image_path = options.input;
    sc.image = io::read_png(options.input);
    sc.resolution = {sc.image.cols, sc.image.rows};
    sc.size_x_m = options.heightmap_size_m;
    sc.size_z_m = options.heightmap_size_m;
    sc.full_scale_m = options.heightmap_full_scale_m;
    sc.blade.length_m = 0.5 * options.heightmap_size_m;
  } else {
    // The scenario and its `haptics:` section (defaults when absent).
    input = haptics::load_haptic_scenario(options.input);
  }
  io::apply_overrides(sc, options.resolution, options.representation, std::nullopt);
  return input;
}

// ---------------------------------------------------------------------------
// Construction and sessions
// ---------------------------------------------------------------------------

ViewerApp::ViewerApp(ViewerOptions options, io::Scenario scenario,
                     const HapticSettings& haptic_settings)
    : options_(std::move(options)),
      base_scenario_(std::move(scenario)),
      scenario_(base_scenario_),
      haptics_(viewer_settings(haptic_settings)),
      live_(std::make_unique<Live>()) {
  pending_representation_ = base_scenario_.representation;
  pending_resolution_[0] = base_scenario_.resolution.cols;
  pending_resolution_[1] = base_scenario_.resolution.rows;
  pending_haptics_ = haptics_;
  style_.color = options_.color;
  camera_.mode = options_.camera;
}

ViewerApp::~ViewerApp() { close_session(); }

void ViewerApp::init_gl_objects() {
  shapes_ = std::make_unique<ShapeRenderer>();
  background_program_ = build_program("background", kBackgroundVertex, kBackgroundFragment);
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  background_vao_ = vao;
}

void ViewerApp::init_imgui(bool with_glfw, GLFWwindow* window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  std::filesystem::path font = options_.font;
  if (font.empty()) font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  std::error_code ec;
  if (std::filesystem::exists(font, ec)) {
    io.Fonts->AddFontFromFileTTF(font.string().c_str(), 15.0f);
  } else {
    ImFontConfig config;
    config.SizePixels = 15.0f;
    io.Fonts->AddFontDefault(&config);
  }
  ImGui::StyleColorsDark();
  ImGuiStyle& style = ImGui::GetStyle();
  style.WindowRounding = 0.0f;
  style.FrameRounding = 3.0f;
  style.GrabRounding = 3.0f;
  style.WindowBorderSize = 0.0f;
  style.ItemSpacing = ImVec2(7.0f, 4.0f);
  style.Colors[ImGuiCol_WindowBg] = ImVec4(0.10f, 0.11f, 0.13f, 0.96f);
  style.Colors[ImGuiCol_PlotLines] = ImVec4(0.95f, 0.70f, 0.30f, 1.0f);
  if (with_glfw) ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;
}

void ViewerApp::shutdown_imgui(bool with_glfw) {
  if (!imgui_ready_) return;
  ImGui_ImplOpenGL3_Shutdown();
  if (with_glfw) ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  imgui_ready_ = false;
}

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

float ViewerApp::ground_height_at(double x, double z) const {
  // Bilinear height of the reader's frame at world (x, z) (samples cell-centred).
  const haptics::ViewFrame& f = driver_->exchange().front();
  const GridSpec& spec = driver_->spec();
  double u = (x - spec.origin_m.x) / spec.cell_x_m() - 0.5;
  double v = (z - spec.origin_m.z) / spec.cell_z_m() - 0.5;
  if (u < -0.5 || v < -0.5 || u > f.cols - 0.5 || v > f.rows - 0.5) return float(spec.origin_m.y);
  u = std::clamp(u, 0.0, double(f.cols - 1));
  v = std::clamp(v, 0.0, double(f.rows - 1));
  int c0 = std::min(int(u), f.cols - 1), r0 = std::min(int(v), f.rows - 1);
  int c1 = std::min(c0 + 1, f.cols - 1), r1 = std::min(r0 + 1, f.rows - 1);
  double fu = u - c0, fv = v - r0;
  auto h = [&](int c, int r) { return double(f.heights[std::size_t(r) * f.cols + c]); };
  double top = h(c0, r0) * (1 - fu) + h(c1, r0) * fu;
  double bottom = h(c0, r1) * (1 - fu) + h(c1, r1) * fu;
  return float(spec.origin_m.y + top * (1 - fv) + bottom * fv);
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

void ViewerApp::print_loop_summary() {
  // The loop's own statistics (its pacer's histograms and its records) are
  // read after it stopped; the device's view covers every session.
  driver_->stop();
  const haptics::HapticLoop& loop = driver_->loop();
  const haptics::LoopStats& ps = loop.pacer_stats();
  const haptics::TimePercentiles period = loop.period();
  const LoopTimingSnapshot t = timing_.snapshot();
  auto us = [](double s) { return s * 1e6; };
  std::printf(
      "  haptic loop at %.0f Hz (last session, %lld ticks): period p50 %.1f us, p99 %.1f us, "
      "max %.1f us; jitter |period - 1 ms| p50 %.1f us, p99 %.1f us, max %.1f us; compute p50 "
      "%.1f us, p99 %.1f us, max %.1f us; missed deadlines %lld, skipped slots %lld\n"
      "  period seen by the device (all %lld ticks of all sessions): p50 %.1f us, p99 %.1f us, "
      "max %.1f us\n"
      "  %s\n",
      driver_->rate_hz(), static_cast<long long>(ps.ticks), period.p50_us, period.p99_us,
      period.max_us, us(ps.period_jitter.p50_s), us(ps.period_jitter.p99_s),
      us(ps.period_jitter.max_s), us(ps.compute.p50_s), us(ps.compute.p99_s), us(ps.compute.max_s),
      static_cast<long long>(ps.missed_deadlines), static_cast<long long>(ps.skipped_slots),
      static_cast<long long>(t.ticks), t.period_p50_us, t.period_p99_us, t.period_max_us,
      loop.realtime_status().message.c_str());
}

void ViewerApp::apply_model_changes() {
  io::Scenario sc = base_scenario_;
  try {
    io::Resolution res{pending_resolution_[0], pending_resolution_[1]};
    io::apply_overrides(sc, res, pending_representation_, std::nullopt);
    HapticSettings hs = with_derived_fields(pending_haptics_, sc.blade.length_m);
    if (std::string m = validate(hs); !m.empty()) throw InputError(m);
    ForceModel check(hs.forces);  // throws InputError on a refused rendering
    (void)check;
    close_session();
    scenario_ = sc;
    haptics_ = hs;
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

  glViewport(0, 0, fb_width, fb_height);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(background_program_);
  glBindVertexArray(background_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glClear(GL_DEPTH_BUFFER_BIT);

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

void ViewerApp::draw_scene(int x, int y, int w, int h) {
  // The scene spans the framebuffer's full height (y = 0), right of the panel.
  (void)y;
  glViewport(x, 0, w, h);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  float aspect = float(w) / float(h);
  Mat4 vp = camera_.projection(aspect) * camera_.view();
  Vec3f eye = camera_.eye();
  // The key light follows the camera: from above, a little left of and behind the eye.
  float yaw = camera_.mode == CameraMode::kTop ? 0.0f : camera_.yaw_rad;
  Vec3f right{std::cos(yaw), 0.0f, -std::sin(yaw)}, back{std::sin(yaw), 0.0f, std::cos(yaw)};
  style_.light_dir = right * -0.45f + back * 0.40f + Vec3f{0.0f, 0.85f, 0.0f};
  terrain_->draw(vp, eye, style_);

  const Live& l = *live_;
  const float extent = float(std::max(driver_->spec().size_x_m, driver_->spec().size_z_m));
  const float blade_len = float(driver_->blade_length_m());
  shapes_->begin(vp, eye, style_.light_dir);

  // Blade: the cutting edge as a rod (red while in contact) under a thin plate.
  Vec3f a = to_f(l.edge.a), b = to_f(l.edge.b);
  bool in_contact = l.contact.length_m > 0.0;
  float rod = std::max(0.006f * blade_len, 0.003f * extent);
  shapes_->cylinder(a, b, rod, in_contact ? Color{0.92f, 0.22f, 0.15f, 1} : Color{0.25f, 0.35f, 0.55f, 1});
  // The plate is drawn last, see-through, so it never hides the cut behind
  // it; it stands 0.12 blade lengths above the soil, however deep the edge is.
  float ground = ground_height_at(l.pose.position_m.x, l.pose.position_m.z);
  float plate_h = 0.12f * blade_len + std::max(0.0f, ground - float(l.pose.position_m.y));
  Mat4 plate = translation(to_f(l.pose.position_m)) * rotation(l.pose.orientation) *
               translation({0.0f, 0.5f * plate_h + rod, 0.0f}) *
               scaling({blade_len, plate_h, 0.6f * rod});

  // Rigid bodies (the Bullet world's), lit, in cool stone colours that stand
  // apart from the soil's browns.
  static const Color kBodyColors[4] = {{0.52f, 0.60f, 0.72f, 1.0f},
                                       {0.60f, 0.64f, 0.70f, 1.0f},
                                       {0.46f, 0.56f, 0.62f, 1.0f},
                                       {0.62f, 0.58f, 0.72f, 1.0f}};
  for (int i = 0; i < l.body_count; ++i) {
    const haptics::ViewBody& body = l.bodies[std::size_t(i)];
    const Color color = kBodyColors[i % 4];
    const Vec3f centre = to_f(body.position_m);
    switch (body.shape) {
      case BodyShape::kBox:
        shapes_->box(translation(centre) * rotation(body.orientation) *
                         scaling(to_f(body.half_extents_m) * 2.0f),
                     color);
        break;
      case BodyShape::kSphere:
        shapes_->sphere(centre, float(body.half_extents_m.x), color);
        break;
      case BodyShape::kCylinder: {
        // The axis is the body's local Y.
        const Vec3 half_axis = rotate(body.orientation, Vec3{0.0, body.half_extents_m.y, 0.0});
        shapes_->cylinder(to_f(body.position_m - half_axis), to_f(body.position_m + half_axis),
                          float(body.half_extents_m.x), color);
        break;
      }
    }
  }

  // Device point, proxy and the spring between them; a drop line to the ground.
  float r = 0.012f * extent;
  Vec3f device = to_f(l.device_m), proxy = to_f(l.proxy_m);
  shapes_->sphere(device, r, {0.20f, 0.45f, 0.95f, 1.0f});
  if (length(proxy - device) > 0.5f * r) {
    shapes_->sphere(proxy, 0.8f * r, {1.0f, 0.60f, 0.10f, 1.0f});
    shapes_->line(device, proxy, {1.0f, 0.6f, 0.1f, 1.0f});
  }
  Vec3f foot{device.x, ground, device.z};
  if (device.y > ground + r) {
    shapes_->line(device, foot, {0.1f, 0.1f, 0.1f, 1.0f});
    shapes_->sphere(foot, 0.35f * r, {0.1f, 0.1f, 0.1f, 1.0f});
  }

  // Force on the tool: an arrow scaled so that the largest force of the plot
  // window is arrow_length_m_ long (the label gives the value).
  float fmag = magnitude(l.force_world_n);
  if (show_force_ && fmag > 1e-3f) {
    float fmax = 1.0f;
    for (float v : l.force_hist) fmax = std::max(fmax, v);
    float len = arrow_length_m_ * std::min(1.0f, fmag / fmax);
    Vec3f dir = to_f(l.force_world_n) * (1.0f / fmag);
    shapes_->arrow(device, device + dir * len, 0.35f * r, {0.98f, 0.85f, 0.15f, 1.0f});
  }
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glDepthMask(GL_FALSE);
  shapes_->box(plate, {0.70f, 0.74f, 0.80f, 0.35f});
  // The edge and the device point once more, faint and without depth test, so
  // they show through the soil that hides them (a blade deep in a trench).
  glDisable(GL_DEPTH_TEST);
  shapes_->cylinder(a, b, rod, in_contact ? Color{0.92f, 0.22f, 0.15f, 0.35f} : Color{0.25f, 0.35f, 0.55f, 0.35f});
  shapes_->sphere(device, r, {0.20f, 0.45f, 0.95f, 0.35f});
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}

void ViewerApp::draw_labels(int x, int y, int w, int h) {
  // Values next to the tool, projected into the scene viewport.
  const Live& l = *live_;
  Mat4 vp = camera_.projection(float(w) / float(h)) * camera_.view();
  Vec3f p = transform_point(vp, to_f(l.device_m) + Vec3f{0.0f, 0.02f * camera_.scene_radius_m, 0.0f});
  if (p.z < -1.0f || p.z > 1.0f) return;
  float sx = float(x) + (0.5f * p.x + 0.5f) * float(w);
  float sy = float(y) + (0.5f - 0.5f * p.y) * float(h);
  char text[160];
  std::snprintf(text, sizeof text, "contact %.3f m\n|F| %.1f N (device %.2f N)", l.contact.length_m,
                double(magnitude(l.force_world_n)), double(magnitude(l.force_device_n)));
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  ImVec2 size = ImGui::CalcTextSize(text);
  ImVec2 at(sx + 18.0f, sy - size.y - 14.0f);
  dl->AddRectFilled(ImVec2(at.x - 5, at.y - 3), ImVec2(at.x + size.x + 5, at.y + size.y + 3),
                    IM_COL32(20, 22, 28, 190), 4.0f);
  dl->AddText(at, IM_COL32(255, 255, 255, 255), text);
}

void ViewerApp::draw_panel(int fb_width, int fb_height) {
  (void)fb_width;
  Live& l = *live_;
  LoopDriver& d = *driver_;
  const GridSpec& spec = d.spec();

  // Frame timing (wall clock between panel draws) and loop statistics, 4 times a second.
  Clock::time_point now = Clock::now();
  double dt_ms = std::chrono::duration<double, std::milli>(now - l.last_frame).count();
  l.last_frame = now;
  l.frame_ms = l.frame_ms <= 0.0 ? dt_ms : 0.9 * l.frame_ms + 0.1 * dt_ms;
  if (std::chrono::duration<double>(now - l.last_stats).count() > 0.25 || l.stats.ticks == 0) {
    l.stats = timing_.snapshot();
    l.last_stats = now;
  }

  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(float(panel_width_), float(fb_height)));
  ImGui::Begin("terracut viewer", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.45f, 1.0f), "%s", scenario_.name.c_str());
  ImGui::Text("%d x %d %s, %.2f x %.2f m", spec.cols, spec.rows,
              std::string(to_string(d.representation())).c_str(), spec.size_x_m, spec.size_z_m);
  ImGui::TextDisabled("mesh %d x %d%s, %lld triangles", terrain_->mesh_cols(), terrain_->mesh_rows(),
                      terrain_->blocky_mesh() ? " (boxes)" : "",
                      static_cast<long long>(terrain_->triangle_count()));

  // --- run controls ---
  section("Run");
  ViewerDevice& dev = d.device();
  bool playing = dev.playing();
  if (ImGui::Button(playing ? "Pause" : "Play", ImVec2(70, 0))) dev.set_playing(!playing);
  ImGui::SameLine();
  if (ImGui::Button("Step", ImVec2(60, 0))) {
    dev.set_playing(false);
    dev.request_steps(1);
  }
  ImGui::SameLine();
  if (ImGui::Button("Reset", ImVec2(60, 0))) reset_requested_ = true;
  float speed = float(dev.speed());
  ImGui::SetNextItemWidth(-70);
  if (ImGui::SliderFloat("speed", &speed, 0.01f, 4.0f, "%.2fx", ImGuiSliderFlags_Logarithmic))
    dev.set_speed(speed);
  int source = int(dev.source());
  ImGui::Text("Tool:");
  ImGui::SameLine();
  bool to_script = ImGui::RadioButton("script", &source, int(ToolSource::kScript));
  ImGui::SameLine();
  bool to_mouse = ImGui::RadioButton("mouse", &source, int(ToolSource::kMouse));
  if (to_script) dev.set_source(ToolSource::kScript);
  if (to_mouse) begin_mouse_drive();
  if (!driver_options_.paced) {
    ImGui::TextDisabled("headless: lock-step, %.4g s per frame", options_.frame_time_s);
  }
  ImGui::Text("t = %.3f s   step %lld", l.t_s, static_cast<long long>(l.step));
  if (dev.source() == ToolSource::kScript) {
    if (d.tour().empty()) {
      ImGui::TextDisabled("no scripted cuts: drive with the mouse");
    } else {
      const double st = dev.script_time_s();
      const PoseLeg* leg = d.tour().leg_at(st);
      char label[128];
      if (dev.script_finished()) {
        std::snprintf(label, sizeof label, "sequence done: Reset to replay");
      } else if (leg && leg->cut >= 0) {
        std::snprintf(label, sizeof label, "cut %s (%d/%zu)  %.2f s",
                      scenario_.cuts[std::size_t(leg->cut)].name.c_str(), leg->sequence_index + 1,
                      scenario_.sequence.size(), st);
      } else {
        std::snprintf(label, sizeof label, "transit to the next cut  %.2f s", st);
      }
      ImGui::ProgressBar(float(std::min(1.0, st / std::max(d.tour().duration_s(), 1e-9))),
                         ImVec2(-1, 0), label);
    }
  }

  // --- live values and plots ---
  section("Contact and force");
  ImGui::Text("contact %.3f m   depth %.3f m", l.contact.length_m, l.contact.max_depth_m);
  ImGui::Text("|F| %.1f N world   %.2f N device", double(magnitude(l.force_world_n)),
              double(magnitude(l.force_device_n)));
  if (l.body_total > 0)
    ImGui::Text("bodies %d (Bullet)   on the blade %.1f N", l.body_total,
                double(magnitude(l.body_force_n)));
  char overlay[64];
  const float plot_w = float(panel_width_) - 20.0f;
  std::snprintf(overlay, sizeof overlay, "contact length %.3f m", l.contact.length_m);
  ImGui::PlotLines("##contact", l.contact_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                   float(std::max(d.blade_length_m(), 1e-3)), ImVec2(plot_w, 52));
  float fmax = 1.0f;
  for (float v : l.force_hist) fmax = std::max(fmax, v);
  std::snprintf(overlay, sizeof overlay, "force |F| %.0f N (max %.0f)", double(magnitude(l.force_world_n)), double(fmax));
  ImGui::PlotLines("##force", l.force_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                   fmax * 1.1f, ImVec2(plot_w, 52));
  float jmax = 50.0f;
  for (float v : l.jitter_hist) jmax = std::max(jmax, v);
  std::snprintf(overlay, sizeof overlay, driver_options_.paced ? "loop jitter, worst per frame (max %.0f us)"
                                                               : "loop jitter: none in lock-step",
                double(jmax));
  ImGui::PlotLines("##jitter", l.jitter_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                   jmax * 1.1f, ImVec2(plot_w, 44));

  // --- timing ---
  section("Timing");
  if (driver_options_.paced) {
    ImGui::Text("%.1f frames/s (%.1f ms)   upload %lld samples",
                l.frame_ms > 0 ? 1000.0 / l.frame_ms : 0.0, l.frame_ms,
                static_cast<long long>(l.uploaded_last));
  } else {
    ImGui::Text("upload %lld samples this frame", static_cast<long long>(l.uploaded_last));
  }
  ImGui::Text("step %.1f us   loop %.0f Hz", l.step_time_s * 1e6, d.rate_hz());
  if (driver_options_.paced) {
    ImGui::Text("period p50 %.0f  p99 %.0f  max %.0f us", l.stats.period_p50_us,
                l.stats.period_p99_us, l.stats.period_max_us);
    ImGui::Text("compute p50 %.0f  p99 %.0f  max %.0f us", l.stats.compute_p50_us,
                l.stats.compute_p99_us, l.stats.compute_max_us);
  }

  const RenderingCheck& check = d.force_model().rendering();
  if (check.any_limited()) {
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.35f, 1.0f), "device limits lowered:%s%s%s",
                       check.surface_stiffness_limited ? " stiffness" : "",
                       check.surface_damping_limited ? " damping" : "",
                       check.cutting_damping_limited ? " cutting damping" : "");
  }

  // --- display ---
  section("Display");
  int color = int(style_.color);
  ImGui::RadioButton("height", &color, int(ColorMode::kHeight));
  ImGui::SameLine();
  ImGui::RadioButton("removed depth", &color, int(ColorMode::kRemoved));
  style_.color = ColorMode(color);
  if (style_.color == ColorMode::kRemoved) {
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderFloat("depth scale", &style_.removed_scale_m, 0.001f * max_initial_height_m_,
                       2.0f * max_initial_height_m_, "%.3f m", ImGuiSliderFlags_Logarithmic);
  }
  bool contours = style_.contour_step_m > 0.0f;
  if (ImGui::Checkbox("contours", &contours))
    style_.contour_step_m = contours ? max_initial_height_m_ / 10.0f : 0.0f;
  ImGui::SameLine();
  ImGui::Checkbox("force arrow", &show_force_);
  ImGui::SameLine();
  bool top = camera_.mode == CameraMode::kTop;
  if (ImGui::Checkbox("top view", &top)) camera_.mode = top ? CameraMode::kTop : CameraMode::kOrbit;

  // --- model parameters (applied by rebuilding the session) ---
  if (ImGui::CollapsingHeader("Model (Apply resets the terrain)")) {
    if (ImGui::Button("Apply (reset)")) apply_model_changes();
    if (!panel_error_.empty()) {
      ImGui::PushTextWrapPos(0.0f);
      ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", panel_error_.c_str());
      ImGui::PopTextWrapPos();
    }
    int rep = int(pending_representation_);
    ImGui::Text("representation");
    ImGui::SameLine();
    ImGui::RadioButton("surface", &rep, int(Representation::kSurface));
    ImGui::SameLine();
    ImGui::RadioButton("columns", &rep, int(Representation::kColumns));
    pending_representation_ = Representation(rep);
    ImGui::SetNextItemWidth(-110);
    ImGui::InputInt2("resolution", pending_resolution_);
    ForceModelParams& fp = pending_haptics_.forces;
    int cutting = int(fp.cutting);
    const char* models[] = {"none", "contact_drag", "earthmoving"};
    ImGui::SetNextItemWidth(-110);
    ImGui::Combo("cutting", &cutting, models, 3);
    fp.cutting = CuttingModel(cutting);
    float k = float(fp.contact_drag.drag_n_per_m);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("drag N/m", &k, 0.0f, 5000.0f, "%.0f")) fp.contact_drag.drag_n_per_m = k;
    float visc = float(fp.contact_drag.viscous_n_s_per_m2);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("viscous Ns/m2", &visc, 0.0f, 5000.0f, "%.0f"))
      fp.contact_drag.viscous_n_s_per_m2 = visc;
    const char* soils[] = {"dry_sand", "loose_sand", "clay"};
    ImGui::SetNextItemWidth(-110);
    if (ImGui::Combo("soil", &pending_soil_, soils, 3))
      fp.earthmoving.soil = soil_preset(SoilPreset(pending_soil_));
    float rake = float(fp.earthmoving.rake_angle_rad / kDegToRad);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("rake deg", &rake, 20.0f, 160.0f, "%.0f"))
      fp.earthmoving.rake_angle_rad = rake * kDegToRad;
    ImGui::Checkbox("surface spring", &fp.surface_enabled);
    float stiff = float(fp.surface.stiffness_n_per_m);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("stiffness N/m", &stiff, 1e3f, 1e6f, "%.0f", ImGuiSliderFlags_Logarithmic))
      fp.surface.stiffness_n_per_m = stiff;
    float scale = float(fp.force_scale);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("force scale", &scale, 1e-3f, 0.2f, "%.3f", ImGuiSliderFlags_Logarithmic))
      fp.force_scale = scale;
  }
  if (ImGui::CollapsingHeader("Mouse and keys")) {
    ImGui::TextWrapped(
        "Left drag: move the tool in its horizontal plane.  Wheel: tool up/down.  Q/E: turn about "
        "Y.  R/F: tilt.  Right drag: orbit.  Middle drag: pan.  Shift+wheel: zoom.  Space: "
        "play/pause.  N: step.  Backspace: reset.  T: top view.  C: colour.");
  }
  ImGui::End();
}

// ---------------------------------------------------------------------------
// Headless
// ---------------------------------------------------------------------------

int ViewerApp::run_headless() {
  std::unique_ptr<HeadlessContext> context;
  try {
    context = std::make_unique<HeadlessContext>();
  } catch (const ContextUnavailable& e) {
    std::cerr << "terracut-viewer: cannot create an OpenGL 3.3 context: " << e.what() << "\n";
    return kExitNoContext;
  }
  const int w = options_.width, h = options_.height;
  Framebuffer fb(w, h, options_.benchmark_frames > 0 ? 0 : options_.msaa);
  fb.bind();
  init_gl_objects();
  init_imgui(false, nullptr);
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(float(w), float(h));

  auto frame = [&](bool with_panel_time) {
    io.DeltaTime = with_panel_time ? float(options_.frame_time_s) : 1.0f / 60.0f;
    ImGui_ImplOpenGL3_NewFrame();
    render(w, h, true);
  };

  int status = 0;
  if (options_.benchmark_frames > 0) {
    // Real time: the haptic loop paced at its rate on its own thread, the
    // blade ploughing the terrain layer by layer (a steady cut of any
    // length), while this thread draws as fast as it can.
    DriverOptions dopt;
    dopt.paced = true;
    dopt.source = ToolSource::kScript;
    dopt.plough = true;
    dopt.pause_at_end = false;
    dopt.record_capacity = std::size_t(1) << 19;  // the newest 524 s of ticks
    dopt.realtime = options_.realtime;
    open_session(dopt);
    std::cerr << "terracut-viewer: " << describe_current_context() << "\n";
    for (int i = 0; i < 5; ++i) {
      consume_frame();
      push_history();
      frame(false);
      glFinish();
    }
    std::int64_t uploaded = 0, frames_with_upload = 0;
    Clock::time_point t0 = Clock::now();
    for (int i = 0; i < options_.benchmark_frames; ++i) {
      consume_frame();
      uploaded += live_->uploaded_last;
      frames_with_upload += live_->uploaded_last > 0 ? 1 : 0;
      push_history();
      if (options_.benchmark_no_draw) {
        // The reference: the same loop and uploads, no drawing (60 frames/s).
        std::this_thread::sleep_for(std::chrono::microseconds(16667));
      } else {
        frame(false);
        glFinish();
      }
    }
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const GridSpec& spec = driver_->spec();
    std::printf(
        "benchmark: %dx%d %s grid, mesh %dx%d (%lld triangles), %dx%d pixels, panel %s, %s\n"
        "  %d frames in %.2f s: %.2f frames/s (%.1f ms/frame); %lld frames uploaded a changed "
        "rectangle, %.0f samples/frame on average\n",
        spec.cols, spec.rows, std::string(to_string(driver_->representation())).c_str(),
        terrain_->mesh_cols(), terrain_->mesh_rows(),
        static_cast<long long>(terrain_->triangle_count()), w, h, options_.panel ? "on" : "off",
        describe_current_context().c_str(), options_.benchmark_frames, wall,
        options_.benchmark_frames / wall, 1000.0 * wall / options_.benchmark_frames,
        static_cast<long long>(frames_with_upload), double(uploaded) / options_.benchmark_frames);
    print_loop_summary();
  } else {
    // Lock-step: frame k shows the state after k * frame_time of the script
    // (tick i plays script time i / rate).
    DriverOptions dopt;
    dopt.paced = false;
    dopt.source = ToolSource::kScript;
    dopt.pause_at_end = false;
    open_session(dopt);
    const std::int64_t total = driver_->script_ticks();
    int frames = options_.frames;
    if (frames < 0) frames = int(std::ceil(driver_->tour().duration_s() / options_.frame_time_s)) + 1;
    for (int k = 1; k <= frames; ++k) {
      const std::int64_t target = std::min<std::int64_t>(
          total, std::llround(double(k) * options_.frame_time_s * driver_->rate_hz()) + 1);
      driver_->run_until_tick(target);
      while (driver_->ticks_done() < target)
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      consume_frame();
      push_history();
      // The panel needs a frame or two to lay itself out; draw only the last three.
      if (k + 3 > frames) frame(true);
    }
    for (int i = frames; i < 3; ++i) frame(true);
    if (!options_.screenshot.empty()) {
      write_png_rgb(options_.screenshot, fb.read());
      std::printf("terracut-viewer: wrote %s (%dx%d, t = %.3f s, %lld ticks)\n",
                  options_.screenshot.string().c_str(), w, h, live_->t_s,
                  static_cast<long long>(driver_->ticks_done()));
    }
  }
  close_session();
  shutdown_imgui(false);
  shapes_.reset();
  return status;
}

// ---------------------------------------------------------------------------
// Window
// ---------------------------------------------------------------------------

void scroll_callback(GLFWwindow* window, double, double dy) {
  auto* app = static_cast<ViewerApp*>(glfwGetWindowUserPointer(window));
  if (app) app->scroll_accum_ += dy;
}

void ViewerApp::begin_mouse_drive() {
  ViewerDevice& dev = driver_->device();
  if (dev.source() != ToolSource::kMouse) {
    device_target_ = live_->pose;
    dev.set_target(device_target_);
    dev.set_source(ToolSource::kMouse);
  }
  dev.set_playing(true);
}

void ViewerApp::handle_window_input(GLFWwindow* window, double dt_s) {
  ImGuiIO& io = ImGui::GetIO();
  int win_w = 1, win_h = 1, fb_w = 1, fb_h = 1;
  glfwGetWindowSize(window, &win_w, &win_h);
  glfwGetFramebufferSize(window, &fb_w, &fb_h);
  const double sx = double(fb_w) / std::max(win_w, 1), sy = double(fb_h) / std::max(win_h, 1);
  double mx = 0, my = 0;
  glfwGetCursorPos(window, &mx, &my);
  mx *= sx;
  my *= sy;
  const double dx = mx - last_mx_, dy = my - last_my_;
  last_mx_ = mx;
  last_my_ = my;
  const bool in_scene = mx >= scene_x_ && mx < scene_x_ + scene_w_ && my >= scene_y_ &&
                        my < scene_y_ + scene_h_;
  const float aspect = float(scene_w_) / float(scene_h_);
  const GridSpec& spec = driver_->spec();
  const float extent = float(std::max(spec.size_x_m, spec.size_z_m));
  bool target_changed = false;

  auto plane_hit = [&](float plane_y, Vec3f& hit) {
    Ray ray = camera_.ray(float((mx - scene_x_) / scene_w_), float((my - scene_y_) / scene_h_), aspect);
    if (std::abs(ray.direction.y) < 1e-4f) return false;
    float t = (plane_y - ray.origin.y) / ray.direction.y;
    if (t < 0.0f) return false;
    hit = ray.origin + ray.direction * t;
    return true;
  };

  // Left drag: the tool follows the cursor in its horizontal plane.
  const bool left = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  if (left && !dragging_tool_ && in_scene && !io.WantCaptureMouse) {
    Vec3f hit;
    if (plane_hit(float(device_target_.position_m.y), hit)) {
      begin_mouse_drive();
      dragging_tool_ = true;
      grab_offset_ = to_f(device_target_.position_m) - hit;
    }
  } else if (left && dragging_tool_) {
    Vec3f hit;
    if (plane_hit(float(device_target_.position_m.y), hit)) {
      Vec3f p = hit + grab_offset_;
      double margin = 0.6 * driver_->blade_length_m();
      device_target_.position_m.x =
          std::clamp(double(p.x), spec.origin_m.x - margin, spec.origin_m.x + spec.size_x_m + margin);
      device_target_.position_m.z =
          std::clamp(double(p.z), spec.origin_m.z - margin, spec.origin_m.z + spec.size_z_m + margin);
      target_changed = true;
    }
  } else if (!left) {
    dragging_tool_ = false;
  }

  // Right drag: orbit; middle drag: pan.
  const bool right = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  const bool middle = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  if (right && (orbiting_ || (in_scene && !io.WantCaptureMouse))) {
    if (orbiting_) {
      camera_.yaw_rad -= float(dx) * 0.006f;
      camera_.pitch_rad = std::clamp(camera_.pitch_rad + float(dy) * 0.006f, 0.03f, 1.55f);
    }
    orbiting_ = true;
  } else {
    orbiting_ = false;
  }
  if (middle && (panning_ || (in_scene && !io.WantCaptureMouse))) {
    if (panning_) {
      float k = camera_.distance_m * 0.0015f;
      Vec3f right_dir{std::cos(camera_.yaw_rad), 0.0f, -std::sin(camera_.yaw_rad)};
      Vec3f fwd{std::sin(camera_.yaw_rad), 0.0f, std::cos(camera_.yaw_rad)};
      camera_.target = camera_.target - right_dir * (float(dx) * k) - fwd * (float(dy) * k);
    }
    panning_ = true;
  } else {
    panning_ = false;
  }

  // Wheel: tool height (shift or ctrl: zoom).
  if (scroll_accum_ != 0.0 && !io.WantCaptureMouse) {
    bool zoom = glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                glfwGetKey(window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS ||
                glfwGetKey(window, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS;
    if (zoom) {
      camera_.distance_m *= std::pow(0.9f, float(scroll_accum_));
    } else {
      begin_mouse_drive();
      double step = 0.04 * std::max(double(max_initial_height_m_), 0.02 * extent);
      device_target_.position_m.y = std::clamp(device_target_.position_m.y + scroll_accum_ * step,
                                               spec.origin_m.y - 0.05 * extent,
                                               spec.origin_m.y + 3.0 * max_initial_height_m_ + 0.2 * extent);
      target_changed = true;
    }
  }
  scroll_accum_ = 0.0;

  if (!io.WantCaptureKeyboard) {
    // Held keys turn the tool: Q/E about world Y, R/F tilt about the blade's own Z.
    auto held = [&](int key) { return glfwGetKey(window, key) == GLFW_PRESS; };
    double yaw = (held(GLFW_KEY_Q) ? 1.0 : 0.0) - (held(GLFW_KEY_E) ? 1.0 : 0.0);
    double tilt = (held(GLFW_KEY_R) ? 1.0 : 0.0) - (held(GLFW_KEY_F) ? 1.0 : 0.0);
    if (yaw != 0.0 || tilt != 0.0) {
      begin_mouse_drive();
      Quat q = device_target_.orientation;
      if (yaw != 0.0) q = quat_from_axis_angle({0, 1, 0}, yaw * 90.0 * kDegToRad * dt_s) * q;
      if (tilt != 0.0) q = q * quat_from_axis_angle({0, 0, 1}, tilt * 45.0 * kDegToRad * dt_s);
      device_target_.orientation = normalized(q);
      target_changed = true;
    }
    // Single presses.
    auto pressed = [&](int key) {
      bool down = held(key);
      bool was = key_down_[key];
      key_down_[key] = down;
      return down && !was;
    };
    ViewerDevice& dev = driver_->device();
    if (pressed(GLFW_KEY_SPACE)) dev.set_playing(!dev.playing());
    if (pressed(GLFW_KEY_N)) {
      dev.set_playing(false);
      dev.request_steps(1);
    }
    if (pressed(GLFW_KEY_BACKSPACE)) reset_requested_ = true;
    if (pressed(GLFW_KEY_T))
      camera_.mode = camera_.mode == CameraMode::kTop ? CameraMode::kOrbit : CameraMode::kTop;
    if (pressed(GLFW_KEY_C))
      style_.color = style_.color == ColorMode::kHeight ? ColorMode::kRemoved : ColorMode::kHeight;
  }
  if (target_changed) driver_->device().set_target(device_target_);
}

int ViewerApp::run_window() {
  if (!glfwInit()) {
    std::cerr << "terracut-viewer: cannot open a window (no display?). Use --screenshot for "
                 "headless rendering, or run under xvfb-run.\n";
    return kExitNoContext;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, 4);
  std::string title = "terracut viewer - " + base_scenario_.name;
  GLFWwindow* window = glfwCreateWindow(options_.width, options_.height, title.c_str(), nullptr, nullptr);
  if (!window) {
    std::cerr << "terracut-viewer: cannot create an OpenGL 3.3 core window.\n";
    glfwTerminate();
    return kExitNoContext;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  glfwSetWindowUserPointer(window, this);
  glfwSetScrollCallback(window, scroll_callback);  // ImGui chains to it
  // Sticky keys and buttons: a tap shorter than a frame is still seen once.
  glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
  glfwSetInputMode(window, GLFW_STICKY_MOUSE_BUTTONS, GLFW_TRUE);
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
    if (reset_requested_) reset_session();
    // Slow drawing posts sparse targets: let the tool glide between them.
    driver_->device().set_lag_s(1.5 * dt);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    handle_window_input(window, dt);
    consume_frame();
    push_history();
    int fb_w = 1, fb_h = 1;
    glfwGetFramebufferSize(window, &fb_w, &fb_h);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    render(fb_w, fb_h, true);
    glfwSwapBuffers(window);
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

}  // namespace terracut::viewer
