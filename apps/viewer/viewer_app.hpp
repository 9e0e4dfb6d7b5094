// The viewer application: one session (a LoopDriver stepping the simulation
// on its own thread) drawn by the terrain and shape renderers, with the
// ImGui panel, either in a GLFW window driven by mouse and keyboard or
// headless (EGL) for screenshots and benchmarks.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "camera.hpp"
#include "gl_context.hpp"
#include "loop_driver.hpp"
#include "viewer_controls.hpp"
#include "shape_renderer.hpp"
#include "terrain_renderer.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/io/scenario.hpp"

struct GLFWwindow;

namespace terracut::viewer {

/// Command-line options of terracut-viewer (see docs/viewer.md).
struct ViewerOptions {
  std::filesystem::path input;  ///< a scenario (.yaml/.yml) or a heightmap (.png)
  std::filesystem::path screenshot;  ///< headless: write the last frame here (PNG)
  bool headless = false;             ///< render with EGL, no window
  /// Headless frames to simulate and draw; -1: enough for the whole scripted sequence.
  int frames = -1;
  double frame_time_s = 1.0 / 60.0;  ///< headless: simulated seconds per frame, > 0
  int width = 1280;                  ///< image or window width, pixels
  int height = 800;                  ///< image or window height, pixels
  CameraMode camera = CameraMode::kOrbit;
  /// Orbit camera override: yaw and pitch in degrees, zoom factor on the framing distance.
  std::optional<std::array<float, 3>> orbit;
  /// Orbit camera override: the point it turns about, world metres.
  std::optional<Vec3> look_at;
  ColorMode color = ColorMode::kHeight;
  bool contours = true;   ///< height contour lines
  bool panel = true;      ///< draw the ImGui panel
  std::optional<Representation> representation;
  std::optional<io::Resolution> resolution;
  int benchmark_frames = 0;  ///< > 0: headless benchmark of this many frames
  bool benchmark_no_draw = false;  ///< benchmark: consume frames at 60/s without drawing (reference)
  int mesh_max = kDefaultMeshMax;
  int msaa = 4;              ///< headless multisampling (0: none)
  int max_fps = 60;          ///< window mode frame cap (0: none)
  double heightmap_size_m = 1.0;        ///< heightmap input: extent along X and Z, metres
  double heightmap_full_scale_m = 0.2;  ///< heightmap input: height of white, metres
  std::filesystem::path font;           ///< TTF for the panel; empty: DejaVu Sans if present
  bool tool_from_script = false;        ///< window mode: start playing the script (else mouse)
  double play_speed = 1.0;              ///< device clock per second, (0, 16]: the script's replay speed
  bool loop_script = false;             ///< window mode: replay the script (a reset) when it ends
  double window_seconds = 0.0;          ///< window mode: close after this many seconds (0: never)
  bool pause_last_frame = false;        ///< headless: draw the last frame paused
  bool realtime = true;                 ///< ask for SCHED_FIFO for the loop thread
  /// Run the scenario's `mmt:` section: the tool drives the operator
  /// station, the remote runs in-process over the emulated link.
  bool mmt = false;
  /// With mmt: the remote station is `terracut mmt --role remote` at this
  /// "ADDR:PORT" or "PORT" (UDP) instead of in-process.
  std::string remote;
  /// With remote: the key both stations share (--key, TERRACUT_MMT_KEY, or
  /// --insecure-loopback's).
  net::LinkKey key;
};

/// Loads the scenario (and its `haptics:` section) or the heightmap named by
/// options.input, with the resolution/representation overrides applied.
/// Throws InputError.
session::Scenario load_input(const ViewerOptions& options);

class ViewerApp {
 public:
  /// haptic_settings: the scenario's `haptics:` section (viewer_settings() is applied).
  ViewerApp(ViewerOptions options, session::Scenario scenario);
  ~ViewerApp();
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  /// Headless: screenshot and/or benchmark. Returns the exit status
  /// (kExitNoContext when EGL gives no context).
  int run_headless();
  /// A GLFW window (needs a display). Returns the exit status.
  int run_window();

 private:
  struct Live;  // the latest frame's scalar fields and the plot histories
  struct ToolMarks;  // where and how large the tool's marks are drawn (viewer_scene.cpp)
  struct Pointer;    // this frame's cursor, framebuffer pixels (viewer_input.cpp)

  void init_gl_objects();
  void init_imgui(bool with_glfw, GLFWwindow* window);
  void shutdown_imgui(bool with_glfw);
  /// Deletes everything made with the OpenGL context (the session's terrain
  /// renderer, the shapes, the window's framebuffer, ImGui's backend) while
  /// it is still current; idempotent. Every way out of run_headless and
  /// run_window calls it, an error included (GLScope): a GL call without a
  /// current context aborts inside epoxy.
  void release_gl(bool with_glfw);
  /// Calls release_gl when it goes out of scope (declare it after the context).
  struct GLScope {
    ViewerApp& app;
    bool with_glfw;
    ~GLScope() { app.release_gl(with_glfw); }
  };
  void open_session(const DriverOptions& driver_options);
  /// Widens the orbit camera's framing to the tool's scripted path.
  void frame_on_tool_path();
  /// Stops the session; end_remote: also tells a remote station in another
  /// process that its session is over (the viewer closes; not on a Reset).
  void close_session(bool end_remote = false);
  /// Takes the newest published frame (if any), uploads its dirty rectangle
  /// and records its values; returns whether one was taken whose picture
  /// differs from the previous one.
  bool consume_frame();
  /// The first frame of a session, or a frame the gate lets through.
  bool take_frame();
  void push_history();
  void render(int fb_width, int fb_height, bool draw_imgui);
  void draw_scene(int x, int y, int w, int h);
  void draw_panel(int fb_width, int fb_height);
  void draw_labels(int x, int y, int w, int h);
  void apply_model_changes();
  void reset_session();
  /// Stops the loop and prints its timing (benchmark).
  void print_loop_summary();
  void handle_window_input(GLFWwindow* window, double dt_s);
  void begin_mouse_drive();
  float ground_height_at(double x, double z) const;
  /// Where the cursor's ray first meets the terrain surface (within the
  /// terrain's extent), world metres; false when it misses.
  bool terrain_hit(const Pointer& p, Vec3f& hit) const;
  /// Prints the loop's real-time line (as `terracut haptics` does).
  void print_realtime_line();

  // Window loop (viewer_app.cpp). open_window: nullptr (and a message) when
  // no window can be made.
  GLFWwindow* open_window();
  /// One iteration of the window: input, the newest frame and, when
  /// something changed, the drawing; returns whether it drew.
  bool window_frame(GLFWwindow* window, double dt_s);

  // Headless runs (viewer_headless.cpp).
  void headless_frame(int w, int h, bool with_panel_time);
  void run_benchmark(int w, int h);
  void print_benchmark(int w, int h, double wall_s, std::int64_t uploaded,
                       std::int64_t frames_with_upload);
  void run_lockstep(int w, int h);

  // The 3D scene's parts, in drawing order (viewer_scene.cpp).
  void draw_background(int fb_width, int fb_height);
  void draw_terrain(const Mat4& vp, Vec3f eye);
  ToolMarks tool_marks() const;
  void draw_blade_edge(const ToolMarks& m);
  void draw_bodies();
  void draw_device(const ToolMarks& m);
  void draw_force_arrow(const ToolMarks& m);
  void draw_see_through(const ToolMarks& m);

  // The panel's sections, top to bottom (viewer_panel.cpp).
  void update_frame_timing();
  void draw_panel_header();
  void draw_run_section();
  void draw_script_progress();
  void draw_tool_section();
  void draw_contact_section();
  void draw_mmt_section();
  void draw_plots();
  void draw_timing_section();
  void draw_display_section();
  void draw_model_section();
  void draw_force_model_params();
  void draw_help_section();

  // Mouse and keyboard, in the order handle_window_input applies them (viewer_input.cpp).
  Pointer read_pointer(GLFWwindow* window);
  bool plane_hit(const Pointer& p, float plane_y, Vec3f& hit) const;
  bool drag_tool(GLFWwindow* window, const Pointer& p);
  void drag_camera(GLFWwindow* window, const Pointer& p);
  bool handle_wheel(GLFWwindow* window);
  bool turn_tool(GLFWwindow* window, double dt_s);
  void key_commands(GLFWwindow* window);
  bool key_pressed(GLFWwindow* window, int key);

  ViewerOptions options_;
  session::Scenario base_scenario_;  // as loaded (overrides applied)
  session::Scenario scenario_;       // the running session's
  haptics::HapticSettings haptics_;
  DriverOptions driver_options_;
  LoopTiming timing_;  // the loop's period and compute time, shared by sessions
  std::unique_ptr<LoopDriver> driver_;
  std::unique_ptr<TerrainRenderer> terrain_;
  std::unique_ptr<ShapeRenderer> shapes_;
  unsigned background_program_ = 0, background_vao_ = 0;
  Camera camera_;
  bool camera_framed_ = false;
  double framed_size_[2] = {0.0, 0.0};  // extent the camera was framed on, metres
  TerrainStyle style_;
  float max_initial_height_m_ = 1.0f;
  int panel_width_ = 0;
  bool imgui_ready_ = false;
  bool reset_requested_ = false;
  FrameGate frame_gate_;
  RedrawGate redraw_;
  std::unique_ptr<Framebuffer> window_fb_;  // the window's multisampled target
  bool mouse_placed_ = false;  // the mouse tool was put down under the cursor this session

  std::unique_ptr<Live> live_;

  // Panel edits that apply on "Apply (reset)".
  Representation pending_representation_ = Representation::kSurface;
  int pending_resolution_[2] = {0, 0};
  haptics::HapticSettings pending_haptics_;
  int pending_soil_ = -1;  // index of the SoilPreset chosen; -1: the scenario's own material
  SoilMaterial pending_material_{};  // the soil's material for the next session
  double pending_rake_deg_ = 90.0;   // the blade's rake for the next session
  std::string panel_error_;

  // Display toggles.
  bool show_force_ = true;
  bool show_labels_ = true;
  float arrow_length_m_ = 0.3f;  // arrow length of the largest force in the plot window, metres

  // Virtual device (window mode).
  BladePose device_target_{};
  bool dragging_tool_ = false;
  Vec3f grab_offset_{};
  bool orbiting_ = false, panning_ = false;
  double last_mx_ = 0.0, last_my_ = 0.0;
  double scroll_accum_ = 0.0;
  bool key_down_[512] = {};
  int scene_x_ = 0, scene_y_ = 0, scene_w_ = 1, scene_h_ = 1;  // window pixels, y down

  friend void scroll_callback(GLFWwindow*, double, double);
  friend void event_callback(GLFWwindow*);
};

}  // namespace terracut::viewer
