// `terracut mmt` (mmt_command.hpp; docs/teleoperation.md).
#include "mmt_command.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "subprocess.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/device_option.hpp"
#include "terracut/session/mmt.hpp"
#include "terracut/session/mmt_process.hpp"

namespace terracut::cli {
namespace {

namespace fs = std::filesystem;

struct Options {
  std::string scenario;
  std::string out;
  std::optional<double> rtt_ms, loss, jitter_ms, deadband, blend_s, duration_s;
  std::optional<long long> seed;
  bool sweep = false;
  std::string rtts = "0,50,100,200,500,1000";
  std::string losses = "0,0.01,0.1";
  std::string device;
  std::string role;
  std::string listen, connect;
  std::string key;
  bool insecure_loopback = false;
  std::vector<std::string> report;
  bool repeat = false;
  bool no_plot = false;
  std::string python = "/usr/bin/python3";
  std::string tools = TERRACUT_TOOLS_DIR;
  bool quiet = false;
};

std::vector<double> numbers(const std::string& text, const char* option) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(v)) throw std::invalid_argument(item);
      out.push_back(v);
    } catch (const std::exception&) {
      throw InputError(std::string(option) + ": '" + item + "' is not a number");
    }
  }
  if (out.empty()) throw InputError(std::string(option) + ": give at least one value");
  return out;
}

session::MmtOverrides overrides_of(const Options& o) {
  session::MmtOverrides v;
  if (o.rtt_ms) v.rtt_s = *o.rtt_ms * 1e-3;
  v.loss = o.loss;
  if (o.jitter_ms) v.jitter_s = *o.jitter_ms * 1e-3;
  if (o.seed) {
    if (*o.seed < 0) throw InputError(must_be("--seed", ">= 0", double(*o.seed)));
    v.seed = std::uint64_t(*o.seed);
  }
  v.deadband = o.deadband;
  v.blend_s = o.blend_s;
  v.duration_s = o.duration_s;
  return v;
}

static_assert(kExitLinkLost == session::kExitLinkLost, "one exit code for a dead link");

// Set by SIGINT and SIGTERM: a station of --role ends at its next tick and
// writes its outputs.
std::atomic<bool> g_stop{false};
extern "C" void request_stop(int) { g_stop.store(true); }
void stop_on_signals() {
  struct sigaction sa {};
  sa.sa_handler = request_stop;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// Draws the figures of a folder with tools/plot_mmt.py; a warning when it cannot.
void plot(const Options& o, const fs::path& dir) {
  if (o.no_plot) return;
  const fs::path script = fs::path(o.tools) / "plot_mmt.py";
  std::vector<std::string> argv{o.python, script.string(), dir.string()};
  if (o.quiet) argv.push_back("--quiet");
  const int code = run_program(argv);
  if (code != 0)
    std::cerr << "terracut mmt: warning: the plot script " << script.string()
              << " failed (exit code " << code << "); the results are written\n";
}

int run_one(const Options& o, const session::Scenario& sc) {
  session::MmtRun run(sc, overrides_of(o));
  run.run();
  run.write_outputs(o.out);
  const session::MmtSummary s = run.summary();
  if (!o.quiet)
    std::cout << "terracut mmt: " << format_number(s.duration_s) << " s, RTT "
              << format_number(s.rtt_s * 1e3) << " ms, loss " << format_number(s.loss * 100)
              << " %: force error RMS " << format_number(s.force_error_rms_mmt_n)
              << " N (MMT) vs " << format_number(s.force_error_rms_dfr_n)
              << " N (direct reflection), remote force RMS " << format_number(s.force_rms_remote_n)
              << " N; terrain RMS " << format_number(s.terrain_rms_final_m * 1e3)
              << " mm at the end; " << s.patches << " patches, " << s.estimates
              << " estimates; soil factor " << format_number(s.force_scale_final) << "\n";
  plot(o, o.out);
  return kExitOk;
}

// The study: every RTT x loss, one run each (MMT and direct reflection are
// measured on the same run), plus the deadband variant at each RTT without
// loss. study.csv, study.md (the README's table), study.png.
int run_sweep(const Options& o, const session::Scenario& sc) {
  const std::vector<double> rtts = numbers(o.rtts, "--rtts");
  const std::vector<double> losses = numbers(o.losses, "--losses");
  const double jnd = o.deadband.value_or(0.1);
  fs::create_directories(o.out);
  std::ofstream csv(fs::path(o.out) / "study.csv");
  if (!csv) throw InputError((fs::path(o.out) / "study.csv").string() + ": cannot be written");
  csv << "rtt_ms,loss,deadband,force_rms_remote_n,mmt_rms_n,mmt_max_n,direct_rms_n,direct_max_n,"
         "terrain_final_mm,tracking_rms_mm,update_packets_per_s,patches,estimates,"
         "to_operator_bytes_per_s,max_update_step_n,passivity_mmt_j,passivity_direct_j,"
         "force_scale\n";
  std::ostringstream md;
  md << "| RTT (ms) | loss | force error MMT, RMS (N) | direct reflection, RMS (N) | "
        "MMT max (N) | direct max (N) | terrain RMS at end (mm) | update packets/s | "
        "with deadband " << format_number(jnd * 100) << " % |\n|---|---|---|---|---|---|---|---|---|\n";
  for (double rtt : rtts) {
    for (double loss : losses) {
      std::vector<session::MmtSummary> pair;
      for (double db : {0.0, jnd}) {
        if (db > 0.0 && loss != losses.front()) continue;  // the variant once per RTT
        Options one = o;
        one.rtt_ms = rtt;
        one.loss = loss;
        one.deadband = db;
        session::MmtRun run(sc, overrides_of(one));
        run.run();
        const session::MmtSummary s = run.summary();
        pair.push_back(s);
        csv << format_number(rtt) << ',' << format_number(loss) << ',' << format_number(db) << ','
            << s.force_rms_remote_n << ',' << s.force_error_rms_mmt_n << ','
            << s.force_error_max_mmt_n << ',' << s.force_error_rms_dfr_n << ','
            << s.force_error_max_dfr_n << ',' << s.terrain_rms_final_m * 1e3 << ','
            << s.tracking_rms_m * 1e3 << ',' << s.update_packets_per_s << ',' << s.patches << ','
            << s.estimates << ',' << s.bytes_per_s_to_operator << ',' << s.max_update_step_n << ','
            << s.passivity_max_mmt_j << ',' << s.passivity_max_dfr_j << ','
            << s.force_scale_final << '\n';
        if (!o.quiet)
          std::cout << "terracut mmt: RTT " << format_number(rtt) << " ms, loss "
                    << format_number(loss * 100) << " %, deadband " << format_number(db * 100)
                    << " %: MMT " << format_number(s.force_error_rms_mmt_n) << " N, direct "
                    << format_number(s.force_error_rms_dfr_n) << " N RMS\n";
      }
      const session::MmtSummary& s = pair.front();
      auto f = [](double v, int digits) {
        std::ostringstream t;
        t << std::fixed << std::setprecision(digits) << v;
        return t.str();
      };
      md << "| " << format_number(rtt) << " | " << format_number(loss * 100) << " % | "
         << f(s.force_error_rms_mmt_n, 1) << " | " << f(s.force_error_rms_dfr_n, 1) << " | "
         << f(s.force_error_max_mmt_n, 0) << " | " << f(s.force_error_max_dfr_n, 0) << " | "
         << f(s.terrain_rms_final_m * 1e3, 2) << " | " << f(s.update_packets_per_s, 1) << " | "
         << (pair.size() > 1 ? f(pair[1].update_packets_per_s, 1) + " (MMT " +
                                   f(pair[1].force_error_rms_mmt_n, 1) + " N)"
                             : std::string("")) << " |\n";
    }
  }
  csv.close();
  if (!csv) throw InputError((fs::path(o.out) / "study.csv").string() + ": cannot be written");
  std::ofstream(fs::path(o.out) / "study.md") << md.str();
  if (!o.quiet) std::cout << md.str();
  plot(o, o.out);
  return kExitOk;
}

}  // namespace

Command add_mmt_command(CLI::App& app) {
  auto opt = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "mmt",
      "Model-mediated teleoperation: the operator's haptic loop on the local model and the\n"
      "remote (\"real\") world, joined by a link with emulated delay, jitter and loss. By\n"
      "default both stations run in this process, in simulated time (reproducible for a seed);\n"
      "--role runs one station per process over UDP (ENet). See docs/teleoperation.md.");
  sub->add_option("scenario", opt->scenario, "Operator scenario with an `mmt:` section")
      ->required()
      ->type_name("SCENARIO.yaml");
  sub->add_option("--out,-o", opt->out,
                  "Output folder: operator.csv, remote.csv, terrain_error.csv, summary.json,\n"
                  "mmt.png (with --sweep: study.csv, study.md, study.png)")
      ->required();
  sub->add_option("--rtt-ms", opt->rtt_ms, "Round-trip delay, ms (half each way); overrides mmt.link.delay_s");
  sub->add_option("--loss", opt->loss, "Independent loss each way, fraction in [0, 1)");
  sub->add_option("--jitter-ms", opt->jitter_ms, "Jitter each way (uniform +-), ms");
  sub->add_option("--seed", opt->seed, "Seed of the link emulator");
  sub->add_option("--deadband", opt->deadband,
                  "Perceptual deadband of the updates, fraction (0.1 = 10 %); with --sweep, the\n"
                  "variant's fraction (default 0.1)");
  sub->add_option("--blend", opt->blend_s, "Blend time of terrain patches, s");
  sub->add_option("--duration", opt->duration_s,
                  "Run length, s (default: the path, settle and a round trip); --role remote: its\n"
                  "lifetime (default: until its operator ends the session, or SIGINT/SIGTERM)");
  sub->add_option("--device", opt->device,
                  "The operator's device: script, sim, or udp[:ADDR:PORT] (a real device over the\n"
                  "bridge, docs/bridge-protocol.md; with --role operator only); default haptics.device");
  sub->add_flag("--sweep", opt->sweep, "Run the study over --rtts x --losses");
  sub->add_option("--rtts", opt->rtts, "Study: round trips, ms, comma-separated")
      ->capture_default_str();
  sub->add_option("--losses", opt->losses, "Study: losses, fractions, comma-separated")
      ->capture_default_str();
  sub->add_option("--role", opt->role,
                  "Two processes: 'remote' (listens on --listen) or 'operator' (connects to\n"
                  "--connect); real time, wall clock")
      ->check(CLI::IsMember({"remote", "operator"}));
  sub->add_option("--listen", opt->listen, "remote: ADDR:PORT to bind (default mmt.udp)");
  sub->add_option("--connect", opt->connect, "operator: ADDR:PORT of the remote (default mmt.udp)");
  sub->add_option("--key", opt->key,
                  "With --role: the key file both stations share (`terracut key --out FILE`; mode\n"
                  "600). Default: the environment variable TERRACUT_MMT_KEY (64 hex digits)")
      ->type_name("FILE");
  sub->add_flag("--insecure-loopback", opt->insecure_loopback,
                "With --role: no key, no authentication (any local process can take the session\n"
                "over): a demo on 127.0.0.1 only");
  sub->add_option("--report", opt->report,
                  "Compare a two-process session: OPERATOR_DIR REMOTE_DIR (the stations' --out\n"
                  "folders) -> --out: summary.json, operator.csv, remote.csv, terrain_error.csv,\n"
                  "mmt.png, as a single-process run")
      ->expected(2)
      ->type_name("OPERATOR_DIR REMOTE_DIR");
  sub->add_flag("--repeat", opt->repeat,
                "--role operator: the script device replays its cut over and over until --duration\n"
                "(a soak)");
  sub->add_flag("--no-plot", opt->no_plot, "Do not draw the figures");
  sub->add_option("--python", opt->python, "Python with matplotlib")->capture_default_str();
  sub->add_option("--tools-dir", opt->tools, "Folder of plot_mmt.py")->capture_default_str();
  sub->add_flag("--quiet,-q", opt->quiet, "No progress lines");
  return [opt]() -> int {
    if (!opt->report.empty()) {
      if (!opt->role.empty() || opt->sweep)
        throw InputError("--report: not with --role or --sweep (it reads two stations' folders)");
      const session::MmtSummary s = session::write_two_process_report(opt->report[0], opt->report[1], opt->out);
      if (!opt->quiet)
        std::cout << std::setprecision(3) << "terracut mmt: two-process session, " << s.duration_s
                  << " s, RTT " << s.rtt_measured_s * 1e3 << " ms measured: force error RMS "
                  << s.force_error_rms_mmt_n << " N (MMT) vs " << s.force_error_rms_dfr_n
                  << " N (direct reflection); terrain RMS " << s.terrain_rms_final_m * 1e3
                  << " mm at the end\n";
      plot(*opt, opt->out);
      return kExitOk;
    }
    session::Scenario sc = session::load_scenario(opt->scenario);
    if (!opt->device.empty()) {
      const haptics::DeviceOption d = haptics::parse_device_option(opt->device);
      sc.haptics.device = d.kind;
      if (d.address) sc.haptics.udp.address = *d.address;
      if (d.port) sc.haptics.udp.port = *d.port;
    }
    if (!opt->role.empty()) {
      session::ProcessOptions po;
      po.overrides = overrides_of(*opt);
      po.endpoint = opt->role == "remote" ? opt->listen : opt->connect;
      po.out = opt->out;
      po.log = opt->quiet ? nullptr : &std::cout;
      po.warn = &std::cerr;
      po.repeat = opt->repeat;
      po.key = session::link_key(opt->key, opt->insecure_loopback);
      if (po.key.insecure)
        std::cerr << "terracut mmt: warning: --insecure-loopback: the link is NOT authenticated; any "
                     "process on this machine can take this session over or feed it datagrams\n";
      g_stop.store(false);
      po.stop = &g_stop;
      stop_on_signals();
      return opt->role == "remote" ? session::run_remote_process(sc, po)
                                   : session::run_operator_process(sc, po);
    }
    if (!opt->key.empty() || opt->insecure_loopback)
      throw InputError(std::string(opt->key.empty() ? "--insecure-loopback" : "--key") +
                       ": only with --role (the single-process run has no network)");
    return opt->sweep ? run_sweep(*opt, sc) : run_one(*opt, sc);
  };
}

Command add_key_command(CLI::App& app) {
  struct KeyOptions {
    std::string out, fingerprint;
  };
  auto opt = std::make_shared<KeyOptions>();
  CLI::App* sub = app.add_subcommand(
      "key",
      "The key of a pair of `terracut mmt --role` stations: --out FILE makes a new random key\n"
      "(64 hex digits, mode 600; an existing file is never overwritten) and prints its\n"
      "fingerprint; --fingerprint FILE prints an existing key's, to check that two machines\n"
      "hold the same key without showing it. Copy the file to the other machine over a\n"
      "channel you trust (scp). See docs/teleoperation.md, \"Keys and the threat model\".");
  sub->add_option("--out,-o", opt->out, "The key file to make")->type_name("FILE");
  sub->add_option("--fingerprint", opt->fingerprint, "A key file whose fingerprint to print")
      ->type_name("FILE");
  return [opt]() -> int {
    if (opt->out.empty() == opt->fingerprint.empty())
      throw InputError("key: give one of --out FILE (a new key) or --fingerprint FILE");
    if (!opt->out.empty()) {
      const net::LinkKey k = net::write_new_key_file(opt->out);
      std::cout << "terracut key: wrote " << opt->out << " (fingerprint " << net::fingerprint(k) << ")\n";
    } else {
      std::cout << net::fingerprint(net::read_key_file(opt->fingerprint)) << "\n";
    }
    return kExitOk;
  };
}

}  // namespace terracut::cli
