// A single-process MMT run: both stations over an in-memory link, its
// summary and its files (mmt.hpp).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "mmt_json.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/haptics/sim_hand.hpp"
#include "terracut/haptics/udp_device.hpp"
#include "terracut/haptics/workspace.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::session {
namespace {

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

namespace {
// The script device at the time modulo its round: the path over and over
// (the soak's --repeat).
class RepeatingScript final : public haptics::Device {
 public:
  explicit RepeatingScript(haptics::DevicePath path)
      : round_s_(path.duration_s() + 0.5), script_(std::move(path)) {}
  std::string_view kind() const override { return "script"; }
  bool read(double t_s, haptics::DeviceSample& out) noexcept override {
    return script_.read(std::fmod(std::max(t_s, 0.0), round_s_), out);
  }
  void write(const haptics::DeviceCommand& c) noexcept override { script_.write(c); }
  std::vector<haptics::DeviceStat> stats() const override { return script_.stats(); }

 private:
  double round_s_;
  haptics::ScriptDevice script_;
};
}  // namespace

std::unique_ptr<haptics::Device> make_operator_device(const Scenario& op, bool repeat) {
  if (!repeat) return make_device(op, op.haptics, op.haptics.udp.port, op.base.source_path.string());
  if (op.haptics.device != haptics::DeviceKind::kScript)
    throw InputError(op.base.source_path.string() +
                     ": --repeat: only the script device replays its cut (haptics.device: script)");
  return std::make_unique<RepeatingScript>(followed_path(op, op.haptics, op.base.source_path.string()));
}

namespace {

constexpr const char* kOperatorCsvHeader =
    "t,x,y,z,fx,fy,fz,fdx,fdy,fdz,remote_fx,remote_fy,remote_fz,contact_length,"
    "unit_weight,cohesion,adhesion,phi,delta,material_blend,updating,link_silent,passivity_j,"
    "passivity_dfr_j,compute_us,command_sequence,round_trip_s,command_loss";
constexpr const char* kRemoteCsvHeader =
    "t,command_sequence,cmd_x,cmd_y,cmd_z,x,y,z,fx,fy,fz,contact_length,cut_depth,"
    "est_unit_weight,est_cohesion,est_adhesion,est_phi,est_delta,sd_unit_weight,sd_cohesion,"
    "sd_adhesion,sd_phi,sd_delta,identifiable,estimate_samples,estimate_error,in_changed_soil,"
    "stalled,holding,active,compute_us";

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
    : file_(std::make_unique<io::CsvFile>(path, header)) {}

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
  const SoilMaterial& m = r.material;
  file_->row({r.t_s, r.tool_m.x, r.tool_m.y, r.tool_m.z, r.force_world_n.x, r.force_world_n.y,
              r.force_world_n.z, r.force_device_n.x, r.force_device_n.y, r.force_device_n.z,
              r.remote_force_world_n.x, r.remote_force_world_n.y, r.remote_force_world_n.z,
              r.contact_length_m, m.unit_weight_n_per_m3, m.cohesion_pa, m.adhesion_pa,
              m.internal_friction_deg, m.soil_tool_friction_deg, r.material_blend, r.updating,
              r.link_silent, r.passivity_j, r.passivity_dfr_j, r.compute_s * 1e6,
              r.command_sequence, r.round_trip_s, r.command_loss});
}

void StationCsv::add(const RemoteRecord& r) {
  const SoilMaterial& m = r.estimate.material;
  const auto& sd = r.estimate.sd;
  static_assert(kSoilFieldCount == 5, "the header names five standard uncertainties");
  file_->row({r.t_s, r.command_sequence, r.commanded_m.x, r.commanded_m.y, r.commanded_m.z,
              r.tool_m.x, r.tool_m.y, r.tool_m.z, r.force_world_n.x, r.force_world_n.y,
              r.force_world_n.z, r.contact_length_m, r.cut_depth_m, m.unit_weight_n_per_m3,
              m.cohesion_pa, m.adhesion_pa, m.internal_friction_deg, m.soil_tool_friction_deg,
              sd[0], sd[1], sd[2], sd[3], sd[4], r.estimate.identifiable, r.estimate.samples,
              r.estimate_error, r.in_changed_soil, r.stalled, r.holding, r.active,
              r.compute_s * 1e6});
}

void StationCsv::finish() { file_->close(); }

StationPair make_station_pair(const Scenario& op, const Scenario& remote, const MmtSettings& settings,
                              haptics::Device& device, const OperatorOptions& operator_options,
                              const RemoteOptions& remote_options) {
  StationPair p;
  p.link = std::make_unique<net::EmulatedLink>(settings.to_remote, settings.to_operator);
  p.operator_station =
      std::make_unique<OperatorStation>(op, settings, device, p.link->a(), 1u, operator_options);
  p.remote_station = std::make_unique<RemoteStation>(remote, settings, op.base.soil.material,
                                                     p.operator_station->simulation().grid(),
                                                     p.link->b(), 2u, remote_options);
  return p;
}

MmtRun::MmtRun(const Scenario& op, const MmtOverrides& overrides) {
  if (!op.mmt) throw InputError(no_mmt_section(op));
  settings_ = apply_overrides(*op.mmt, overrides);
  op_ = std::make_unique<Scenario>(op);
  remote_scn_ = std::make_unique<Scenario>(load_remote_scenario(op));
  if (remote_scn_->base.rate_hz != op_->base.rate_hz)
    throw InputError(settings_.remote_scenario.string() +
                     ": rate_hz: the remote must run at the operator's rate (" +
                     format_number(op_->base.rate_hz) + " Hz)");
  if (op_->haptics.device == haptics::DeviceKind::kUdp)
    throw InputError(op.base.source_path.string() +
                     ": haptics.device: a real device over udp runs in real time: run the "
                     "stations as two processes (--role remote / --role operator)");
  device_ = make_operator_device(*op_);
  StationPair pair = make_station_pair(*op_, *remote_scn_, settings_, *device_);
  link_ = std::move(pair.link);
  operator_ = std::move(pair.operator_station);
  remote_ = std::move(pair.remote_station);
  rate_hz_ = operator_->rate_hz();
  // The run's length: the one rule (mmt_run_length_s), with the emulated
  // round trip.
  const net::LinkConditions& back = settings_.to_operator;
  const double duration = overrides.duration_s.value_or(mmt_run_length_s(
      settings_, operator_duration_s(*op_), settings_.to_remote.delay_s + back.delay_s,
      net::retransmit_timeout_s(back, net::emulated_round_trip_s(back))));
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
  link_->release(t);
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
  s.rtt_measured_s = operator_->rtt_s();
  s.loss = settings_.to_remote.loss;
  s.deadband = settings_.deadband;
  // With the arm in the operator's model both blades move alike: no lag to align.
  compare_records(operator_->records(), remote_->records(), rate_hz_,
                  settings_.models_arm ? 0.0 : settings_.follower_time_constant_s, s);
  for (const auto& [t, e] : terrain_error_) s.terrain_rms_max_m = std::max(s.terrain_rms_max_m, e);
  s.terrain_rms_final_m = terrain_error_.empty() ? 0.0 : terrain_error_.back().second;
  const double d = std::max(s.duration_s, 1e-9);
  const net::TrafficCounters& up = link_->a().traffic();
  const net::TrafficCounters& down = link_->b().traffic();
  s.packets_per_s_to_remote = double(up.sent) / d;
  s.bytes_per_s_to_remote = double(up.sent_bytes) / d;
  s.packets_per_s_to_operator = double(down.sent) / d;
  s.bytes_per_s_to_operator = double(down.sent_bytes) / d;
  s.lost_to_remote = link_->a().emulator().counters().lost;
  s.lost_to_operator = link_->b().emulator().counters().lost;
  s.patches = remote_->counters().patches;
  s.estimates = remote_->counters().estimates;
  s.patches_merged = operator_->counters().patches;
  s.estimates_applied = operator_->counters().estimates;
  s.update_packets_per_s = double(remote_->update_packets()) / d;
  s.max_update_step_n = operator_->max_update_step_n();
  s.max_step_while_updating_n = operator_->max_step_while_updating_n();
  s.estimate = remote_->estimate();
  s.remote_material = remote_->true_material();
  s.material_applied = operator_->simulation().force_material();
  s.arm_force_limit_n = settings_.arm_force_limit_n;
  s.stalled_ticks = remote_->stalled_ticks();
  s.rejected_operator = operator_->counters().rejected;
  s.rejected_remote = remote_->counters().rejected;
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
  j["link"] = link_json(settings_.to_remote);
  j["link"]["rtt_s"] = s.rtt_s;
  j["link"]["rtt_measured_s"] = s.rtt_measured_s;
  j["operator"] = {{"blend_s", settings_.blend_s},
                   {"max_update_step_n", settings_.max_update_step_n},
                   {"deadband", settings_.deadband}};
  j["remote_soil"] = {{"material", detail::material_json(remote_->base_material())},
                      {"changed_to", settings_.change_soil
                                         ? detail::material_json(remote_->changed_material())
                                         : nlohmann::ordered_json()},
                      {"change_z_below_m", settings_.change_soil ? nlohmann::ordered_json(settings_.change_z_m)
                                                                 : nlohmann::ordered_json()},
                      {"changed_at_s", s.settle_excluded_from_s > 0.0
                                           ? nlohmann::ordered_json(s.settle_excluded_from_s)
                                           : nlohmann::ordered_json()}};
  j.update(summary_json(s));
  std::ofstream out = open_out(dir / "summary.json");
  out << j.dump(2) << "\n";
  if (!out) throw InputError((dir / "summary.json").string() + ": cannot be written");
}

}  // namespace terracut::session
