// The viewer's input and panel logic that needs no window and no OpenGL, so
// tests can check what the controls mean: the tool readout (height, depth,
// yaw, tilt), the key commands, when a frame is taken while paused, when the
// window is redrawn, where the tool's label goes, and what a reset keeps.
#pragma once

#include <cstdint>

#include "terracut/core/blade.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/grid.hpp"

namespace terracut::viewer {

/// Where the tool is, as the panel shows it.
struct ToolReadout {
  /// Height of the blade's centre above the terrain's ground level (the
  /// rigid floor, grid origin y), metres.
  double height_m = 0.0;
  /// Depth of the blade's centre below the soil beside it, metres: positive
  /// when it is in the soil, negative when it is above (then -depth is the
  /// clearance). The soil beside the edge, not at it: the edge's own trench
  /// is cut down to the edge.
  double depth_m = 0.0;
  /// Heading of the edge about world +Y, degrees, (-180, 180]: 0 along +X,
  /// +90 along -Z (the Q key turns it positive).
  double yaw_deg = 0.0;
  /// Rise of the edge's +X end above the horizontal, degrees, [-90, 90].
  double tilt_deg = 0.0;
};

/// The readout of pose over the terrain heights (rows x cols, metres above
/// ground, as a ViewFrame holds them) read as representation does. The soil
/// beside the edge is read one and a half cell diagonals to each side along
/// its horizontal normal (the higher side counts), at the blade's centre.
ToolReadout tool_readout(const BladePose& pose, const GridSpec& spec, const float* heights,
                         Representation representation);

/// What a single key press does in the window.
enum class KeyCommand {
  kNone,
  kQuit,       ///< Esc or Ctrl+Q (a plain Q turns the tool while held)
  kPlayPause,  ///< Space
  kStep,       ///< N: one step of kStepTime_s of device time, then paused
  kReset,      ///< Backspace
  kTopView,    ///< T
  kColour,     ///< C
};
/// The command of a key press (GLFW key code and modifier bits).
KeyCommand key_command(int glfw_key, int glfw_mods);

/// Device time one Step plays (then the tool holds still again), seconds:
/// long enough to be seen (12 mm at 0.6 m/s), short enough to follow a cut.
inline constexpr double kStepTime_s = 0.02;

/// Whether the drawing thread takes the newest frame from the loop. Playing,
/// always; paused, only while the device's clock still moves (a Step being
/// played) and for a few frames after it stopped, so that what is shown is
/// the state the step left, and then nothing: paused freezes what is shown
/// (the clock, the force, the plots), although the loop keeps ticking.
class FrameGate {
 public:
  /// device_clock_s: the device's own clock (ViewerDevice::clock_s()), which
  /// stands still while paused.
  bool take(bool playing, double device_clock_s);
  /// Forget the clock (a new session starts).
  void reset() { has_clock_ = false; }

 private:
  static constexpr int kSettleFrames = 3;
  bool has_clock_ = false;
  double clock_s_ = 0.0;
  int settle_ = 0;
};

/// Whether the window draws this iteration: only when something changed (a
/// new frame whose content differs, input, a resize), then for a few more
/// frames so the panel settles; otherwise the window sleeps until an event or
/// the next frame time, so an idle viewer costs no CPU.
class RedrawGate {
 public:
  void changed() { remaining_ = kSettleFrames; }
  /// True when this iteration should draw (and counts it).
  bool draw();
  static constexpr int kSettleFrames = 3;

 private:
  int remaining_ = kSettleFrames;
};

/// A rectangle on the screen, pixels, y down.
struct ScreenRect {
  float x = 0.0f, y = 0.0f, w = 0.0f, h = 0.0f;
};

/// Where the tool's value label goes: beside the tool's screen point
/// (tool_x, tool_y), offset by `gap` pixels so it never covers that point or
/// the blade drawn through it along (edge_dx, edge_dy) (the blade's screen
/// direction, any length), and moved to stay wholly inside the viewport.
/// Returns the label's top-left corner.
void label_position(float tool_x, float tool_y, float edge_dx, float edge_dy, float label_w,
                    float label_h, const ScreenRect& viewport, float gap, float& out_x,
                    float& out_y);

}  // namespace terracut::viewer
