#!/usr/bin/env bash
# Formats every C++ source of the project with clang-format (.clang-format), or with
# --check says which files are not formatted and exits 1 (./test.sh runs that).
set -euo pipefail
cd "$(dirname "$0")/.."
# One version: another formats some lines differently (install-deps.sh --for-tests installs this one).
format=clang-format-14
if ! command -v "$format" >/dev/null 2>&1; then
  echo "format.sh: $format not found (apt-get install clang-format-14; scripts/install-deps.sh --for-tests does)" >&2
  exit 2
fi
mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
if [ "${1:-}" = --check ]; then
  # Forty files to a process, on every core: one process per file took 34 s of ./test.sh,
  # this takes about one. Only when a batch fails are its files looked at one by one.
  if printf '%s\0' "${files[@]}" | xargs -0 -n 40 -P "$(nproc)" "$format" --style=file --dry-run --Werror >/dev/null 2>&1; then
    exit 0
  fi
  bad=()
  for f in "${files[@]}"; do
    "$format" --style=file --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
  done
  if [ ${#bad[@]} -gt 0 ]; then
    printf 'format.sh: not formatted (run scripts/format.sh): %s\n' "${bad[@]}" >&2
    exit 1
  fi
  exit 0
fi
"$format" --style=file -i "${files[@]}"
