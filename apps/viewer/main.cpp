// terracut-viewer: a live 3D view of a cut. Opens a scenario (or a heightmap
// PNG) in a window, where the mouse and keyboard drive the tool, or renders
// headless (EGL, no display) to a PNG or for a benchmark. See docs/viewer.md.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "../exit_codes.hpp"
#include "gl_context.hpp"
#include "terracut/core/error.hpp"
#include "terracut/session/mmt_process.hpp"
#include "viewer_app.hpp"

namespace {

using terracut::viewer::ViewerOptions;

// "WxH" -> width, height (each in [16, 16384]).
bool parse_size(const std::string& text, int& w, int& h) {
  int a = 0, b = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &a, &x, &b, &extra) != 3 || (x != 'x' && x != 'X'))
    return false;
  if (a < 16 || b < 16 || a > 16384 || b > 16384) return false;
  w = a;
  h = b;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"terracut-viewer: watch and drive a cut in 3D (window), or render it headless"};
  ViewerOptions opt;
  std::string input, size = "1280x800", camera = "orbit", color = "height", orbit, representation,
              resolution, screenshot, font;
  bool no_panel = false, no_contours = false;
  app.add_option("input", input, "scenario (.yaml) or heightmap (.png)")->required();
  app.add_option("--screenshot", screenshot,
                 "render headless (EGL, no display) and write the last frame to this PNG");
  app.add_flag("--headless", opt.headless, "render without a window (implied by --screenshot)");
  app.add_option("--frames", opt.frames,
                 "headless: frames to simulate and draw, each --frame-time of the script "
                 "(default: the whole sequence)")
      ->check(CLI::Range(0, 10000000));
  app.add_option("--frame-time", opt.frame_time_s, "headless: simulated seconds per frame")
      ->check(CLI::Range(1e-6, 1e3));
  app.add_option("--size", size, "image or window size WxH (default 1280x800)");
  app.add_option("--camera", camera, "orbit (default) or top (orthographic, straight down)")
      ->check(CLI::IsMember({"orbit", "top"}));
  app.add_option("--orbit", orbit, "orbit camera YAW,PITCH,ZOOM (degrees, degrees, factor)");
  std::string look_at;
  app.add_option("--look-at", look_at, "orbit camera centre X,Y,Z (world metres)");
  app.add_option("--color", color, "height (default) or removed")
      ->check(CLI::IsMember({"height", "removed"}));
  app.add_flag("--no-contours", no_contours, "no height contour lines");
  app.add_flag("--no-panel", no_panel, "no ImGui panel or labels");
  app.add_option("--representation", representation, "surface or columns (overrides the scenario)")
      ->check(CLI::IsMember({"surface", "columns"}));
  app.add_option("--resolution", resolution, "N or COLSxROWS (overrides the scenario)");
  app.add_option("--benchmark-frames", opt.benchmark_frames,
                 "headless: draw this many frames while the loop cuts in real time; print "
                 "frames/s and the loop's period percentiles")
      ->check(CLI::Range(1, 1000000));
  app.add_flag("--benchmark-no-draw", opt.benchmark_no_draw,
               "benchmark: take the frames at 60/s without drawing them (the loop's reference)");
  app.add_option("--mesh-max", opt.mesh_max, "largest terrain mesh side, vertices (default 512)")
      ->check(CLI::Range(2, 8192));
  app.add_option("--msaa", opt.msaa, "multisampling samples, window and headless (default 4, 0: none)")
      ->check(CLI::Range(0, 16));
  app.add_option("--max-fps", opt.max_fps, "window: frame cap (default 60, 0: none)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--extent", opt.heightmap_size_m, "heightmap input: side of the terrain, metres")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--full-scale", opt.heightmap_full_scale_m,
                 "heightmap input: height of a white pixel, metres")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--font", font, "TTF font for the panel (default DejaVu Sans when installed)");
  app.add_flag("--play-script", opt.tool_from_script,
               "window: start by playing the scenario's cuts (default: the mouse drives)");
  app.add_option("--speed", opt.play_speed,
                 "window: replay speed of the script (device seconds per second)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 16.0));
  app.add_flag("--loop", opt.loop_script,
               "window: replay the script from the initial terrain each time it ends");
  app.add_option("--window-seconds", opt.window_seconds,
                 "window: close after this many seconds and print the frame count (measurements)")
      ->check(CLI::Range(0.0, 86400.0));
  app.add_flag("--paused", opt.pause_last_frame,
               "headless: draw the last frame as paused (for screenshots of the panel)");
  app.add_flag("--mmt", opt.mmt,
               "teleoperation: the tool drives the operator station of the scenario's mmt: "
               "section; the remote station runs in-process over the emulated link");
  app.add_option("--remote", opt.remote,
                 "with --mmt: the remote station is another process (`terracut mmt --role "
                 "remote`) at ADDR:PORT or PORT (UDP, IPv4), not in-process");
  std::string key_file;
  app.add_option("--key", key_file,
                 "with --remote: the key file the remote was started with (`terracut key`); "
                 "default: the environment variable TERRACUT_MMT_KEY");
  bool insecure_loopback = false;
  app.add_flag("--insecure-loopback", insecure_loopback,
               "with --remote: no key, no authentication (a demo on 127.0.0.1 only)");
  bool no_realtime = false;
  app.add_flag("--no-realtime", no_realtime,
               "do not ask for SCHED_FIFO for the haptic loop's thread");
  app.footer(terracut::apps::kExitCodesHelp);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every command-line error exits with the
    // one usage code (CLI11's own codes differ by error).
    const int code = app.exit(e);
    return code == 0 ? terracut::apps::kExitOk : terracut::apps::kExitUsage;
  }
  opt.realtime = !no_realtime;

  try {
    if (!opt.remote.empty()) {
      if (!opt.mmt)
        throw terracut::InputError("--remote: needs --mmt (the viewer is then the operator station)");
      terracut::session::parse_endpoint(opt.remote, "--remote", "127.0.0.1");  // refused here if bad
      opt.key = terracut::session::link_key(key_file, insecure_loopback);
      if (opt.key.insecure)
        std::cerr << "terracut-viewer: warning: --insecure-loopback: the link is NOT authenticated\n";
    } else if (!key_file.empty() || insecure_loopback) {
      throw terracut::InputError(std::string(key_file.empty() ? "--insecure-loopback" : "--key") +
                                 ": only with --remote");
    }
    opt.input = input;
    opt.screenshot = screenshot;
    opt.font = font;
    opt.panel = !no_panel;
    opt.contours = !no_contours;
    if (!parse_size(size, opt.width, opt.height))
      throw terracut::InputError("--size: expected WxH with sides in [16, 16384], got '" + size + "'");
    opt.camera = camera == "top" ? terracut::viewer::CameraMode::kTop
                                 : terracut::viewer::CameraMode::kOrbit;
    opt.color = color == "removed" ? terracut::viewer::ColorMode::kRemoved
                                   : terracut::viewer::ColorMode::kHeight;
    if (!orbit.empty()) {
      float y = 0, p = 0, z = 0;
      char extra = 0;
      if (std::sscanf(orbit.c_str(), "%f,%f,%f%c", &y, &p, &z, &extra) != 3 || !(z > 0.0f) ||
          !(p > 0.0f) || !(p < 90.0f))
        throw terracut::InputError("--orbit: expected YAW,PITCH,ZOOM with PITCH in (0, 90) and "
                                   "ZOOM > 0, got '" + orbit + "'");
      opt.orbit = std::array<float, 3>{y, p, z};
    }
    if (!look_at.empty()) {
      double x = 0, y = 0, z = 0;
      char extra = 0;
      if (std::sscanf(look_at.c_str(), "%lf,%lf,%lf%c", &x, &y, &z, &extra) != 3 ||
          !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
        throw terracut::InputError("--look-at: expected X,Y,Z in metres, got '" + look_at + "'");
      opt.look_at = terracut::Vec3{x, y, z};
    }
    if (!representation.empty())
      opt.representation = terracut::parse_enum<terracut::Representation>(representation);
    if (!resolution.empty()) opt.resolution = terracut::io::parse_resolution(resolution);
    if (!opt.screenshot.empty() || opt.benchmark_frames > 0) opt.headless = true;
    // A screenshot that cannot be written is said before the whole sequence is drawn.
    if (!opt.screenshot.empty()) {
      const std::filesystem::path folder = opt.screenshot.parent_path();
      std::error_code ec;
      if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
        throw terracut::InputError("--screenshot: the folder " + folder.string() +
                                   " does not exist (the PNG is written into an existing folder)");
    }
    if (std::filesystem::path(input).extension() == ".png" && app.count("--extent") == 0)
      std::cerr << "terracut-viewer: " << input << " opens as " << opt.heightmap_size_m << " x "
                << opt.heightmap_size_m << " m with white = " << opt.heightmap_full_scale_m
                << " m high (the defaults; set --extent and --full-scale)\n";

    terracut::viewer::ViewerApp viewer(opt, terracut::viewer::load_input(opt));
    return opt.headless ? viewer.run_headless() : viewer.run_window();
  } catch (const terracut::InputError& e) {
    std::cerr << "terracut-viewer: error: " << e.what() << "\n";
    return terracut::apps::kExitError;
  } catch (const std::exception& e) {
    std::cerr << "terracut-viewer: error: " << e.what() << "\n";
    return terracut::apps::kExitError;
  }
}
