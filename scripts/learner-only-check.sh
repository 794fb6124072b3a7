#!/usr/bin/env bash
# Configures, builds and tests the maths alone (cmake -DHBIRL_LEARNER_ONLY=ON: learner/,
# problem/ and their tests) the way it would go on a machine without OpenCV, LCM, CLI11
# or cpp-httplib: in a private mount namespace (unshare -rm) where their headers and
# libraries are hidden, so a stray dependency fails the build here. Nothing outside the
# namespace changes.   scripts/learner-only-check.sh BUILD_DIR [JOBS [CTEST_ARGS...]]
# (CTEST_ARGS: ./test.sh leaves out the heavy tests the Release build ran.)
set -euo pipefail
build="$1"
jobs="${2:-$(nproc)}"
ctest_args=("${@:3}")
repo="$(cd "$(dirname "$0")/.." && pwd)"
if [ -z "${HBIRL_HIDDEN:-}" ]; then
  if unshare -rm true 2>/dev/null; then
    exec unshare -rm env HBIRL_HIDDEN=1 bash "$0" "$@"
  fi
  echo "learner-only: no private mount namespaces here (unshare -rm): building without hiding the other packages" >&2
  export HBIRL_HIDDEN=0
fi
empty="$(mktemp -d)"
hidden=()
if [ "$HBIRL_HIDDEN" = 1 ]; then
for dir in /usr/include/opencv4 /usr/include/lcm /usr/include/CLI; do
  [ -d "$dir" ] && mount --bind "$empty" "$dir" && hidden+=("$dir")
done
for file in /usr/include/httplib.h /usr/lib/*/liblcm.so* /usr/lib/*/libopencv_*; do
  [ -f "$file" ] && mount --bind /dev/null "$file" && hidden+=("$file")
done
fi
echo "learner-only: hidden ${#hidden[@]} headers and libraries of OpenCV, LCM, CLI11, cpp-httplib"
# -O1: the point is what it needs, not its speed (the Release build runs the same tests).
cmake -S "$repo" -B "$build" -DHBIRL_LEARNER_ONLY=ON -DHBIRL_WERROR=ON -DHBIRL_BUILD_BENCH=OFF \
      -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" >/dev/null
cmake --build "$build" -j"$jobs"
ctest --test-dir "$build" --output-on-failure -j"$jobs" "${ctest_args[@]}"
