// The `mmt:` section: reading, validation, overrides and the remote world
// (mmt_settings.hpp, mmt.hpp).
#include "terracut/session/mmt_settings.hpp"

#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/io/yaml_reader.hpp"
#include "terracut/session/mmt.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::session {
namespace {

namespace yaml = io::yaml;

bool in(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// The ranges of the section's own numbers (link: net::link_ranges()).
// link.seed and link_id are the reader's alone (whole numbers).
constexpr Range kRanges[] = {
    {"remote.follower_speed_m_per_s", 0.0, 100.0, RangeEnds::kOpenLow},
    {"remote.follower_time_constant_s", 0.0, 10.0, RangeEnds::kClosed},
    {"remote.sense_period_s", 0.0, 10.0, RangeEnds::kOpenLow},
    {"remote.sense_radius_m", 0.0, 100.0, RangeEnds::kOpenLow},
    {"remote.forgetting", 0.0, 1.0, RangeEnds::kOpenLow},
    {"remote.estimate_period_s", 1e-6, 1.0, RangeEnds::kClosed},
    {"remote.estimate_resend_s", 0.0, 60.0, RangeEnds::kOpenLow},
    {"remote.arm_force_limit_n", 0.0, 1e7, RangeEnds::kOpenLow},
    {"remote.soil_change.z_below_m", -1e6, 1e6, RangeEnds::kClosed},
    {"link.seed", 0, 1e9, RangeEnds::kClosed, true},
    {"operator.blend_s", 0.0, 10.0, RangeEnds::kClosed},
    {"operator.max_update_step_n", 0.0, 100.0, RangeEnds::kOpenLow},
    {"operator.exclusion_m", 0.0, 100.0, RangeEnds::kClosed},
    {"operator.deadband", 0.0, 1.0, RangeEnds::kOpenHigh},
    {"timeout_s", 0.0, 60.0, RangeEnds::kOpenLow},
    {"link_lost_s", 0.0, 3600.0, RangeEnds::kOpenLow},
    {"udp.port", 1, 65535, RangeEnds::kClosed, true},
    {"link_id", 0, 1e9, RangeEnds::kClosed, true},
};

const Range& range(std::string_view path) { return find_range(kRanges, path); }
std::string check(std::string_view path, double value) { return terracut::check(range(path), value); }

// One direction's conditions from `link:`.
void read_link(const yaml::Map& link, net::LinkConditions& c) {
  link.read_number("delay_s", c.delay_s);
  link.read_number("jitter_s", c.jitter_s);
  link.read_number("loss", c.loss);
  link.read_number("reorder", c.reorder);
  link.read_number("reorder_delay_s", c.reorder_delay_s);
  if (const auto f = link.get("retransmit_s")) c.retransmit_s = f->number();
  if (const auto f = link.get("seed")) c.seed = std::uint64_t(f->in(range("link.seed")));
  const yaml::Map burst =
      link.section("burst", {"p_good_to_bad", "p_bad_to_good", "loss_good", "loss_bad"});
  burst.read_number("p_good_to_bad", c.burst.p_good_to_bad);
  burst.read_number("p_bad_to_good", c.burst.p_bad_to_good);
  burst.read_number("loss_good", c.burst.loss_good);
  burst.read_number("loss_bad", c.burst.loss_bad);
}

}  // namespace

std::string validate(const MmtSettings& s) {
  std::string m;
  if (!(m = check("remote.follower_speed_m_per_s", s.follower_speed_m_per_s)).empty()) return m;
  if (!(m = check("remote.follower_time_constant_s", s.follower_time_constant_s)).empty()) return m;
  if (!(m = check("remote.sense_period_s", s.sense_period_s)).empty()) return m;
  if (!(m = check("remote.sense_radius_m", s.sense_radius_m)).empty()) return m;
  if (!(m = check("remote.forgetting", s.forgetting)).empty()) return m;
  if (!(m = check("remote.estimate_period_s", s.estimate_period_s)).empty()) return m;
  if (!(m = check("remote.estimate_resend_s", s.estimate_resend_s)).empty()) return m;
  if (!(m = check("remote.arm_force_limit_n", s.arm_force_limit_n)).empty()) return m;
  if (!(m = check("remote.soil_change.z_below_m", s.change_z_m)).empty()) return m;
  if (std::string p = net::validate(s.to_remote); !p.empty()) return "link." + p;
  if (std::string p = net::validate(s.to_operator); !p.empty()) return "link." + p;
  if (!(m = check("operator.blend_s", s.blend_s)).empty()) return m;
  if (!(m = check("operator.max_update_step_n", s.max_update_step_n)).empty()) return m;
  if (!(m = check("operator.exclusion_m", s.exclusion_m)).empty()) return m;
  if (!(m = check("operator.deadband", s.deadband)).empty()) return m;
  if (!(m = check("timeout_s", s.timeout_s)).empty()) return m;
  if (!(m = check("link_lost_s", s.link_lost_s)).empty()) return m;
  if (!(s.link_lost_s > s.timeout_s))
    return "link_lost_s " + format_number(s.link_lost_s) + " s is not longer than timeout_s (" +
           format_number(s.timeout_s) + " s): the link would be dead before its silence faded the force";
  if (!(m = check("udp.port", s.port)).empty()) return m;
  return {};
}

std::span<const Range> mmt_ranges() { return kRanges; }

void MmtReader::read(const YAML::Node& value, const std::string& file) {
  MmtSettings s;
  const yaml::Field root(yaml::Context(file), value, "mmt", value.Mark());
  if (value.IsNull()) {
    settings = s;
    return;
  }
  const yaml::Map top(root, {"remote", "link", "operator", "timeout_s", "link_lost_s", "udp", "link_id"});
  const yaml::Map remote =
      top.section("remote", {"scenario", "soil", "follower_speed_m_per_s",
                             "follower_time_constant_s", "sense_period_s",
                             "sense_radius_m", "estimate", "forgetting",
                             "estimate_period_s", "estimate_resend_s", "arm_force_limit_n",
                             "soil_change"});
  if (const auto f = remote.get("scenario")) {
    const std::filesystem::path p = f->text();
    s.remote_scenario = p.is_absolute() ? p : std::filesystem::path(file).parent_path() / p;
  }
  if (const auto f = remote.get("soil"))
    s.remote_soil = f->choice({SoilPreset::kDrySand, SoilPreset::kLooseSand, SoilPreset::kClay,
                               SoilPreset::kGravel});
  const yaml::Map change = remote.section("soil_change", {"z_below_m", "soil"});
  if (const auto f = change.get("soil")) {
    s.change_soil = f->choice({SoilPreset::kDrySand, SoilPreset::kLooseSand, SoilPreset::kClay,
                               SoilPreset::kGravel});
    const auto z = change.get("z_below_m");
    if (!z) f->fail("soil_change needs z_below_m: where along z the soil changes");
    s.change_z_m = z->number();
  } else if (change.get("z_below_m")) {
    change.get("z_below_m")->fail("soil_change needs soil: the soil beyond z_below_m");
  }
  remote.read_number("estimate_period_s", s.estimate_period_s);
  remote.read_number("estimate_resend_s", s.estimate_resend_s);
  remote.read_number("arm_force_limit_n", s.arm_force_limit_n);
  remote.read_number("follower_speed_m_per_s", s.follower_speed_m_per_s);
  remote.read_number("follower_time_constant_s", s.follower_time_constant_s);
  remote.read_number("sense_period_s", s.sense_period_s);
  remote.read_number("sense_radius_m", s.sense_radius_m);
  remote.read_boolean("estimate", s.estimate);
  remote.read_number("forgetting", s.forgetting);

  const yaml::Map link = top.section("link", {"delay_s", "jitter_s", "loss", "reorder",
                                              "reorder_delay_s", "retransmit_s", "seed", "burst"});
  read_link(link, s.to_remote);
  s.to_operator = s.to_remote;
  s.to_operator.seed = s.to_remote.seed + 1;  // the two directions draw independently

  const yaml::Map op =
      top.section("operator", {"blend_s", "max_update_step_n", "exclusion_m", "deadband", "models_arm"});
  op.read_number("blend_s", s.blend_s);
  op.read_number("max_update_step_n", s.max_update_step_n);
  op.read_number("exclusion_m", s.exclusion_m);
  op.read_number("deadband", s.deadband);
  op.read_boolean("models_arm", s.models_arm);
  top.read_number("timeout_s", s.timeout_s);
  top.read_number("link_lost_s", s.link_lost_s);
  const yaml::Map udp = top.section("udp", {"address", "port"});
  udp.read_text("address", s.address);
  udp.read_integer("port", s.port);
  if (const auto f = top.get("link_id")) s.link_id = std::uint32_t(f->in(range("link_id")));
  if (const std::string problem = validate(s); !problem.empty()) {
    const yaml::Problem p = yaml::split_problem(problem);
    root.fail_at(p.path, p.what);
  }
  settings = s;
}

MmtSettings apply_overrides(MmtSettings s, const MmtOverrides& o) {
  if (o.rtt_s) {
    if (!in(*o.rtt_s, 0.0, 20.0)) throw InputError(must_be("--rtt-ms", "in [0, 20000]", *o.rtt_s * 1e3));
    s.to_remote.delay_s = s.to_operator.delay_s = 0.5 * *o.rtt_s;
  }
  if (o.loss) {
    if (auto m = terracut::check(find_range(net::link_ranges(), "loss"), *o.loss, "--loss"); !m.empty())
      throw InputError(m);
    s.to_remote.loss = s.to_operator.loss = *o.loss;
  }
  if (o.jitter_s) {
    if (!in(*o.jitter_s, 0.0, 10.0)) throw InputError(must_be("--jitter-ms", "in [0, 10000]", *o.jitter_s * 1e3));
    s.to_remote.jitter_s = s.to_operator.jitter_s = *o.jitter_s;
  }
  if (o.seed) {
    s.to_remote.seed = *o.seed;
    s.to_operator.seed = *o.seed + 1;
  }
  if (o.deadband) {
    if (auto m = terracut::check(range("operator.deadband"), *o.deadband, "--deadband"); !m.empty())
      throw InputError(m);
    s.deadband = *o.deadband;
  }
  if (o.blend_s) {
    if (auto m = terracut::check(range("operator.blend_s"), *o.blend_s, "--blend"); !m.empty())
      throw InputError(m);
    s.blend_s = *o.blend_s;
  }
  if (const std::string problem = validate(s); !problem.empty()) throw InputError("mmt." + problem);
  return s;
}

std::string no_mmt_section(const Scenario& sc) {
  return sc.base.source_path.string() +
         ": mmt: the scenario has no mmt: section (the remote world and the link; "
         "docs/teleoperation.md)";
}

double mmt_run_length_s(const MmtSettings& settings, double path_s, double round_trip_s,
                        double retransmit_s) {
  const net::LinkConditions& back = settings.to_operator;
  const bool lossy = back.loss > 0.0 || back.burst.p_good_to_bad > 0.0;
  constexpr double kLandingMargin_s = 0.2;  // the last update's tick and a few more
  return path_s + round_trip_s + settings.sense_period_s + settings.blend_s + kLandingMargin_s +
         (lossy ? 3.0 * retransmit_s : 0.0);
}

Scenario load_remote_scenario(const Scenario& op) {
  if (!op.mmt) throw InputError(no_mmt_section(op));
  const MmtSettings& s = *op.mmt;
  Scenario remote;
  try {
    remote = s.remote_scenario.empty() ? op : load_scenario(s.remote_scenario);
  } catch (const InputError& e) {
    throw InputError(op.base.source_path.string() + ": mmt.remote.scenario: " + e.what());
  }
  remote.mmt.reset();
  if (s.remote_soil) remote.base.soil.material = soil_preset(*s.remote_soil);
  // Both stations speak of the same samples: the grids must agree.
  const GridSpec a = io::grid_spec(op.base), b = io::grid_spec(remote.base);
  if (a.cols != b.cols || a.rows != b.rows || a.size_x_m != b.size_x_m ||
      a.size_z_m != b.size_z_m || a.origin_m.x != b.origin_m.x ||
      a.origin_m.y != b.origin_m.y || a.origin_m.z != b.origin_m.z)
    throw InputError(op.base.source_path.string() +
                     ": mmt.remote.scenario: the remote terrain's grid (" + std::to_string(b.cols) +
                     "x" + std::to_string(b.rows) + " samples over " + format_number(b.size_x_m) +
                     " x " + format_number(b.size_z_m) + " m) must be the operator's (" +
                     std::to_string(a.cols) + "x" + std::to_string(a.rows) + " over " +
                     format_number(a.size_x_m) + " x " + format_number(a.size_z_m) +
                     " m, same origin)");
  return remote;
}

}  // namespace terracut::session
