// A wait-free exchange of terrain snapshots from the real-time loop (one
// writer) to a viewer or network sender (one reader), so the reader never
// blocks the loop and never sees a torn frame.
//
// Triple buffering: the writer fills its back frame and swaps it with the
// shared middle frame; the reader swaps its front frame with the middle one
// when a newer frame is there. Only the samples that changed are copied: each
// frame remembers the rectangle changed since it was last written, and each
// published frame carries `dirty`, a rectangle that holds every sample changed
// since the frame the reader took before (conservative: it may be larger), so
// a renderer uploads just that region.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

#include "terracut/core/bodies.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::haptics {

/// Most rigid bodies a ViewFrame carries (a fixed array: publishing never allocates).
inline constexpr int kMaxViewBodies = 64;

/// A rigid body's shape and pose in a ViewFrame.
using ViewBody = BodyView;  // terracut/core/bodies.hpp

/// The ticks a reader has not seen yet, summed up when a frame is published:
/// every tick since the frame the reader took before (it may count a few
/// ticks twice when the reader takes a frame during a publish), so brief
/// contacts between two drawn frames are seen.
struct ViewWindow {
  std::int64_t ticks = 0;           ///< ticks summed, >= 1 in a published frame
  double force_max_n = 0.0;         ///< largest |world force on the tool|, N
  double force_sum_n = 0.0;         ///< sum of |world force| over the ticks, N
  double body_force_max_n = 0.0;    ///< largest |rigid bodies' force|, N
  double body_force_sum_n = 0.0;    ///< sum of |rigid bodies' force|, N
  double device_force_max_n = 0.0;  ///< largest |force sent to the device|, device N
  double contact_max_m = 0.0;       ///< longest contact, m
  double contact_sum_m = 0.0;       ///< sum of the contact lengths, m
  /// Mean of a sum over the ticks (0 for no ticks).
  double mean(double sum) const { return ticks > 0 ? sum / double(ticks) : 0.0; }
  /// Adds the ticks of another window.
  void merge(const ViewWindow& other);
};

/// One consistent picture of the simulation.
struct ViewFrame {
  int cols = 0;
  int rows = 0;
  std::vector<float> heights;  ///< rows x cols, row-major, metres above ground
  Rect dirty{};                ///< samples changed since the reader's previous frame (may be larger)
  std::uint64_t sequence = 0;  ///< publish count, from 1
  double t_s = 0.0;            ///< simulation time, seconds
  std::int64_t step = 0;       ///< simulation step
  BladePose pose{};            ///< blade pose, world
  Segment edge{};              ///< cutting edge, world metres
  ContactResult contact{};     ///< contact measured at that step
  Vec3 device_position_m{};    ///< device (operator) point mapped to world, metres
  Vec3 proxy_position_m{};     ///< surface proxy, world metres
  Vec3 force_world_n{};        ///< force on the tool in the world, newtons
  Vec3 force_device_n{};       ///< force sent to the device, newtons
  Vec3 body_force_world_n{};   ///< the step listeners' (rigid bodies') part of force_world_n, newtons
  double penetration_force_n = 0.0;  ///< the penetration model's part of force_world_n (+Y up), N
  double twist_torque_n_m = 0.0;     ///< twist torque about world +Y, N m (not in force_world_n)
  double yaw_rate_rad_per_s = 0.0;   ///< estimated yaw rate of the tool, rad/s
  double bucket_load_m3 = 0.0;       ///< soil in the bucket (SoilStepResult::bucket_load_m3), m^3
  /// The ticks since the reader's previous frame; publish() fills it from
  /// this frame's values (force_world_n, body_force_world_n, force_device_n,
  /// contact) and those of the frames the reader skipped.
  ViewWindow window{};
  double step_time_s = 0.0;    ///< compute time of the step, seconds
  double period_s = 0.0;       ///< measured loop period before the step, seconds
  /// Rigid bodies (filled by fill_bodies from the loop's BodySource): the
  /// first body_count entries of bodies are valid, body_count in
  /// [0, kMaxViewBodies]; body_total counts all the simulated bodies (more
  /// than body_count when there are more than kMaxViewBodies).
  int body_count = 0;
  int body_total = 0;
  std::array<ViewBody, kMaxViewBodies> bodies{};
};

/// Writes the bodies of `source` into the frame (body_count, body_total and
/// bodies[]); none when source is null. Allocation-free.
void fill_bodies(ViewFrame& frame, const BodySource* source) noexcept;

class SnapshotExchange {
 public:
  /// Allocates three frames holding the grid's current heights.
  explicit SnapshotExchange(const HeightGrid& grid);

  // --- writer side (one thread) ---

  /// Records that the samples in rect changed in the grid (call after each step).
  void note_changed(const Rect& rect);
  /// The frame being written: fill its scalar fields, then publish().
  ViewFrame& back() { return frames_[back_]; }
  /// Copies the changed samples of grid into the back frame and makes it the
  /// newest frame. Never blocks and never allocates.
  void publish(const HeightGrid& grid);

  // --- reader side (one thread) ---

  /// Takes the newest frame if one was published since the last call and
  /// returns it, else nullptr. The frame stays valid and unchanged until the
  /// next call.
  const ViewFrame* acquire();
  /// The frame the reader holds (initially the starting heights).
  const ViewFrame& front() const { return frames_[front_]; }

 private:
  static constexpr unsigned kFresh = 4u;  // bit set in middle_ when the reader has not taken it

  ViewFrame frames_[3];
  Rect pending_[3];  // per frame: samples changed since that frame was last written (writer only)
  Rect dirty_since_publish_{};
  Rect last_published_dirty_{};
  ViewWindow last_published_window_{};
  std::uint64_t sequence_ = 0;
  unsigned back_ = 0;
  unsigned front_ = 2;
  std::atomic<unsigned> middle_{1};
};

}  // namespace terracut::haptics
