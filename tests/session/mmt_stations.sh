# Shared by the two-process MMT tests (sourced): the work folder made empty,
# no key from the environment, and the stations started and waited for.
# Expects terracut, scenario and work set. Every station started is killed
# when the test exits early.
rm -rf "$work"
mkdir -p "$work"
unset TERRACUT_MMT_KEY || true
pids=""
trap 'for p in $pids; do kill -9 $p 2>/dev/null || true; done' EXIT

# Starts a remote station on any free port of 127.0.0.1: $1 its folder, then
# its options (its log: $1.log, $1.err); sets remote_pid and port.
start_remote() {
  out=$1
  shift
  "$terracut" mmt "$scenario" --role remote --listen 127.0.0.1:0 --out "$out" "$@" \
    > "$out.log" 2> "$out.err" &
  remote_pid=$!
  pids="$pids $remote_pid"
  port=""
  for _ in $(seq 1 200); do
    port=$(sed -n 's/.*remote listening on 127.0.0.1:\([0-9]*\).*/\1/p' "$out.log" 2>/dev/null || true)
    [ -n "$port" ] && break
    sleep 0.05
  done
  [ -n "$port" ] || { echo "the remote did not say its port"; cat "$out.log" "$out.err"; exit 1; }
}

# Waits for pid; its exit code in code (not in a subshell: only the shell
# that started it may wait for it).
code_of() {
  set +e
  wait "$1"
  code=$?
  set -e
}
