#!/bin/sh
# An authenticated two-process session under attack from the same machine
# (loopback): a 50 000 datagram/s junk flood from another local port and an
# ENet intruder (terracut-netprobe) against the remote's port for the whole
# session, against the same session without them.
#  - the intruder never takes the session over: one session, the operator's;
#    every connection it made is refused and counted (but one still in its
#    handshake when the remote ended);
#  - every flood datagram is counted by the remote before terracut's
#    stations see anything (no peer's, oversize, a connection request, or
#    dropped by the kernel);
#  - the operator keeps at least 90 % of its commands, and the session's
#    force error (the report's, MMT) stays within 20 % of the clean run's.
# Usage: mmt_flood_test.sh TERRACUT NETPROBE SOURCE_DIR WORK_DIR
set -eu
terracut=$1
netprobe=$2
src=$3
work=$4
scenario="$work/trench.yaml"
. "$src/tests/session/mmt_stations.sh"
# The trench without the soil estimate: its fit follows the timing of the
# commands' arrival, which a loaded machine changes (a clean run's estimate
# read 1.19 instead of 1.45 at a load average of 6, the force error 67
# instead of 45 N; docs/teleoperation.md, "Not done yet"), and this test is
# about what the flood does to the link, not what load does to the fit.
sed -e 's/^    estimate: true$/    estimate: false/' "$src/scenarios/mmt_trench_clay.yaml" > "$scenario"
grep -q "estimate: false" "$scenario" || { echo "the scenario copy still estimates"; exit 1; }
# No jitter: without it no command arrives out of order, so a clean run keeps
# them all and every command lost is the flood's doing.
link="--rtt-ms 100 --jitter-ms 0"
"$terracut" key --out "$work/mmt.key" > /dev/null
key="--key $work/mmt.key"

# The clean session.
start_remote "$work/clean_remote" $key $link
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" $key $link \
  --out "$work/clean_operator" > "$work/clean_operator.log" 2>&1
wait $remote_pid
"$terracut" mmt "$scenario" --report "$work/clean_operator" "$work/clean_remote" --out "$work/clean" -q --no-plot

# The attacked session: the flood and the intruder start before the operator
# and stop before it ends (so that the remote reads every datagram of theirs).
start_remote "$work/remote" $key $link
"$netprobe" --port "$port" --flood-rate 50000 --intruder --duration 3.5 --out "$work/probe.json" &
probe_pid=$!
pids="$pids $probe_pid"
sleep 0.3
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" $key $link \
  --out "$work/operator" > "$work/operator.log" 2> "$work/operator.err"
wait $probe_pid
wait $remote_pid
trap - EXIT
"$terracut" mmt "$scenario" --report "$work/operator" "$work/remote" --out "$work/attacked" -q --no-plot

/usr/bin/python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
def load(p):
    return json.load(open(f"{work}/{p}"))
probe, op, rm = load("probe.json"), load("operator/summary.json"), load("remote/summary.json")
clean, attacked = load("clean/summary.json"), load("attacked/summary.json")
ok = True
def check(cond, what):
    global ok
    if not cond:
        print("FAILED:", what)
        ok = False
flood, intr, udp = probe["flood"], probe["intruder"], rm["udp"]
print(f"flood {flood['sent']} datagrams ({flood['sent'] / 3.5:.0f}/s), intruder {intr['connected']} connections; "
      f"remote: unknown {udp['dropped_unknown_source']}, oversize {udp['dropped_oversize']}, requests "
      f"{udp['connection_requests']}, kernel {udp['dropped_by_kernel']}, refused {udp['peers_refused']}; "
      f"commands {op['commands']['received_by_remote']} of {op['commands']['followed']}; force error "
      f"{attacked['force_error']['mmt_rms_n']:.1f} N against {clean['force_error']['mmt_rms_n']:.1f} N clean")
check(flood["sent"] > 0.2 * 50000 * 3.5, f"the flood sent only {flood['sent']}")
check(intr["connected"] > 0, "the intruder never connected")
# The intruder: refused, counted, never the session's.
refused = sum(udp["peers_refused"].values())
check(udp["sessions"] == 1 and udp["resumed"] == 0, f"sessions {udp['sessions']}, resumed {udp['resumed']}")
check(rm["operator"]["id"] != 0 and rm["operator"]["state_at_end"] == "ended_the_session", f"remote's operator {rm['operator']}")
check(intr["connected"] - 1 <= refused <= intr["connected"], f"{refused} refused of {intr['connected']} intruder connections")
check(op["ended"]["how"] == "completed" and rm["ended"]["how"] == "operator_ended", f"ended {op['ended']} / {rm['ended']}")
# Every flood datagram counted before a station saw it: no peer's, oversize,
# a connection request, the kernel's drop, or passed to a connection a
# random request opened (ENet then discards it; the count is ours). The
# counts also hold the intruder's and the operator's connection traffic
# (ENet's handshake, acknowledgements and pings, the intruder's tries: at
# most about ten datagrams a connection) and the operator's datagrams the
# kernel dropped.
counted = (udp["dropped_unknown_source"] + udp["dropped_oversize"] + udp["connection_requests"] + udp["dropped_by_kernel"]
           + udp["to_half_open_connections"] + udp["to_unauthenticated_peers"])
lost = op["commands"]["followed"] - op["commands"]["received_by_remote"]
check(counted >= flood["sent"], f"counted {counted} of {flood['sent']} flood datagrams")
check(counted <= flood["sent"] + 20 * intr["attempts"] + 20 + 3 * lost, f"counted {counted} for {flood['sent']} sent")
check(udp["dropped_oversize"] == flood["oversize"], f"oversize {udp['dropped_oversize']} of {flood['oversize']}")
check(udp["dropped_by_kernel"] >= flood["empty"], f"kernel drops {udp['dropped_by_kernel']}, empty datagrams {flood['empty']}")
# Nothing of the operator's lost without a count: over loopback only a full
# receive buffer loses a datagram, and the kernel counts those.
check(lost <= udp["dropped_by_kernel"] - flood["empty"], f"{lost} commands lost, the kernel dropped {udp['dropped_by_kernel'] - flood['empty']} beyond the empty ones")
# The session survived: commands kept, and the force the operator felt. The
# buffer the remote asks for (8 MiB; the kernel doubles it) holds a third of
# a second of this flood, so a station that ticks keeps every command; a
# buffer capped by net.core.rmem_max (not root: no SO_RCVBUFFORCE; Debian's
# default 208 KiB holds 8 ms) loses commands whenever a loaded machine stalls
# the remote longer than that: then only the counts above are checked.
kept = op["commands"]["received_by_remote"] / max(1, op["commands"]["followed"])
if udp["receive_buffer_bytes"] >= 4 << 20:
    check(kept >= 0.9, f"the remote received {kept:.3f} of the commands")
    check(rm["accepted"] >= 0.9 * op["commands"]["sent"] - 200, f"remote accepted {rm['accepted']} of {op['commands']['sent']}")
    f_att, f_clean = attacked["force_error"]["mmt_rms_n"], clean["force_error"]["mmt_rms_n"]
    check(abs(f_att - f_clean) <= 0.2 * f_clean, f"force error {f_att:.1f} N against {f_clean:.1f} N clean")
else:
    print(f"note: the remote's receive buffer is {udp['receive_buffer_bytes']} bytes (raise net.core.rmem_max, "
          f"or run as root): the commands kept ({kept:.3f}) and the force error are not checked")
sys.exit(0 if ok else 1)
PY
echo "MMT under a flood and an intruder: ok"
