#include "terracut/haptics/snapshot.hpp"

#include <algorithm>
#include <cstring>

namespace terracut::haptics {

SnapshotExchange::SnapshotExchange(const HeightGrid& grid) {
  for (ViewFrame& f : frames_) {
    f.cols = grid.cols();
    f.rows = grid.rows();
    f.heights.assign(grid.heights(), grid.heights() + grid.spec().sample_count());
  }
  // The reader's first frame counts as having seen everything.
  frames_[front_].dirty = {0, 0, grid.cols(), grid.rows()};
}

void SnapshotExchange::note_changed(const Rect& rect) {
  if (rect.empty()) return;
  for (Rect& p : pending_) p.include(rect);
  dirty_since_publish_.include(rect);
}

void SnapshotExchange::publish(const HeightGrid& grid) {
  ViewFrame& f = frames_[back_];
  // Bring this frame up to date: copy what changed since it was last written.
  Rect& p = pending_[back_];
  if (!p.empty()) {
    const float* src = grid.heights();
    size_t width = size_t(p.c1 - p.c0);
    for (int r = p.r0; r < p.r1; ++r) {
      std::int64_t i = std::int64_t(r) * f.cols + p.c0;
      std::memcpy(f.heights.data() + i, src + i, width * sizeof(float));
    }
    p = {};
  }
  // If the reader has not taken the previous frame, it will skip it, so this
  // frame's dirty region must also hold the previous one's.
  // The same for the window of ticks the frame sums up.
  ViewWindow window;
  window.ticks = 1;
  window.force_max_n = window.force_sum_n = length(f.force_world_n);
  window.body_force_max_n = window.body_force_sum_n = length(f.body_force_world_n);
  window.device_force_max_n = length(f.force_device_n);
  window.contact_max_m = window.contact_sum_m = f.contact.length_m;
  Rect dirty = dirty_since_publish_;
  if (middle_.load(std::memory_order_acquire) & kFresh) {
    dirty.include(last_published_dirty_);
    window.merge(last_published_window_);
  }
  f.dirty = dirty;
  f.window = window;
  last_published_dirty_ = dirty;
  last_published_window_ = window;
  dirty_since_publish_ = {};
  f.sequence = ++sequence_;
  unsigned old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
  back_ = old & ~kFresh;
}

const ViewFrame* SnapshotExchange::acquire() {
  if (!(middle_.load(std::memory_order_acquire) & kFresh)) return nullptr;
  unsigned old = middle_.exchange(front_, std::memory_order_acq_rel);
  front_ = old & ~kFresh;
  return &frames_[front_];
}

void ViewWindow::merge(const ViewWindow& other) {
  ticks += other.ticks;
  force_max_n = std::max(force_max_n, other.force_max_n);
  force_sum_n += other.force_sum_n;
  body_force_max_n = std::max(body_force_max_n, other.body_force_max_n);
  body_force_sum_n += other.body_force_sum_n;
  device_force_max_n = std::max(device_force_max_n, other.device_force_max_n);
  contact_max_m = std::max(contact_max_m, other.contact_max_m);
  contact_sum_m += other.contact_sum_m;
}

void fill_bodies(ViewFrame& frame, const BodySource* source) noexcept {
  if (!source) {
    frame.body_count = 0;
    frame.body_total = 0;
    return;
  }
  frame.body_count = source->write_bodies(frame.bodies);
  frame.body_total = source->body_total();
}

}  // namespace terracut::haptics
