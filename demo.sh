#!/usr/bin/env bash
# The main job: install what is missing, build, and learn a reward from the example
# problem (MaxCausalEnt IRL on the true trajectories of the paper's 5x5 Gridworld).
set -euo pipefail
cd "$(dirname "$0")"
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target hbirl -j"$(nproc)" >/dev/null
echo "Learning the reward of examples/gridworld_5x5.json from its true trajectories:" >&2
build/hbirl learn --problem examples/gridworld_5x5.json --from truth
