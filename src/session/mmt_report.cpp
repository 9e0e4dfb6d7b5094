// The comparison of an MMT session from its two stations' records, its
// summary.json entries, and the report of a two-process session from the
// stations' folders (mmt.hpp, mmt_process.hpp, mmt_json.hpp).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "mmt_json.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"
#include "terracut/session/mmt_process.hpp"

namespace terracut::session {
namespace {

double rms_of(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / double(v.size()));
}

// A station's CSV: its columns by name and its rows of numbers.
struct Table {
  std::filesystem::path path;
  std::unordered_map<std::string, std::size_t> column;
  std::vector<std::vector<double>> rows;
  std::size_t at(const std::string& name) const {
    const auto it = column.find(name);
    if (it == column.end())
      throw InputError(path.string() + ": no column '" + name + "' (not a file of this terracut's `mmt --role`?)");
    return it->second;
  }
};

Table read_table(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot be read (run both stations with --out first)");
  Table t;
  t.path = path;
  std::string line;
  if (!std::getline(in, line)) throw InputError(path.string() + ": empty");
  {
    std::stringstream header(line);
    std::string name;
    while (std::getline(header, name, ',')) t.column.emplace(name, t.column.size());
  }
  std::size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::vector<double>& row = t.rows.emplace_back();
    row.reserve(t.column.size());
    const char* p = line.data();
    const char* end = line.data() + line.size();
    while (p <= end) {
      double v = 0.0;
      const auto [next, ec] = std::from_chars(p, end, v);
      if (ec != std::errc()) {
        // "inf" and "nan" as the stream wrote them
        if (std::string_view(p, std::size_t(end - p)).substr(0, 3) == "nan") v = NAN, p += 3;
        else if (std::string_view(p, std::size_t(end - p)).substr(0, 3) == "inf") v = INFINITY, p += 3;
        else if (std::string_view(p, std::size_t(end - p)).substr(0, 4) == "-inf") v = -INFINITY, p += 4;
        else throw InputError(path.string() + ":" + std::to_string(number) + ": not a number");
      } else {
        p = next;
      }
      row.push_back(v);
      if (p < end && *p != ',') throw InputError(path.string() + ":" + std::to_string(number) + ": not a number");
      ++p;
    }
    if (row.size() != t.column.size())
      throw InputError(path.string() + ":" + std::to_string(number) + ": " + std::to_string(row.size()) +
                       " values, the header has " + std::to_string(t.column.size()));
  }
  return t;
}

// The five fields of a material from five columns, first at `at`.
SoilMaterial material_at(const std::vector<double>& r, std::size_t at) {
  SoilMaterial m;
  m.unit_weight_n_per_m3 = r[at];
  m.cohesion_pa = r[at + 1];
  m.adhesion_pa = r[at + 2];
  m.internal_friction_deg = r[at + 3];
  m.soil_tool_friction_deg = r[at + 4];
  return m;
}

std::vector<OperatorRecord> operator_records(const Table& t) {
  const std::size_t ct = t.at("t"), x = t.at("x"), fx = t.at("fx"), fdx = t.at("fdx"),
                    rfx = t.at("remote_fx"), cl = t.at("contact_length"), uw = t.at("unit_weight"),
                    mb = t.at("material_blend"), up = t.at("updating"), ls = t.at("link_silent"),
                    pj = t.at("passivity_j"), pd = t.at("passivity_dfr_j"), cu = t.at("compute_us"),
                    cs = t.at("command_sequence"), rt = t.at("round_trip_s"), lo = t.at("command_loss");
  std::vector<OperatorRecord> out;
  out.reserve(t.rows.size());
  for (const auto& r : t.rows) {
    OperatorRecord o;
    o.t_s = r[ct];
    o.tool_m = {r[x], r[x + 1], r[x + 2]};
    o.force_world_n = {r[fx], r[fx + 1], r[fx + 2]};
    o.force_device_n = {r[fdx], r[fdx + 1], r[fdx + 2]};
    o.remote_force_world_n = {r[rfx], r[rfx + 1], r[rfx + 2]};
    o.contact_length_m = r[cl];
    o.material = material_at(r, uw);
    o.material_blend = r[mb];
    o.updating = r[up] != 0.0;
    o.link_silent = r[ls] != 0.0;
    o.passivity_j = r[pj];
    o.passivity_dfr_j = r[pd];
    o.compute_s = r[cu] * 1e-6;
    o.command_sequence = std::uint32_t(std::llround(r[cs]));
    o.round_trip_s = r[rt];
    o.command_loss = r[lo];
    out.push_back(o);
  }
  return out;
}

std::vector<RemoteRecord> remote_records(const Table& t) {
  const std::size_t ct = t.at("t"), cs = t.at("command_sequence"), cx = t.at("cmd_x"), x = t.at("x"),
                    fx = t.at("fx"), cl = t.at("contact_length"), cd = t.at("cut_depth"),
                    eu = t.at("est_unit_weight"), su = t.at("sd_unit_weight"), id = t.at("identifiable"),
                    es = t.at("estimate_samples"), ee = t.at("estimate_error"),
                    ic = t.at("in_changed_soil"), st = t.at("stalled"), ho = t.at("holding"),
                    ac = t.at("active"), cu = t.at("compute_us");
  std::vector<RemoteRecord> out;
  out.reserve(t.rows.size());
  for (const auto& r : t.rows) {
    RemoteRecord o;
    o.t_s = r[ct];
    o.command_sequence = std::uint32_t(std::llround(r[cs]));
    o.commanded_m = {r[cx], r[cx + 1], r[cx + 2]};
    o.tool_m = {r[x], r[x + 1], r[x + 2]};
    o.force_world_n = {r[fx], r[fx + 1], r[fx + 2]};
    o.contact_length_m = r[cl];
    o.cut_depth_m = r[cd];
    o.estimate.material = material_at(r, eu);
    for (std::size_t f = 0; f < std::size_t(kSoilFieldCount); ++f) o.estimate.sd[f] = r[su + f];
    o.estimate.identifiable = std::uint32_t(std::llround(r[id]));
    o.estimate.samples = std::llround(r[es]);
    o.estimate.known = o.estimate.samples > 0;
    o.estimate_error = r[ee];
    o.in_changed_soil = r[ic] != 0.0;
    o.stalled = r[st] != 0.0;
    o.holding = r[ho] != 0.0;
    o.active = r[ac] != 0.0;
    o.compute_s = r[cu] * 1e-6;
    out.push_back(o);
  }
  return out;
}

nlohmann::ordered_json read_summary(const std::filesystem::path& dir, const char* role) {
  const std::filesystem::path p = dir / "summary.json";
  std::ifstream in(p);
  if (!in) throw InputError(p.string() + ": cannot be read (run both stations with --out first)");
  nlohmann::ordered_json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    throw InputError(p.string() + ": not JSON: " + e.what());
  }
  if (!j.is_object() || j.value("role", "") != role)
    throw InputError(p.string() + ": not the summary of a " + role + " station (`terracut mmt --role " +
                     role + "`)");
  return j;
}

template <class T>
T number_at(const nlohmann::ordered_json& j, const std::filesystem::path& dir,
            std::initializer_list<const char*> path) {
  const nlohmann::ordered_json* at = &j;
  std::string name;
  for (const char* key : path) {
    name += name.empty() ? key : std::string(".") + key;
    if (!at->is_object() || !at->contains(key) || (*at)[key].is_null())
      throw InputError((dir / "summary.json").string() + ": no " + name);
    at = &(*at)[key];
  }
  return at->get<T>();
}

Rect rect_at(const nlohmann::ordered_json& j, const std::filesystem::path& dir) {
  if (!j.contains("worked") || !j["worked"].is_array() || j["worked"].size() != 4)
    throw InputError((dir / "summary.json").string() + ": no worked rectangle");
  const auto& w = j["worked"];
  return {w[0].get<int>(), w[1].get<int>(), w[2].get<int>(), w[3].get<int>()};
}

net::RejectCounts rejected_of(const nlohmann::ordered_json& j) {
  net::RejectCounts c;
  if (!j.contains("rejected")) return c;
  for (std::size_t i = 1; i < net::kRejectReasonCount; ++i)
    c.by_reason[i] = j["rejected"].value(std::string(net::to_string(net::Reject(i))), std::int64_t(0));
  return c;
}

}  // namespace

void compare_records(const std::vector<OperatorRecord>& op, const std::vector<RemoteRecord>& rm,
                     double rate_hz, double follower_lag_s, MmtSummary& s) {
  const std::size_t lag = std::size_t(std::max<long long>(0, std::llround(follower_lag_s * rate_hz)));
  s.aligned_after_s = double(lag) / rate_hz;
  // The remote's cutting: from its first tick with a cut on.
  double first_cut_s = -1.0, change_s = -1.0;
  for (const RemoteRecord& r : rm) {
    if (first_cut_s < 0.0 && r.active && r.cut_depth_m > 0.0 && r.estimate_error >= 0.0)
      first_cut_s = r.t_s;
    if (change_s < 0.0 && r.in_changed_soil) change_s = r.t_s;
  }
  s.cutting_from_s = first_cut_s < 0.0 ? -1.0 : first_cut_s + 1.0;
  s.settle_excluded_from_s = s.settle_excluded_to_s = 0.0;
  if (change_s >= 0.0) {
    s.settle_excluded_from_s = change_s;
    s.settle_excluded_to_s = change_s + s.rtt_s + 0.5;
  }
  std::vector<double> e_mmt, e_dfr, f_rem, e_mmt1, e_dfr1, f_rem1;
  std::size_t j = 0;  // the remote's first tick that followed command i (or a newer one)
  for (std::size_t i = 0; i < op.size(); ++i) {
    const std::uint32_t q = op[i].command_sequence;
    while (j < rm.size() && !(rm[j].active && std::int32_t(rm[j].command_sequence - q) >= 0)) ++j;
    if (j + lag >= rm.size()) break;
    const RemoteRecord& r = rm[j + lag];
    // Over the ticks where some force is felt or measured: the time in
    // soil, not the idle time before and after, so that runs of different
    // lengths compare.
    if (length(op[i].force_world_n) == 0.0 && length(op[i].remote_force_world_n) == 0.0 &&
        length(r.force_world_n) == 0.0)
      continue;
    const double em = length(op[i].force_world_n - r.force_world_n);
    const double ed = length(op[i].remote_force_world_n - r.force_world_n);
    const double fr = length(r.force_world_n);
    e_mmt.push_back(em);
    e_dfr.push_back(ed);
    f_rem.push_back(fr);
    if (first_cut_s >= 0.0 && r.t_s >= s.cutting_from_s &&
        !(change_s >= 0.0 && r.t_s >= s.settle_excluded_from_s && r.t_s < s.settle_excluded_to_s)) {
      e_mmt1.push_back(em);
      e_dfr1.push_back(ed);
      f_rem1.push_back(fr);
    }
  }
  s.force_rms_remote_n = rms_of(f_rem);
  s.force_error_rms_mmt_n = rms_of(e_mmt);
  s.force_error_rms_dfr_n = rms_of(e_dfr);
  s.force_error_max_mmt_n = s.force_error_max_dfr_n = 0.0;
  for (double e : e_mmt) s.force_error_max_mmt_n = std::max(s.force_error_max_mmt_n, e);
  for (double e : e_dfr) s.force_error_max_dfr_n = std::max(s.force_error_max_dfr_n, e);
  s.force_rms_remote_after_1s_n = rms_of(f_rem1);
  s.force_error_rms_mmt_after_1s_n = rms_of(e_mmt1);
  s.force_error_rms_dfr_after_1s_n = rms_of(e_dfr1);
  // A window with less than 0.1 s of the remote cutting (a change of soil
  // whose left-out round trip reaches past the end of the cut) has no
  // figure: -1.
  std::size_t cutting_ticks = 0;
  for (double f : f_rem1) cutting_ticks += f > 1.0;
  s.force_error_rel_mmt_after_1s = s.force_error_rel_dfr_after_1s = -1.0;
  if (s.force_rms_remote_after_1s_n > 0.0 && double(cutting_ticks) >= 0.1 * rate_hz) {
    s.force_error_rel_mmt_after_1s = s.force_error_rms_mmt_after_1s_n / s.force_rms_remote_after_1s_n;
    s.force_error_rel_dfr_after_1s = s.force_error_rms_dfr_after_1s_n / s.force_rms_remote_after_1s_n;
  }
  // Re-identification: from the blade entering the new soil to the last
  // tick, while it cuts, whose estimate was more than 5 % off the measured
  // horizontal force.
  s.reidentified_after_s = -1.0;
  if (change_s >= 0.0) {
    double last_off_s = change_s;
    for (const RemoteRecord& r : rm)
      if (r.t_s >= change_s && r.estimate_error > 0.05) last_off_s = r.t_s;
    s.reidentified_after_s = last_off_s - change_s;
  }
  std::vector<double> track;
  for (const RemoteRecord& r : rm)
    if (r.active) track.push_back(length(r.tool_m - r.commanded_m));
  s.tracking_rms_m = rms_of(track);
  s.tracking_max_m = 0.0;
  for (double e : track) s.tracking_max_m = std::max(s.tracking_max_m, e);
  s.passivity_max_mmt_j = s.passivity_max_dfr_j = 0.0;
  for (const OperatorRecord& r : op) {
    s.passivity_max_mmt_j = std::max(s.passivity_max_mmt_j, r.passivity_j);
    s.passivity_max_dfr_j = std::max(s.passivity_max_dfr_j, r.passivity_dfr_j);
  }
  if (!op.empty()) s.material_applied = op.back().material;
  std::vector<double> c;
  for (const OperatorRecord& r : op) c.push_back(r.compute_s);
  s.operator_compute = timing_stats(c);
  c.clear();
  for (const RemoteRecord& r : rm) c.push_back(r.compute_s);
  s.remote_compute = timing_stats(c);
}

nlohmann::ordered_json rejected_json(const net::RejectCounts& c) {
  nlohmann::ordered_json r;
  for (std::size_t i = 1; i < net::kRejectReasonCount; ++i)
    r[std::string(net::to_string(net::Reject(i)))] = c.by_reason[i];
  return r;
}

nlohmann::ordered_json link_json(const net::LinkConditions& c) {
  return {{"delay_s_each_way", c.delay_s},
          {"jitter_s", c.jitter_s},
          {"loss", c.loss},
          {"burst_p_good_to_bad", c.burst.p_good_to_bad},
          {"reorder", c.reorder},
          {"seed", c.seed}};
}

nlohmann::ordered_json summary_json(const MmtSummary& s) {
  nlohmann::ordered_json j;
  j["duration_s"] = s.duration_s;
  j["force_error"] = {{"remote_force_rms_n", s.force_rms_remote_n},
                      {"mmt_rms_n", s.force_error_rms_mmt_n},
                      {"mmt_max_n", s.force_error_max_mmt_n},
                      {"direct_rms_n", s.force_error_rms_dfr_n},
                      {"direct_max_n", s.force_error_max_dfr_n},
                      {"aligned_by", "command_sequence"},
                      {"aligned_after_s", s.aligned_after_s}};
  j["terrain_error"] = {{"final_rms_m", s.terrain_rms_final_m}, {"max_rms_m", s.terrain_rms_max_m}};
  j["tracking"] = {{"rms_m", s.tracking_rms_m}, {"max_m", s.tracking_max_m}};
  j["traffic"] = {{"to_remote_packets_per_s", s.packets_per_s_to_remote},
                  {"to_remote_bytes_per_s", s.bytes_per_s_to_remote},
                  {"to_operator_packets_per_s", s.packets_per_s_to_operator},
                  {"to_operator_bytes_per_s", s.bytes_per_s_to_operator},
                  {"update_packets_per_s", s.update_packets_per_s},
                  {"lost_to_remote", s.lost_to_remote},
                  {"lost_to_operator", s.lost_to_operator}};
  j["updates"] = {{"patches", s.patches},
                  {"estimates", s.estimates},
                  {"patches_merged", s.patches_merged},
                  {"estimates_applied", s.estimates_applied},
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
  j["estimate"] = detail::estimate_json(s.estimate, &s.remote_material);
  j["estimate"]["material_applied_by_operator"] = detail::material_json(s.material_applied);
  j["estimate"]["reidentified_after_s"] = s.reidentified_after_s;
  j["remote_arm"] = {{"force_limit_n", s.arm_force_limit_n}, {"stalled_ticks", s.stalled_ticks}};
  j["passivity"] = {{"window_s", 1.0},
                    {"mmt_max_energy_into_hand_j", s.passivity_max_mmt_j},
                    {"direct_max_energy_into_hand_j", s.passivity_max_dfr_j}};
  j["rejected"] = {{"operator", rejected_json(s.rejected_operator)},
                   {"remote", rejected_json(s.rejected_remote)}};
  auto timing = [](const TimingStats& t) {
    return nlohmann::ordered_json{{"p50_us", t.p50_us}, {"p99_us", t.p99_us}, {"max_us", t.max_us}};
  };
  j["timing"] = {{"operator_tick", timing(s.operator_compute)},
                 {"remote_tick", timing(s.remote_compute)}};
  return j;
}

MmtSummary write_two_process_report(const std::filesystem::path& operator_dir,
                                    const std::filesystem::path& remote_dir,
                                    const std::filesystem::path& out) {
  const nlohmann::ordered_json js_op = read_summary(operator_dir, "operator");
  const nlohmann::ordered_json js_rm = read_summary(remote_dir, "remote");
  const std::vector<OperatorRecord> op = operator_records(read_table(operator_dir / "operator.csv"));
  const std::vector<RemoteRecord> rm = remote_records(read_table(remote_dir / "remote.csv"));
  MmtSummary s;
  s.duration_s = number_at<double>(js_op, operator_dir, {"duration_s"});
  s.rtt_s = number_at<double>(js_op, operator_dir, {"round_trip", "emulated_s"});
  s.rtt_measured_s = number_at<double>(js_op, operator_dir, {"round_trip", "measured_s"});
  s.loss = number_at<double>(js_op, operator_dir, {"link", "loss"});
  // With the arm in the operator's model both blades move alike: no lag to
  // align (a summary from before models_arm existed had none).
  const bool models_arm = js_op.value("models_arm", false);
  compare_records(op, rm, number_at<double>(js_op, operator_dir, {"rate_hz"}),
                  models_arm ? 0.0
                             : number_at<double>(js_rm, remote_dir, {"remote_arm", "follower_time_constant_s"}),
                  s);
  // The terrain at the end: the local model against what the remote's camera
  // saw, over every sample either station worked.
  int rows_a = 0, cols_a = 0, rows_b = 0, cols_b = 0;
  const std::vector<float> local = io::read_npy(operator_dir / "heights.npy", &rows_a, &cols_a);
  const std::vector<float> remote = io::read_npy(remote_dir / "surface.npy", &rows_b, &cols_b);
  if (rows_a != rows_b || cols_a != cols_b)
    throw InputError((remote_dir / "surface.npy").string() + ": " + std::to_string(rows_b) + " x " +
                     std::to_string(cols_b) + " samples, the operator's heights.npy " +
                     std::to_string(rows_a) + " x " + std::to_string(cols_a));
  Rect region = rect_at(js_op, operator_dir);
  const Rect w = rect_at(js_rm, remote_dir);
  if (region.empty()) region = w;
  else if (!w.empty()) region.include(w);
  region.c1 = std::min(region.c1, cols_a);
  region.r1 = std::min(region.r1, rows_a);
  double sum = 0.0;
  for (int r = region.r0; r < region.r1; ++r)
    for (int c = region.c0; c < region.c1; ++c) {
      const std::size_t i = std::size_t(r) * std::size_t(cols_a) + std::size_t(c);
      const double d = double(local[i]) - double(remote[i]);
      sum += d * d;
    }
  s.terrain_rms_final_m = region.empty() || region.area() <= 0 ? 0.0 : std::sqrt(sum / double(region.area()));
  s.terrain_rms_max_m = s.terrain_rms_final_m;  // the stations keep no terrain over time
  const double d_op = std::max(s.duration_s, 1e-9);
  const double d_rm = std::max(number_at<double>(js_rm, remote_dir, {"duration_s"}), 1e-9);
  s.packets_per_s_to_remote = number_at<double>(js_op, operator_dir, {"traffic", "sent_packets_per_s"});
  s.bytes_per_s_to_remote = number_at<double>(js_op, operator_dir, {"traffic", "sent_bytes_per_s"});
  s.packets_per_s_to_operator = number_at<double>(js_rm, remote_dir, {"traffic", "sent_packets_per_s"});
  s.bytes_per_s_to_operator = number_at<double>(js_rm, remote_dir, {"traffic", "sent_bytes_per_s"});
  s.lost_to_remote = number_at<std::int64_t>(js_op, operator_dir, {"traffic", "emulated_losses"});
  s.lost_to_operator = number_at<std::int64_t>(js_rm, remote_dir, {"traffic", "emulated_losses"});
  s.patches = number_at<std::int64_t>(js_rm, remote_dir, {"patches"});
  s.estimates = number_at<std::int64_t>(js_rm, remote_dir, {"estimates"});
  s.patches_merged = number_at<std::int64_t>(js_op, operator_dir, {"patches"});
  s.estimates_applied = number_at<std::int64_t>(js_op, operator_dir, {"estimates"});
  // Update packets per second of the session (the remote's, over its own time).
  s.update_packets_per_s = double(s.patches + s.estimates) / d_rm;
  (void)d_op;
  s.max_update_step_n = number_at<double>(js_op, operator_dir, {"max_force_step_at_update_n"});
  s.max_step_while_updating_n = number_at<double>(js_op, operator_dir, {"max_force_step_while_updating_n"});
  if (!js_rm.contains("estimate")) throw InputError((remote_dir / "summary.json").string() + ": no estimate");
  s.estimate = detail::estimate_from_json(js_rm["estimate"], remote_dir / "summary.json", &s.remote_material);
  // The station's own figure (its CSV rounds to 9 digits).
  if (!js_op.contains("material_applied"))
    throw InputError((operator_dir / "summary.json").string() + ": no material_applied");
  s.material_applied = detail::material_from_json(js_op["material_applied"], operator_dir / "summary.json");
  s.arm_force_limit_n = number_at<double>(js_rm, remote_dir, {"remote_arm", "force_limit_n"});
  s.stalled_ticks = number_at<std::int64_t>(js_rm, remote_dir, {"remote_arm", "stalled_ticks"});
  s.rejected_operator = rejected_of(js_op);
  s.rejected_remote = rejected_of(js_rm);

  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) throw InputError(out.string() + ": cannot create the folder: " + ec.message());
  write_operator_csv(op, out / "operator.csv");
  write_remote_csv(rm, out / "remote.csv");
  {
    std::ofstream te(out / "terrain_error.csv");
    te.precision(9);
    te << "t,rms_m\n" << s.duration_s << ',' << s.terrain_rms_final_m << '\n';
    if (!te) throw InputError((out / "terrain_error.csv").string() + ": cannot be written");
  }
  nlohmann::ordered_json j;
  j["two_process"] = {{"operator_dir", operator_dir.string()},
                      {"remote_dir", remote_dir.string()},
                      {"operator_ended", js_op["ended"]},
                      {"remote_ended", js_rm["ended"]},
                      {"terrain_error", "at the end only"}};
  j["link"] = js_op["link"];
  j["link"]["rtt_s"] = s.rtt_s;
  j["link"]["rtt_measured_s"] = s.rtt_measured_s;
  j["commands"] = js_op["commands"];
  j["udp"] = {{"operator", js_op["udp"]}, {"remote", js_rm["udp"]}};
  j.update(summary_json(s));
  std::ofstream f(out / "summary.json", std::ios::binary);
  f << j.dump(2) << "\n";
  if (!f) throw InputError((out / "summary.json").string() + ": cannot be written");
  return s;
}

}  // namespace terracut::session
