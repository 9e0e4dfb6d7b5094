// The viewer's ImGui side: the ImGui context (font, style, backends), the
// panel on the left, one function per section (run controls, contact and
// force with the plots, timing, display, model parameters, help), and the
// value labels drawn next to the tool.
#include "terracut/core/soil.hpp"
#include "viewer_app_internal.hpp"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace terracut::viewer {
namespace {

// A titled separator (ImGui 1.86 has no SeparatorText).
void section(const char* title) {
  ImGui::Spacing();
  ImGui::TextColored(ImVec4(0.55f, 0.75f, 1.0f, 1.0f), "%s", title);
  ImGui::Separator();
}

}  // namespace

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
  // Beside the tool, clear of the blade's line on the screen, inside the
  // scene (label_position: a resize never clips it).
  const Vec3f ea = transform_point(vp, to_f(l.edge.a)), eb = transform_point(vp, to_f(l.edge.b));
  const float edx = 0.5f * (eb.x - ea.x) * float(w), edy = -0.5f * (eb.y - ea.y) * float(h);
  const float pad = 6.0f;
  float lx = 0.0f, ly = 0.0f;
  label_position(sx, sy, edx, edy, size.x + 2.0f * pad, size.y + 2.0f * pad,
                 ScreenRect{float(x), float(y), float(w), float(h)}, 22.0f, lx, ly);
  ImVec2 at(lx + pad, ly + pad);
  dl->AddRectFilled(ImVec2(lx, ly), ImVec2(lx + size.x + 2.0f * pad, ly + size.y + 2.0f * pad),
                    IM_COL32(20, 22, 28, 190), 4.0f);
  dl->AddText(at, IM_COL32(255, 255, 255, 255), text);
}

void ViewerApp::draw_panel(int fb_width, int fb_height) {
  (void)fb_width;
  update_frame_timing();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(float(panel_width_), float(fb_height)));
  ImGui::Begin("terracut viewer", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  draw_panel_header();
  draw_run_section();
  draw_tool_section();
  draw_contact_section();
  draw_mmt_section();
  draw_timing_section();
  draw_display_section();
  draw_model_section();
  draw_help_section();
  ImGui::End();
}

void ViewerApp::update_frame_timing() {
  // Frame timing (wall clock between panel draws) and loop statistics, 4 times a second.
  Live& l = *live_;
  Clock::time_point now = Clock::now();
  double dt_ms = std::chrono::duration<double, std::milli>(now - l.last_frame).count();
  l.last_frame = now;
  l.frame_ms = l.frame_ms <= 0.0 ? dt_ms : 0.9 * l.frame_ms + 0.1 * dt_ms;
  if (std::chrono::duration<double>(now - l.last_stats).count() > 0.25 || l.stats.ticks == 0) {
    l.stats = timing_.snapshot();
    l.last_stats = now;
  }
}

void ViewerApp::draw_panel_header() {
  // The scenario's name, its grid and the terrain mesh.
  LoopDriver& d = *driver_;
  const GridSpec& spec = d.spec();
  ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.45f, 1.0f), "%s", scenario_.base.name.c_str());
  ImGui::Text("%d x %d %s, %.2f x %.2f m", spec.cols, spec.rows,
              std::string(to_string(d.representation())).c_str(), spec.size_x_m, spec.size_z_m);
  ImGui::TextDisabled("mesh %d x %d%s, %lld triangles", terrain_->mesh_cols(), terrain_->mesh_rows(),
                      terrain_->blocky_mesh() ? " (boxes)" : "",
                      static_cast<long long>(terrain_->triangle_count()));
}

void ViewerApp::draw_mmt_section() {
  // --- teleoperation: the link and what came back over it ---
  if (!driver_->mmt()) return;
  const MmtLive& m = driver_->mmt_live();
  section("Teleoperation (MMT)");
  ImGui::Text("RTT %.0f ms measured (%.0f ms emulated)", m.rtt_s.load() * 1e3,
              m.emulated_rtt_s.load() * 1e3);
  ImGui::Text("loss %.1f %% to remote, %.1f %% back (emulated)", m.loss_to_remote.load() * 100.0,
              m.loss_to_operator.load() * 100.0);
  ImGui::Text("commands lost %.1f %% (last second)", m.command_loss.load() * 100.0);
  ImGui::Text("updates: %lld patches, %lld estimates", static_cast<long long>(m.patches.load()),
              static_cast<long long>(m.estimates.load()));
  ImGui::Text("soil factor %.3f (remote says %.3f)", m.scale_applied.load(), m.scale_target.load());
  ImGui::Text("force error %.1f N RMS (remote %.1f N)", m.force_error_rms_n.load(),
              m.remote_force_n.load());
  if (m.rejected.load() > 0)
    ImGui::TextDisabled("%lld datagrams rejected", static_cast<long long>(m.rejected.load()));
  if (m.udp_dropped.load() > 0 || m.peers_refused.load() > 0)
    ImGui::TextDisabled("UDP: %lld datagrams dropped, %lld peers refused",
                        static_cast<long long>(m.udp_dropped.load()),
                        static_cast<long long>(m.peers_refused.load()));
  if (m.link_silent.load())
    ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.35f, 1.0f), "link silent: force fading out");
}

void ViewerApp::draw_run_section() {
  // --- run controls ---
  const Live& l = *live_;
  section("Run");
  ViewerDevice& dev = driver_->device();
  bool playing = dev.playing();
  if (ImGui::Button(playing ? "Pause" : "Play", ImVec2(70, 0))) dev.set_playing(!playing);
  ImGui::SameLine();
  char step_label[32];
  std::snprintf(step_label, sizeof step_label, "Step %.0f ms", kStepTime_s * 1e3);
  if (ImGui::Button(step_label, ImVec2(90, 0))) {
    dev.set_playing(false);
    dev.request_step_s(kStepTime_s);
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
  // The device's clock: it stands still while paused (the loop's own time,
  // which keeps ticking, is the step count's).
  ImGui::Text("t = %.3f s   step %lld", dev.clock_s(), static_cast<long long>(l.step));
  if (!playing) {
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.35f, 1.0f), "%s",
                       dev.stepping() ? "stepping" : "paused");
  }
  if (dev.source() == ToolSource::kScript) draw_script_progress();
}

void ViewerApp::draw_script_progress() {
  // Where the script is: the cut being played, or the transit to the next.
  LoopDriver& d = *driver_;
  ViewerDevice& dev = d.device();
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
                    scenario_.base.cuts[std::size_t(leg->cut)].name.c_str(), leg->sequence_index + 1,
                    scenario_.base.sequence.size(), st);
    } else {
      std::snprintf(label, sizeof label, "transit to the next cut  %.2f s", st);
    }
    ImGui::ProgressBar(float(std::min(1.0, st / std::max(d.tour().duration_s(), 1e-9))),
                       ImVec2(-1, 0), label);
  }
}

void ViewerApp::draw_tool_section() {
  // --- where the tool is ---
  const Live& l = *live_;
  const ToolReadout& r = l.readout;
  section("Tool");
  ImGui::Text("height %.3f m", r.height_m);
  ImGui::SameLine();
  if (r.depth_m > 0.0)
    ImGui::Text("  depth %.3f m in the soil", r.depth_m);
  else
    ImGui::Text("  %.3f m above the soil", -r.depth_m);
  // Rounded to the shown tenth first, so that -0.01 reads 0.0, not -0.0.
  auto tenth = [](double deg) { return std::round(deg * 10.0) / 10.0 + 0.0; };
  ImGui::Text("yaw %.1f deg   tilt %.1f deg", tenth(r.yaw_deg), tenth(r.tilt_deg));
  if (driver_->bucket().enabled()) {
    BladeSpec blade;
    blade.length_m = driver_->blade_length_m();
    blade.bucket = driver_->bucket();
    const double holds = bucket_retained_m3(blade, l.pose.orientation, driver_->repose_deg());
    ImGui::Text("bucket %.2f l of %.2f l it holds now", l.bucket_load_m3 * 1e3, holds * 1e3);
  }
  if (driver_->device().source() == ToolSource::kMouse && r.depth_m <= 0.0)
    ImGui::TextDisabled("scroll down to dig; left drag moves the tool");
}

void ViewerApp::draw_contact_section() {
  // --- live values and plots ---
  const Live& l = *live_;
  const haptics::ViewWindow& w = l.window;
  section("Contact and force");
  ImGui::Text("contact %.3f m   deepest %.3f m", l.contact.length_m, l.contact.max_depth_m);
  ImGui::Text("|F| %.1f N world   %.2f N device", double(magnitude(l.force_world_n)),
              double(magnitude(l.force_device_n)));
  // Every tick since the previous drawn frame, so a brief contact shows.
  ImGui::Text("this frame (%lld ticks): mean %.1f  max %.1f N", static_cast<long long>(w.ticks),
              w.mean(w.force_sum_n), w.force_max_n);
  if (std::abs(l.penetration_n) >= 0.05 || std::abs(l.twist_torque_n_m) >= 0.05)
    ImGui::Text("push-in %.1f N   twist %.1f N m", l.penetration_n, l.twist_torque_n_m);
  if (l.body_total > 0) {
    ImGui::Text("bodies %d (Bullet)   on the blade %.1f N", l.body_total,
                double(magnitude(l.body_force_n)));
    ImGui::Text("  this frame: mean %.1f  max %.1f N", w.mean(w.body_force_sum_n),
                w.body_force_max_n);
    ImGui::Text("  largest since the start or Reset: %.1f N", l.body_force_max_n);
  }
  draw_plots();
}

void ViewerApp::draw_plots() {
  // Contact length, force and loop jitter over the last kHistory frames.
  const Live& l = *live_;
  char overlay[64];
  const float plot_w = float(panel_width_) - 20.0f;
  std::snprintf(overlay, sizeof overlay, "contact length %.3f m", l.contact.length_m);
  ImGui::PlotLines("##contact", l.contact_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                   float(std::max(driver_->blade_length_m(), 1e-3)), ImVec2(plot_w, 52));
  float fmax = 1.0f;
  for (float v : l.force_hist) fmax = std::max(fmax, v);
  std::snprintf(overlay, sizeof overlay, "|F| per frame max, N (plot max %.0f)", double(fmax));
  ImGui::PlotLines("##force", l.force_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                   fmax * 1.1f, ImVec2(plot_w, 52));
  if (l.body_total > 0) {
    float bmax = 1.0f;
    for (float v : l.body_hist) bmax = std::max(bmax, v);
    std::snprintf(overlay, sizeof overlay, "bodies' force per frame max, N (%.0f)", double(bmax));
    ImGui::PlotLines("##bodies", l.body_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                     bmax * 1.1f, ImVec2(plot_w, 44));
  }
  float jmax = 50.0f;
  for (float v : l.jitter_hist) jmax = std::max(jmax, v);
  std::snprintf(overlay, sizeof overlay, driver_options_.paced ? "loop jitter, worst per frame (max %.0f us)"
                                                               : "loop jitter: none in lock-step",
                double(jmax));
  ImGui::PlotLines("##jitter", l.jitter_hist.data(), kHistory, l.hist_next, overlay, 0.0f,
                   jmax * 1.1f, ImVec2(plot_w, 44));
}

void ViewerApp::draw_timing_section() {
  // --- timing ---
  const Live& l = *live_;
  LoopDriver& d = *driver_;
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

  // What the device check lowered, requested -> used.
  const std::vector<std::string> changes = d.force_model().limit_changes();
  if (!changes.empty()) {
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.35f, 1.0f), "device limits lowered:");
    ImGui::PushTextWrapPos(0.0f);
    for (const std::string& c : changes)
      ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.35f, 1.0f), "  %s", c.c_str());
    ImGui::PopTextWrapPos();
  }
}

void ViewerApp::draw_display_section() {
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
}

void ViewerApp::draw_model_section() {
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
    draw_force_model_params();
  }
}

void ViewerApp::draw_force_model_params() {
  // The pending force model: cutting model, drag, soil, rake, surface spring, scale.
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
  // The soil's material: a preset's (or the scenario's own), and the blade's rake.
  const char* soils[] = {"scenario's", "dry_sand", "loose_sand", "clay", "gravel"};
  int soil = pending_soil_ + 1;
  ImGui::SetNextItemWidth(-110);
  if (ImGui::Combo("soil", &soil, soils, 5)) {
    pending_soil_ = soil - 1;
    pending_material_ = pending_soil_ < 0 ? base_scenario_.base.soil.material
                                          : soil_preset(SoilPreset(pending_soil_));
  }
  float rake = float(pending_rake_deg_);
  ImGui::SetNextItemWidth(-110);
  if (ImGui::SliderFloat("rake deg", &rake, 20.0f, 160.0f, "%.0f")) pending_rake_deg_ = rake;
  ImGui::Checkbox("push-in resistance", &fp.penetration_enabled);
  ImGui::SameLine();
  ImGui::Checkbox("twist resistance", &fp.twist_enabled);
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

void ViewerApp::draw_help_section() {
  if (ImGui::CollapsingHeader("Mouse and keys")) {
    ImGui::TextWrapped(
        "Left drag: move the tool in its horizontal plane (the first drag puts it down just above "
        "the soil under the cursor).  Wheel: tool up/down (scroll down to dig).  Q/E: turn about "
        "Y.  R/F: tilt.  Right drag: orbit.  Middle drag: pan.  Shift+wheel: zoom.  Space: "
        "play/pause.  N: step 20 ms.  Backspace: reset.  T: top view.  C: colour.  Esc or "
        "Ctrl+Q: quit.");
  }
}

}  // namespace terracut::viewer
