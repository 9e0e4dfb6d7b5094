#!/usr/bin/env bash
# `terracut haptics` end to end: the trench
# scenario with the script device (fake clock, fast) writes its outputs; bad
# input exits non-zero with a message naming the problem; --help is complete.
set -uo pipefail
cli=$1 source=$2 scratch=$3 device=${4:-}
rm -rf "$scratch" && mkdir -p "$scratch"
fail() { echo "cli_test: FAIL: $*" >&2; exit 1; }
scenario="$source/scenarios/trench_dry_sand.yaml"

# A script session: outputs, one CSV row per tick, a parseable summary, a plot.
"$cli" haptics "$scenario" --device script --out "$scratch/script" --tools-dir "$source/tools" \
  > "$scratch/script.out" 2> "$scratch/script.err" || fail "script session: exit $? ($(cat "$scratch/script.err"))"
for f in haptics.csv summary.json haptics.png; do
  [ -s "$scratch/script/$f" ] || fail "script session: $f missing"
done
rows=$(($(wc -l < "$scratch/script/haptics.csv") - 1))
[ "$rows" -eq 3700 ] || fail "script session: $rows rows, expected 3700 (3.7 s at 1 kHz)"
/usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1])); assert s['device']=='script' and s['ticks']==3700, s" \
  "$scratch/script/summary.json" || fail "summary.json"
grep -q "script device, 3700 ticks" "$scratch/script.out" || fail "summary line: $(cat "$scratch/script.out")"

# Bad input: exit 1 and a message naming it.
expect_error() {  # expected-text, then the arguments
  local want=$1; shift
  "$cli" haptics "$@" > "$scratch/err.out" 2> "$scratch/err.txt"
  local code=$?
  [ "$code" -eq 1 ] || fail "'$*': exit $code, expected 1"
  grep -q -- "$want" "$scratch/err.txt" || fail "'$*': message lacks '$want': $(cat "$scratch/err.txt")"
}
expect_error "scenario file not found" "$scratch/missing.yaml" --out "$scratch/x"
expect_error "unknown device 'falcon'" "$scratch/../missing.yaml" --device falcon --out "$scratch/x"
expect_error "--clock fake cannot be used with the udp device" "$scenario" --device udp:127.0.0.1:0 --clock fake --out "$scratch/x"
sed 's/    scale: 15/    scale: -15/' "$scenario" > "$scratch/bad.yaml"
expect_error "bad.yaml:[0-9]*: haptics.workspace.scale" "$scratch/bad.yaml" --device script --out "$scratch/x"

# Bad command line: exit 2.
"$cli" haptics "$scenario" --out "$scratch/x" --clock slow > /dev/null 2>&1
[ $? -eq 2 ] || fail "--clock slow: expected exit 2"

# --help names every output and option.
"$cli" haptics --help > "$scratch/help.txt" || fail "--help exit"
for word in haptics.csv summary.json haptics.png --device --duration --clock --no-realtime --out "udp[:ADDR:PORT]"; do
  grep -qF -- "$word" "$scratch/help.txt" || fail "--help lacks $word"
done
# A device process over UDP on loopback: terracut-device plays the simulated
# hand against the loop; both finish, the loop used its poses, nothing was rejected.
if [ -n "$device" ]; then
  port=$((40000 + $$ % 20000))
  "$cli" haptics "$scenario" --device "udp:127.0.0.1:$port" --duration 2.5 --no-realtime --no-plot \
    --out "$scratch/udp" > "$scratch/udp.out" 2> "$scratch/udp.err" &
  loop_pid=$!
  "$device" "$scenario" --connect "127.0.0.1:$port" --mode sim --duration 1.5 --start-delay 0.3 \
    > "$scratch/device.out" 2> "$scratch/device.err"
  device_code=$?
  wait $loop_pid || fail "udp session: exit $? ($(cat "$scratch/udp.err"))"
  [ "$device_code" -eq 0 ] || fail "terracut-device: exit $device_code ($(cat "$scratch/device.err"))"
  /usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1])); assert s['loop']['samples']>0 and s['rejected_packets']['total']==0, (s['loop'], s['rejected_packets'])" \
    "$scratch/udp/summary.json" || fail "udp summary.json"
  grep -q "forces accepted" "$scratch/device.out" || fail "terracut-device output: $(cat "$scratch/device.out")"
fi
echo "cli_test: ok"
