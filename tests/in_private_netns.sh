# shellcheck shell=bash
# Sourced first by a multi-process test: re-runs the test script inside a private network
# namespace of its own (unshare -rn; lo up with multicast; 224.0.0.0/4 routed to lo), so
# its processes see only each other and no packet reaches a real network.
if [ -z "${HBIRL_IN_NETNS:-}" ]; then
  export HBIRL_IN_NETNS=1
  # shellcheck disable=SC2016  # $0 and $@ are the inner shell's
  exec unshare -rn -- bash -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" "$@"' \
    "$0" "$@"
fi
