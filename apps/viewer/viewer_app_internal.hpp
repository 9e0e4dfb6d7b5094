// Internal to the files that define ViewerApp (viewer_app, viewer_input,
// viewer_panel, viewer_scene and viewer_headless .cpp); nothing else includes
// it. What they share: the clock, the plot length, the degree factor, the
// force magnitude helper, the GLFW scroll callback and ViewerApp::Live (the
// latest frame's values and the plot histories).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <numbers>
#include <vector>

#include "viewer_app.hpp"

namespace terracut::viewer {

using Clock = std::chrono::steady_clock;
inline constexpr int kHistory = 240;  // plot samples (4 s at 60 frames/s)
inline constexpr double kDegToRad = std::numbers::pi / 180.0;

inline float magnitude(Vec3 v) { return float(length(v)); }

/// GLFW scroll callback of the window (viewer_input.cpp): adds the wheel's
/// motion to the app's scroll_accum_.
void scroll_callback(GLFWwindow* window, double, double dy);
/// Marks the window for redrawing (any input event, a resize).
void event_callback(GLFWwindow* window);

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
  double penetration_n = 0.0, twist_torque_n_m = 0.0, yaw_rate_rad_per_s = 0.0;
  double bucket_load_m3 = 0.0;  // soil in the bucket
  /// The ticks since the previously taken frame (max and mean of the forces).
  haptics::ViewWindow window{};
  /// Largest |force| and |bodies' force| of any tick since the session (or
  /// Reset) began, N.
  double force_max_n = 0.0, body_force_max_n = 0.0;
  ToolReadout readout{};
  double step_time_s = 0.0, period_s = 0.0;
  // Rigid bodies of the frame (the first body_count are valid).
  int body_count = 0, body_total = 0;
  std::array<haptics::ViewBody, haptics::kMaxViewBodies> bodies{};
  std::int64_t uploaded_last = 0;

  std::vector<float> contact_hist = std::vector<float>(kHistory, 0.0f);
  // Per drawn frame: the largest |force| of the ticks it sums up (so brief
  // contacts between frames show), and the same for the bodies' force.
  std::vector<float> force_hist = std::vector<float>(kHistory, 0.0f);
  std::vector<float> body_hist = std::vector<float>(kHistory, 0.0f);
  std::vector<float> jitter_hist = std::vector<float>(kHistory, 0.0f);
  int hist_next = 0;

  Clock::time_point last_frame = Clock::now();
  double frame_ms = 0.0;  // smoothed wall time between rendered frames
  LoopTimingSnapshot stats{};
  Clock::time_point last_stats = Clock::now();
};

}  // namespace terracut::viewer
