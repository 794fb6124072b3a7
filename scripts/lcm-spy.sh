#!/usr/bin/env bash
# lcm-spy -- LCM's live message browser -- with hbirl's message types
# (build/lcmtypes/lcmtypes_hbirl.jar, docs/services.md "LCM's own tools"), on:
#   scripts/lcm-spy.sh [--build DIR] [--url URL]       the bus of this network namespace
#   scripts/lcm-spy.sh [--build DIR] --run OUT         a run of services/launch.sh, also one it
#                                                      ran in a private network namespace
#   scripts/lcm-spy.sh [--build DIR] --log RUN.lcmlog  a recording, played by lcm-logplayer-gui
#                                                      in a private namespace lcm-spy shares
# Debian's lcm-spy and lcm-logplayer-gui scripts pass -Xincgc, which Java 17 refuses, and
# ignore CLASSPATH: the tools are started here with java directly.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
build="$here/../build"
url=""
run=""
log=""
usage() { sed -n '2,10p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --url) url="$2"; shift 2 ;;
    --run) run="$2"; shift 2 ;;
    --log) log="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "lcm-spy.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
jar="$build/lcmtypes/lcmtypes_hbirl.jar"
for f in /usr/share/java/lcm.jar /usr/share/java/jchart2d.jar; do
  [ -f "$f" ] || { echo "lcm-spy.sh: $f is missing: apt-get install liblcm-java libjchart2d-java" >&2; exit 1; }
done
[ -f "$jar" ] || { echo "lcm-spy.sh: $jar is missing: install a JDK (apt-get install default-jdk-headless) and build again" >&2; exit 1; }
command -v java >/dev/null || { echo "lcm-spy.sh: java is missing: apt-get install default-jdk-headless" >&2; exit 1; }
[ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] || { echo "lcm-spy.sh: lcm-spy is a window: it needs a display (DISPLAY is not set)" >&2; exit 1; }
classpath="/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:$jar"
spy=(java -Djava.net.preferIPv4Stack=true -Xmx256m -cp "$classpath" lcm.spy.Spy)
[ -z "$url" ] || spy+=(--lcm-url="$url")

if [ -n "$log" ]; then
  [ -f "$log" ] || { echo "lcm-spy.sh: --log: '$log' is not a file" >&2; exit 2; }
  # A namespace of its own: the replay reaches lcm-spy and nothing else.
  # shellcheck disable=SC2016  # the inner shell's $0 and $@
  exec unshare -rn -- bash -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo || exit 1
    java -Djava.net.preferIPv4Stack=true -cp "$0" lcm.logging.LogPlayer "$1" & player=$!; shift
    "$@"; status=$?; kill "$player" 2>/dev/null; exit "$status"' \
    "$classpath" "$log" "${spy[@]}"
fi
if [ -n "$run" ]; then
  # launch.sh in a private network namespace says which process holds it (logs/netns.pid).
  if [ -f "$run/logs/netns.pid" ]; then
    pid="$(cat "$run/logs/netns.pid")"
    # (still the run's launch.sh, not a process that took its number since)
    if ! kill -0 "$pid" 2>/dev/null || ! tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null | grep -q "launch.sh"; then
      echo "lcm-spy.sh: the run in $run has ended (its namespace is gone): spy on its recording with --log" >&2
      exit 1
    fi
    if [ "$(id -u)" = 0 ]; then
      exec nsenter -t "$pid" -n -- "${spy[@]}"
    fi
    exec nsenter -t "$pid" -U -n --preserve-credentials -- "${spy[@]}"
  fi
fi
exec "${spy[@]}"
