// `terracut haptics`: one haptic session, outputs into a folder.
#include "haptics_command.hpp"


#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "subprocess.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/device_option.hpp"
#include "terracut/io/files.hpp"
#include "terracut/session/haptic.hpp"

namespace terracut::cli {
namespace {

namespace fs = std::filesystem;

// Set by SIGINT / SIGTERM while a session runs: the loop stops and the
// outputs of what ran are written.
std::atomic<bool> g_interrupt{false};
extern "C" void on_interrupt(int) { g_interrupt.store(true); }

}  // namespace

Command add_haptics_command(CLI::App& app) {
  struct Options {
    std::string scenario;
    std::string out;
    std::string device;
    double duration_s = 0.0;
    double rate_hz = 0.0;
    std::string clock;
    bool no_realtime = false;
    bool no_plot = false;
    std::string python = "/usr/bin/python3";
    std::string tools = TERRACUT_TOOLS_DIR;
    bool quiet = false;
    bool end_with_device = false;
  };
  auto opt = std::make_shared<Options>();

  CLI::App* sub = app.add_subcommand(
      "haptics",
      "Run the haptic loop on a scenario: a device (scripted, a simulated hand, or a real one\n"
      "over UDP) drives the blade at the scenario's rate_hz (default 1 kHz) and feels the\n"
      "cutting force.\n"
      "Writes the per-tick log, a summary and a force plot into an output folder.");
  sub->add_option("scenario", opt->scenario,
                  "Scenario file (YAML) with a `haptics:` section (docs/haptics.md; without one\n"
                  "the defaults apply)")
      ->required()
      ->type_name("SCENARIO.yaml");
  sub->add_option("--out,-o", opt->out, "Output folder; created if missing, files replaced")
      ->required()
      ->type_name("DIR");
  sub->add_option(
         "--device,-d", opt->device,
         "Device backend, overriding haptics.device:\n"
         "  script          the tool follows the cut's keyframes exactly; forces recorded\n"
         "  sim             a simulated hand pulled along the cut feels the force\n"
         "  udp[:ADDR:PORT] a device process over the UDP bridge protocol\n"
         "                  (docs/bridge-protocol.md); default haptics.udp (127.0.0.1:47000);\n"
         "                  udp:PORT keeps the address; IPv6 as udp:[::1]:PORT")
      ->type_name("script|sim|udp[:ADDR:PORT]");
  sub->add_option("--duration", opt->duration_s,
                  "Session length in seconds, overriding haptics.duration_s. Default: the cut's\n"
                  "duration plus haptics.settle_s (script, sim), 30 s (udp)")
      ->type_name("S")
      ->check(CLI::Range(1e-6, 86400.0));
  sub->add_option("--rate", opt->rate_hz,
                  "Loop rate in Hz, overriding the scenario's rate_hz for this session (the\n"
                  "simulation steps at it too)")
      ->type_name("HZ")
      ->check(CLI::Range(haptics::kLoopRateRange.lo, haptics::kLoopRateRange.hi));
  sub->add_flag("--end-with-device", opt->end_with_device,
                "End the session when the device stops sending: after its first pose, 0.5 s\n"
                "without one (udp: the device process's own session ended). --duration still\n"
                "bounds the session");
  sub->add_option("--clock", opt->clock,
                  "'real': the loop runs on its own thread paced by the wall clock (default for\n"
                  "sim and udp); 'fake': synchronously, no sleeping, t = i / rate, so the same\n"
                  "scenario gives the same haptics.csv (default for script; not for udp)")
      ->check(CLI::IsMember({"real", "fake"}))
      ->type_name("real|fake");
  sub->add_flag("--no-realtime", opt->no_realtime,
                "Do not ask for SCHED_FIFO scheduling and locked memory (real clock). By\n"
                "default they are asked for; where refused, a one-line message says so and the\n"
                "loop runs at normal priority");
  sub->add_flag("--no-plot", opt->no_plot, "Do not draw haptics.png");
  sub->add_option("--python", opt->python,
                  "Python interpreter for the plot (needs numpy and matplotlib)")
      ->type_name("PATH")
      ->capture_default_str();
  sub->add_option("--tools-dir", opt->tools, "Folder of plot_haptics.py")
      ->type_name("DIR")
      ->capture_default_str();
  sub->add_flag("--quiet,-q", opt->quiet, "No messages except errors and warnings");
  sub->footer(
      "Each tick: read the device -> map its workspace to the world (haptics.workspace) ->\n"
      "set the tool pose -> contact, cut -> force models (haptics.forces) -> safety limiter\n"
      "(haptics.safety) -> map the force to the device and send it -> record.\n"
      "\n"
      "Outputs in DIR:\n"
      "  haptics.csv   one row per tick (SI units):\n"
      "                  t, tick                   loop time (s), tick index\n"
      "                  dev_x,dev_y,dev_z         device handle, device frame, m\n"
      "                  tool_x..tool_z, qw..qz    tool pose, world (m, unit quaternion)\n"
      "                  contact_length, cut_depth blade length in soil, depth cut (m)\n"
      "                  removed_volume            volume cut this tick (m^3)\n"
      "                  vel_x,vel_y,vel_z         estimated tool velocity, world m/s\n"
      "                  fw_x,fw_y,fw_z            the rendered force in world newtons (before\n"
      "                                            force_scale): models + rigid bodies (N)\n"
      "                  fb_x,fb_y,fb_z            the rigid bodies' part of it (N; 0 without)\n"
      "                  fd_x,fd_y,fd_z            force sent to the device, device frame (N)\n"
      "                  clamped,rate_limited,watchdog,ramping,nonfinite  safety flags (0/1)\n"
      "                  bad_sample,silent,missed_deadline                loop flags (0/1)\n"
      "                  period, compute           time since the previous tick, compute (s)\n"
      "                  f_penetration             the push-in resistance's part of fw_y (N)\n"
      "                  twist_torque, yaw_rate    torque about +Y on the tool (N m; not\n"
      "                                            rendered), tool yaw rate (rad/s)\n"
      "                  fp_x,fp_y,fp_z            the physical force on the tool (N), what\n"
      "                                            terracut run's force.csv has for the path\n"
      "  summary.json  settings used, period jitter and compute percentiles (p50, p99, max,\n"
      "                us), missed deadlines, loop and safety counters, rejected packets by\n"
      "                reason (udp), device figures, forces, cutting totals, warnings\n"
      "  haptics.png   force and contact over time (tools/plot_haptics.py)\n"
      "  bodies.csv    only when the scenario has bodies: one row per body per tick,\n"
      "                t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz (SI; Bullet rigid bodies on\n"
      "                the same terrain, pushed by the blade's plate: the force they put on\n"
      "                it joins the force felt, scaled by forces.force_scale; summary.json\n"
      "                \"bodies\" gives the peak)\n"
      "\n"
      "Exit codes: 0 done; 1 bad input or failed output; 2 bad command line; 3 outputs\n"
      "written but the plot could not be made. Ctrl-C ends the session early and still\n"
      "writes the outputs.\n"
      "\n"
      "Examples:\n"
      "  terracut haptics scenarios/trench_dry_sand.yaml --out out/trench\n"
      "  terracut haptics scenarios/trench_dry_sand.yaml --device script --out out/trench_script\n"
      "  terracut haptics scenarios/trench_dry_sand.yaml --device udp:127.0.0.1:47000 \\\n"
      "      --end-with-device --duration 30 --out out/trench_udp   # then terracut-device\n"
      "  terracut haptics scenarios/rock_push.yaml --out out/rock   # the blade hits a rock\n"
      "Docs: docs/haptics.md (what you feel and why), docs/bridge-protocol.md (the bridge),\n"
      "docs/bullet.md (rigid bodies).");

  return [opt]() {
    session::SessionOptions so;
    if (!opt->device.empty()) {
      const haptics::DeviceOption d = haptics::parse_device_option(opt->device);
      so.device = d.kind;
      so.udp_address = d.address;
      so.udp_port = d.port;
    }
    if (opt->duration_s > 0.0) so.duration_s = opt->duration_s;
    if (opt->rate_hz > 0.0) so.rate_hz = opt->rate_hz;
    if (!opt->clock.empty())
      so.clock = opt->clock == "fake" ? session::ClockMode::kFake : session::ClockMode::kReal;
    so.realtime = !opt->no_realtime;
    so.end_with_device = opt->end_with_device;
    so.log = &std::cerr;
    so.interrupt = &g_interrupt;
    const auto say = [&](const std::string& line) {
      if (!opt->quiet) std::cerr << "terracut haptics: " << line << "\n";
    };

    const session::Scenario input = session::load_scenario(opt->scenario);
    // Rigid bodies: the Bullet world is stepped with the terrain (the force
    // on the blade's plate is felt) and writes bodies.csv into the output
    // folder, which must exist before the world is built.
    if (!input.bodies.empty()) {
      io::make_output_folder(opt->out);
      so.bodies_csv = fs::path(opt->out) / "bodies.csv";
    }
    session::HapticSession session(input, so);
    if (session.world().bodies())
      say(std::to_string(input.bodies.size()) +
          " rigid bodies (Bullet) on the terrain: their force on the blade is felt");
    if (session.device_kind() == haptics::DeviceKind::kUdp)
      say("listening for a device on udp " + session.loop().settings().udp.address + ":" +
          std::to_string(session.udp_port()) +
          " (the session clock runs from now; the force is zero until poses arrive" +
          (opt->end_with_device ? std::string("; the session ends when they stop)")
                                : std::string(")")));
    say("running the " + std::string(to_string(session.device_kind())) + " device for " +
        format_number(session.duration_s()) + " s (" +
        (session.clock() == session::ClockMode::kFake ? "fake" : "real") + " clock)");

    g_interrupt.store(false);
    struct sigaction action {};
    struct sigaction old_int {
    }, old_term{};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int);
    sigaction(SIGTERM, &action, &old_term);
    session.run();
    sigaction(SIGINT, &old_int, nullptr);
    sigaction(SIGTERM, &old_term, nullptr);

    session.write_outputs(opt->out);
    // (The real-time line was printed when the loop started, the device
    // check's changes when the session was built: each is said once.)
    for (const std::string& w : session.run_warnings())
      if (w.rfind("real-time:", 0) != 0) std::cerr << "terracut haptics: warning: " << w << "\n";
    if (!opt->quiet) std::cout << session.summary_line() << " -> " << opt->out << "\n";
    if (session.world().bodies()) {
      char line[160];
      std::snprintf(line, sizeof line,
                    "bodies: peak force of the bodies on the blade %.4g N (world); bodies.csv",
                    session.loop().max_body_force_n());
      say(line);
    }
    if (opt->no_plot) return kExitOk;

    // The plot, by the plot script; a failure leaves the outputs in place.
    const fs::path script = fs::path(opt->tools) / "plot_haptics.py";
    std::string problem;
    if (access(opt->python.c_str(), X_OK) != 0) {
      problem = "the Python interpreter " + opt->python +
                " is missing (on Debian: apt-get install python3 python3-matplotlib python3-numpy)";
    } else if (!fs::exists(script)) {
      problem = "the plot script " + script.string() + " is missing (use --tools-dir)";
    } else {
      std::vector<std::string> argv{opt->python, script.string(), opt->out};
      if (opt->quiet) argv.push_back("--quiet");
      const int code = run_program(argv);
      if (code == 3)
        problem =
            "Python modules are missing (on Debian: apt-get install python3-matplotlib "
            "python3-numpy)";
      else if (code != 0)
        problem = "the plot script " + script.string() + " failed (exit code " +
                  std::to_string(code) + ")";
    }
    if (!problem.empty()) {
      std::cerr << "terracut haptics: error: plot not made: " << problem
                << "\nThe other outputs are in " << opt->out << "\n";
      return kExitNoFigures;
    }
    say("plot: " + (fs::path(opt->out) / "haptics.png").string());
    return kExitOk;
  };
}

}  // namespace terracut::cli
