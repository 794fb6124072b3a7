#!/usr/bin/env bash
# The main job: install what is missing, build, and run the onion-sorting demo as LCM
# services -- simulator and camera, perception, labeller, two sampler workers, optimiser
# (services/launch.sh; pass its options, e.g. --workers 4 or --config controlled) -- with
# the live dashboard on http://127.0.0.1:8765/; then print the learned reward, its ILE,
# the static report and where the logs and the recorded run are. In a terminal, the
# dashboard stays up after the run until Ctrl-C.
set -euo pipefail
cd "$(dirname "$0")"
scripts/install-deps.sh  # only what the demo needs; ./test.sh installs the rest
# The tests' configuration (scripts/configure.sh), without the tests on a first build: their
# libraries are ./test.sh's to install, and it builds on this folder without recompiling it.
tests=()
[ -f build/CMakeCache.txt ] || tests=(-DHBIRL_BUILD_TESTS=OFF -DHBIRL_BUILD_BENCH=OFF)
scripts/configure.sh build "${tests[@]}"
targets=(hbirl hbirl-services hbirl-dashboard)
# The Python package too, when it is configured (pybind11 and numpy there): docs/python.md "Python".
[ -d build/python/hbirl ] && targets+=(hbirl_python)
cmake --build build --target "${targets[@]}" -j"$(nproc)" >/dev/null
keep=()
[ -t 0 ] && [ -t 1 ] && keep=(--keep-dashboard)
exec services/launch.sh --record "${keep[@]}" "$@"
