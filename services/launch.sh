#!/usr/bin/env bash
# Starts hbirl's service set -- simulator, perception and labeller (onion), sampler
# workers, optimiser -- waits for the optimiser to learn, prints the learned reward and shuts
# everything down (also on Ctrl-C). Exits non-zero if any service failed.
#
# LCM talks UDP multicast. Where multicast to loopback is not routed (the usual case in
# containers), the set runs in a private network namespace of its own (unshare -rn, lo
# up, 224.0.0.0/4 routed to lo): nothing leaves the machine and other runs do not see
# it. See --help.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$here")"
build="$repo/build"
workers=2
domain=onion
confounders=3
trajectories=20
eta=plausible
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

usage() {
  cat <<USAGE
usage: services/launch.sh [options]

Runs a demo as separate processes over LCM and prints the learned reward.
  --domain D             onion (camera frames -> perception -> labeller -> learner) or
                         gridworld (the paper's 5x5 Gridworld; its simulator publishes the
                         observations itself) (default $domain)
  --workers N            sampler workers (default $workers)
  --seed S               seed of the run (default $seed)
 onion:
  --config C             demonstrations' scene: all, controlled, or a list of
                         blue-shirt, other-onions, foreground, mirror (default $config)
  --sorts N              demonstrated sorts (default $sorts)
  --controlled-sorts N   sorts in the controlled run that gives the subject prior ($controlled_sorts)
  --fps F                camera frames per simulated second (default $fps)
  --max-fps F            pacing of the camera, frames per wall-clock second (default $max_fps;
                         gridworld: steps per second)
 gridworld:
  --confounders N        confounding elements |E| (default $confounders)
  --trajectories N       demonstrations (default $trajectories)
  --eta K                plausible or uniform (default $eta)
 both:
  --record               record every message with lcm-logger to OUT/run.lcmlog
                         (replay: build/hbirl learn --log OUT/run.lcmlog)
  --out DIR              where logs and results go (default runs/<date-time>)
  --build DIR            the build folder with hbirl-services (default build/)
  --url URL              an LCM URL to use instead of a private network namespace, e.g.
                         udpm://239.255.76.67:7667?ttl=1 to include workers on other
                         machines (they run: hbirl-sampler --url URL)
  --timeout S            give up (and fail) when there is no result after S seconds (default $timeout)
  --kill-worker-after-blocks N
                         (testing) the first worker SIGKILLs itself after computing N blocks
USAGE
}

while [ $# -gt 0 ]; do
  case "$1" in
    --workers) workers="$2"; shift 2 ;;
    --domain) domain="$2"; shift 2 ;;
    --confounders) confounders="$2"; shift 2 ;;
    --trajectories) trajectories="$2"; shift 2 ;;
    --eta) eta="$2"; shift 2 ;;
    --config) config="$2"; shift 2 ;;
    --sorts) sorts="$2"; shift 2 ;;
    --controlled-sorts) controlled_sorts="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --fps) fps="$2"; shift 2 ;;
    --max-fps) max_fps="$2"; shift 2 ;;
    --record) record=1; shift ;;
    --out) out="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --url) url="$2"; shift 2 ;;
    --kill-worker-after-blocks) kill_worker_after_blocks="$2"; shift 2 ;;
    --timeout) timeout="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "launch.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

case "$domain" in
  onion|gridworld) ;;
  *) echo "launch.sh: --domain must be onion or gridworld, not '$domain'" >&2; exit 2 ;;
esac
bin="$build/hbirl-services"
if [ ! -x "$bin" ]; then
  echo "launch.sh: $bin not found: build first (cmake -S . -B build && cmake --build build -j)" >&2
  exit 2
fi
[ -n "$out" ] || out="$repo/runs/$(date +%Y%m%d-%H%M%S)"
mkdir -p "$out/logs"
out="$(cd "$out" && pwd)"

# Where will multicast go? Only ever to loopback.
if [ -z "$url" ] && [ -z "${HBIRL_IN_NETNS:-}" ]; then
  if ip route get 239.255.76.67 2>/dev/null | grep -q " dev lo "; then
    echo "launch.sh: multicast is routed to loopback here: running on this machine's network (ttl=0)"
  elif unshare -rn true 2>/dev/null; then
    echo "launch.sh: multicast is not routed to loopback here: running the set in a private network namespace"
    echo "           (unshare -rn; lo up; ip route add 224.0.0.0/4 dev lo)"
    export HBIRL_IN_NETNS=1
    exec unshare -rn -- bash -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' \
      "${BASH_SOURCE[0]}" --out "$out" --domain "$domain" --confounders "$confounders" --trajectories "$trajectories" \
      --eta "$eta" --workers "$workers" --config "$config" --sorts "$sorts" \
      --controlled-sorts "$controlled_sorts" --seed "$seed" --fps "$fps" --max-fps "$max_fps" --build "$build" --timeout "$timeout" \
      $([ "$record" = 1 ] && echo --record) ${kill_worker_after_blocks:+--kill-worker-after-blocks "$kill_worker_after_blocks"}
  else
    echo "launch.sh: multicast is not routed to loopback and private network namespaces are not allowed here." >&2
    echo "           Route it (as root): ip route add 224.0.0.0/4 dev lo   -- or pass --url." >&2
    exit 1
  fi
fi
[ -n "$url" ] || url="udpm://239.255.76.67:7667?ttl=0"

pids=()
names=()
start() {  # start NAME COMMAND...: in the background, output to logs/NAME.log
  local name="$1"; shift
  "$@" >"$out/logs/$name.log" 2>&1 &
  pids+=($!)
  names+=("$name")
}
stop_all() {
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
}
trap 'echo "launch.sh: interrupted: stopping the services"; stop_all; exit 130' INT TERM
trap 'stop_all' EXIT

echo "launch.sh: logs and results in $out"
if [ "$record" = 1 ]; then
  start lcm-logger lcm-logger --lcm-url="$url" -f "$out/run.lcmlog"
fi
for i in $(seq 1 "$workers"); do
  if [ "$i" = 1 ] && [ -n "$kill_worker_after_blocks" ]; then
    start "sampler-$i" "$build/hbirl-sampler" --url "$url" --domain "$domain" --id "sampler-$i" \
      --kill-self-after-blocks "$kill_worker_after_blocks"
  else
    start "sampler-$i" "$build/hbirl-sampler" --url "$url" --domain "$domain" --id "sampler-$i"
  fi
done
if [ "$domain" = onion ]; then
  start labeller "$build/hbirl-labeller" --url "$url"
  start perception "$build/hbirl-perception" --url "$url"
fi
"$build/hbirl-optimiser" --url "$url" --workers "$workers" --out "$out/result.json" >"$out/logs/optimiser.log" 2>"$out/logs/optimiser.err" &
optimiser=$!
pids+=("$optimiser")
names+=(optimiser)
if [ "$domain" = onion ]; then
  start sim-driver "$build/hbirl-sim-driver" --url "$url" --domain onion --config "$config" --sorts "$sorts" \
    --controlled-sorts "$controlled_sorts" --seed "$seed" --fps "$fps" --max-frames-per-second "$max_fps"
else
  start sim-driver "$build/hbirl-sim-driver" --url "$url" --domain gridworld --confounders "$confounders" \
    --trajectories "$trajectories" --eta "$eta" --seed "$seed" --max-frames-per-second "$max_fps"
fi


failed=0
checked=()
# Watch everything until the optimiser is done: a service that dies with an error (except
# a worker we asked to die) fails the run at once; so does running past --timeout.
check_services() {
  for i in "${!pids[@]}"; do
    [ "${pids[$i]}" = "$optimiser" ] && continue
    [ -n "${checked[$i]:-}" ] && continue
    if ! kill -0 "${pids[$i]}" 2>/dev/null; then
      checked[$i]=1
      set +e; wait "${pids[$i]}"; s=$?; set -e
      if [ "$s" -ne 0 ] && ! { [ -n "$kill_worker_after_blocks" ] && [ "${names[$i]}" = sampler-1 ]; }; then
        echo "launch.sh: ${names[$i]} failed (exit $s); see $out/logs/${names[$i]}.log" >&2
        failed=1
      fi
    fi
  done
}
deadline=$((SECONDS + timeout))
while kill -0 "$optimiser" 2>/dev/null; do
  check_services
  if [ "$failed" = 1 ]; then break; fi
  if [ "$SECONDS" -ge "$deadline" ]; then
    echo "launch.sh: no result after $timeout s (--timeout); stopping" >&2
    failed=1
    break
  fi
  sleep 0.2
done
if [ "$failed" = 0 ]; then
  set +e
  wait "$optimiser"
  status=$?
  set -e
  if [ "$status" -ne 0 ]; then
    echo "launch.sh: the optimiser failed (exit $status); see $out/logs/optimiser.err" >&2
    failed=1
  fi
  check_services
fi
stop_all
trap - INT TERM EXIT

if [ "$failed" = 0 ] && [ -f "$out/result.json" ]; then
  echo "launch.sh: learned (also in $out/result.json):"
  cat "$out/result.json"
  [ "$record" = 1 ] && echo "launch.sh: recorded $out/run.lcmlog; replay: $build/hbirl learn --log $out/run.lcmlog"
fi
exit "$failed"
