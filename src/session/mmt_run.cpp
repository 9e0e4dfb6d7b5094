// A single-process MMT run: both stations over an in-memory link, its
// summary and its files (mmt.hpp).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/haptics/sim_hand.hpp"
#include "terracut/haptics/udp_device.hpp"
#include "terracut/haptics/workspace.hpp"
#include "terracut/session/mmt.hpp"

#include "mmt_json.hpp"

namespace terracut::session {
namespace {

double rms(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / double(v.size()));
}

std::ofstream open_out(const std::filesystem::path& p) {
  std::ofstream out(p, std::ios::binary);
  if (!out) throw InputError(p.string() + ": cannot be written");
  out.precision(9);
  return out;
}

}  // namespace

double operator_duration_s(const Scenario& op) {
  if (op.haptics.duration_s) return *op.haptics.duration_s;
  if (op.haptics.device == haptics::DeviceKind::kUdp) return 30.0;  // as terracut haptics
  return followed_path(op, op.haptics, op.base.source_path.string()).duration_s() + op.haptics.settle_s;
}

std::unique_ptr<haptics::Device> make_operator_device(const Scenario& op) {
  return make_device(op, op.haptics, op.haptics.udp.port, op.base.source_path.string());
}

namespace {

constexpr const char* kOperatorCsvHeader =
    "t,x,y,z,fx,fy,fz,fdx,fdy,fdz,remote_fx,remote_fy,remote_fz,contact_length,"
    "unit_weight,cohesion,adhesion,phi,delta,material_blend,updating,link_silent,passivity_j,"
    "passivity_dfr_j,compute_us\n";
constexpr const char* kRemoteCsvHeader =
    "t,command_sequence,cmd_x,cmd_y,cmd_z,x,y,z,fx,fy,fz,contact_length,cut_depth,"
    "est_unit_weight,est_cohesion,est_adhesion,est_phi,est_delta,sd_unit_weight,sd_cohesion,"
    "sd_adhesion,sd_phi,sd_delta,identifiable,estimate_samples,estimate_error,in_changed_soil,"
    "stalled,holding,active,compute_us\n";

void write_material(std::ostream& out, const SoilMaterial& m) {
  out << m.unit_weight_n_per_m3 << ',' << m.cohesion_pa << ',' << m.adhesion_pa << ','
      << m.internal_friction_deg << ',' << m.soil_tool_friction_deg << ',';
}

void write_row(std::ostream& out, const OperatorRecord& r) {
  out << r.t_s << ',' << r.tool_m.x << ',' << r.tool_m.y << ',' << r.tool_m.z << ','
      << r.force_world_n.x << ',' << r.force_world_n.y << ',' << r.force_world_n.z << ','
      << r.force_device_n.x << ',' << r.force_device_n.y << ',' << r.force_device_n.z << ','
      << r.remote_force_world_n.x << ',' << r.remote_force_world_n.y << ','
      << r.remote_force_world_n.z << ',' << r.contact_length_m << ',';
  write_material(out, r.material);
  out << r.material_blend << ',' << int(r.updating) << ',' << int(r.link_silent) << ','
      << r.passivity_j << ',' << r.passivity_dfr_j << ',' << r.compute_s * 1e6 << '\n';
}

void write_row(std::ostream& out, const RemoteRecord& r) {
  out << r.t_s << ',' << r.command_sequence << ',' << r.commanded_m.x << ',' << r.commanded_m.y
      << ',' << r.commanded_m.z << ',' << r.tool_m.x << ',' << r.tool_m.y << ',' << r.tool_m.z
      << ',' << r.force_world_n.x << ',' << r.force_world_n.y << ',' << r.force_world_n.z << ','
      << r.contact_length_m << ',' << r.cut_depth_m << ',';
  write_material(out, r.estimate.material);
  for (double sd : r.estimate.sd) out << sd << ',';
  out << r.estimate.identifiable << ',' << r.estimate.samples << ',' << r.estimate_error << ','
      << int(r.in_changed_soil) << ',' << int(r.stalled) << ',' << int(r.holding) << ','
      << int(r.active) << ',' << r.compute_s * 1e6 << '\n';
}

}  // namespace

// The batch files are the streamed ones written in one go: one writer.
void write_operator_csv(const std::vector<OperatorRecord>& records,
                        const std::filesystem::path& path) {
  StationCsv csv = StationCsv::operator_csv(path);
  for (const OperatorRecord& r : records) csv.add(r);
  csv.finish();
}

void write_remote_csv(const std::vector<RemoteRecord>& records, const std::filesystem::path& path) {
  StationCsv csv = StationCsv::remote_csv(path);
  for (const RemoteRecord& r : records) csv.add(r);
  csv.finish();
}

StationCsv::StationCsv(const std::filesystem::path& path, const char* header)
    : path_(path), buffer_(new char[std::size_t(1) << 16]), out_(std::make_unique<std::ofstream>()) {
  // The buffer is set before the file opens (libstdc++ uses it only then).
  out_->rdbuf()->pubsetbuf(buffer_.get(), std::streamsize(1) << 16);
  out_->open(path, std::ios::binary);
  if (!*out_) throw InputError(path.string() + ": cannot be written");
  out_->precision(9);
  *out_ << header;
}

StationCsv::StationCsv(StationCsv&&) noexcept = default;
StationCsv& StationCsv::operator=(StationCsv&&) noexcept = default;
StationCsv::~StationCsv() = default;

StationCsv StationCsv::operator_csv(const std::filesystem::path& path) {
  return StationCsv(path, kOperatorCsvHeader);
}

StationCsv StationCsv::remote_csv(const std::filesystem::path& path) {
  return StationCsv(path, kRemoteCsvHeader);
}

void StationCsv::add(const OperatorRecord& r) {
  write_row(*out_, r);
  if (!*out_) throw InputError(path_.string() + ": cannot be written");
}

void StationCsv::add(const RemoteRecord& r) {
  write_row(*out_, r);
  if (!*out_) throw InputError(path_.string() + ": cannot be written");
}

void StationCsv::finish() {
  out_->close();
  if (!*out_) throw InputError(path_.string() + ": cannot be written");
}

MmtRun::MmtRun(const Scenario& op, const MmtOverrides& overrides) {
  if (!op.mmt)
    throw InputError(op.base.source_path.string() +
                     ": mmt: the scenario has no mmt: section (the remote world and the link)");
  settings_ = apply_overrides(*op.mmt, overrides);
  op_ = std::make_unique<Scenario>(op);
  remote_scn_ = std::make_unique<Scenario>(load_remote_scenario(op));
  if (remote_scn_->haptics.rate_hz != op_->haptics.rate_hz)
    throw InputError(settings_.remote_scenario.string() +
                     ": haptics.rate_hz: the remote must run at the operator's rate (" +
                     format_number(op_->haptics.rate_hz) + " Hz)");
  if (op_->haptics.device == haptics::DeviceKind::kUdp)
    throw InputError(op.base.source_path.string() +
                     ": haptics.device: a real device over udp runs in real time: run the "
                     "stations as two processes (--role remote / --role operator)");
  device_ = make_operator_device(*op_);
  link_ = std::make_unique<net::MemoryLink>(settings_.to_remote, settings_.to_operator);
  operator_ = std::make_unique<OperatorStation>(*op_, settings_, *device_, link_->a(), 1u);
  remote_ = std::make_unique<RemoteStation>(*remote_scn_, settings_, op_->base.soil.material,
                                            operator_->simulation().grid(), link_->b(), 2u);
  rate_hz_ = operator_->rate_hz();
  // After the path: a round trip, a sensing period and a blend for the last
  // updates to land, and on a lossy link three retransmissions more.
  const net::LinkConditions& back = settings_.to_operator;
  const bool lossy = back.loss > 0.0 || back.burst.p_good_to_bad > 0.0;
  const double retransmit_s = back.retransmit_s.value_or(2.0 * back.delay_s + 0.02);
  const double duration = overrides.duration_s.value_or(
      operator_duration_s(*op_) + settings_.to_remote.delay_s + back.delay_s +
      settings_.sense_period_s + settings_.blend_s + 0.2 + (lossy ? 3.0 * retransmit_s : 0.0));
  if (!(duration > 0.0) || duration > 3600.0)
    throw InputError(must_be("--duration", "in (0, 3600]", duration));
  total_ticks_ = std::max<std::int64_t>(1, std::llround(duration * rate_hz_));
  // Every record of the run has its room now: a tick allocates nothing.
  operator_->reserve_records(std::size_t(total_ticks_));
  remote_->reserve_records(std::size_t(total_ticks_));
  sensed_.reserve(std::size_t(operator_->simulation().grid().spec().sample_count()));
  terrain_error_.reserve(std::size_t(total_ticks_ / std::max<std::int64_t>(1, std::llround(0.05 * rate_hz_)) + 1));
}

MmtRun::~MmtRun() = default;

void MmtRun::tick() {
  const double t = double(tick_) / rate_hz_;
  operator_->tick(t);
  remote_->tick(t);
  ++tick_;
  if (tick_ % std::max<std::int64_t>(1, std::llround(0.05 * rate_hz_)) == 0)
    terrain_error_.emplace_back(t, terrain_rms());
}

void MmtRun::run() {
  while (tick_ < total_ticks_) tick();
}

// RMS of local - remote over every sample either station worked (cut or
// merged), metres; 0 before anything was worked. The remote's heights are
// its surface as sensed (the soil, or the top of an uncovered body): what
// the local model is to predict.
double MmtRun::terrain_rms() const {
  Rect region = operator_->worked();
  const Rect& w = remote_->worked();
  if (region.empty())
    region = w;
  else if (!w.empty())
    region.include(w);
  if (region.empty()) return 0.0;
  const HeightGrid& a = operator_->simulation().grid();
  sensed_.resize(std::size_t(region.area()));
  remote_->rig().world().sense_heights(region, sensed_);
  double s = 0.0;
  std::size_t k = 0;
  for (int r = region.r0; r < region.r1; ++r)
    for (int c = region.c0; c < region.c1; ++c) {
      const double d = double(a.heights()[a.index(c, r)]) - sensed_[k++];
      s += d * d;
    }
  return std::sqrt(s / double(region.area()));
}

MmtSummary MmtRun::summary() const {
  MmtSummary s;
  s.duration_s = double(tick_) / rate_hz_;
  s.rtt_s = settings_.to_remote.delay_s + settings_.to_operator.delay_s;
  s.loss = settings_.to_remote.loss;
  s.deadband = settings_.deadband;
  const auto& op = operator_->records();
  const auto& rm = remote_->records();
  // The remote acts on command i one one-way delay later, and its arm, a
  // first-order servo, follows a steady motion one time constant behind:
  // compare there (the same commanded motion). Direct reflection is
  // compared the same way.
  const std::int64_t lag = std::llround(
      (settings_.to_remote.delay_s + settings_.follower_time_constant_s) * rate_hz_);
  // The remote's cutting: from its first tick with a cut on.
  double first_cut_s = -1.0, change_s = -1.0;
  for (const RemoteRecord& r : rm) {
    if (first_cut_s < 0.0 && r.active && r.cut_depth_m > 0.0 && r.estimate_error >= 0.0)
      first_cut_s = r.t_s;
    if (change_s < 0.0 && r.in_changed_soil) change_s = r.t_s;
  }
  s.cutting_from_s = first_cut_s < 0.0 ? -1.0 : first_cut_s + 1.0;
  if (change_s >= 0.0) {
    s.settle_excluded_from_s = change_s;
    s.settle_excluded_to_s = change_s + s.rtt_s + 0.5;
  }
  std::vector<double> e_mmt, e_dfr, f_rem, e_mmt1, e_dfr1, f_rem1;
  for (std::size_t i = 0; i < op.size(); ++i) {
    const std::size_t j = i + std::size_t(lag);
    if (j >= rm.size() || !rm[j].active) continue;
    // Over the ticks where some force is felt or measured: the time in
    // soil, not the idle time before and after, so that runs of different
    // lengths compare.
    if (length(op[i].force_world_n) == 0.0 && length(op[i].remote_force_world_n) == 0.0 &&
        length(rm[j].force_world_n) == 0.0)
      continue;
    const double em = length(op[i].force_world_n - rm[j].force_world_n);
    const double ed = length(op[i].remote_force_world_n - rm[j].force_world_n);
    const double fr = length(rm[j].force_world_n);
    e_mmt.push_back(em);
    e_dfr.push_back(ed);
    f_rem.push_back(fr);
    const double t = rm[j].t_s;
    if (first_cut_s >= 0.0 && t >= s.cutting_from_s &&
        !(change_s >= 0.0 && t >= s.settle_excluded_from_s && t < s.settle_excluded_to_s)) {
      e_mmt1.push_back(em);
      e_dfr1.push_back(ed);
      f_rem1.push_back(fr);
    }
  }
  s.force_rms_remote_n = rms(f_rem);
  s.force_error_rms_mmt_n = rms(e_mmt);
  s.force_error_rms_dfr_n = rms(e_dfr);
  for (double e : e_mmt) s.force_error_max_mmt_n = std::max(s.force_error_max_mmt_n, e);
  for (double e : e_dfr) s.force_error_max_dfr_n = std::max(s.force_error_max_dfr_n, e);
  s.force_rms_remote_after_1s_n = rms(f_rem1);
  s.force_error_rms_mmt_after_1s_n = rms(e_mmt1);
  s.force_error_rms_dfr_after_1s_n = rms(e_dfr1);
  // A window with less than 0.1 s of the remote cutting (a change of soil
  // whose left-out round trip reaches past the end of the cut) has no
  // figure: -1.
  std::size_t cutting_ticks = 0;
  for (double f : f_rem1) cutting_ticks += f > 1.0;
  s.force_error_rel_mmt_after_1s = s.force_error_rel_dfr_after_1s = -1.0;
  if (s.force_rms_remote_after_1s_n > 0.0 && double(cutting_ticks) >= 0.1 * rate_hz_) {
    s.force_error_rel_mmt_after_1s = s.force_error_rms_mmt_after_1s_n / s.force_rms_remote_after_1s_n;
    s.force_error_rel_dfr_after_1s = s.force_error_rms_dfr_after_1s_n / s.force_rms_remote_after_1s_n;
  }
  // Re-identification: from the blade entering the new soil to the last
  // tick, while it cuts, whose estimate was more than 5 % off the measured
  // horizontal force.
  if (change_s >= 0.0) {
    double last_off_s = change_s;
    for (const RemoteRecord& r : rm)
      if (r.t_s >= change_s && r.estimate_error > 0.05) last_off_s = r.t_s;
    s.reidentified_after_s = last_off_s - change_s;
  }
  for (const auto& [t, e] : terrain_error_) s.terrain_rms_max_m = std::max(s.terrain_rms_max_m, e);
  s.terrain_rms_final_m = terrain_error_.empty() ? 0.0 : terrain_error_.back().second;
  std::vector<double> track;
  for (const RemoteRecord& r : rm)
    if (r.active) track.push_back(length(r.tool_m - r.commanded_m));
  s.tracking_rms_m = rms(track);
  for (double e : track) s.tracking_max_m = std::max(s.tracking_max_m, e);
  const double d = std::max(s.duration_s, 1e-9);
  const net::TrafficCounters& up = link_->a().traffic();
  const net::TrafficCounters& down = link_->b().traffic();
  s.packets_per_s_to_remote = double(up.sent) / d;
  s.bytes_per_s_to_remote = double(up.sent_bytes) / d;
  s.packets_per_s_to_operator = double(down.sent) / d;
  s.bytes_per_s_to_operator = double(down.sent_bytes) / d;
  s.patches = remote_->counters().patches;
  s.estimates = remote_->counters().estimates;
  s.update_packets_per_s = double(remote_->update_packets()) / d;
  s.max_update_step_n = operator_->max_update_step_n();
  s.max_step_while_updating_n = operator_->max_step_while_updating_n();
  for (const OperatorRecord& r : op) {
    s.passivity_max_mmt_j = std::max(s.passivity_max_mmt_j, r.passivity_j);
    s.passivity_max_dfr_j = std::max(s.passivity_max_dfr_j, r.passivity_dfr_j);
  }
  s.estimate = remote_->estimate();
  s.remote_material = remote_->true_material();
  s.material_applied = operator_->simulation().force_material();
  s.stalled_ticks = remote_->stalled_ticks();
  std::vector<double> c;
  for (const OperatorRecord& r : op) c.push_back(r.compute_s);
  s.operator_compute = timing_stats(c);
  c.clear();
  for (const RemoteRecord& r : rm) c.push_back(r.compute_s);
  s.remote_compute = timing_stats(c);
  return s;
}

void MmtRun::write_outputs(const std::filesystem::path& dir) const {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir.string() + ": cannot create the folder: " + ec.message());
  write_operator_csv(operator_->records(), dir / "operator.csv");
  write_remote_csv(remote_->records(), dir / "remote.csv");
  {
    std::ofstream out = open_out(dir / "terrain_error.csv");
    out << "t,rms_m\n";
    for (const auto& [t, e] : terrain_error_) out << t << ',' << e << '\n';
  }
  const MmtSummary s = summary();
  nlohmann::ordered_json j;
  j["scenario"] = op_->base.source_path.string();
  j["remote_scenario"] = remote_scn_->base.source_path.string();
  j["link"] = {{"rtt_s", s.rtt_s},
               {"delay_s_each_way", settings_.to_remote.delay_s},
               {"jitter_s", settings_.to_remote.jitter_s},
               {"loss", settings_.to_remote.loss},
               {"burst_p_good_to_bad", settings_.to_remote.burst.p_good_to_bad},
               {"reorder", settings_.to_remote.reorder},
               {"seed", settings_.to_remote.seed}};
  j["operator"] = {{"blend_s", settings_.blend_s},
                   {"max_update_step_n", settings_.max_update_step_n},
                   {"deadband", settings_.deadband}};
  j["duration_s"] = s.duration_s;
  j["force_error"] = {{"remote_force_rms_n", s.force_rms_remote_n},
                      {"mmt_rms_n", s.force_error_rms_mmt_n},
                      {"mmt_max_n", s.force_error_max_mmt_n},
                      {"direct_rms_n", s.force_error_rms_dfr_n},
                      {"direct_max_n", s.force_error_max_dfr_n},
                      {"aligned_by_s", settings_.to_remote.delay_s + settings_.follower_time_constant_s}};
  j["terrain_error"] = {{"final_rms_m", s.terrain_rms_final_m}, {"max_rms_m", s.terrain_rms_max_m}};
  j["tracking"] = {{"rms_m", s.tracking_rms_m}, {"max_m", s.tracking_max_m}};
  j["traffic"] = {{"to_remote_packets_per_s", s.packets_per_s_to_remote},
                  {"to_remote_bytes_per_s", s.bytes_per_s_to_remote},
                  {"to_operator_packets_per_s", s.packets_per_s_to_operator},
                  {"to_operator_bytes_per_s", s.bytes_per_s_to_operator},
                  {"update_packets_per_s", s.update_packets_per_s},
                  {"lost_to_remote", link_->a().emulator().counters().lost},
                  {"lost_to_operator", link_->b().emulator().counters().lost}};
  j["updates"] = {{"patches", s.patches},
                  {"estimates", s.estimates},
                  {"patches_merged", operator_->counters().patches},
                  {"estimates_applied", operator_->counters().estimates},
                  {"max_force_step_at_update_n", s.max_update_step_n},
                  {"max_force_step_while_updating_n", s.max_step_while_updating_n}};
  j["force_error_after_1s"] = {{"from_s", s.cutting_from_s},
                               {"left_out_from_s", s.settle_excluded_from_s},
                               {"left_out_to_s", s.settle_excluded_to_s},
                               {"remote_force_rms_n", s.force_rms_remote_after_1s_n},
                               {"mmt_rms_n", s.force_error_rms_mmt_after_1s_n},
                               {"direct_rms_n", s.force_error_rms_dfr_after_1s_n},
                               {"mmt_relative", s.force_error_rel_mmt_after_1s},
                               {"direct_relative", s.force_error_rel_dfr_after_1s}};
  j["remote_soil"] = {{"material", detail::material_json(remote_->base_material())},
                      {"changed_to", settings_.change_soil
                                         ? detail::material_json(remote_->changed_material())
                                         : nlohmann::ordered_json()},
                      {"change_z_below_m", settings_.change_soil ? nlohmann::ordered_json(settings_.change_z_m)
                                                                 : nlohmann::ordered_json()},
                      {"changed_at_s", s.settle_excluded_from_s > 0.0
                                           ? nlohmann::ordered_json(s.settle_excluded_from_s)
                                           : nlohmann::ordered_json()}};
  j["estimate"] = detail::estimate_json(s.estimate, &s.remote_material);
  j["estimate"]["material_applied_by_operator"] = detail::material_json(s.material_applied);
  j["estimate"]["reidentified_after_s"] = s.reidentified_after_s;
  j["remote_arm"] = {{"force_limit_n", settings_.arm_force_limit_n},
                     {"stalled_ticks", s.stalled_ticks}};
  j["passivity"] = {{"window_s", 1.0},
                    {"mmt_max_energy_into_hand_j", s.passivity_max_mmt_j},
                    {"direct_max_energy_into_hand_j", s.passivity_max_dfr_j}};
  auto rejected = [](const StationCounters& c) {
    nlohmann::ordered_json r;
    for (std::size_t i = 1; i < net::kRejectReasonCount; ++i)
      r[std::string(net::to_string(net::Reject(i)))] = c.rejected.by_reason[i];
    return r;
  };
  j["rejected"] = {{"operator", rejected(operator_->counters())},
                   {"remote", rejected(remote_->counters())}};
  auto timing = [](const TimingStats& t) {
    return nlohmann::ordered_json{{"p50_us", t.p50_us}, {"p99_us", t.p99_us}, {"max_us", t.max_us}};
  };
  j["timing"] = {{"operator_tick", timing(s.operator_compute)},
                 {"remote_tick", timing(s.remote_compute)}};
  std::ofstream out = open_out(dir / "summary.json");
  out << j.dump(2) << "\n";
  if (!out) throw InputError((dir / "summary.json").string() + ": cannot be written");
}

}  // namespace terracut::session
