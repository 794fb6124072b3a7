#!/usr/bin/env bash
# The README's dashboard screenshot, from a real run: the onion demo (services/launch.sh
# with --anytime and any options given here) in a private network namespace of its own,
# its dashboard opened in headless Chromium (tests/dashboard/browser_check.py) once every
# panel shows data and the run has finished, saved as docs/dashboard.png (or --out FILE).
#   scripts/dashboard-screenshot.sh [--out FILE] [--build DIR] [launch.sh options...]
# Needs what ./test.sh installs (chromium, chromium-driver) and a build (./demo.sh).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$repo/docs/dashboard.png"
build="$repo/build"
launch_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$(realpath -m "${2:?--out needs a file}")"; shift 2 ;;
    --build) build="$(realpath -m "${2:?--build needs a folder}")"; shift 2 ;;
    -h|--help) sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) launch_args+=("$1"); shift ;;
  esac
done
for tool in chromium chromedriver; do
  command -v "$tool" >/dev/null || { echo "dashboard-screenshot: $tool not installed (./test.sh installs it)" >&2; exit 2; }
done
[ -x "$build/hbirl-dashboard" ] || { echo "dashboard-screenshot: no $build/hbirl-dashboard (run ./demo.sh first)" >&2; exit 2; }

source "$repo/tests/in_private_netns.sh"

tmp="$(mktemp -d)"
launch=""
trap '[ -n "$launch" ] && kill -TERM "$launch" 2>/dev/null; wait 2>/dev/null; rm -rf "$tmp"' EXIT
port=8765  # the namespace's own loopback
"$repo/services/launch.sh" --build "$build" --out "$tmp/run" --anytime --dashboard-port "$port" --keep-dashboard \
  "${launch_args[@]}" >"$tmp/launch.out" 2>&1 &
launch=$!
if ! HOME="$tmp" python3 "$repo/tests/dashboard/browser_check.py" "http://127.0.0.1:$port/" "$tmp/dashboard.png" 600 \
  "$tmp/run/result.json"; then
  echo "dashboard-screenshot: no screenshot; the run said:" >&2
  cat "$tmp/launch.out" >&2
  exit 1
fi
mkdir -p "$(dirname "$out")"
cp "$tmp/dashboard.png" "$out"
echo "dashboard-screenshot: $out (run: $(grep -m1 '^Learned on' "$tmp/launch.out" || echo 'see above'))"
