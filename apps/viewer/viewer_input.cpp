// The window's mouse and keyboard: the cursor, the tool drag (left button),
// the camera drags (right: orbit, middle: pan), the wheel (tool height or
// zoom), held keys that turn the tool and single-press commands; and the
// switch of the virtual device to the mouse.
#include "viewer_app_internal.hpp"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>

#include "viewer_controls.hpp"

namespace terracut::viewer {
namespace {

bool key_held(GLFWwindow* window, int key) { return glfwGetKey(window, key) == GLFW_PRESS; }

}  // namespace

// The cursor this frame, in framebuffer pixels (y down), and its motion since the last.
struct ViewerApp::Pointer {
  double mx = 0.0, my = 0.0;
  double dx = 0.0, dy = 0.0;
  bool in_scene = false;  // over the scene viewport (right of the panel)
};

void scroll_callback(GLFWwindow* window, double, double dy) {
  auto* app = static_cast<ViewerApp*>(glfwGetWindowUserPointer(window));
  if (app) {
    app->scroll_accum_ += dy;
    app->redraw_.changed();
  }
}

void event_callback(GLFWwindow* window) {
  auto* app = static_cast<ViewerApp*>(glfwGetWindowUserPointer(window));
  if (app) app->redraw_.changed();
}

void ViewerApp::begin_mouse_drive() {
  // The mouse takes the tool where it is; a paused viewer stays paused (the
  // tool follows once playing again).
  ViewerDevice& dev = driver_->device();
  if (dev.source() != ToolSource::kMouse) {
    device_target_ = live_->pose;
    dev.set_target(device_target_);
    dev.set_source(ToolSource::kMouse);
    mouse_placed_ = false;
  }
}

bool ViewerApp::terrain_hit(const Pointer& p, Vec3f& hit) const {
  // March the cursor's ray through the terrain's box in steps of half a
  // cell, then bisect the step where it passes below the surface.
  const GridSpec& spec = driver_->spec();
  const float aspect = float(scene_w_) / float(scene_h_);
  const Ray ray =
      camera_.ray(float((p.mx - scene_x_) / scene_w_), float((p.my - scene_y_) / scene_h_), aspect);
  const float top = float(spec.origin_m.y) + max_initial_height_m_ * 1.05f + 1e-3f;
  const float ground = float(spec.origin_m.y);
  // Where the ray enters the slab between the ground and the top.
  if (std::abs(ray.direction.y) < 1e-6f) return false;
  const float t_top = (top - ray.origin.y) / ray.direction.y;
  const float t_ground = (ground - ray.origin.y) / ray.direction.y;
  float t0 = std::max(0.0f, std::min(t_top, t_ground)), t1 = std::max(t_top, t_ground);
  if (t1 <= 0.0f) return false;
  const float step = 0.5f * float(std::min(spec.cell_x_m(), spec.cell_z_m()));
  auto below = [&](float t) {
    const Vec3f q = ray.origin + ray.direction * t;
    return q.y <= ground_height_at(q.x, q.z);
  };
  auto on_terrain = [&](float t) {
    const Vec3f q = ray.origin + ray.direction * t;
    return q.x >= spec.origin_m.x && q.x <= spec.origin_m.x + spec.size_x_m &&
           q.z >= spec.origin_m.z && q.z <= spec.origin_m.z + spec.size_z_m;
  };
  const int max_steps = 100000;
  float prev = t0;
  for (int i = 1; i <= max_steps; ++i) {
    const float t = std::min(t0 + step * float(i), t1);
    if (below(t)) {
      float a = prev, b = t;
      for (int k = 0; k < 30; ++k) {
        const float m = 0.5f * (a + b);
        (below(m) ? b : a) = m;
      }
      if (!on_terrain(b)) return false;
      hit = ray.origin + ray.direction * b;
      return true;
    }
    prev = t;
    if (t >= t1) break;
  }
  return false;
}

void ViewerApp::handle_window_input(GLFWwindow* window, double dt_s) {
  const Pointer p = read_pointer(window);
  bool target_changed = drag_tool(window, p);
  drag_camera(window, p);
  if (handle_wheel(window)) target_changed = true;
  if (!ImGui::GetIO().WantCaptureKeyboard) {
    if (turn_tool(window, dt_s)) target_changed = true;
    key_commands(window);
  }
  if (target_changed) driver_->device().set_target(device_target_);
}

ViewerApp::Pointer ViewerApp::read_pointer(GLFWwindow* window) {
  int win_w = 1, win_h = 1, fb_w = 1, fb_h = 1;
  glfwGetWindowSize(window, &win_w, &win_h);
  glfwGetFramebufferSize(window, &fb_w, &fb_h);
  const double sx = double(fb_w) / std::max(win_w, 1), sy = double(fb_h) / std::max(win_h, 1);
  Pointer p;
  glfwGetCursorPos(window, &p.mx, &p.my);
  p.mx *= sx;
  p.my *= sy;
  p.dx = p.mx - last_mx_;
  p.dy = p.my - last_my_;
  last_mx_ = p.mx;
  last_my_ = p.my;
  p.in_scene = p.mx >= scene_x_ && p.mx < scene_x_ + scene_w_ && p.my >= scene_y_ &&
               p.my < scene_y_ + scene_h_;
  return p;
}

bool ViewerApp::plane_hit(const Pointer& p, float plane_y, Vec3f& hit) const {
  // Where the cursor's ray meets the horizontal plane at plane_y (in front of the camera).
  const float aspect = float(scene_w_) / float(scene_h_);
  Ray ray = camera_.ray(float((p.mx - scene_x_) / scene_w_), float((p.my - scene_y_) / scene_h_), aspect);
  if (std::abs(ray.direction.y) < 1e-4f) return false;
  float t = (plane_y - ray.origin.y) / ray.direction.y;
  if (t < 0.0f) return false;
  hit = ray.origin + ray.direction * t;
  return true;
}

bool ViewerApp::drag_tool(GLFWwindow* window, const Pointer& p) {
  // Left drag: the tool follows the cursor in its horizontal plane.
  const ImGuiIO& io = ImGui::GetIO();
  const GridSpec& spec = driver_->spec();
  bool target_changed = false;
  const bool left = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  if (left && !dragging_tool_ && p.in_scene && !io.WantCaptureMouse) {
    begin_mouse_drive();
    Vec3f ground;
    if (!mouse_placed_ && terrain_hit(p, ground)) {
      // The first drag puts the tool down just above the soil under the
      // cursor, so it digs at the first scroll down.
      device_target_.position_m = {double(ground.x),
                                   double(ground.y) + mouse_clearance_m(spec, max_initial_height_m_),
                                   double(ground.z)};
      mouse_placed_ = true;
      target_changed = true;
    }
    Vec3f hit;
    if (plane_hit(p, float(device_target_.position_m.y), hit)) {
      dragging_tool_ = true;
      grab_offset_ = to_f(device_target_.position_m) - hit;
      grab_offset_.y = 0.0f;
    }
  } else if (left && dragging_tool_) {
    Vec3f hit;
    if (plane_hit(p, float(device_target_.position_m.y), hit)) {
      Vec3f q = hit + grab_offset_;
      double margin = 0.6 * driver_->blade_length_m();
      device_target_.position_m.x =
          std::clamp(double(q.x), spec.origin_m.x - margin, spec.origin_m.x + spec.size_x_m + margin);
      device_target_.position_m.z =
          std::clamp(double(q.z), spec.origin_m.z - margin, spec.origin_m.z + spec.size_z_m + margin);
      target_changed = true;
    }
  } else if (!left) {
    dragging_tool_ = false;
  }
  return target_changed;
}

void ViewerApp::drag_camera(GLFWwindow* window, const Pointer& p) {
  // Right drag: orbit; middle drag: pan.
  const ImGuiIO& io = ImGui::GetIO();
  const bool right = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  const bool middle = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  if (right && (orbiting_ || (p.in_scene && !io.WantCaptureMouse))) {
    if (orbiting_) {
      camera_.yaw_rad -= float(p.dx) * 0.006f;
      camera_.pitch_rad = std::clamp(camera_.pitch_rad + float(p.dy) * 0.006f, 0.03f, 1.55f);
    }
    orbiting_ = true;
  } else {
    orbiting_ = false;
  }
  if (middle && (panning_ || (p.in_scene && !io.WantCaptureMouse))) {
    if (panning_) {
      float k = camera_.distance_m * 0.0015f;
      Vec3f right_dir{std::cos(camera_.yaw_rad), 0.0f, -std::sin(camera_.yaw_rad)};
      Vec3f fwd{std::sin(camera_.yaw_rad), 0.0f, std::cos(camera_.yaw_rad)};
      camera_.target = camera_.target - right_dir * (float(p.dx) * k) - fwd * (float(p.dy) * k);
    }
    panning_ = true;
  } else {
    panning_ = false;
  }
}

bool ViewerApp::handle_wheel(GLFWwindow* window) {
  // Wheel: tool height (shift or ctrl: zoom).
  const ImGuiIO& io = ImGui::GetIO();
  const GridSpec& spec = driver_->spec();
  const float extent = float(std::max(spec.size_x_m, spec.size_z_m));
  bool target_changed = false;
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
  return target_changed;
}

bool ViewerApp::turn_tool(GLFWwindow* window, double dt_s) {
  // Held keys turn the tool: Q/E about world Y, R/F tilt about the blade's own Z.
  double yaw = (key_held(window, GLFW_KEY_Q) ? 1.0 : 0.0) -
               (key_held(window, GLFW_KEY_E) ? 1.0 : 0.0);
  double tilt = (key_held(window, GLFW_KEY_R) ? 1.0 : 0.0) -
                (key_held(window, GLFW_KEY_F) ? 1.0 : 0.0);
  if (yaw == 0.0 && tilt == 0.0) return false;
  // Ctrl+Q quits: not a turn.
  if (key_held(window, GLFW_KEY_LEFT_CONTROL) || key_held(window, GLFW_KEY_RIGHT_CONTROL)) return false;
  begin_mouse_drive();
  Quat q = device_target_.orientation;
  if (yaw != 0.0) q = quat_from_axis_angle({0, 1, 0}, yaw * 90.0 * kDegToRad * dt_s) * q;
  if (tilt != 0.0) q = q * quat_from_axis_angle({0, 0, 1}, tilt * 45.0 * kDegToRad * dt_s);
  device_target_.orientation = normalized(q);
  return true;
}

bool ViewerApp::key_pressed(GLFWwindow* window, int key) {
  // Down now and not at the last look: a single press.
  bool down = key_held(window, key);
  bool was = key_down_[key];
  key_down_[key] = down;
  return down && !was;
}

void ViewerApp::key_commands(GLFWwindow* window) {
  // Single presses (viewer_controls.hpp says which key does what).
  ViewerDevice& dev = driver_->device();
  const int mods = (key_held(window, GLFW_KEY_LEFT_CONTROL) || key_held(window, GLFW_KEY_RIGHT_CONTROL))
                       ? GLFW_MOD_CONTROL
                       : 0;
  for (int key : {GLFW_KEY_ESCAPE, GLFW_KEY_Q, GLFW_KEY_SPACE, GLFW_KEY_N, GLFW_KEY_BACKSPACE,
                  GLFW_KEY_T, GLFW_KEY_C}) {
    if (!key_pressed(window, key)) continue;
    switch (key_command(key, mods)) {
      case KeyCommand::kQuit:
        glfwSetWindowShouldClose(window, GLFW_TRUE);
        break;
      case KeyCommand::kPlayPause:
        dev.set_playing(!dev.playing());
        break;
      case KeyCommand::kStep:
        dev.set_playing(false);
        dev.request_step_s(kStepTime_s);
        break;
      case KeyCommand::kReset:
        reset_requested_ = true;
        break;
      case KeyCommand::kTopView:
        camera_.mode = camera_.mode == CameraMode::kTop ? CameraMode::kOrbit : CameraMode::kTop;
        break;
      case KeyCommand::kColour:
        style_.color =
            style_.color == ColorMode::kHeight ? ColorMode::kRemoved : ColorMode::kHeight;
        break;
      case KeyCommand::kNone:
        break;
    }
  }
}

}  // namespace terracut::viewer
