// The two stations of model-mediated teleoperation (mmt.hpp).
#include <algorithm>
#include <span>
#include <chrono>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/haptics/workspace.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::session {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::uint64_t to_ns(double t_s) { return std::uint64_t(std::llround(std::max(0.0, t_s) * 1e9)); }

// The loop's parameters of a scenario, with the scenario named in errors.
haptics::LoopParams loop_params(const Scenario& sc) {
  try {
    return haptics::LoopParams(sc.haptics, sc.base.blade, sc.base.rate_hz);
  } catch (const InputError& e) {
    throw InputError(sc.base.source_path.string() + ": " + e.what());
  }
}

// The orientation of the first keyframe of the followed cut, or identity
// (a remote world with no cut of its own).
Quat first_orientation(const Scenario& sc) {
  const std::vector<int> cuts = followed_cuts(sc, sc.haptics);
  return cuts.empty() ? Quat{} : sc.base.cuts[std::size_t(cuts.front())].keyframes.front().pose.orientation;
}

// Adds a rectangle to the rectangle of everything worked so far.
void include_rect(Rect& into, const Rect& r) {
  if (r.empty()) return;
  if (into.empty())
    into = r;
  else
    into.include(r);
}

// The working size of a patch, samples: the sensed square and, in a sensing
// period, as much again of changed samples.
std::size_t patch_samples(const MmtSettings& s, const GridSpec& g) {
  const double side = 2.0 * s.sense_radius_m;
  const std::size_t window =
      std::size_t(side / g.cell_x_m() + 2.0) * std::size_t(side / g.cell_z_m() + 2.0);
  return std::min<std::size_t>(
      {2 * window, std::size_t(g.sample_count()), std::size_t(net::kMaxPatchSamples)});
}

// How long a datagram sent one way can be held in flight, s: the delay, the
// jitter, a hold-back and, for a reliable one, three retransmissions.
double in_flight_s(const net::LinkConditions& c) {
  const double retransmit_s = net::retransmit_timeout_s(c, net::emulated_round_trip_s(c));
  return c.delay_s + c.jitter_s + c.reorder_delay_s + 3.0 * retransmit_s;
}

constexpr std::size_t kInboxSlots = 32;  // datagrams arriving in one tick, made room for

// The horizontal cutting force a material gives at a sample's cut, N.
double predicted_horizontal_n(const SoilMaterial& m, const SoilSample& s) {
  EarthmovingParams p;
  p.soil = m;
  p.rake_angle_deg = s.rake_deg;
  return earthmoving_force(p, s.width_m, s.depth_m, m.unit_weight_n_per_m3 * s.pile_m).horizontal_n;
}

}  // namespace

namespace {

// The fields an estimate carries are the same in a and b (to the bit).
bool same_estimated_fields(const SoilMaterial& a, const SoilMaterial& b) {
  for (int f = 0; f < kSoilFieldCount; ++f)
    if (field_value(a, SoilField(f)) != field_value(b, SoilField(f))) return false;
  return true;
}

// A first-order servo's tick (time constant tau: the step is the error x
// dt / tau, gain = dt / tau), limited to the arm's speed (step_m per tick).
Vec3 servo_step(Vec3 at, Vec3 target, double gain, double step_m) {
  Vec3 d = (target - at) * gain;
  const double l = length(d);
  if (l > step_m) d = d * (step_m / l);
  return at + d;
}

}  // namespace

// ---------------------------------------------------------------------------
// The remote's arm: follows the newest command as a first-order servo at a
// limited speed (a real arm lags, and does not jump when a command is late).
// ---------------------------------------------------------------------------

class FollowerDevice final : public haptics::Device {
 public:
  FollowerDevice(const haptics::WorkspaceMapping& mapping, double speed_m_per_s,
                 double time_constant_s, double rate_hz)
      : workspace_(mapping),
        step_m_(speed_m_per_s / rate_hz),
        gain_(std::min(1.0, 1.0 / (time_constant_s * rate_hz))) {}

  std::string_view kind() const override { return "follower"; }

  /// The newest command. The first one places the arm (it starts there).
  void command(const BladePose& target) {
    target_ = target;
    if (!has_pose_) pose_ = target;
    has_pose_ = true;
  }
  /// Link silent: stay where the arm is.
  void hold() { target_ = pose_; }
  /// The arm's force limit reached: it does not move this tick (a stalled
  /// arm holds where it is while the load exceeds what it can push).
  void set_stalled(bool stalled) { stalled_ = stalled; }
  /// The arm is where its force-limited plate stopped (World::limited_arm).
  void place(const Vec3& position_m) { pose_.position_m = position_m; }
  const BladePose& pose() const { return pose_; }

  bool read(double, haptics::DeviceSample& out) noexcept override {
    if (!has_pose_) return false;
    if (stalled_) {
      workspace_.fill_sample(pose_, out);
      return true;
    }
    pose_.position_m = servo_step(pose_.position_m, target_.position_m, gain_, step_m_);
    pose_.orientation = target_.orientation;
    workspace_.fill_sample(pose_, out);
    return true;
  }
  void write(const haptics::DeviceCommand&) noexcept override {}

 private:
  haptics::Workspace workspace_;
  double step_m_;  // largest step per tick, m
  double gain_;    // dt / tau, at most 1
  BladePose pose_{}, target_{};
  bool has_pose_ = false;
  bool stalled_ = false;
};

// ---------------------------------------------------------------------------
// The remote's arm in the operator's model (mmt.operator.models_arm): the
// local tool follows the hand through the same servo as the remote's arm
// follows the commands (FollowerDevice), so that the local blade makes the
// motion the remote's will make, a one-way delay later, and the local force
// is the one the remote will measure. The handle's own position stays in
// the sample (what the device and the passivity observer see); the tool's
// pose goes as the sample's world pose. The command sent is the hand's pose
// (hand()), which the remote's arm follows.
// ---------------------------------------------------------------------------

class ArmModelDevice final : public haptics::Device {
 public:
  ArmModelDevice(haptics::Device& inner, const haptics::WorkspaceMapping& mapping,
                 Quat orientation, double speed_m_per_s, double time_constant_s, double rate_hz)
      : inner_(inner), workspace_(mapping), orientation_(orientation),
        step_m_(speed_m_per_s / rate_hz),
        gain_(std::min(1.0, 1.0 / (time_constant_s * rate_hz))) {}
  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  bool read(double t_s, haptics::DeviceSample& out) noexcept override {
    // The sample is the loop's, kept between ticks: its world pose is ours
    // from the last tick unless the device gives one itself.
    const haptics::DeviceSample kept = out;
    out.has_world_pose = false;
    if (!inner_.read(t_s, out)) {
      out = kept;  // no sample: the loop keeps the one it had
      return false;
    }
    hand_ = out.has_world_pose ? out.world_pose.position_m : workspace_.to_world(out.position_m);
    // The first sample places the arm (the remote's starts at its first command).
    tool_ = has_pose_ ? servo_step(tool_, hand_, gain_, step_m_) : hand_;
    has_pose_ = true;
    if (!out.has_world_pose) {
      out.world_pose.orientation =
          out.has_orientation ? workspace_.orientation_to_world(out.orientation) : orientation_;
      out.has_world_pose = true;
    }
    out.world_pose.position_m = tool_;
    return true;
  }
  void write(const haptics::DeviceCommand& c) noexcept override { inner_.write(c); }
  void stop() noexcept override { inner_.stop(); }
  std::vector<haptics::DeviceStat> stats() const override { return inner_.stats(); }
  /// The hand's position, world (the newest sample's).
  Vec3 hand() const { return hand_; }

 private:
  haptics::Device& inner_;
  haptics::Workspace workspace_;
  Quat orientation_;
  double step_m_;
  double gain_;
  Vec3 hand_{}, tool_{};
  bool has_pose_ = false;
};

// ---------------------------------------------------------------------------
// The operator's device seen through the link: while the link is silent the
// loop gets no samples, so its watchdog fades the force out; the first
// sample after a silence is a reconnection (no sweep, a new soft start).
// ---------------------------------------------------------------------------

class LinkGuardDevice final : public haptics::Device {
 public:
  explicit LinkGuardDevice(haptics::Device& inner) : inner_(inner) {}
  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  void set_silent(bool silent) {
    if (silent_ && !silent) resumed_ = true;
    silent_ = silent;
  }
  bool read(double t_s, haptics::DeviceSample& out) noexcept override {
    haptics::DeviceSample fresh = out;
    const bool got = inner_.read(t_s, fresh);  // the hand moves on, heard or not
    if (silent_ || !got) return false;
    fresh.reconnected = fresh.reconnected || resumed_;
    resumed_ = false;
    out = fresh;
    return true;
  }
  void write(const haptics::DeviceCommand& c) noexcept override { inner_.write(c); }
  void stop() noexcept override { inner_.stop(); }
  std::vector<haptics::DeviceStat> stats() const override { return inner_.stats(); }

 private:
  haptics::Device& inner_;
  bool silent_ = false;
  bool resumed_ = false;
};

// ---------------------------------------------------------------------------
// The soil estimate on the operator's side: the local model's material
// moves from the one it had to the remote's estimate (every fitted field
// along the same fraction s of the way, the operator's own repose kept),
// through Simulation::set_force_material between steps, so the physical
// force and everything rendered from it follow. s advances by as much as
// keeps the change of the cutting force at the newest cut under
// max_update_step_n of device force per tick; out of a cut the new material
// applies at once (no force to jump).
// ---------------------------------------------------------------------------

class MaterialBlend {
 public:
  MaterialBlend(Simulation& sim, const haptics::HapticLoop& loop, double max_step_n)
      : sim_(sim), loop_(loop), max_step_n_(max_step_n), from_(sim.force_material()),
        to_(sim.force_material()) {}
  /// A new estimate: the blend restarts from the material in use. The
  /// same one again (the remote's periodic resend) changes nothing.
  void set_target(const SoilMaterial& estimate) {
    if (same_estimated_fields(estimate, to_)) return;
    from_ = sim_.force_material();
    to_ = from_;
    to_.unit_weight_n_per_m3 = estimate.unit_weight_n_per_m3;
    to_.cohesion_pa = estimate.cohesion_pa;
    to_.adhesion_pa = estimate.adhesion_pa;
    to_.internal_friction_deg = estimate.internal_friction_deg;
    to_.soil_tool_friction_deg = estimate.soil_tool_friction_deg;
    s_ = 0.0;
  }
  const SoilMaterial& applied() const { return sim_.force_material(); }
  double fraction() const { return s_; }
  bool moving() const { return moving_; }
  /// The device force the change added this tick, N (<= max_step_n).
  double last_step_n() const { return last_step_n_; }

  /// Before a step: moves the material on.
  void tick() {
    moving_ = false;
    last_step_n_ = 0.0;
    if (s_ >= 1.0) return;
    moving_ = true;
    const ToolForce& f = sim_.last().force;
    if (!(f.engaged_width_m > 0.0) || !(f.cut_depth_m > 0.0)) {
      s_ = 1.0;
      sim_.set_force_material(to_);
      return;
    }
    const double scale = loop_.force_model().params().force_scale;
    const Vec3 now = force_at(s_, f);
    const double remaining_n = length(force_at(1.0, f) - now) * scale;
    double next = 1.0;
    if (remaining_n > max_step_n_) {
      // The force is nearly linear in s over a tick's step; halve until the
      // step's own change is under the bound.
      next = s_ + (1.0 - s_) * max_step_n_ / remaining_n;
      for (int i = 0; i < 8 && length(force_at(next, f) - now) * scale > max_step_n_; ++i)
        next = s_ + 0.5 * (next - s_);
    }
    last_step_n_ = length(force_at(next, f) - now) * scale;
    s_ = next;
    sim_.set_force_material(material_at(s_));
  }

 private:
  SoilMaterial material_at(double s) const {
    SoilMaterial m = to_;
    auto mix = [s](double a, double b) { return a + (b - a) * s; };
    m.unit_weight_n_per_m3 = mix(from_.unit_weight_n_per_m3, to_.unit_weight_n_per_m3);
    m.cohesion_pa = mix(from_.cohesion_pa, to_.cohesion_pa);
    m.adhesion_pa = mix(from_.adhesion_pa, to_.adhesion_pa);
    m.internal_friction_deg = mix(from_.internal_friction_deg, to_.internal_friction_deg);
    m.soil_tool_friction_deg = mix(from_.soil_tool_friction_deg, to_.soil_tool_friction_deg);
    return m;
  }
  // The cutting force (horizontal, vertical) at the cut f with material(s).
  Vec3 force_at(double s, const ToolForce& f) const {
    EarthmovingParams p;
    p.soil = material_at(s);
    p.rake_angle_deg = sim_.params().blade.rake_angle_deg;
    const EarthmovingResult r = earthmoving_force(p, f.engaged_width_m, f.cut_depth_m,
                                                  p.soil.unit_weight_n_per_m3 * f.pile_m);
    return {r.horizontal_n, r.vertical_n, 0.0};
  }

  Simulation& sim_;
  const haptics::HapticLoop& loop_;
  double max_step_n_;
  SoilMaterial from_, to_;
  double s_ = 1.0;
  bool moving_ = false;
  double last_step_n_ = 0.0;
};

// ---------------------------------------------------------------------------
// Remote station
// ---------------------------------------------------------------------------

RemoteStation::RemoteStation(const Scenario& remote, const MmtSettings& settings,
                             const SoilMaterial& nominal, const HeightGrid& operator_initial,
                             net::Endpoint& link, std::uint32_t session,
                             const RemoteOptions& options)
    : settings_(settings), link_(link), session_(session), options_(options) {
  const haptics::LoopParams params = loop_params(remote);
  device_ = std::make_unique<FollowerDevice>(params.settings().workspace,
                                             settings_.follower_speed_m_per_s,
                                             settings_.follower_time_constant_s, params.rate_hz());
  RigOptions ro;
  ro.loop.record_capacity = 0;
  ro.loop.realtime = false;
  // The arm's limit also limits the Bullet plate (1e7, the default: none).
  ro.arm_force_limit_n = settings_.arm_force_limit_n < 1e7 ? settings_.arm_force_limit_n : 0.0;
  rig_ = std::make_unique<HapticRig>(remote, params, first_orientation(remote), *device_, ro);
  plate_limits_ = rig_->world().limited_arm().has_value();
  const HeightGrid& grid = rig_->world().simulation().grid();
  if (grid.cols() != operator_initial.cols() || grid.rows() != operator_initial.rows())
    throw InputError("mmt.remote.scenario: the remote grid must have the operator's samples");
  // The soil, and the one beyond the change along the path.
  base_material_ = simulation().force_material();
  changed_material_ = base_material_;
  if (settings_.change_soil) {
    const SoilMaterial m = soil_preset(*settings_.change_soil);
    changed_material_ = m;
    EarthmovingParams check;
    check.soil = m;
    check.rake_angle_deg = simulation().params().blade.rake_angle_deg;
    if (std::string e = validate(check); !e.empty())
      throw InputError("mmt.remote.soil_change.soil: " + e);
  }
  // The estimate: from the operator's material (what the operator's model
  // starts from), a sample every estimate_period_s, its candidates spread
  // over the ticks to the next sample.
  SoilEstimatorSettings es;
  es.prior = nominal;
  estimate_every_ = std::max<std::int64_t>(
      1, std::llround(settings_.estimate_period_s * params.rate_hz()));
  es.forgetting_per_sample = std::pow(settings_.forgetting, double(estimate_every_));
  estimator_ = std::make_unique<SoilEstimator>(es);
  estimate_slice_ = int((estimator_->candidate_count() + estimate_every_ - 1) / estimate_every_);
  sent_ = nominal;
  mirror_.assign(operator_initial.initial(),
                 operator_initial.initial() + grid.spec().sample_count());
  // The buffers of the working traffic, made now: patches of their working
  // size, a measurement every tick and an update every sensing period in
  // flight, the commands of a tick arriving.
  const std::size_t samples = patch_samples(settings_, grid.spec());
  patch_.heights.reserve(samples);
  sensed_.reserve(samples);
  buffer_.reserve(net::patch_datagram_bound(samples));
  codec_.reserve(samples);
  const double flight_s = in_flight_s(settings_.to_operator);
  link_.reserve_in_flight(std::size_t(flight_s * params.rate_hz()) + 16,
                          net::kHeaderSize + net::kMeasurementPayloadSize + net::kCrcSize);
  link_.reserve_in_flight(2 * std::size_t(flight_s / settings_.sense_period_s) + 8,
                          net::patch_datagram_bound(samples));
  inbox_ = net::Inbox(kInboxSlots, net::kHeaderSize + net::kCommandPayloadSize + net::kCrcSize);
}

RemoteStation::~RemoteStation() = default;

const Simulation& RemoteStation::simulation() const { return rig_->world().simulation(); }

void RemoteStation::receive(double t_s) {
  inbox_.clear();
  link_.receive(t_s, inbox_);
  for (const auto& d : inbox_) {
    net::Header h;
    net::Reject r = net::decode_header(d.data(), d.size(), settings_.link_id, h);
    if (r == net::Reject::kNone && h.type != net::MessageType::kCommand) r = net::Reject::kBadType;
    net::Command c;
    if (r == net::Reject::kNone) r = net::decode_command(d.data(), d.size(), c);
    if (r == net::Reject::kNone) {
      r = net::to_reject(commands_.check(h.session, h.sequence, h.timestamp_ns));
      // Arrived, but older than the newest: not followed, yet not lost.
      if ((r == net::Reject::kReordered || r == net::Reject::kStale) && h.session == commands_.session())
        ++commands_received_;
    }
    if (r != net::Reject::kNone) {
      counters_.rejected.add(r);
      continue;
    }
    ++counters_.accepted;
    counters_.sessions = commands_.sessions();
    if (commands_.new_session()) commands_received_ = 0;
    ++commands_received_;
    if (c.round_trip_us > 0) {  // the operator's measured round trip: for the retransmissions
      round_trip_s_ = double(c.round_trip_us) * 1e-6;
      link_.note_round_trip_s(round_trip_s_);
    }
    // A new operator session, or a lifted tool: the next pose is a jump.
    if ((c.flags & net::kCommandLifted) || (commands_.new_session() && has_command_))
      rig_->world().simulation().lift();
    device_->command(c.pose);
    command_sequence_ = h.sequence;
    commanded_m_ = c.pose.position_m;
    has_command_ = true;
    last_command_s_ = t_s;
  }
}

Rect RemoteStation::window_around(Vec3 p) const {
  const GridSpec& g = simulation().grid().spec();
  const double r = settings_.sense_radius_m;
  auto lo = [](double v, double origin, double cell) {
    return int(std::ceil((v - origin) / cell - 0.5));
  };
  auto hi = [](double v, double origin, double cell) {
    return int(std::floor((v - origin) / cell - 0.5)) + 1;
  };
  Rect w{lo(p.x - r, g.origin_m.x, g.cell_x_m()), lo(p.z - r, g.origin_m.z, g.cell_z_m()),
         hi(p.x + r, g.origin_m.x, g.cell_x_m()), hi(p.z + r, g.origin_m.z, g.cell_z_m())};
  w.c0 = std::clamp(w.c0, 0, g.cols);
  w.c1 = std::clamp(w.c1, 0, g.cols);
  w.r0 = std::clamp(w.r0, 0, g.rows);
  w.r1 = std::clamp(w.r1, 0, g.rows);
  return w;
}

const SoilMaterial& RemoteStation::true_material() const { return simulation().force_material(); }

// The remote's soil where its blade is: the base soil, or soil_change's
// beyond z_below_m (set between steps, through the simulation's owner).
void RemoteStation::choose_material() {
  if (!settings_.change_soil || !has_command_) return;
  const bool in = device_->pose().position_m.z < settings_.change_z_m;
  if (in == in_changed_soil_) return;
  in_changed_soil_ = in;
  rig_->world().simulation().set_force_material(in ? changed_material_ : base_material_);
}

// The soil estimate: a sample of the step's physical cutting force every
// estimate_every_ ticks (when the estimator is free and the tool cuts),
// its candidates taken a slice per tick. Only the physical force of the
// step enters (soil_sample: the cutting and surcharge parts of
// StepOutput::force), never what the remote's own loop renders. Also how
// far the estimate's force is from this tick's measured one.
void RemoteStation::update_estimate() {
  estimate_error_ = -1.0;
  const StepOutput& out = simulation().last();
  const BladeSpec& blade = simulation().params().blade;
  const StepSample s = soil_sample(out.force, out.motion, blade.rake_angle_deg, blade.edge_thickness_m);
  if (settings_.estimate) {
    if (s.valid && !estimator_->busy() && ticks_ % estimate_every_ == 0)
      estimator_->begin(s.sample);
    estimator_->advance(estimate_slice_);
  }
  if (s.valid && s.sample.horizontal_n > 1.0) {
    last_sample_ = s.sample;
    has_sample_ = true;
    estimate_error_ = std::fabs(predicted_horizontal_n(estimate().material, s.sample) -
                                s.sample.horizontal_n) /
                      s.sample.horizontal_n;
  }
}

// The sensed patch: the rectangle changed since the last one and the square
// around the tool. With the deadband it is cut down to the samples that
// differ from what the operator was sent by more than a JND fraction of the
// cut depth (the force of a cut grows at least linearly with its depth, so
// a relative depth change of the JND changes it by at least the JND).
void RemoteStation::sense(double t_s, const haptics::LoopRecord& r) {
  Rect cand = dirty_;
  dirty_ = {};
  if (has_command_) include_rect(cand, window_around(device_->pose().position_m));
  // And where bodies moved: a rock the plate tipped over after it left.
  include_rect(cand, rig_->world().take_moved_body_rect());
  if (cand.empty()) return;
  const HeightGrid& grid = simulation().grid();
  // What the camera sees: the soil, and the top of any body over it.
  sensed_.resize(std::size_t(cand.area()));
  rig_->world().sense_heights(cand, sensed_);
  const int width = cand.c1 - cand.c0;
  const auto seen = [&](int col, int row) {
    return sensed_[std::size_t((row - cand.r0) * width + (col - cand.c0))];
  };
  // Without the deadband the whole sensed rectangle goes (a depth camera's
  // frame: it also corrects what the operator's model did on its own);
  // with it, only the samples past the threshold, and nothing below it.
  const double threshold =
      settings_.deadband > 0.0 ? settings_.deadband * std::max(r.cut_depth_m, 0.02) : -1.0;
  Rect diff{};
  for (int row = cand.r0; row < cand.r1; ++row)
    for (int col = cand.c0; col < cand.c1; ++col) {
      const std::int64_t i = grid.index(col, row);
      if (std::fabs(seen(col, row) - mirror_[std::size_t(i)]) > threshold) {
        if (diff.empty())
          diff = {col, row, col + 1, row + 1};
        else
          diff.include(col, row);
      }
    }
  if (!diff.empty()) {
    patch_.t_s = t_s;
    patch_.rect = diff;
    patch_.heights.resize(std::size_t(diff.area()));
    std::size_t k = 0;
    for (int row = diff.r0; row < diff.r1; ++row)
      for (int col = diff.c0; col < diff.c1; ++col) {
        const std::int64_t i = grid.index(col, row);
        patch_.heights[k++] = seen(col, row);
        mirror_[std::size_t(i)] = seen(col, row);
      }
    net::Header h{net::MessageType::kPatch, settings_.link_id, session_, seq_patch_++, to_ns(t_s)};
    if (codec_.encode(h, patch_, buffer_) > 0) {
      link_.send(net::Channel::kReliable, buffer_.data(), buffer_.size(), t_s);
      ++counters_.patches;
    }
  }
}

// The estimate, when it changed (with the deadband: when it changes the
// horizontal force at the newest cut by more than the JND fraction), and
// again when none has gone for estimate_resend_s. It is state, newest
// wins: it goes unreliably, so a lost one holds back nothing behind it (on
// the in-order reliable channel a lost estimate held the newer ones until
// its retransmission, a round trip later), and the resend replaces it.
void RemoteStation::send_estimate(double t_s) {
  const SoilEstimate& est = estimate();
  // The first samples of the first cut fit many materials that
  // agree at those few depths and nowhere else: the estimate goes out once
  // kFirstSent samples (0.1 s of cutting at the default period) are in.
  constexpr std::int64_t kFirstSent = 10;
  if (!est.known || est.samples < kFirstSent) return;
  const SoilMaterial& m = est.material;
  bool send = !estimate_sent_;
  if (!send && settings_.deadband > 0.0) {
    if (has_sample_) {
      const double was = predicted_horizontal_n(sent_, last_sample_);
      send = std::fabs(predicted_horizontal_n(m, last_sample_) - was) >
             settings_.deadband * std::max(was, 1e-9);
    }
  } else if (!send) {
    send = !same_estimated_fields(m, sent_);
  }
  if (!send && t_s - estimate_sent_s_ + 1e-9 < settings_.estimate_resend_s) return;
  net::Estimate e;
  e.t_s = t_s;
  e.material = m;
  e.sd = est.sd;
  e.samples = std::uint32_t(std::min<std::int64_t>(est.samples, 0xFFFFFFFF));
  e.identifiable = est.identifiable;
  std::uint8_t out[net::kHeaderSize + net::kEstimatePayloadSize + net::kCrcSize];
  net::Header h{net::MessageType::kEstimate, settings_.link_id, session_, seq_estimate_++,
                to_ns(t_s)};
  const std::size_t n = net::encode_estimate(h, e, out);
  link_.send(net::Channel::kUnreliable, out, n, t_s);
  sent_ = m;
  estimate_sent_ = true;
  estimate_sent_s_ = t_s;
  ++counters_.estimates;
}

void RemoteStation::tick(double t_s) {
  const auto tick_start = std::chrono::steady_clock::now();
  receive(t_s);
  // Silence: the arm holds where it is.
  const bool holding = has_command_ && t_s - last_command_s_ > settings_.timeout_s;
  if (holding) {
    device_->hold();
    ++counters_.silent_ticks;
  }
  haptics::HapticLoop& loop = rig_->loop();
  const Simulation& sim = simulation();
  const std::int64_t steps_before = sim.step_count();
  const auto start = std::chrono::steady_clock::now();
  // The arm stalls while the force on it exceeds what it can push (the
  // previous tick's physical force: a sensor's newest reading). With
  // bodies the Bullet plate's servo holds the limit itself (it stops short,
  // and the arm is placed where it stopped, below): holding here as well
  // would drop its push to nothing every other tick.
  const bool stalled = !plate_limits_ &&
                       length(loop.last().physical_force_world_n) > settings_.arm_force_limit_n;
  device_->set_stalled(stalled);
  if (stalled) ++stalled_ticks_;
  choose_material();
  loop.step1(t_s);
  const haptics::LoopRecord& r =
      loop.step2(ticked_ ? t_s - previous_t_s_ : 0.0, seconds_since(start), false);
  previous_t_s_ = t_s;
  ticked_ = true;
  const bool stepped = sim.step_count() > steps_before;
  // A force-limited plate stopped short against a body: the arm is where
  // it is (the next tick moves on from there), and reports that pose.
  BladePose arm_pose = r.tool;
  const std::optional<ArmState> arm = rig_->world().limited_arm();
  const bool arm_stalled = arm && stepped && arm->stalled;
  // Only where it stopped short: elsewhere the plate is at the pose to
  // Bullet's float rounding, and the arm keeps its own (an arm that meets
  // nothing runs exactly as without the limit).
  if (arm && stepped &&
      length(arm->pose.position_m - r.tool.position_m) >
          1e-6 * std::max(1.0, length(r.tool.position_m))) {
    device_->place(arm->pose.position_m);
    arm_pose.position_m = arm->pose.position_m;
  }
  if (arm_stalled && !stalled) ++stalled_ticks_;
  if (stepped) {
    include_rect(dirty_, sim.last().changed);
    include_rect(worked_, sim.last().changed);
  }
  // The measurement, every tick once commanded.
  if (has_command_) {
    net::Measurement m;
    m.t_s = t_s;
    m.command_sequence = command_sequence_;
    m.flags = holding ? net::kMeasurementHolding : 0u;
    m.pose = arm_pose;
    // What a force sensor on the arm reads: the physical force.
    m.force_world_n = r.physical_force_world_n;
    m.contact_length_m = r.contact_length_m;
    m.cut_depth_m = r.cut_depth_m;
    m.commands_received = std::uint32_t(commands_received_);
    std::uint8_t out[net::kHeaderSize + net::kMeasurementPayloadSize + net::kCrcSize];
    net::Header h{net::MessageType::kMeasurement, settings_.link_id, session_,
                  seq_measurement_++, to_ns(t_s)};
    const std::size_t n = net::encode_measurement(h, m, out);
    link_.send(net::Channel::kUnreliable, out, n, t_s);
    if (stepped) update_estimate();
  }
  ++ticks_;
  if (t_s + 1e-9 >= next_sense_s_) {
    sense(t_s, r);
    next_sense_s_ += settings_.sense_period_s;
  }
  // The estimate the tick it changes (its refits come every fifth sample),
  // not at the next sensing: up to a sensing period sooner.
  if (has_command_) send_estimate(t_s);
  RemoteRecord rec;
  rec.t_s = t_s;
  rec.command_sequence = command_sequence_;
  rec.commanded_m = commanded_m_;
  rec.tool_m = arm_pose.position_m;
  rec.force_world_n = has_command_ ? r.physical_force_world_n : Vec3{};
  rec.contact_length_m = r.contact_length_m;
  rec.cut_depth_m = r.cut_depth_m;
  rec.estimate = estimate();
  rec.estimate_error = stepped ? estimate_error_ : -1.0;
  rec.in_changed_soil = in_changed_soil_;
  rec.stalled = stalled || arm_stalled;
  rec.holding = holding;
  rec.active = has_command_;
  rec.compute_s = seconds_since(tick_start);  // the whole tick: what arrived, the loop, the estimate, what it sent
  last_ = rec;
  if (options_.keep_records) records_.push_back(rec);
}

// ---------------------------------------------------------------------------
// Operator station
// ---------------------------------------------------------------------------

OperatorStation::OperatorStation(const Scenario& op, const MmtSettings& settings,
                                 haptics::Device& device, net::Endpoint& link,
                                 std::uint32_t session, const OperatorOptions& options)
    : settings_(settings), link_(link), session_(session), options_(options) {
  const haptics::LoopParams params = loop_params(op);
  haptics::Device* hand = &device;
  if (settings_.models_arm) {
    arm_ = std::make_unique<ArmModelDevice>(device, params.settings().workspace, first_orientation(op),
                                            settings_.follower_speed_m_per_s,
                                            settings_.follower_time_constant_s, params.rate_hz());
    hand = arm_.get();
  }
  guard_ = std::make_unique<LinkGuardDevice>(*hand);
  RigOptions ro;
  ro.loop.record_capacity = 0;
  ro.loop.realtime = false;
  ro.loop.snapshot = options_.snapshot;
  // Round trips of up to 8 s at 1 kHz are measured.
  command_sent_s_.assign(std::size_t(8.0 * params.rate_hz()) + 1, 0.0);
  rig_ = std::make_unique<HapticRig>(op, params, first_orientation(op), *guard_, ro);
  blend_ = std::make_unique<MaterialBlend>(rig_->world().simulation(), rig_->loop(),
                                           settings_.max_update_step_n);
  const GridSpec& g = rig_->world().simulation().grid().spec();
  stamp_s_.assign(std::size_t(g.sample_count()), -1e30f);
  protect_s_ = protection_s();
  const std::size_t window = std::size_t(std::llround(params.rate_hz()));  // 1 s
  power_.assign(window, 0.0);
  power_dfr_.assign(window, 0.0);
  loss_sequence_.assign(window, 0);
  loss_received_.assign(window, -1);
  // The buffers of the working traffic, made now: a command every tick in
  // flight, the datagrams of a tick arriving (any may be a patch), and the
  // blends of the patches merging at once (a blend waits while protected
  // or under the tool: a round trip, a blend and a second of cutting).
  const std::size_t samples = patch_samples(settings_, g);
  link_.reserve_in_flight(std::size_t(in_flight_s(settings_.to_remote) * params.rate_hz()) + 16,
                          net::kHeaderSize + net::kCommandPayloadSize + net::kCrcSize);
  inbox_ = net::Inbox(kInboxSlots, net::patch_datagram_bound(samples));
  patch_.heights.reserve(samples);
  codec_.reserve(samples);
  blends_.resize(std::min<std::size_t>(
      std::size_t((protect_s_ + settings_.blend_s + 1.0) / settings_.sense_period_s) + 8, 256));
  for (Blend& b : blends_) {
    b.t0_s.reserve(samples);
    b.from.reserve(samples);
    b.to.reserve(samples);
    b.scratch.reserve(samples);
  }
}

OperatorStation::~OperatorStation() = default;

const Simulation& OperatorStation::simulation() const { return rig_->world().simulation(); }
double OperatorStation::rate_hz() const { return rig_->loop().params().rate_hz(); }

void OperatorStation::receive(double t_s) {
  inbox_.clear();
  link_.receive(t_s, inbox_);
  const GridSpec& g = simulation().grid().spec();
  for (const auto& d : inbox_) {
    net::Header h;
    net::Reject r = net::decode_header(d.data(), d.size(), settings_.link_id, h);
    net::Measurement m;
    net::Estimate e;
    wire::SequenceFilter* filter = nullptr;
    if (r == net::Reject::kNone) {
      switch (h.type) {
        case net::MessageType::kMeasurement:
          r = net::decode_measurement(d.data(), d.size(), m);
          filter = &measurements_;
          break;
        case net::MessageType::kPatch:
          r = codec_.decode(d.data(), d.size(), patch_);
          if (r == net::Reject::kNone && (patch_.rect.c1 > g.cols || patch_.rect.r1 > g.rows))
            r = net::Reject::kBadPayload;  // outside the grid
          filter = &patches_;
          break;
        case net::MessageType::kEstimate:
          r = net::decode_estimate(d.data(), d.size(), e);
          // A material this blade cannot cut (rake + delta + phi leaves no
          // failure wedge) is no estimate for this model.
          if (r == net::Reject::kNone) {
            EarthmovingParams check;
            check.soil = e.material;
            check.rake_angle_deg = simulation().params().blade.rake_angle_deg;
            if (!validate(check).empty()) r = net::Reject::kBadPayload;
          }
          filter = &estimates_;
          break;
        default:
          r = net::Reject::kBadType;
      }
    }
    if (r == net::Reject::kNone)
      r = net::to_reject(filter->check(h.session, h.sequence, h.timestamp_ns));
    if (r != net::Reject::kNone) {
      counters_.rejected.add(r);
      continue;
    }
    ++counters_.accepted;
    heard_ = true;
    last_heard_s_ = t_s;
    counters_.sessions = std::max(counters_.sessions, measurements_.sessions());
    switch (h.type) {
      case net::MessageType::kMeasurement: {
        remote_force_ = m.force_world_n;
        // The round trip of the first measurement that follows a newer command.
        const std::uint32_t age = seq_command_ - m.command_sequence;
        if (age > 0 && age < command_sent_s_.size() &&
            (!rtt_known_ || std::int32_t(m.command_sequence - rtt_sequence_) > 0)) {
          rtt_s_ = round_trip_clock_s(t_s) - command_sent_s_[m.command_sequence % command_sent_s_.size()];
          rtt_sequence_ = m.command_sequence;
          rtt_known_ = true;
          rtt_max_now_s_ = std::max(rtt_max_now_s_, rtt_s_);
        }
        // How many of the commands up to the one it follows the remote received.
        ack_sequence_ = m.command_sequence;
        ack_received_ = m.commands_received;
        ack_known_ = true;
        break;
      }
      case net::MessageType::kPatch: {
        ++counters_.patches;
        // A new blend from the heights as they are now to the remote's, in
        // a pooled blend (its buffers reused) after those merging.
        if (active_blends_ == blends_.size()) blends_.emplace_back();
        Blend& b = blends_[active_blends_++];
        b.rect = patch_.rect;
        b.done = false;
        b.to.assign(patch_.heights.begin(), patch_.heights.end());
        b.from.resize(b.to.size());
        const HeightGrid& grid = simulation().grid();
        std::size_t k = 0;
        for (int row = b.rect.r0; row < b.rect.r1; ++row)
          for (int col = b.rect.c0; col < b.rect.c1; ++col)
            b.from[k++] = grid.heights()[grid.index(col, row)];
        b.scratch.resize(b.to.size());
        b.t0_s.assign(b.to.size(), float(t_s));
        break;
      }
      case net::MessageType::kEstimate:
        ++counters_.estimates;
        blend_->set_target(e.material);
        last_estimate_ = e;
        break;
      default:
        break;
    }
  }
}

// Moves every blend one tick on: each sample goes from its height when the
// patch came to the remote's over blend_s. While the tool is in contact, the
// samples near its edge (within exclusion_m, where the force is read: the
// depth ahead and the failure wedge) are not touched: their ramp starts
// again from their current height once the tool has left them, so a patch
// never changes the terrain the tool is feeling. Out of contact the same
// holds for the samples a patch would raise to the edge or above (the top
// of a body the remote sensed under the tool): a patch never makes contact. Samples the local tool
// changed recently wait the same way (the remote has not seen that change
// yet); every sample ends at the remote's height.
void OperatorStation::merge(double t_s) {
  const HeightGrid& grid = rig_->world().simulation().grid();
  const haptics::LoopRecord& last = rig_->loop().last();
  const bool in_contact = last.contact_length_m > 0.0;
  // The edge where the tool is now (the loop steps the simulation only
  // near the terrain, so its last step's edge can be old).
  const Segment edge = blade_segment(simulation().params().blade, last.tool);
  const double ex = settings_.exclusion_m;
  const double x0 = std::min(edge.a.x, edge.b.x) - ex, x1 = std::max(edge.a.x, edge.b.x) + ex;
  const double z0 = std::min(edge.a.z, edge.b.z) - ex, z1 = std::max(edge.a.z, edge.b.z) + ex;
  const float edge_low = float(std::min(edge.a.y, edge.b.y) - grid.spec().origin_m.y);
  for (std::size_t bi = 0; bi < active_blends_; ++bi) {
    Blend& b = blends_[bi];
    b.done = true;
    std::size_t k = 0;
    for (int row = b.rect.r0; row < b.rect.r1; ++row)
      for (int col = b.rect.c0; col < b.rect.c1; ++col, ++k) {
        const std::int64_t i = grid.index(col, row);
        const float now = grid.heights()[i];
        // Near the edge a sample waits while the tool is in contact, and
        // also out of contact when the patch would lift it to the edge (a
        // body's top under the tool): a patch never pushes terrain into it.
        if (in_contact || b.to[k] >= edge_low) {
          const double x = grid.sample_x(col), z = grid.sample_z(row);
          if (x >= x0 && x <= x1 && z >= z0 && z <= z1) {
            b.t0_s[k] = float(t_s);  // wait, and start from here later
            b.from[k] = now;
            b.scratch[k] = now;
            b.done = false;
            continue;
          }
        }
        const double ramp = settings_.blend_s > 0.0
                                ? std::clamp((t_s - b.t0_s[k]) / settings_.blend_s, 0.0, 1.0)
                                : 1.0;
        if (ramp < 1.0) b.done = false;
        // A sample the local tool changed within the last round trip is
        // ahead of what the remote has reported: it waits like the samples
        // under the tool, and ramps from where it is once it is settled.
        if (t_s - stamp_s_[std::size_t(i)] < protect_s_) {
          b.t0_s[k] = float(t_s);
          b.from[k] = now;
          b.scratch[k] = now;
          b.done = false;
          continue;
        }
        b.scratch[k] = float(b.from[k] + (b.to[k] - b.from[k]) * ramp);
      }
    // Through the simulation's validated edit, so that its listeners (a
    // Bullet world) and the soil phase hear of it; a height the patch could
    // not give (non-finite, below the floor) is the floor, as set_heights has it.
    const std::size_t n = std::size_t(b.rect.area());
    for (std::size_t j = 0; j < n; ++j)
      if (!(b.scratch[j] >= 0.0f) || !std::isfinite(b.scratch[j])) b.scratch[j] = 0.0f;
    const Rect changed =
        rig_->world().simulation().edit_heights(b.rect, std::span<const float>(b.scratch.data(), n));
    if (options_.snapshot) options_.snapshot->note_changed(changed);
    include_rect(worked_, b.rect);
  }
  // The finished blends go back to the pool; the others keep their order
  // (a later patch lands over an earlier one).
  std::size_t kept = 0;
  for (std::size_t bi = 0; bi < active_blends_; ++bi)
    if (!blends_[bi].done) {
      if (bi != kept) std::swap(blends_[kept], blends_[bi]);
      ++kept;
    }
  active_blends_ = kept;
}

double OperatorStation::round_trip_clock_s(double t_s) const {
  if (!options_.wall_clock) return t_s;
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double OperatorStation::round_trip_bound_s() const {
  if (!rtt_known_)
    return settings_.to_remote.delay_s + settings_.to_operator.delay_s +
           settings_.to_remote.jitter_s + settings_.to_operator.jitter_s;
  const double recent = std::max(rtt_max_now_s_, rtt_max_before_s_);
  return recent > 0.0 ? recent : rtt_s_;
}

// A local cut younger than a round trip (plus the sensing period and the
// blend) is not yet in what the remote sends: it is kept that long.
double OperatorStation::protection_s() const {
  return round_trip_bound_s() + settings_.sense_period_s + settings_.blend_s + 0.05;
}

double OperatorStation::command_loss() const {
  if (!ack_known_) return 0.0;
  const double followed = double(ack_sequence_) + 1.0;
  return std::clamp(1.0 - double(ack_received_) / followed, 0.0, 1.0);
}

// The round trip's buckets, the protection window, and the command loss over
// the last second (the remote's reports a second apart).
void OperatorStation::measure_link(double t_s) {
  if (t_s - rtt_bucket_s_ >= 1.0) {
    rtt_max_before_s_ = rtt_max_now_s_;
    rtt_max_now_s_ = 0.0;
    rtt_bucket_s_ = t_s;
  }
  protect_s_ = protection_s();
  link_.note_round_trip_s(round_trip_bound_s());
  const std::size_t at = std::size_t(ticks_) % loss_sequence_.size();
  if (ack_known_ && loss_received_[at] >= 0) {
    const double commands = double(std::int32_t(ack_sequence_ - loss_sequence_[at]));
    if (commands >= 10.0)
      loss_recent_ = std::clamp(1.0 - double(ack_received_ - loss_received_[at]) / commands, 0.0, 1.0);
  }
  loss_sequence_[at] = ack_sequence_;
  loss_received_[at] = ack_known_ ? ack_received_ : -1;
}

void OperatorStation::tick(double t_s) {
  const auto start = std::chrono::steady_clock::now();
  receive(t_s);
  measure_link(t_s);
  const bool updating_terrain = active_blends_ > 0;
  merge(t_s);
  const bool silent = heard_ && t_s - last_heard_s_ > settings_.timeout_s;
  guard_->set_silent(silent);
  if (silent) {
    ++counters_.silent_ticks;
    if (!was_silent_) ++silences_;
    longest_silence_s_ = std::max(longest_silence_s_, t_s - last_heard_s_);
  }
  was_silent_ = silent;

  haptics::HapticLoop& loop = rig_->loop();
  Simulation& sim = rig_->world().simulation();
  const std::int64_t steps_before = sim.step_count();
  blend_->tick();  // the material, moved on between steps
  loop.step1(t_s);
  const double period = ticks_ == 0 ? 0.0 : t_s - previous_t_s_;
  const haptics::LoopRecord& r = loop.step2(period, seconds_since(start), false);
  if (sim.step_count() > steps_before) {
    const Rect c = sim.last().changed;
    for (int row = c.r0; row < c.r1; ++row)
      for (int col = c.c0; col < c.c1; ++col)
        stamp_s_[std::size_t(sim.grid().index(col, row))] = float(t_s);
    include_rect(worked_, c);
  }

  // The command: where the operator's hand puts the tool (with the arm
  // modelled, the hand's pose: the remote's arm follows it as the local
  // tool did).
  net::Command cmd;
  cmd.t_s = t_s;
  cmd.pose = r.tool;
  if (arm_) cmd.pose.position_m = arm_->hand();
  cmd.flags = (r.flags & haptics::kFlagReconnected) ? net::kCommandLifted : 0u;
  if (rtt_known_)
    cmd.round_trip_us = std::uint32_t(std::clamp(round_trip_bound_s() * 1e6, 1.0, 4e9));
  std::uint8_t out[net::kHeaderSize + net::kCommandPayloadSize + net::kCrcSize];
  const std::uint32_t sent_sequence = seq_command_;
  command_sent_s_[seq_command_ % command_sent_s_.size()] = round_trip_clock_s(t_s);
  net::Header h{net::MessageType::kCommand, settings_.link_id, session_, seq_command_++,
                to_ns(t_s)};
  const std::size_t n = net::encode_command(h, cmd, out);
  link_.send(net::Channel::kUnreliable, out, n, t_s);

  // The passivity observer: energy the device put into the hand over the
  // last second (force held over the tick times the handle's displacement),
  // for the force rendered (MMT) and for the remote's force as it arrives
  // (direct force reflection, on the same motion).
  const haptics::Workspace& ws = loop.workspace();
  const double scale = loop.force_model().params().force_scale;
  double power = 0.0, power_dfr = 0.0;
  const Vec3 dfr_device = ws.direction_to_device(remote_force_ * scale);
  if (has_previous_) {
    const Vec3 dx = r.device_position_m - previous_device_m_;
    power = dot(previous_force_device_n_, dx);
    power_dfr = dot(previous_dfr_device_n_, dx);
  }
  window_j_ += power - power_[power_at_];
  window_dfr_j_ += power_dfr - power_dfr_[power_at_];
  power_[power_at_] = power;
  power_dfr_[power_at_] = power_dfr;
  power_at_ = (power_at_ + 1) % power_.size();

  const bool updating = updating_terrain || blend_->moving();
  max_update_step_n_ = std::max(max_update_step_n_, blend_->last_step_n());
  if (updating && has_previous_)
    max_step_while_updating_n_ =
        std::max(max_step_while_updating_n_, length(r.force_device_n - previous_force_device_n_));

  previous_device_m_ = r.device_position_m;
  previous_force_device_n_ = r.force_device_n;
  previous_dfr_device_n_ = dfr_device;
  has_previous_ = true;
  previous_t_s_ = t_s;
  ++ticks_;

  OperatorRecord rec;
  rec.t_s = t_s;
  rec.tool_m = r.tool.position_m;
  rec.device_m = r.device_position_m;
  rec.force_world_n = r.physical_force_world_n;
  rec.force_device_n = r.force_device_n;
  rec.remote_force_world_n = remote_force_;
  rec.contact_length_m = r.contact_length_m;
  rec.material = blend_->applied();
  rec.material_blend = blend_->fraction();
  rec.updating = updating;
  rec.link_silent = silent;
  rec.passivity_j = window_j_;
  rec.passivity_dfr_j = window_dfr_j_;
  rec.compute_s = seconds_since(start);
  rec.command_sequence = sent_sequence;
  rec.round_trip_s = rtt_s_;
  rec.command_loss = loss_recent_;
  last_ = rec;
  if (options_.keep_records) records_.push_back(rec);
}

}  // namespace terracut::session
