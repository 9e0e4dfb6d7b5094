#!/bin/sh
# How long the two-process stations live, and how their sessions end
# (docs/teleoperation.md, "Lifetimes and exit codes"):
#  - a remote lives as long as it is told: --duration with no operator
#    (exit 0, "duration", "never_connected"), and without --duration it waits
#    for an operator that connects 15 s late (the hidden 13.7 s limit is gone);
#  - an operator whose remote is killed mid-session fades its force out, says
#    so on stderr and exits 4 ("link_lost");
#  - a remote whose operator is killed exits 4 at its --duration ("lost");
#  - a remote stopped by SIGTERM writes its outputs ("stopped", exit 0) and
#    its operator hears it: exit 4, "remote_ended".
# Usage: mmt_lifetime_test.sh TERRACUT SOURCE_DIR WORK_DIR
set -eu
terracut=$1
src=$2
work=$3
scenario="$work/trench.yaml"
. "$src/tests/session/mmt_stations.sh"
# The trench with a 20 ms round trip and a link that is dead after 1.5 s unheard.
sed -e 's/^  timeout_s: 0.2$/  timeout_s: 0.2\n  link_lost_s: 1.5/' \
    -e 's/^    delay_s: 0.05 .*/    delay_s: 0.01/' \
    -e 's/^    jitter_s: 0.002$/    jitter_s: 0.0/' \
    "$src/scenarios/mmt_trench_clay.yaml" > "$work/trench.yaml"
grep -q "link_lost_s: 1.5" "$work/trench.yaml" || { echo "the scenario copy has no link_lost_s"; exit 1; }
"$terracut" key --out "$work/mmt.key" > /dev/null
key="--key $work/mmt.key"

# A remote that waits for a late operator: started now, joined in 15 s.
start_remote "$work/late_remote" $key
late_pid=$remote_pid
late_port=$port
late_start=$(date +%s.%N)

# No operator at all: the remote lives its --duration and says so.
start_remote "$work/alone" $key --duration 2
code_of $remote_pid; [ "$code" = 0 ] || { echo "the lone remote failed"; cat "$work/alone.err"; exit 1; }

# The remote is killed mid-session: the operator ends with exit code 4.
start_remote "$work/killed_remote" $key
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" $key --out "$work/orphan" \
  > "$work/orphan.log" 2> "$work/orphan.err" &
orphan_pid=$!
pids="$pids $orphan_pid"
sleep 2
kill -9 $remote_pid
t0=$(date +%s.%N)
code_of $orphan_pid; [ "$code" = 4 ] || { echo "the operator of a killed remote did not exit 4"; cat "$work/orphan.err"; exit 1; }
t1=$(date +%s.%N)
grep -q "the link to the remote died" "$work/orphan.err" || { cat "$work/orphan.err"; exit 1; }

# The operator is killed mid-session: the remote ends at its --duration with exit code 4.
start_remote "$work/bereft" $key --duration 5
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" $key --out "$work/killed_operator" \
  > /dev/null 2>&1 &
victim=$!
pids="$pids $victim"
sleep 2
kill -9 $victim
code_of $remote_pid; [ "$code" = 4 ] || { echo "the remote of a killed operator did not exit 4"; cat "$work/bereft.err"; exit 1; }

# SIGTERM stops a remote cleanly; its operator hears that the session is over.
start_remote "$work/stopped" $key
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$port" $key --out "$work/cut_short" \
  > /dev/null 2> "$work/cut_short.err" &
cut_pid=$!
pids="$pids $cut_pid"
sleep 1.5
kill -TERM $remote_pid
code_of $remote_pid; [ "$code" = 0 ] || { echo "the stopped remote failed"; cat "$work/stopped.err"; exit 1; }
code_of $cut_pid; [ "$code" = 4 ] || { echo "the operator of a stopped remote did not exit 4"; cat "$work/cut_short.err"; exit 1; }

# The late operator: 15 s after its remote started.
now=$(date +%s.%N)
wait_s=$(/usr/bin/python3 -c "print(max(0.0, 15.0 - ($now - $late_start)))")
sleep "$wait_s"
"$terracut" mmt "$scenario" --role operator --connect "127.0.0.1:$late_port" $key --out "$work/late_operator" \
  > "$work/late_operator.log" 2>&1 || { echo "the late operator failed"; cat "$work/late_operator.log"; exit 1; }
code_of $late_pid; [ "$code" = 0 ] || { echo "the late operator's remote failed"; cat "$work/late_remote.err"; exit 1; }
trap - EXIT

/usr/bin/python3 - "$work" "$t0" "$t1" <<'PY'
import csv, json, sys
work, t0, t1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
def summary(name):
    return json.load(open(f"{work}/{name}/summary.json"))
ok = True
def check(cond, what):
    global ok
    if not cond:
        print("FAILED:", what)
        ok = False
alone = summary("alone")
check(alone["ended"]["how"] == "duration" and abs(alone["ended"]["t_s"] - 2.0) < 0.1, f"lone remote: {alone['ended']}")
check(alone["operator"]["state_at_end"] == "never_connected", f"lone remote: {alone['operator']}")
orphan = summary("orphan")
check(orphan["ended"]["how"] == "link_lost", f"orphan: {orphan['ended']}")
# It gave up link_lost_s after it last heard the remote (plus the ticks' and the process's own time).
check(1.4 <= t1 - t0 < 4.0, f"the orphan took {t1 - t0:.2f} s to end")
rows = list(csv.DictReader(open(f"{work}/orphan/operator.csv")))
last = rows[-1]
check(last["link_silent"] == "1", "the orphan's last tick is not silent")
check(all(float(last[k]) == 0.0 for k in ("fdx", "fdy", "fdz")), f"the orphan's force did not fade out: {last}")
check(orphan["silences"]["count"] >= 1, f"orphan silences {orphan['silences']}")
bereft = summary("bereft")
check(bereft["ended"]["how"] == "duration" and bereft["operator"]["state_at_end"] == "lost", f"bereft: {bereft['ended']}, {bereft['operator']}")
stopped = summary("stopped")
check(stopped["ended"]["how"] == "stopped", f"stopped: {stopped['ended']}")
cut = summary("cut_short")
check(cut["ended"]["how"] == "remote_ended", f"cut short: {cut['ended']}")
late = summary("late_remote")
lop = summary("late_operator")
check(late["ended"]["how"] == "operator_ended" and late["ended"]["t_s"] > 15.0, f"late remote: {late['ended']}")
check(late["udp"]["sessions"] == 1 and late["accepted"] > 3000, f"late remote: {late['udp']['sessions']} sessions, {late['accepted']} commands")
check(lop["ended"]["how"] == "completed", f"late operator: {lop['ended']}")
sys.exit(0 if ok else 1)
PY
echo "MMT lifetimes: ok"
