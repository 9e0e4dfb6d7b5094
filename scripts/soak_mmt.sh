#!/usr/bin/env bash
# The two-process teleoperation soak (docs/reliability.md, "Teleoperation
# over a hostile network"): an authenticated remote and operator over
# loopback for SECONDS (default 3600), the operator's script replaying the
# trench over and over, while terracut-netprobe floods the remote's port
# with junk (FLOOD_RATE datagrams/s, default 50 000) and an ENet intruder
# tries to take the session over, throughout. Not in CI.
#
# Checks: no crash (both stations exit 0, the session ended by its
# operator); memory flat (each station's resident memory at the end within
# 8 MiB of that at a tenth of the run); every refused peer counted (the
# remote's refusals are the intruder's connections); every flood datagram
# counted (no peer's, oversize, a connection request, the kernel's drop, or
# passed to a connection a random request opened: at least the flood, at
# most the flood, the intruder's and operator's connection traffic and the
# operator's own lost datagrams); nothing uncounted lost (the commands
# the remote missed are at most the kernel's drops). Writes OUT/soak.md
# (the figures for docs/reliability.md), rss.csv, the stations' folders and
# the report of the two (`terracut mmt --report`); exit 1 when a check fails.
#
#   nice -n 10 ./scripts/soak_mmt.sh 3600 out/soak_mmt     # after ./scripts/build.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TERRACUT_BUILD_DIR:-$root/build}
seconds=${1:-3600}
out=${2:-$root/out/soak_mmt}
rate=${FLOOD_RATE:-50000}
terracut=$build/apps/terracut/terracut
probe=$build/tests/soak/terracut-netprobe
scenario=$root/scenarios/mmt_trench_clay.yaml
for p in "$terracut" "$probe"; do
  [[ -x $p ]] || { echo "soak_mmt: $p not built (./scripts/build.sh, with the soak suite)" >&2; exit 1; }
done
unset TERRACUT_MMT_KEY || true
rm -rf "$out"
mkdir -p "$out"
"$terracut" key --out "$out/mmt.key" > /dev/null
pids=()
trap 'for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done' EXIT

start=$(date +%s)
"$terracut" mmt "$scenario" --role remote --listen 127.0.0.1:0 --key "$out/mmt.key" \
  --duration $((seconds + 120)) --out "$out/remote" > "$out/remote.log" 2> "$out/remote.err" &
remote_pid=$!
pids+=("$remote_pid")
port=""
for _ in $(seq 1 200); do
  port=$(sed -n 's/.*remote listening on 127.0.0.1:\([0-9]*\).*/\1/p' "$out/remote.log" 2>/dev/null || true)
  [[ -n $port ]] && break
  sleep 0.05
done
[[ -n $port ]] || { echo "soak_mmt: the remote did not start"; cat "$out/remote.err"; exit 1; }
"$probe" --port "$port" --flood-rate "$rate" --intruder --duration "$seconds" --out "$out/probe.json" &
probe_pid=$!
pids+=("$probe_pid")
sleep 0.5
# The operator outlives the flood by 5 s: the remote reads every datagram of it.
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" --key "$out/mmt.key" \
  --repeat --duration $((seconds + 5)) --out "$out/operator" > "$out/operator.log" 2> "$out/operator.err" &
op_pid=$!
pids+=("$op_pid")

rss() { awk '/^VmRSS/ {print $2}' "/proc/$1/status" 2>/dev/null || echo ""; }
echo "t_s,remote_rss_kib,operator_rss_kib" > "$out/rss.csv"
while kill -0 "$op_pid" 2>/dev/null; do
  echo "$(( $(date +%s) - start )),$(rss "$remote_pid"),$(rss "$op_pid")" >> "$out/rss.csv"
  sleep 10
done
set +e
wait "$op_pid"; op_code=$?
wait "$probe_pid"
wait "$remote_pid"; remote_code=$?
set -e
trap - EXIT
"$terracut" mmt "$scenario" --report "$out/operator" "$out/remote" --out "$out/report" -q --no-plot

/usr/bin/python3 - "$out" "$seconds" "$rate" "$op_code" "$remote_code" <<'PY'
import csv, json, sys
out, seconds, rate, op_code, remote_code = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
load = lambda p: json.load(open(f"{out}/{p}"))
probe, op, rm, rep = load("probe.json"), load("operator/summary.json"), load("remote/summary.json"), load("report/summary.json")
rows = [r for r in csv.DictReader(open(f"{out}/rss.csv")) if r["remote_rss_kib"] and r["operator_rss_kib"]]
flood, intr, udp, cmd = probe["flood"], probe["intruder"], rm["udp"], op["commands"]
broken = []
def check(ok, what):
    if not ok:
        broken.append(what)
check(op_code == 0 and remote_code == 0, f"exit codes: operator {op_code}, remote {remote_code}")
check(op["ended"]["how"] == "completed" and rm["ended"]["how"] == "operator_ended", f"ended: {op['ended']} / {rm['ended']}")
tenth = [r for r in rows if float(r["t_s"]) >= 0.1 * seconds]
growth = {}
for who in ("remote", "operator"):
    at = float(tenth[0][f"{who}_rss_kib"]) if tenth else float("nan")
    end = float(rows[-1][f"{who}_rss_kib"]) if rows else float("nan")
    growth[who] = (at / 1024, end / 1024)
    check(end - at <= 8 * 1024, f"{who} resident memory grew from {at / 1024:.1f} to {end / 1024:.1f} MiB")
refused = sum(udp["peers_refused"].values())
check(intr["connected"] - 1 <= refused <= intr["connected"], f"{refused} refused of {intr['connected']} intruder connections")
check(udp["sessions"] == 1, f"{udp['sessions']} sessions")
counted = (udp["dropped_unknown_source"] + udp["dropped_oversize"] + udp["connection_requests"] + udp["dropped_by_kernel"]
           + udp["to_half_open_connections"] + udp["to_unauthenticated_peers"])
lost = cmd["followed"] - cmd["received_by_remote"]
check(counted >= flood["sent"], f"counted {counted} of {flood['sent']} flood datagrams")
check(counted <= flood["sent"] + 20 * intr["attempts"] + 20 + 3 * lost, f"counted {counted} for {flood['sent']} sent")
check(lost <= udp["dropped_by_kernel"], f"{lost} commands lost, the kernel dropped {udp['dropped_by_kernel']}")
kept = cmd["received_by_remote"] / max(1, cmd["followed"])
lines = [
    f"| figure | value |", "|---|---|",
    f"| session | {op['ended']['t_s']:.0f} s of two-process teleoperation over loopback, authenticated; flood and intruder for {seconds:.0f} s |",
    f"| exit codes, how it ended | operator {op_code} ({op['ended']['how']}), remote {remote_code} ({rm['ended']['how']}) |",
    f"| junk flood | {flood['sent']} datagrams ({flood['sent'] / seconds:.0f}/s of {rate:.0f} asked): random {flood['random']}, empty {flood['empty']}, truncated {flood['truncated']}, connection requests {flood['connection_requests']}, ENet-looking {flood['enet_like']}, oversize {flood['oversize']} |",
    f"| counted by the remote | {counted}: no peer's {udp['dropped_unknown_source']}, oversize {udp['dropped_oversize']}, connection requests {udp['connection_requests']}, kernel {udp['dropped_by_kernel']}, to half-open connections {udp['to_half_open_connections']}, to unauthenticated peers {udp['to_unauthenticated_peers']} (receive buffer {udp['receive_buffer_bytes'] // 1024} KiB) |",
    f"| intruder | {intr['attempts']} tries, {intr['connected']} connections; refused {refused} ({', '.join(f'{k} {v}' for k, v in udp['peers_refused'].items() if v)}); sessions {udp['sessions']}, resumed {udp['resumed']} |",
    f"| commands | {cmd['sent']} sent, the remote received {cmd['received_by_remote']} of {cmd['followed']} ({kept * 100:.3f} %); worst second {100 * (1 - cmd['worst_loss_over_a_second']):.1f} % |",
    f"| operator's view | {op['accepted']} datagrams accepted, rejected {sum(op['rejected'].values())}, silences {op['silences']['count']} (longest {op['silences']['longest_s'] * 1e3:.0f} ms), RTT {op['round_trip']['measured_s'] * 1e3:.1f} ms measured |",
    f"| resident memory, at a tenth and at the end | remote {growth['remote'][0]:.1f} -> {growth['remote'][1]:.1f} MiB, operator {growth['operator'][0]:.1f} -> {growth['operator'][1]:.1f} MiB |",
    f"| force error (report) | MMT {rep['force_error']['mmt_rms_n']:.1f} N RMS, direct reflection {rep['force_error']['direct_rms_n']:.1f} N; tick p99 operator {rep['timing']['operator_tick']['p99_us']:.0f} us, remote {rep['timing']['remote_tick']['p99_us']:.0f} us |",
    f"| checks | {'all kept' if not broken else 'BROKEN: ' + '; '.join(broken)} |",
]
open(f"{out}/soak.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
sys.exit(1 if broken else 0)
PY
