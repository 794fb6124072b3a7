#!/usr/bin/env bash
# Installs the Debian packages hbirl needs that are not installed yet (apt-get, with
# sudo when not root). Safe to run again: it does nothing when everything is there.
#   scripts/install-deps.sh              what ./demo.sh needs: build, run the services, the
#                                        dashboard and the report
#   scripts/install-deps.sh --for-tests  and what ./test.sh needs too: the test and benchmark
#                                        libraries, clang (sanitizers, libFuzzer), headless
#                                        Chromium, the Python package's build (pybind11, numpy)
#                                        and a JDK for lcmtypes_hbirl.jar (lcm-spy)
set -euo pipefail

run_packages=(
  build-essential cmake pkg-config ninja-build
  libeigen3-dev nlohmann-json3-dev libcli11-dev liblbfgs-dev
  libboost-dev gnuplot-nox
  libopencv-core-dev libopencv-imgproc-dev libspng-dev libturbojpeg0-dev
  liblcm-dev liblcm-bin iproute2 util-linux
  libcpp-httplib-dev libjs-chart.js ca-certificates libsodium-dev
  fonts-dejavu-core python3
)
test_packages=(
  default-jdk-headless liblcm-java libjchart2d-java
  chromium chromium-driver
  libgtest-dev libgmock-dev libbenchmark-dev
  clang clang-format-14 libclang-rt-14-dev shellcheck
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib python3-scipy
  python3-pip python3-venv python3-setuptools python3-wheel
)
packages=("${run_packages[@]}")
case "${1:-}" in
  "") ;;
  --for-tests) packages+=("${test_packages[@]}") ;;
  *) echo "install-deps: unknown option '$1' (usage: scripts/install-deps.sh [--for-tests])" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    sudo=(sudo)
  else
    echo "install-deps: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
fi
echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
