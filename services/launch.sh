#!/usr/bin/env bash
# Starts hbirl's service set -- simulator, perception and labeller (a camera's domain),
# sampler workers, optimiser -- and the dashboard, waits for the optimiser to learn, prints the
# learned reward, writes the report and shuts everything down (also on Ctrl-C). Exits
# non-zero if any service failed.
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
orig_args=("$@")

usage() {
  cat <<USAGE
usage: services/launch.sh [options]

Runs a demo as separate processes over LCM and prints the learned reward.
  --domain D             onion (camera frames -> perception -> labeller -> learner),
                         gridworld (the paper's Gridworld; its simulator publishes the
                         observations itself), or a domain file (README.md "Your own task":
                         its simulated sensor publishes the observations) (default $domain)
  --size N               gridworld: cells a side (default $size)
  --no-sim               no simulator: the learning side only (optimiser, workers, dashboard),
                         waiting for a sensor that publishes EPISODE, OBSERVATIONS (and
                         GROUND_TRUTH for controlled episodes) -- e.g. hbirl publish
  --sensor CMD           with --no-sim: run CMD as the sensor inside the set (its LCM URL is
                         appended as --url URL), e.g. "build/hbirl publish --problem F"
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
                         (replay: build/hbirl learn --log OUT/run.lcmlog); on with the dashboard
  --dashboard-port P     serve the live dashboard on http://127.0.0.1:P/ (default $dashboard_port)
  --no-dashboard         no dashboard
  --keep-dashboard       after the run, keep the dashboard up until Ctrl-C
  --no-report            do not write the static report (OUT/report/index.html)
  --out DIR              where logs and results go (default runs/<date-time>)
  --build DIR            the build folder with hbirl-services (default build/)
  --url URL              an LCM URL to use instead of a private network namespace, e.g.
                         udpm://239.255.76.67:7667?ttl=1 to include workers on other
                         machines (they run: hbirl-sampler --url URL)
  --timeout S            give up (and fail) when there is no result after S seconds (default $timeout)
  --key FILE             the run's key (hbirl keygen FILE). By default a fresh one is written to
                         OUT/run.key (mode 0600) for every run whose sensor is the set's own
                         simulator (or --sensor-key): every service, the recording's readers and
                         the dashboard then believe only messages signed with it
                         (docs/RELIABILITY.md). A run waiting for an outside sensor is
                         unauthenticated unless --key is given (the sensor must sign with it)
  --no-key               no key: the bus is unauthenticated (every service says so)
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

# The run's key: made once, by the outer launch.sh, and handed to the copy in the namespace.
inner="${HBIRL_LAUNCH_INNER:-}"
if [ "$key_mode" = auto ]; then
  if [ "$no_sim" = 1 ] && [ "${sensor_key:-0}" = 0 ]; then
    key_mode=none
    echo "launch.sh: the sensor is outside the set: the bus is unauthenticated (--key FILE, with a sensor that signs, makes it authenticated)"
  elif [ -z "$inner" ]; then
    key="$out/run.key"
    rm -f "$key"
    "$build/hbirl" keygen "$key" 2>/dev/null || { echo "launch.sh: could not write the run key $key" >&2; exit 2; }
    key_mode=given
  fi
fi
key_args=()
if [ "$key_mode" = given ]; then
  [ -f "$key" ] || { echo "launch.sh: --key: $key not found" >&2; exit 2; }
  key="$(cd "$(dirname "$key")" && pwd)/$(basename "$key")"
  key_args=(--key "$key")
fi

# The outer launch.sh (not the copy run inside a namespace) owns the dashboard and the report.
[ -z "$dashboard_port" ] || record=1  # the dashboard follows the recording
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
stop_dashboard() {
  if [ -n "$dashboard_pid" ]; then kill -TERM "$dashboard_pid" 2>/dev/null || true; wait "$dashboard_pid" 2>/dev/null || true; fi
  dashboard_pid=""
}
# After the run (outer launch.sh): the report, and the dashboard kept up or stopped.
finish() {
  local status="$1"
  trap 'stop_dashboard; exit 130' INT TERM
  if [ -z "$inner" ] && [ "$report" = 1 ] && [ "$record" = 1 ] && [ -f "$out/run.lcmlog" ] && [ -x "$build/hbirl" ]; then
    if "$build/hbirl" report --log "$out/run.lcmlog" --out "$out/report" "${domain_args[@]}" "${key_args[@]}" \
      >/dev/null 2>"$out/logs/report.log"; then
      echo "launch.sh: report: $out/report/index.html"
    else
      echo "launch.sh: the report could not be written (see $out/logs/report.log)" >&2
    fi
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
    HBIRL_IN_NETNS=1 HBIRL_LAUNCH_INNER=1 unshare -rn -- bash -c \
      'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' \
      "${BASH_SOURCE[0]}" "${orig_args[@]}" --out "$out" --build "$build" $([ "$record" = 1 ] && echo --record) \
      $([ "$key_mode" = given ] && echo --key "$key") $([ "$key_mode" = none ] && echo --no-key) &
    set_pid=$!
    trap 'echo "launch.sh: interrupted: stopping the services"; kill -TERM "$set_pid" 2>/dev/null; wait "$set_pid" 2>/dev/null; stop_dashboard; exit 130' INT TERM
    set +e
    wait "$set_pid"
    status=$?
    set -e
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
# result. lcm-logger is not restarted (what it missed cannot be recorded again: the
# recording is then incomplete, and `hbirl learn --log` says so). logs/pids lists every
# process started, restarts included.
pids=()
names=()
cmds=()
restarts=()
max_restarts=3
supervised() { case "$1" in perception|labeller|sampler-*|optimiser|sim-driver) return 0 ;; *) return 1 ;; esac; }
run_service() {  # run_service INDEX: (re)start it in the background
  local i="$1" name="${names[$1]}" extra=""
  supervised "$name" && [ "${restarts[$i]}" -gt 0 ] && extra="--restarts ${restarts[$i]}"
  if [ "$name" = optimiser ]; then  # stdout is its result, stderr its log
    eval "exec ${cmds[$i]} $extra" >>"$out/logs/optimiser.log" 2>>"$out/logs/optimiser.err" &
  else
    eval "exec ${cmds[$i]} $extra" >>"$out/logs/$name.log" 2>&1 &
  fi
  pids[$i]=$!
  echo "$name ${pids[$i]}" >>"$out/logs/pids"
}
start() {  # start NAME COMMAND...: in the background, output to logs/NAME.log
  local name="$1"; shift
  local i="${#names[@]}"
  names[$i]="$name"
  cmds[$i]="$(printf '%q ' "$@")"
  restarts[$i]=0
  run_service "$i"
}
: >"$out/logs/pids"
logger=""
stop_all() {  # the services, then the logger (it records their last heartbeats)
  for pid in "${pids[@]}"; do [ "$pid" = "$logger" ] || kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do [ "$pid" = "$logger" ] || wait "$pid" 2>/dev/null || true; done
  if [ -n "$logger" ]; then
    sleep 0.2
    kill -TERM "$logger" 2>/dev/null || true
    wait "$logger" 2>/dev/null || true
  fi
}
trap 'echo "launch.sh: interrupted: stopping the services"; stop_all; stop_dashboard; exit 130' INT TERM
trap 'stop_all; stop_dashboard' EXIT

echo "launch.sh: logs and results in $out"
if [ "$record" = 1 ]; then
  start lcm-logger lcm-logger --lcm-url="$url" -f "$out/run.lcmlog"
  logger="${pids[-1]}"
fi
for i in $(seq 1 "$workers"); do
  sampler=("$build/hbirl-sampler" --url "$url" --id "sampler-$i" "${key_args[@]}")  # the MDP comes over the bus
  if [ "$i" = 1 ] && [ -n "$kill_worker_after_blocks" ]; then
    start "sampler-$i" "${sampler[@]}" --kill-self-after-blocks "$kill_worker_after_blocks"
    cmds[$((${#names[@]} - 1))]="$(printf '%q ' "${sampler[@]}")"  # (testing) restarted, it does not kill itself again
  else
    start "sampler-$i" "${sampler[@]}"
  fi
done
if [ "$no_sim" = 0 ]; then
  for service in $listeners; do
    case "$service" in
      perception|labeller) start "$service" "$build/hbirl-$service" --url "$url" "${key_args[@]}" ;;
    esac
  done
fi
: >"$out/logs/optimiser.log"
: >"$out/logs/optimiser.err"
start optimiser "$build/hbirl-optimiser" --url "$url" --workers "$workers" "${domain_args[@]}" "${key_args[@]}" "${learn_eta_args[@]}" --out "$out/result.json"
optimiser_index=$((${#names[@]} - 1))
if [ "$no_sim" = 0 ]; then
  # Each domain's simulator reads the options that concern it.
  start sim-driver "$build/hbirl-sim-driver" --url "$url" "${domain_args[@]}" "${key_args[@]}" --config "$config" --sorts "$sorts" \
    --controlled-sorts "$controlled_sorts" --fps "$fps" --confounders "$confounders" --trajectories "$trajectories" \
    --eta "$eta" --seed "$seed" --max-frames-per-second "$max_fps"
elif [ -n "$sensor" ]; then
  if [ "${sensor_key:-0}" = 1 ] && [ "$key_mode" = given ]; then
    start sensor bash -c "$sensor --url \"\$0\" --key \"\$1\"" "$url" "$key"
  else
    start sensor bash -c "$sensor --url \"\$0\"" "$url"
  fi
else
  echo "launch.sh: no simulator (--no-sim): waiting for a sensor on $url (hbirl publish --problem F --url '$url')"
fi


failed=0
finished=()
optimiser_done=0
describe() { if [ "$1" -gt 128 ]; then echo "killed by signal $(($1 - 128))"; else echo "exit $1"; fi; }
# Watch everything until the optimiser is done: a service that dies is restarted (above);
# one that dies more than $max_restarts times, or anything else that fails, fails the run
# at once; so does running past --timeout.
check_services() {
  for i in "${!pids[@]}"; do
    [ -n "${finished[$i]:-}" ] && continue
    kill -0 "${pids[$i]}" 2>/dev/null && continue
    set +e; wait "${pids[$i]}"; s=$?; set -e
    name="${names[$i]}"
    if [ "$s" = 0 ]; then
      finished[$i]=1
      [ "$i" = "$optimiser_index" ] && optimiser_done=1
      continue
    fi
    if supervised "$name" && [ "${restarts[$i]}" -lt "$max_restarts" ]; then
      restarts[$i]=$((restarts[$i] + 1))
      delay="$(awk -v k="${restarts[$i]}" 'BEGIN { print 0.5 * 2 ^ (k - 1) }')"
      echo "launch.sh: $name died ($(describe "$s")); restarting it in $delay s (restart ${restarts[$i]} of $max_restarts)" >&2
      sleep "$delay"
      run_service "$i"
      continue
    fi
    finished[$i]=1
    if [ "$name" = lcm-logger ]; then
      echo "launch.sh: lcm-logger died ($(describe "$s")): the recording $out/run.lcmlog is incomplete" >&2
      continue
    fi
    if supervised "$name"; then
      echo "launch.sh: $name died $((max_restarts + 1)) times (last: $(describe "$s")); giving up: see $out/logs/$name.log" >&2
    else
      echo "launch.sh: $name failed ($(describe "$s")); see $out/logs/$name.log" >&2
    fi
    failed=1
  done
}
deadline=$((SECONDS + timeout))
while [ "$optimiser_done" = 0 ]; do
  check_services
  if [ "$failed" = 1 ]; then break; fi
  if [ "$SECONDS" -ge "$deadline" ]; then
    echo "launch.sh: no result after $timeout s (--timeout); stopping" >&2
    failed=1
    break
  fi
  sleep 0.2
done
[ "$failed" = 1 ] || check_services
restarted=""
for i in "${!names[@]}"; do [ "${restarts[$i]}" = 0 ] || restarted+=" ${names[$i]} (${restarts[$i]})"; done
[ -z "$restarted" ] || echo "launch.sh: restarted during the run:$restarted"
stop_all
trap - INT TERM EXIT

if [ "$failed" = 0 ] && [ -f "$out/result.json" ]; then
  echo "launch.sh: learned (also in $out/result.json):"
  cat "$out/result.json"
  [ "$record" = 1 ] && echo "launch.sh: recorded $out/run.lcmlog; replay: $build/hbirl learn --log $out/run.lcmlog ${key_args[*]}"
fi
finish "$failed"
