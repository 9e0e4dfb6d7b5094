// The viewer's window-free input and panel logic (viewer_controls.hpp).
#include "viewer_controls.hpp"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "terracut/core/surface.hpp"

namespace terracut::viewer {

ToolReadout tool_readout(const BladePose& pose, const GridSpec& spec, const float* heights,
                         Representation representation) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  ToolReadout out;
  const Vec3 c = pose.position_m;
  out.height_m = c.y - spec.origin_m.y;
  const Vec3 e = rotate(pose.orientation, Vec3{1.0, 0.0, 0.0});
  const double eh = std::hypot(e.x, e.z);
  out.yaw_deg = eh > 1e-9 ? std::atan2(-e.z, e.x) * kDeg : 0.0;
  out.tilt_deg = std::asin(std::clamp(e.y, -1.0, 1.0)) * kDeg;
  // The soil on either face of the blade (the higher side), or around it for
  // a vertical edge; the blade's centre, not its ends.
  const double look = 1.5 * std::hypot(spec.cell_x_m(), spec.cell_z_m());
  auto soil_at = [&](double dx, double dz) {
    return spec.origin_m.y +
           surface_height_m(spec, heights, representation, c.x + dx, c.z + dz);
  };
  double beside = 0.0;
  if (eh > 1e-9) {
    const double nx = e.z / eh, nz = -e.x / eh;
    beside = std::max(soil_at(nx * look, nz * look), soil_at(-nx * look, -nz * look));
  } else {
    beside = std::max({soil_at(look, 0.0), soil_at(-look, 0.0), soil_at(0.0, look),
                       soil_at(0.0, -look)});
  }
  beside = std::max(beside, soil_at(0.0, 0.0));
  out.depth_m = beside - c.y;
  return out;
}

KeyCommand key_command(int glfw_key, int glfw_mods) {
  switch (glfw_key) {
    case GLFW_KEY_ESCAPE:
      return KeyCommand::kQuit;
    case GLFW_KEY_Q:
      return (glfw_mods & GLFW_MOD_CONTROL) ? KeyCommand::kQuit : KeyCommand::kNone;
    case GLFW_KEY_SPACE:
      return KeyCommand::kPlayPause;
    case GLFW_KEY_N:
      return KeyCommand::kStep;
    case GLFW_KEY_BACKSPACE:
      return KeyCommand::kReset;
    case GLFW_KEY_T:
      return KeyCommand::kTopView;
    case GLFW_KEY_C:
      return KeyCommand::kColour;
    default:
      return KeyCommand::kNone;
  }
}

bool FrameGate::take(bool playing, double device_clock_s) {
  const bool moved = !has_clock_ || device_clock_s != clock_s_;
  has_clock_ = true;
  clock_s_ = device_clock_s;
  if (playing || moved) {
    settle_ = kSettleFrames;
    return true;
  }
  // Paused and still: a few more frames, for the ticks that were in flight
  // when the clock stopped, then hold what is shown.
  if (settle_ > 0) {
    --settle_;
    return true;
  }
  return false;
}

bool RedrawGate::draw() {
  if (remaining_ <= 0) return false;
  --remaining_;
  return true;
}

void label_position(float tool_x, float tool_y, float edge_dx, float edge_dy, float label_w,
                    float label_h, const ScreenRect& viewport, float gap, float& out_x,
                    float& out_y) {
  // The four diagonal placements; a line through the tool point leaves at
  // least two of them wholly on one side of it. The first that is also
  // inside the viewport wins; else the first clear of the blade, moved inside.
  const float corners[4][2] = {{gap, -gap - label_h},
                               {-gap - label_w, -gap - label_h},
                               {gap, gap},
                               {-gap - label_w, gap}};
  auto clear_of_blade = [&](float x, float y) {
    if (edge_dx == 0.0f && edge_dy == 0.0f) return true;
    int sign = 0;
    const float xs[2] = {x, x + label_w}, ys[2] = {y, y + label_h};
    for (float px : xs)
      for (float py : ys) {
        const float cr = edge_dx * (py - tool_y) - edge_dy * (px - tool_x);
        const int s = cr > 0.0f ? 1 : (cr < 0.0f ? -1 : 0);
        if (s == 0 || (sign != 0 && s != sign)) return false;
        sign = s;
      }
    return true;
  };
  auto inside = [&](float x, float y) {
    return x >= viewport.x && y >= viewport.y && x + label_w <= viewport.x + viewport.w &&
           y + label_h <= viewport.y + viewport.h;
  };
  int chosen = -1;
  for (int k = 0; k < 4 && chosen < 0; ++k) {
    const float x = tool_x + corners[k][0], y = tool_y + corners[k][1];
    if (clear_of_blade(x, y) && inside(x, y)) chosen = k;
  }
  for (int k = 0; k < 4 && chosen < 0; ++k)
    if (clear_of_blade(tool_x + corners[k][0], tool_y + corners[k][1])) chosen = k;
  if (chosen < 0) chosen = 0;
  out_x = tool_x + corners[chosen][0];
  out_y = tool_y + corners[chosen][1];
  // Keep it inside the viewport (a label larger than it starts at its corner).
  out_x = std::max(viewport.x, std::min(out_x, viewport.x + viewport.w - label_w));
  out_y = std::max(viewport.y, std::min(out_y, viewport.y + viewport.h - label_h));
}

}  // namespace terracut::viewer
