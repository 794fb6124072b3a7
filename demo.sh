#!/usr/bin/env bash
# The main job: install what is missing, build, and run the onion-sorting demo as LCM
# services -- simulator and camera, perception, labeller, two sampler workers, optimiser
# (services/launch.sh; pass its options, e.g. --workers 4 or --config controlled) -- then
# print the learned reward, its ILE, and where the logs and the recorded run are.
set -euo pipefail
cd "$(dirname "$0")"
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target hbirl hbirl-services -j"$(nproc)" >/dev/null
exec services/launch.sh --record "$@"
