#!/usr/bin/env bash
# Runs a command inside a private network namespace (lo up with multicast; 224.0.0.0/4
# routed to lo), as the multi-process tests do: the benchmarks over LCM need loopback
# multicast, which is not routed outside one here, and send nothing to a real network.
#   bench/in_netns.sh build/bench/services_bench --benchmark_filter=OverLcm
# shellcheck disable=SC2016  # $0 and $@ are the inner shell's
exec unshare -rn -- bash -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' "$@"
