#!/usr/bin/env bash
# The dashboard in a browser (issue 6). Inside a private network namespace of its own, the
# onion demo runs with its dashboard (services/launch.sh); headless Chromium opens the
# page while the run goes on, waits until every panel shows data, fails on any console
# error and saves a screenshot (BUILD_DIR/dashboard_screenshot.png). Then the run's static
# report must be there with its figures.
#   tests/dashboard/browser_test.sh BUILD_DIR
set -euo pipefail
build="$1"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"

source "$repo/tests/in_private_netns.sh"

tmp="$(mktemp -d)"
launch=""
trap '[ -n "$launch" ] && kill -TERM "$launch" 2>/dev/null; wait 2>/dev/null; if [ -n "${HBIRL_KEEP:-}" ]; then echo "kept $tmp" >&2; else rm -rf "$tmp"; fi' EXIT
fail() { echo "FAIL: $*" >&2; cat "$tmp/launch.out" >&2 2>/dev/null || true; tail -n 20 "$tmp"/run/logs/* >&2 2>/dev/null || true; exit 1; }

port=8765  # the namespace's own loopback: no other test sees it
"$repo/services/launch.sh" --build "$build" --out "$tmp/run" --sorts 4 --controlled-sorts 6 --fps 5 --max-fps 250 --anytime \
  --dashboard-port "$port" --keep-dashboard >"$tmp/launch.out" 2>&1 &
launch=$!
HOME="$tmp" python3 "$here/browser_check.py" "http://127.0.0.1:$port/" "$build/dashboard_screenshot.png" 240 || fail "the browser check"
# The panels fill at the first EM iteration: let the run finish (and write its report)
# before stopping the dashboard it keeps up.
for _ in $(seq 1 600); do
  grep -q "the dashboard stays up" "$tmp/launch.out" && break
  kill -0 "$launch" 2>/dev/null || break
  sleep 0.5
done
grep -q "the dashboard stays up" "$tmp/launch.out" || fail "the run did not finish"
kill -TERM "$launch"
wait "$launch" || fail "launch.sh exited non-zero"
launch=""
if ! grep -q "launch.sh: the full result: " "$tmp/launch.out" || ! grep -q "^  weights: " "$tmp/launch.out"; then
  fail "no learned reward"
fi
for f in index.html state.json camera.png em.svg em.png estimates.svg theta.svg posterior.svg observation_model.svg eta.svg; do
  [ -s "$tmp/run/report/$f" ] || fail "the report has no $f"
done
echo "report: $(find "$tmp/run/report" -mindepth 1 -maxdepth 1 -printf '%f ')"
# The subject's map: each state named at the middle of its rows (one per action), the
# actions named in order (they used to be unnamed, each state on its first action's row).
python3 - "$tmp/run/report" <<'PY' || fail "the subject map's states or actions are not labelled as they should be"
import json, sys
report = sys.argv[1]
names = json.load(open(report + "/state.json"))["names"]
script = open(report + "/observation_model.gp").read()
actions = len(names["actions"])
for s in (0, len(names["states"]) - 1):
    tic = "'%s' %g" % (names["states"][s].replace("'", "''"), s * actions + (actions - 1) / 2)
    assert tic in script, tic
assert "its actions " + ", ".join(names["actions"]) in script
print("subject map: %d states centred on their %d action rows" % (len(names["states"]), actions))
PY
# The learned policy, by state and action names, as result.json has it.
python3 - "$tmp/run/report/index.html" "$tmp/run/result.json" <<'PY' || fail "the report does not show the learned policy as result.json has it"
import html, json, sys
page = open(sys.argv[1]).read()
policy = json.load(open(sys.argv[2]))["policy"]
assert "<h2>Learned policy</h2>" in page
for step in policy[:5]:
    row = "<tr><td>%s</td><td>%s</td>" % (html.escape(str(step["state"]), quote=False), html.escape(str(step["action"]), quote=False))
    assert row in page, row
print("report: the learned policy in %d states, as result.json has it" % len(policy))
PY
