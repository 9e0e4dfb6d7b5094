// The viewer without a window (EGL): the lock-step run that draws the
// scripted sequence and writes the screenshot, and the real-time benchmark
// with its report (frame rate, uploads, the haptic loop's timing).
#include "viewer_app_internal.hpp"

#include <backends/imgui_impl_opengl3.h>
#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "gl_context.hpp"
#include "png_rgb.hpp"

namespace terracut::viewer {

int ViewerApp::run_headless() {
  std::unique_ptr<HeadlessContext> context;
  try {
    context = std::make_unique<HeadlessContext>();
  } catch (const ContextUnavailable& e) {
    std::cerr << "terracut-viewer: cannot create an OpenGL 3.3 context: " << e.what() << "\n";
    return kExitNoContext;
  }
  // What is drawn with the context goes before it, also when a step below
  // throws (a session the scenario cannot open, a PNG that cannot be written).
  const GLScope gl_scope{*this, false};
  const int w = options_.width, h = options_.height;
  Framebuffer fb(w, h, options_.benchmark_frames > 0 ? 0 : options_.msaa);
  fb.bind();
  init_gl_objects();
  init_imgui(false, nullptr);
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(float(w), float(h));

  int status = 0;
  if (options_.benchmark_frames > 0) {
    run_benchmark(w, h);
  } else {
    run_lockstep(w, h);
    if (!options_.screenshot.empty()) {
      write_png_rgb(options_.screenshot, fb.read());
      std::printf("terracut-viewer: wrote %s (%dx%d, t = %.3f s, %lld ticks)\n",
                  options_.screenshot.string().c_str(), w, h, live_->t_s,
                  static_cast<long long>(driver_->ticks_done()));
    }
  }
  close_session(true);  // the end of the session, told to a remote; the GL objects go with gl_scope
  return status;
}

void ViewerApp::headless_frame(int w, int h, bool with_panel_time) {
  ImGui::GetIO().DeltaTime = with_panel_time ? float(options_.frame_time_s) : 1.0f / 60.0f;
  ImGui_ImplOpenGL3_NewFrame();
  render(w, h, true);
}

void ViewerApp::run_benchmark(int w, int h) {
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
    headless_frame(w, h, false);
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
      headless_frame(w, h, false);
      glFinish();
    }
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  print_benchmark(w, h, wall, uploaded, frames_with_upload);
  if (!options_.benchmark_no_draw) {
    // Where a frame goes: more frames, phase by phase, each phase ended by
    // glFinish (llvmpipe rasterises at the flush, so the time is the phase's
    // own): the terrain upload (taking the newest frame), the terrain alone,
    // the scene (sky, terrain, tool, bodies) and the whole frame with the
    // panel. Medians over the frames.
    std::vector<double> upload_s, terrain_s, scene_s, full_s;
    std::vector<double> triangles;
    auto timed = [](auto&& phase) {
      const Clock::time_point start = Clock::now();
      phase();
      glFinish();
      return std::chrono::duration<double>(Clock::now() - start).count();
    };
    const int phase_frames = std::clamp(options_.benchmark_frames / 2, 1, 40);
    for (int i = 0; i < phase_frames; ++i) {
      upload_s.push_back(timed([&] { consume_frame(); }));
      push_history();
      full_s.push_back(timed([&] { headless_frame(w, h, false); }));
      scene_s.push_back(timed([&] { render(w, h, false); }));
      terrain_s.push_back(timed([&] {
        draw_background(w, h);
        glViewport(scene_x_, 0, scene_w_, scene_h_);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        draw_terrain(camera_.projection(float(scene_w_) / float(scene_h_)) * camera_.view(),
                     camera_.eye());
      }));
      triangles.push_back(double(terrain_->triangle_count()));
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    auto median_ms = [&](const std::vector<double>& v) { return 1000.0 * median(v); };
    const double full = median_ms(full_s), scene = median_ms(scene_s);
    std::printf(
        "  frame phases (median of %d frames, each ended by glFinish): upload %.2f ms, terrain "
        "%.2f ms (%.0f triangles), scene %.2f ms (sky, terrain, tool, bodies), panel %.2f ms "
        "(frame %.2f ms less the scene)\n",
        phase_frames, median_ms(upload_s), median_ms(terrain_s), median(triangles),
        scene, full - scene, full);
  }
  print_loop_summary();
}

void ViewerApp::print_benchmark(int w, int h, double wall_s, std::int64_t uploaded,
                                std::int64_t frames_with_upload) {
  const GridSpec& spec = driver_->spec();
  std::printf(
      "benchmark: %dx%d %s grid, mesh %dx%d (%lld triangles), %dx%d pixels, panel %s, %s\n"
      "  %d frames in %.2f s: %.2f frames/s (%.1f ms/frame); %lld frames uploaded a changed "
      "rectangle, %.0f samples/frame on average\n",
      spec.cols, spec.rows, std::string(to_string(driver_->representation())).c_str(),
      terrain_->mesh_cols(), terrain_->mesh_rows(),
      static_cast<long long>(terrain_->triangle_count()), w, h, options_.panel ? "on" : "off",
      describe_current_context().c_str(), options_.benchmark_frames, wall_s,
      options_.benchmark_frames / wall_s, 1000.0 * wall_s / options_.benchmark_frames,
      static_cast<long long>(frames_with_upload), double(uploaded) / options_.benchmark_frames);
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
      driver_->realtime_line().c_str());
}

void ViewerApp::run_lockstep(int w, int h) {
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
    if (k == frames && options_.pause_last_frame) driver_->device().set_playing(false);
    // The panel needs a frame or two to lay itself out; draw only the last three.
    if (k + 3 > frames) headless_frame(w, h, true);
  }
  for (int i = frames; i < 3; ++i) headless_frame(w, h, true);
}

}  // namespace terracut::viewer
