#!/usr/bin/env bash
# The Release build's one configuration, for ./demo.sh and ./test.sh alike: a folder the
# demo built is the folder the tests build on, with nothing compiled again for want of a
# flag. Ninja when there is one (it keeps both cores busy; a folder made before keeps the
# generator it was made with), Release, warnings as errors.
#   scripts/configure.sh BUILD_DIR [cmake options...]
set -euo pipefail
build="${1:?usage: scripts/configure.sh BUILD_DIR [cmake options...]}"
shift
repo="$(cd "$(dirname "$0")/.." && pwd)"
generator=()
if [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
cmake -S "$repo" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DHBIRL_WERROR=ON "$@" >/dev/null
