#!/bin/sh
# Two-process model-mediated teleoperation over loopback UDP (ENet), with an
# authenticated session: the remote station in one process, the operator in
# another, with delay, jitter, loss and reordering emulated at each sender.
# Checks that commands, measurements, patches and estimates crossed, that
# both wrote their files and said how the session ended, and that the report
# of the two compares them as the single-process run does. Bad keys and
# flags are refused naming what is wrong. Also the single-process run and a
# small study, with their figures.
# Usage: mmt_two_process_test.sh TERRACUT SOURCE_DIR WORK_DIR
set -eu
terracut=$1
src=$2
work=$3
scenario="$src/scenarios/mmt_trench_clay.yaml"
. "$src/tests/session/mmt_stations.sh"
link="--rtt-ms 100 --jitter-ms 2 --loss 0.05"

# Bad command lines are refused with a message naming the option (exit 1).
refuse() {
  expect=$1
  shift
  if "$terracut" "$@" > "$work/refused.log" 2>&1; then
    echo "accepted: $*"; exit 1
  fi
  grep -q -- "$expect" "$work/refused.log" || { echo "no '$expect' in:"; cat "$work/refused.log"; exit 1; }
}
refuse "no mmt: section" mmt "$src/scenarios/trench_dry_sand.yaml" --out "$work/x"
refuse "--loss must be in" mmt "$scenario" --out "$work/x" --loss 2
refuse "runs in real time" mmt "$scenario" --out "$work/x" --device udp
refuse "--rtts: 'abc'" mmt "$scenario" --out "$work/x" --sweep --rtts 0,abc --no-plot
# Keys: none at all, one of the wrong form, one others may read, the flag off loopback.
refuse "the link between the stations is authenticated" mmt "$scenario" --out "$work/x" --role remote
"$terracut" key --out "$work/mmt.key" > "$work/key.log"
grep -q "fingerprint" "$work/key.log" || { cat "$work/key.log"; exit 1; }
refuse "never overwritten" key --out "$work/mmt.key"
refuse "--connect: .nowhere." mmt "$scenario" --out "$work/x" --role operator --connect nowhere --key "$work/mmt.key"
cp "$work/mmt.key" "$work/open.key"
chmod 644 "$work/open.key"
refuse "read or written by others (mode 0644)" mmt "$scenario" --out "$work/x" --role remote --key "$work/open.key"
printf 'abc\n' > "$work/short.key"
chmod 600 "$work/short.key"
refuse "holds 4 bytes" mmt "$scenario" --out "$work/x" --role remote --key "$work/short.key"
TERRACUT_MMT_KEY=xyz refuse "TERRACUT_MMT_KEY: a key is 64 hex digits" mmt "$scenario" --out "$work/x" --role remote
refuse "only on a loopback address" mmt "$scenario" --out "$work/x" --role remote --listen 0.0.0.0:0 --insecure-loopback
refuse "not with --key" mmt "$scenario" --out "$work/x" --role remote --insecure-loopback --key "$work/mmt.key"
refuse "only with --role" mmt "$scenario" --out "$work/x" --key "$work/mmt.key"

# One process: the run's files and figure; a small study: its table and figure.
"$terracut" mmt "$scenario" --out "$work/single" -q
for f in operator.csv remote.csv terrain_error.csv summary.json mmt.png; do
  [ -s "$work/single/$f" ] || { echo "single-process run: no $f"; exit 1; }
done
"$terracut" mmt "$scenario" --sweep --rtts 0,200 --losses 0,0.1 --out "$work/study" -q
for f in study.csv study.md study.png; do
  [ -s "$work/study/$f" ] || { echo "study: no $f"; exit 1; }
done
# 2 RTTs x 2 losses, plus the deadband variant per RTT, and the header.
[ "$(wc -l < "$work/study/study.csv")" -eq 7 ] || { echo "study.csv:"; cat "$work/study/study.csv"; exit 1; }

# Another key: the operator is refused by name (exit 1), the remote counts it.
"$terracut" key --out "$work/other.key" > /dev/null
start_remote "$work/refusing" --key "$work/mmt.key" --duration 4
refuse "refused this operator (bad_key" mmt "$scenario" --role operator --connect "127.0.0.1:$port" \
  --key "$work/other.key" --out "$work/x"
wait $remote_pid

# The session, authenticated.
start_remote "$work/remote" $link --key "$work/mmt.key"
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" $link \
  --key "$work/mmt.key" --out "$work/operator" > "$work/operator.log" 2>&1
wait $remote_pid
"$terracut" mmt "$scenario" --report "$work/operator" "$work/remote" --out "$work/report" -q
for f in operator.csv remote.csv terrain_error.csv summary.json mmt.png; do
  [ -s "$work/report/$f" ] || { echo "two-process report: no $f"; exit 1; }
done

# The demo without a key, on loopback, says so.
start_remote "$work/insecure_remote" --insecure-loopback --duration 30
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" --insecure-loopback \
  --duration 1 --out "$work/insecure_operator" > "$work/insecure.log" 2>&1
wait $remote_pid
grep -q "NOT authenticated" "$work/insecure.log" || { cat "$work/insecure.log"; exit 1; }
grep -q "NOT authenticated" "$work/insecure_remote.err" || { cat "$work/insecure_remote.err"; exit 1; }
trap - EXIT

/usr/bin/python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
op = json.load(open(f"{work}/operator/summary.json"))
rm = json.load(open(f"{work}/remote/summary.json"))
rep = json.load(open(f"{work}/report/summary.json"))
single = json.load(open(f"{work}/single/summary.json"))
refusing = json.load(open(f"{work}/refusing/summary.json"))
ok = True
def check(cond, what):
    global ok
    if not cond:
        print("FAILED:", what)
        ok = False
# About 4 s at 1 kHz, 5 % lost each way, some reordered by the jitter.
check(op["accepted"] > 1500, f"operator accepted {op['accepted']} messages")
check(rm["accepted"] > 1500, f"remote accepted {rm['accepted']} commands")
check(op["patches"] >= 10, f"operator merged {op['patches']} patches")
check(op["estimates"] >= 1, f"operator applied {op['estimates']} estimates")
check(op["rejected"]["reordered"] > 0, "no reordered measurement was rejected")
check(op["traffic"]["emulated_losses"] > 0, "no loss was emulated operator -> remote")
check(rm["udp"]["sessions"] == 1 and rm["connections"] == 1, "one operator session")
check(rm["udp"]["authenticated"] and op["udp"]["authenticated"], "the session was not authenticated")
# The remote's estimate of its soil, from its physical force, as the one-process
# run finds it (the same cut; the two-process run's tool lags in real time).
check(rm["estimate"]["samples"] > 500, f"remote estimate from {rm['estimate']['samples']} samples")
one = single["estimate"]["force_scale"]
check(abs(rm["force_scale"] - one) < 0.05 * one, f"remote estimate {rm['force_scale']}, one process {one}")
# How each ended: the operator its run, the remote with it.
check(op["ended"]["how"] == "completed", f"operator ended {op['ended']}")
check(rm["ended"]["how"] == "operator_ended", f"remote ended {rm['ended']}")
check(rm["operator"]["state_at_end"] == "ended_the_session", f"remote saw {rm['operator']}")
# Measured, not configured: a round trip of about the emulated 100 ms (+-4 ms
# jitter), and the commands lost about the emulated 5 % (plus the reordered ones that arrived).
rt = op["round_trip"]
check(0.096 <= rt["measured_s"] <= 0.2, f"measured round trip {rt['measured_s']}")
check(rt["bound_s"] >= rt["measured_s"], f"round trip bound {rt['bound_s']} below the measured one")
c = op["commands"]
check(0.0 <= c["loss"] < 0.15, f"command loss {c['loss']}")
check(c["received_by_remote"] <= c["followed"] <= c["sent"], f"commands {c}")
rows = open(f"{work}/operator/operator.csv").read().splitlines()
check(len(rows) > 3000, f"operator.csv has {len(rows)} rows")
rows = open(f"{work}/remote/remote.csv").read().splitlines()
check(len(rows) > 3000, f"remote.csv has {len(rows)} rows")
# The refused operator never had a session.
check(refusing["udp"]["peers_refused"]["bad_key"] == 1, f"refusals {refusing['udp']['peers_refused']}")
check(refusing["udp"]["sessions"] == 0 and refusing["operator"]["state_at_end"] == "never_connected",
      f"the refused operator had a session: {refusing['operator']}")
# The report has the single-process run's figures, and they are of its size:
# the two processes ran the same session over the same emulated link.
for key in ("force_error", "terrain_error", "tracking", "traffic", "updates", "estimate", "passivity", "rejected", "timing"):
    check(key in rep and set(single[key]) <= set(rep[key]), f"report's {key}: {rep.get(key)} against {single[key]}")
fe, fs = rep["force_error"], single["force_error"]
check(fe["mmt_rms_n"] < 2.0 * fs["mmt_rms_n"] + 20.0, f"MMT force error {fe['mmt_rms_n']} N against {fs['mmt_rms_n']} N in one process")
check(fe["direct_rms_n"] > fe["mmt_rms_n"], f"direct reflection {fe['direct_rms_n']} N not worse than MMT {fe['mmt_rms_n']} N at 100 ms")
check(rep["terrain_error"]["final_rms_m"] < 0.002, f"terrain {rep['terrain_error']}")
check(rep["traffic"]["to_remote_packets_per_s"] > 900, f"traffic {rep['traffic']}")
sys.exit(0 if ok else 1)
PY
echo "two-process MMT: ok"
