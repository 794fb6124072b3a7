#!/usr/bin/env bash
# Starts hbirl's service set -- simulator, perception and labeller (a camera's domain),
# sampler workers, optimiser -- and the dashboard, waits for the optimiser to learn (showing
# its progress), prints a summary of the learned reward (hbirl summary), writes the report and
# shuts everything down (also on Ctrl-C). Exits
# non-zero if any service failed, or if the run is incomplete (unless --allow-incomplete).
#
# LCM talks UDP multicast. Where multicast to loopback is not routed (the usual case in
# containers), the set runs in a private network namespace of its own (unshare -rn, lo
# up, 224.0.0.0/4 routed to lo): nothing leaves the machine and other runs do not see
# it. The dashboard runs outside it, following the run's recording, so a browser on this
# machine reaches it. See --help.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$here")"
build="$repo/build"
workers=2
domain=onion
size=5
no_sim=0
sensor=""
confounders=3
trajectories=20
eta=plausible
learn_eta_args=()
stop_args=()
config=all
sorts=6
controlled_sorts=20
seed=1
record=0
out=""
url=""
fps=15
max_fps=400
kill_worker_after_blocks=""
timeout=900
dashboard_port=8765
keep_dashboard=0
report=1
key=""
key_mode=auto
stall=20
allow_incomplete=0
incomplete_after=60
orig_args=("$@")
progress_open=0  # a progress line is being rewritten in the terminal (show_progress)
end_progress() {  # the rewritten line ends before anything else is said
  if [ "$progress_open" = 1 ]; then echo; progress_open=0; fi
}

usage() {
  cat <<USAGE
usage: services/launch.sh [options]

Runs a demo as separate processes over LCM and prints the learned reward.
  --domain D             onion (camera frames -> perception -> labeller -> learner),
                         gridworld (the paper's Gridworld; its simulator publishes the
                         observations itself), or a domain file (docs/your-task.md "Your own task":
                         its simulated sensor publishes the observations) (default $domain)
  --size N               gridworld: cells a side (default $size)
  --no-sim               no simulator: the learning side only (optimiser, workers, dashboard),
                         waiting for a sensor that publishes EPISODE, OBSERVATIONS (and
                         GROUND_TRUTH for controlled episodes) -- e.g. hbirl publish
  --sensor CMD           with --no-sim: run CMD as the sensor inside the set (its LCM URL is
                         appended as --url URL), e.g. "build/hbirl publish --problem F" or a
                         Python sensor, "python3 examples/python/sensor.py" (the build's
                         hbirl package is on its PYTHONPATH)
  --sensor-key           the sensor signs its messages: append --key FILE to CMD as well (hbirl
                         publish does), so the run is authenticated with a sensor too
  --workers N            sampler workers (default $workers)
  --seed S               seed of the run (default $seed)
  --learn-eta K          the optimiser takes the sensor's eta as stated, or learns it per
                         context (the labeller's rule): stated or learned (default: learned,
                         or a domain file's observation_model.learn_eta)
 onion:
  --config C             demonstrations' scene: all, controlled, or a list of
                         blue-shirt, other-onions, foreground, mirror (default $config)
  --sorts N              demonstrated sorts (default $sorts)
  --controlled-sorts N   sorts in the controlled run that gives the subject prior ($controlled_sorts)
  --fps F                camera frames per simulated second (default $fps)
  --max-fps F            pacing of the camera, frames per wall-clock second (default $max_fps;
                         gridworld: steps per second)
 gridworld (a domain file's sensor section says these for its run):
  --confounders N        confounding elements |E| (default $confounders)
  --trajectories N       demonstrations (default $trajectories)
  --eta K                plausible, uniform or true (default $eta)
 all:
  --record               record every message with lcm-logger to OUT/run.lcmlog
                         (replay: build/hbirl learn --log OUT/run.lcmlog); on with the
                         dashboard or the report, which are made from the recording
  --dashboard-port P     serve the live dashboard on http://127.0.0.1:P/ (default $dashboard_port)
  --no-dashboard         no dashboard
  --keep-dashboard       after the run, keep the dashboard up until Ctrl-C
  --no-report            do not write the static report (OUT/report/index.html; written
                         for every run by default, even one that did not finish)
  --out DIR              where logs and results go (default runs/<date-time>)
  --build DIR            the build folder with hbirl-services (default build/)
  --url URL              an LCM URL to use instead of a private network namespace, e.g.
                         udpm://239.255.76.67:7667?ttl=1 to include workers on other
                         machines (they run: hbirl-sampler --url URL)
  --timeout S            give up (and fail) when there is no result after S seconds (default $timeout)
  --key FILE             a key for many runs (hbirl keygen FILE; e.g. shared with sampler workers
                         on other machines, started with --key FILE: they serve any run of it).
                         Every run gets its own key file OUT/run.key (mode 0600): the key and a
                         fresh run identity; every service, the recording's readers and the
                         dashboard believe only messages signed with the key for this run, so
                         one run's messages (a replayed recording) never enter another. Without
                         --key a fresh key is made for the run whose sensor is the set's own
                         simulator (or --sensor-key) (docs/RELIABILITY.md). A run waiting for an
                         outside sensor is unauthenticated unless --key is given (the sensor
                         must then sign with OUT/run.key)
  --no-key               no key: the bus is unauthenticated (every service says so)
  --stall-timeout S      a service that has neither beaten its heartbeat nor computed for S
                         seconds (stopped, or blocked: alive, but silent) is killed and
                         restarted, like one that died (default $stall; 0: only deaths are noticed)
  --anytime              the optimiser publishes an estimate after each demonstration
                         (ESTIMATE, with its confidence: 100 posterior draws each), drawn by
                         the dashboard demonstration by demonstration
  --stop-at-confidence P knowing when it has seen enough: once --stop-after estimates in a row
                         have a confidence >= P (in (0, 1)), the optimiser sends STOP and the
                         sensor ends the run after the episode under way (implies --anytime)
  --stop-after K         estimates in a row for --stop-at-confidence (default 3)
  --allow-incomplete     learn from what came when a run's frames stop coming before it is
                         complete, and exit 0 (the result says what is missing under
                         "incomplete"); by default such a run fails, after
  --incomplete-after S   seconds without a frame since the end of the run, while asking for
                         the missing ones again (default $incomplete_after)
  --kill-worker-after-blocks N
                         (testing) the first worker SIGKILLs itself after computing N blocks
USAGE
}

while [ $# -gt 0 ]; do
  case "$1" in
    --workers) workers="$2"; shift 2 ;;
    --domain) domain="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --no-sim) no_sim=1; shift ;;
    --sensor) sensor="$2"; shift 2 ;;
    --confounders) confounders="$2"; shift 2 ;;
    --trajectories) trajectories="$2"; shift 2 ;;
    --eta) eta="$2"; shift 2 ;;
    --config) config="$2"; shift 2 ;;
    --sorts) sorts="$2"; shift 2 ;;
    --controlled-sorts) controlled_sorts="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --learn-eta) learn_eta_args=(--eta "$2"); shift 2 ;;
    --fps) fps="$2"; shift 2 ;;
    --max-fps) max_fps="$2"; shift 2 ;;
    --record) record=1; shift ;;
    --out) out="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --url) url="$2"; shift 2 ;;
    --kill-worker-after-blocks) kill_worker_after_blocks="$2"; shift 2 ;;
    --timeout) timeout="$2"; shift 2 ;;
    --dashboard-port) dashboard_port="$2"; shift 2 ;;
    --no-dashboard) dashboard_port=""; shift ;;
    --keep-dashboard) keep_dashboard=1; shift ;;
    --no-report) report=0; shift ;;
    --key) key="$2"; key_mode=given; shift 2 ;;
    --no-key) key_mode=none; shift ;;
    --stall-timeout) stall="$2"; shift 2 ;;
    --anytime) stop_args+=(--anytime); shift ;;
    --stop-at-confidence) stop_args+=(--stop-at-confidence "$2"); shift 2 ;;
    --stop-after) stop_args+=(--stop-after "$2"); shift 2 ;;
    --allow-incomplete) allow_incomplete=1; shift ;;
    --incomplete-after) incomplete_after="$2"; shift 2 ;;
    --sensor-key) sensor_key=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "launch.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

bin="$build/hbirl-services"
if [ ! -x "$bin" ]; then
  echo "launch.sh: $bin not found: build first (cmake -S . -B build && cmake --build build -j)" >&2
  exit 2
fi
# A domain file by its absolute path (the services may run elsewhere); the simulator
# says what the domain needs (perception and the labeller for a camera) and checks it.
if [ -f "$domain" ]; then domain="$(cd "$(dirname "$domain")" && pwd)/$(basename "$domain")"; fi
domain_args=(--domain "$domain" --size "$size")
if ! listeners="$("$build/hbirl-sim-driver" "${domain_args[@]}" --print-listeners)"; then
  exit 2  # the simulator said why, in one line
fi
if [ -n "$sensor" ] && [ "$no_sim" = 0 ]; then
  echo "launch.sh: --sensor needs --no-sim (the simulator is the sensor otherwise)" >&2
  exit 2
fi
[ -n "$out" ] || out="$repo/runs/$(date +%Y%m%d-%H%M%S)"
mkdir -p "$out/logs"
out="$(cd "$out" && pwd)"

# The run's key file, OUT/run.key: the key (a fresh one, or --key's) and a fresh run
# identity. Made once, by the outer launch.sh; the copy in the namespace is handed it.
inner="${HBIRL_LAUNCH_INNER:-}"
if [ "$key_mode" = auto ] && [ "$no_sim" = 1 ] && [ "${sensor_key:-0}" = 0 ]; then
  key_mode=none
  echo "launch.sh: the sensor is outside the set: the bus is unauthenticated (--key FILE, with a sensor that signs, makes it authenticated)"
fi
run_key="$out/run.key"
if [ "$key_mode" != none ] && [ -z "$inner" ]; then
  keygen=(--run)
  if [ "$key_mode" = given ]; then
    [ -f "$key" ] || { echo "launch.sh: --key: $key not found" >&2; exit 2; }
    keygen=(--run-of "$key")
  fi
  rm -f "$run_key"
  "$build/hbirl" keygen "${keygen[@]}" "$run_key" 2>"$out/logs/keygen.log" ||
    { echo "launch.sh: could not write the run's key file $run_key: $(cat "$out/logs/keygen.log")" >&2; exit 2; }
fi
key_args=()
if [ "$key_mode" != none ]; then
  [ -f "$run_key" ] || { echo "launch.sh: the run's key file $run_key is missing" >&2; exit 2; }
  key_args=(--key "$run_key")
  [ -n "$inner" ] || echo "launch.sh: run $(sed -n 's/^run //p' "$run_key"): every message signed with the key for it ($run_key)"
fi

# The outer launch.sh (not the copy run inside a namespace) owns the dashboard and the report.
# The dashboard follows the recording and the report is made from it: either records the run.
if [ -n "$dashboard_port" ] || [ "$report" = 1 ]; then record=1; fi
dashboard_pid=""
if [ -z "$inner" ] && [ -n "$dashboard_port" ]; then
  rm -f "$out/run.lcmlog"  # an earlier run's recording is not this one's
  if [ -x "$build/hbirl-dashboard" ]; then
    "$build/hbirl-dashboard" --log "$out/run.lcmlog" --port "$dashboard_port" "${domain_args[@]}" "${key_args[@]}" \
      >"$out/logs/dashboard.log" 2>&1 &
    dashboard_pid=$!
    sleep 0.3
    if kill -0 "$dashboard_pid" 2>/dev/null; then
      echo "launch.sh: dashboard: http://127.0.0.1:$dashboard_port/  (follows $out/run.lcmlog)"
    else
      echo "launch.sh: the dashboard did not start (see $out/logs/dashboard.log); going on without it" >&2
      dashboard_pid=""
    fi
  else
    echo "launch.sh: $build/hbirl-dashboard not built: no dashboard" >&2
  fi
fi
# Stops a process and waits for it, whatever its state: SIGTERM, SIGCONT (a stopped process
# acts on SIGTERM only once continued), and SIGKILL if it is still there after GRACE seconds
# (5 unless given; then the status is 1).
stop_process() {
  local pid="$1" grace="${2:-5}" _ status=0
  kill -TERM "$pid" 2>/dev/null || return 0
  kill -CONT "$pid" 2>/dev/null || true
  for _ in $(seq 1 $((grace * 10))); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  ! kill -KILL "$pid" 2>/dev/null || status=1
  wait "$pid" 2>/dev/null || true
  return "$status"
}
# The scheduler states of a process's threads, one letter each (R running, S asleep, D
# waiting on the disk, T or t stopped: proc(5)); bash alone, for it is asked 20 times a second.
thread_states() {
  local stat line states=""
  for stat in /proc/"$1"/task/*/stat; do
    read -r line 2>/dev/null <"$stat" || continue
    line="${line##*) }"  # after the command name, which may hold spaces and parentheses
    states+="${line%% *}"
  done
  echo "$states"
}
# The inodes of a process's sockets, space-separated (once: its sockets do not change).
socket_inodes() {
  local fd link inodes=""
  for fd in /proc/"$1"/fd/*; do
    link="$(readlink "$fd" 2>/dev/null)" || continue
    [[ "$link" =~ ^socket:\[([0-9]+)\]$ ]] && inodes+=" ${BASH_REMATCH[1]}"
  done
  echo "$inodes "
}
# A receiver has caught up with the bus: every thread asleep (none running or writing to
# the disk) and nothing waiting in the receive queues of its sockets (INODES, from
# socket_inodes; /proc/PID/net/udp: field 5 is tx_queue:rx_queue, field 10 the inode).
caught_up() {
  local pid="$1" inodes="$2" states _ queues rest inode
  states="$(thread_states "$pid")"
  if [ -z "$states" ] || [ -n "${states//S/}" ]; then return 1; fi
  while read -r _ _ _ _ queues _ _ _ _ inode rest; do
    [[ "$inodes" == *" $inode "* ]] || continue
    [[ "${queues#*:}" =~ ^0+$ ]] || return 1
  done <"/proc/$pid/net/udp"
}
stop_dashboard() {
  if [ -n "$dashboard_pid" ]; then stop_process "$dashboard_pid" || true; fi
  dashboard_pid=""
}
# After the run (outer launch.sh): the report, and the dashboard kept up or stopped.
finish() {
  local status="$1"
  trap 'stop_dashboard; exit 130' INT TERM
  if [ -z "$inner" ] && [ "$report" = 1 ] && [ "$record" = 1 ] && [ -f "$out/run.lcmlog" ] && [ -x "$build/hbirl" ]; then
    local report_status=0
    "$build/hbirl" report --log "$out/run.lcmlog" --out "$out/report" "${domain_args[@]}" "${key_args[@]}" \
      >/dev/null 2>"$out/logs/report.log" || report_status=$?
    case "$report_status" in
      0) echo "launch.sh: report: $out/report/index.html" ;;
      1) echo "launch.sh: report of the unfinished run: $out/report/index.html" ;;
      *) echo "launch.sh: the report could not be written (see $out/logs/report.log)" >&2 ;;
    esac
  fi
  if [ -n "$dashboard_pid" ] && [ "$keep_dashboard" = 1 ]; then
    echo "launch.sh: the dashboard stays up at http://127.0.0.1:$dashboard_port/ -- Ctrl-C to stop it"
    trap 'stop_dashboard' INT TERM
    wait "$dashboard_pid" 2>/dev/null || true
  fi
  stop_dashboard
  exit "$status"
}

# Where will multicast go? Only ever to loopback.
if [ -z "$url" ] && [ -z "${HBIRL_IN_NETNS:-}" ]; then
  if ip route get 239.255.76.67 2>/dev/null | grep -q " dev lo "; then
    echo "launch.sh: multicast is routed to loopback here: running on this machine's network (ttl=0)"
  elif unshare -rn true 2>/dev/null; then
    echo "launch.sh: multicast is not routed to loopback here: running the set in a private network namespace"
    echo "           (unshare -rn; lo up; ip route add 224.0.0.0/4 dev lo)"
    # In the background, so that a signal to this script reaches its trap at once, which
    # passes it on (the set's own launch.sh then stops its services).
    inner_args=("${orig_args[@]}" --out "$out" --build "$build")
    [ "$record" = 0 ] || inner_args+=(--record)
    [ "$key_mode" != none ] || inner_args+=(--no-key)
    [ "$key_mode" = none ] || inner_args+=(--key "$run_key")  # the run's key file, as it is
    # shellcheck disable=SC2016  # $0 and $@ are the inner shell's
    HBIRL_IN_NETNS=1 HBIRL_LAUNCH_INNER=1 unshare -rn -- bash -c \
      'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' \
      "${BASH_SOURCE[0]}" "${inner_args[@]}" &
    set_pid=$!
    # The process that holds the namespace: scripts/lcm-spy.sh --run OUT enters it.
    mkdir -p "$out/logs" && echo "$set_pid" >"$out/logs/netns.pid"
    trap 'end_progress; echo "launch.sh: interrupted: stopping the services"; kill -TERM "$set_pid" 2>/dev/null; wait "$set_pid" 2>/dev/null; rm -f "$out/logs/netns.pid"; stop_dashboard; exit 130' INT TERM
    set +e
    wait "$set_pid"
    status=$?
    set -e
    rm -f "$out/logs/netns.pid"
    trap - INT TERM
    finish "$status"
  else
    echo "launch.sh: multicast is not routed to loopback and private network namespaces are not allowed here." >&2
    echo "           Route it (as root): ip route add 224.0.0.0/4 dev lo   -- or pass --url." >&2
    stop_dashboard
    exit 1
  fi
fi
# A 2 MB receive buffer per socket (capped by net.core.rmem_max) rides out bursts and
# busy moments: a receiver that loses a message (lcm-logger above all: it cannot ask for
# it again) makes the recording differ from what the optimiser learned from.
[ -n "$url" ] || url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152"

# The supervisor: every service started with start() is watched, and one that dies (an
# exit status other than 0, or a signal) is started again with the same command, after a
# back-off of 0.5, 1, 2 s, at most $max_restarts times; the protocol asks again for what it
# lost (frames, end markers, E-step blocks), so the run still completes with the same
# result. A service alive but silent -- no heartbeat for --stall-timeout seconds: stopped
# (SIGSTOP) or blocked -- is killed and restarted the same way (each touches logs/NAME.alive
# once a second while it beats its heartbeat or computes, hbirl-services --alive-file).
# Exit 2 (bad input) and 3 (the run
# cannot be learned: incomplete, or contradicting itself) are not restarted: they fail the
# run. lcm-logger is not restarted (what it missed cannot be recorded again: the recording
# is then incomplete, and `hbirl learn --log` says so). logs/pids lists every process
# started, restarts included.
pids=()
names=()
cmds=()
restarts=()
max_restarts=3
supervised() { case "$1" in perception|labeller|sampler-*|optimiser|sim-driver) return 0 ;; *) return 1 ;; esac; }
run_service() {  # run_service INDEX: (re)start it in the background
  local i="$1" name="${names[$1]}" extra=""
  if supervised "$name"; then
    [ "${restarts[$i]}" = 0 ] || extra="--restarts ${restarts[$i]}"
    touch "$out/logs/$name.alive"  # its silence is counted from now
    extra+=" --alive-file $(printf '%q' "$out/logs/$name.alive")"
  fi
  if [ "$name" = optimiser ]; then  # stdout is its result, stderr its log
    eval "exec ${cmds[$i]} $extra" >>"$out/logs/optimiser.log" 2>>"$out/logs/optimiser.err" &
  else
    eval "exec ${cmds[$i]} $extra" >>"$out/logs/$name.log" 2>&1 &
  fi
  pids[i]=$!
  echo "$name ${pids[$i]}" >>"$out/logs/pids"
}
start() {  # start NAME COMMAND...: in the background, output to logs/NAME.log (emptied first: not an earlier run's)
  local name="$1"; shift
  local i="${#names[@]}"
  : >"$out/logs/$name.log"
  names[i]="$name"
  cmds[i]="$(printf '%q ' "$@")"
  restarts[i]=0
  run_service "$i"
}
: >"$out/logs/pids"
logger=""
stop_all() {  # the services, then the logger (it records their last heartbeats); never waits on a stopped one
  local pid _
  for pid in "${pids[@]}"; do [ "$pid" = "$logger" ] || { kill -TERM "$pid" 2>/dev/null && kill -CONT "$pid" 2>/dev/null; } || true; done
  for _ in $(seq 1 50); do
    local left=0
    for pid in "${pids[@]}"; do [ "$pid" = "$logger" ] || ! kill -0 "$pid" 2>/dev/null || left=1; done
    [ "$left" = 1 ] || break
    sleep 0.1
  done
  for pid in "${pids[@]}"; do [ "$pid" = "$logger" ] || kill -KILL "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do [ "$pid" = "$logger" ] || wait "$pid" 2>/dev/null || true; done
  if [ -n "$logger" ]; then
    # lcm-logger (1.3) drops the messages still in its write queue when it is stopped, and
    # the file's size says nothing of that queue (it writes through a stdio buffer, and a
    # disk busy with its fdatasync holds the queue for seconds; docs/RELIABILITY.md). Stop
    # it once it has caught up with what the services sent last (their last heartbeats),
    # 0.3 s in a row, after 30 s at most.
    local calm=0 inodes states deadline=$((SECONDS + 30))
    inodes="$(socket_inodes "$logger")"
    while [ "$SECONDS" -lt "$deadline" ]; do
      if caught_up "$logger" "$inodes"; then calm=$((calm + 1)); else calm=0; fi
      [ "$calm" -lt 6 ] || break
      states="$(thread_states "$logger")"
      if [ -z "$states" ] || [[ "$states" == *[Tt]* ]]; then break; fi  # gone, or stopped: it cannot catch up
      sleep 0.05
    done
    [ "$calm" -ge 6 ] || ! kill -0 "$logger" 2>/dev/null ||
      echo "launch.sh: lcm-logger had not caught up with the bus when it was stopped: the recording may lack the last messages" >&2
    stop_process "$logger" 30 || echo "launch.sh: lcm-logger did not stop in 30 s: killed; the recording may lack the last messages" >&2
  fi
}
trap 'end_progress; echo "launch.sh: interrupted: stopping the services"; stop_all; stop_dashboard; exit 130' INT TERM
trap 'end_progress; stop_all; stop_dashboard' EXIT

echo "launch.sh: logs and results in $out"
if [ "$record" = 1 ]; then
  start lcm-logger lcm-logger --lcm-url="$url" -f "$out/run.lcmlog"
  logger="${pids[-1]}"
fi
for i in $(seq 1 "$workers"); do
  sampler=("$build/hbirl-sampler" --url "$url" --id "sampler-$i" "${key_args[@]}")  # the MDP comes over the bus
  if [ "$i" = 1 ] && [ -n "$kill_worker_after_blocks" ]; then
    start "sampler-$i" "${sampler[@]}" --kill-self-after-blocks "$kill_worker_after_blocks"
    cmds[${#names[@]} - 1]="$(printf '%q ' "${sampler[@]}")"  # (testing) restarted, it does not kill itself again
  else
    start "sampler-$i" "${sampler[@]}"
  fi
done
if [ "$no_sim" = 0 ]; then
  for service in $listeners; do
    case "$service" in
      perception) start perception "$build/hbirl-perception" --url "$url" "${key_args[@]}" ;;
      labeller) start labeller "$build/hbirl-labeller" --url "$url" "${domain_args[@]}" "${key_args[@]}" ;;
    esac
  done
fi
: >"$out/logs/optimiser.log"
: >"$out/logs/optimiser.err"
optimiser_args=(--incomplete-after-ms "$((incomplete_after * 1000))")
# Live estimates carry a confidence from 100 posterior draws (learner/reward_posterior.hpp's
# kLiveConfidenceDraws, as the stopping experiment; docs/MODEL.md).
[ "${#stop_args[@]}" = 0 ] || optimiser_args+=("${stop_args[@]}" --posterior-samples 100)
[ "$allow_incomplete" = 0 ] || optimiser_args+=(--allow-incomplete)
# The recording is complete whenever the run is: the optimiser asks again for what
# lcm-logger lost (a receiver like any other, but one that cannot ask itself).
[ "$record" = 0 ] || optimiser_args+=(--recording "$out/run.lcmlog")
start optimiser "$build/hbirl-optimiser" --url "$url" --workers "$workers" "${domain_args[@]}" "${key_args[@]}" "${learn_eta_args[@]}" \
  "${optimiser_args[@]}" --out "$out/result.json"
optimiser_index=$((${#names[@]} - 1))
if [ "$no_sim" = 0 ]; then
  # Each domain's simulator reads the options that concern it.
  start sim-driver "$build/hbirl-sim-driver" --url "$url" "${domain_args[@]}" "${key_args[@]}" --config "$config" --sorts "$sorts" \
    --controlled-sorts "$controlled_sorts" --fps "$fps" --confounders "$confounders" --trajectories "$trajectories" \
    --eta "$eta" --seed "$seed" --max-frames-per-second "$max_fps"
elif [ -n "$sensor" ]; then
  # A Python sensor finds `import hbirl` in the build (examples/python/sensor.py).
  [ ! -d "$build/python/hbirl" ] || export PYTHONPATH="$build/python${PYTHONPATH:+:$PYTHONPATH}"
  if [ "${sensor_key:-0}" = 1 ] && [ "$key_mode" != none ]; then
    start sensor bash -c "$sensor --url \"\$0\" --key \"\$1\"" "$url" "$run_key"
  else
    start sensor bash -c "$sensor --url \"\$0\"" "$url"
  fi
else
  echo "launch.sh: no simulator (--no-sim): waiting for a sensor on $url (hbirl publish --problem F --url '$url'$([ "$key_mode" = none ] || printf ' --key %q' "$run_key"))"
fi


failed=0
finished=()
optimiser_done=0
describe() { if [ "$1" -gt 128 ]; then echo "killed by signal $(($1 - 128))"; else echo "exit $1"; fi; }
# Watch everything until the optimiser is done: a service that dies is restarted (above);
# one that dies more than $max_restarts times, or anything else that fails, fails the run
# at once; so does running past --timeout.
# Silent: running, but no heartbeat (its alive file untouched) for $stall seconds.
silent() {
  [ "$stall" != 0 ] && supervised "${names[$1]}" && [ "$out/logs/${names[$1]}.alive" -ot "$out/logs/.stall" ]
}
check_services() {
  [ "$stall" = 0 ] || touch -d "@$(($(date +%s) - stall))" "$out/logs/.stall"
  for i in "${!pids[@]}"; do
    [ -n "${finished[$i]:-}" ] && continue
    name="${names[$i]}"
    if kill -0 "${pids[$i]}" 2>/dev/null; then
      silent "$i" || continue
      # Alive but silent: stopped or hung. SIGKILL works on a stopped process too.
      kill -KILL "${pids[$i]}" 2>/dev/null || true
      set +e; wait "${pids[$i]}"; set -e
      s=137
      why="silent for over $stall s: stopped or hung; killed"
    else
      set +e; wait "${pids[$i]}"; s=$?; set -e
      why="$(describe "$s")"
    fi
    if [ "$s" = 0 ]; then
      finished[i]=1
      [ "$i" = "$optimiser_index" ] && optimiser_done=1
      continue
    fi
    if supervised "$name" && [ "$s" != 2 ] && [ "$s" != 3 ] && [ "${restarts[$i]}" -lt "$max_restarts" ]; then
      restarts[i]=$((restarts[i] + 1))
      delay="$(awk -v k="${restarts[$i]}" 'BEGIN { print 0.5 * 2 ^ (k - 1) }')"
      end_progress
      echo "launch.sh: $name died ($why); restarting it in $delay s (restart ${restarts[$i]} of $max_restarts)" >&2
      sleep "$delay"
      run_service "$i"
      continue
    fi
    finished[i]=1
    if [ "$name" = lcm-logger ]; then
      end_progress
      echo "launch.sh: lcm-logger died ($why): the recording $out/run.lcmlog is incomplete" >&2
      continue
    fi
    if [ "$name" = optimiser ] && [ "$s" = 3 ]; then
      end_progress
      echo "launch.sh: $(tail -n 1 "$out/logs/optimiser.err")" >&2
    elif supervised "$name" && [ "$s" != 2 ] && [ "$s" != 3 ]; then
      end_progress
      echo "launch.sh: $name died $((max_restarts + 1)) times (last: $why); giving up: see $out/logs/$name.log" >&2
    else
      end_progress
      echo "launch.sh: $name failed ($why); see $out/logs/$name.log" >&2
    fi
    failed=1
  done
}
# A service that refused the first messages of a sensor's kind, every one (another domain's
# name, another alphabet: Counters::all_refused in services/typed.hpp writes this line),
# cannot make the run: said at once, with the first reason, rather than at --timeout.
refused_all() {  # only the watching services' own lines (a message's text cannot begin a line: it is escaped)
  grep -h -m1 -E -- "^(optimiser|perception|labeller): refused every message on [A-Z_]+: the first [0-9]+, none accepted; " \
    "$out/logs/optimiser.err" "$out/logs/perception.log" "$out/logs/labeller.log" 2>/dev/null | head -n 1 || true
}
# The optimiser's progress (its "progress:" lines on stderr: collecting, then each EM
# iteration's log-likelihood), the newest shown every few seconds while the run lasts.
# In a terminal the line is rewritten in place (the demo's output then fits a screen); in
# a log, each is a line of its own.
shown_progress=""
show_progress() {
  local line
  line="$(tail -n 40 "$out/logs/optimiser.err" 2>/dev/null | grep -F "hbirl-optimiser: progress: " | tail -n 1 || true)"
  [ -n "$line" ] && [ "$line" != "$shown_progress" ] || return 0
  shown_progress="$line"
  if [ -t 1 ]; then
    # Cut to the terminal's width: a line that wraps cannot be rewritten in place.
    local cols
    cols="$(tput cols 2>/dev/null || echo 80)"
    line="launch.sh: ${line#hbirl-optimiser: progress: }"
    printf '\r\033[K%s' "${line:0:$((cols - 1))}"
    progress_open=1
  else
    echo "launch.sh: ${line#hbirl-optimiser: progress: }"
  fi
}
deadline=$((SECONDS + timeout))
next_refusal_check=0
while [ "$optimiser_done" = 0 ]; do
  check_services
  if [ "$failed" = 1 ]; then break; fi
  if [ "$SECONDS" -ge "$next_refusal_check" ]; then
    next_refusal_check=$((SECONDS + 1))
    show_progress
    refusal="$(refused_all)"
    if [ -n "$refusal" ]; then
      end_progress
      echo "launch.sh: $refusal; stopping (logs: $out/logs)" >&2
      failed=1
      break
    fi
  fi
  if [ "$SECONDS" -ge "$deadline" ]; then
    end_progress
    echo "launch.sh: no result after $timeout s (--timeout); stopping" >&2
    failed=1
    break
  fi
  sleep 0.2
done
end_progress
[ "$failed" = 1 ] || check_services
restarted=""
for i in "${!names[@]}"; do [ "${restarts[$i]}" = 0 ] || restarted+=" ${names[$i]} (${restarts[$i]})"; done
[ -z "$restarted" ] || echo "launch.sh: restarted during the run:$restarted"
stop_all
trap - INT TERM EXIT

if [ "$failed" = 0 ] && [ -f "$out/result.json" ]; then
  # A summary a person reads (hbirl summary); the full record stays in result.json.
  "$build/hbirl" summary "$out/result.json" || cat "$out/result.json"
  echo "launch.sh: the full result: $out/result.json; logs: $out/logs"
  if grep -q '"incomplete":' "$out/result.json"; then
    missing="$(sed -n 's/^ *"incomplete": "\(.*\)",*$/\1/p' "$out/result.json")"
    if [ "$allow_incomplete" = 1 ]; then
      echo "launch.sh: learned from an incomplete run, as --allow-incomplete allows: $missing" >&2
    else
      echo "launch.sh: the run is incomplete ($missing): not a success" >&2
      failed=1
    fi
  fi
  if [ "$record" = 1 ]; then
    replay="$(printf '%q ' "$build/hbirl" learn --log "$out/run.lcmlog" "${key_args[@]}")"
    echo "launch.sh: recorded $out/run.lcmlog; replay: ${replay% }"
  fi
fi
finish "$failed"
