// The window's mouse and keyboard: the cursor, the tool drag (left button),
// the camera drags (right: orbit, middle: pan), the wheel (tool height or
// zoom), held keys that turn the tool and single-press commands; and the
// switch of the virtual device to the mouse.
#include "viewer_app_internal.hpp"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>

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
    Vec3f hit;
    if (plane_hit(p, float(device_target_.position_m.y), hit)) {
      begin_mouse_drive();
      dragging_tool_ = true;
      grab_offset_ = to_f(device_target_.position_m) - hit;
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
  // Single presses.
  ViewerDevice& dev = driver_->device();
  if (key_pressed(window, GLFW_KEY_SPACE)) dev.set_playing(!dev.playing());
  if (key_pressed(window, GLFW_KEY_N)) {
    dev.set_playing(false);
    dev.request_steps(1);
  }
  if (key_pressed(window, GLFW_KEY_BACKSPACE)) reset_requested_ = true;
  if (key_pressed(window, GLFW_KEY_T))
    camera_.mode = camera_.mode == CameraMode::kTop ? CameraMode::kOrbit : CameraMode::kTop;
  if (key_pressed(window, GLFW_KEY_C))
    style_.color = style_.color == ColorMode::kHeight ? ColorMode::kRemoved : ColorMode::kHeight;
}

}  // namespace terracut::viewer
