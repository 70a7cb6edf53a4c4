#!/usr/bin/env bash
# Run a command in a fresh private network namespace, for DDS tests:
#
#   scripts/ros2/netns.sh CMD ARGS...
#
# Inside, only loopback exists (up, with multicast routed to it), and
# CYCLONEDDS_URI points at scripts/ros2/cyclonedds.xml, so DDS discovery and
# data stay on loopback: nothing outside can see them, and no other DDS
# process on the machine can disturb them. Uses `unshare -n` as root and
# `unshare -rn` (a user namespace) otherwise. Where that is not possible it
# exits 77 (skip) with a sentence saying why; it never runs CMD on the real
# network. Otherwise it exits with CMD's status.
set -u
here=$(cd "$(dirname "$0")" && pwd)
[ $# -gt 0 ] || { echo "usage: $0 CMD ARGS..." >&2; exit 2; }

skip() { echo "netns.sh: skipped: $*" >&2; exit 77; }
command -v unshare >/dev/null || skip "unshare is not installed, so no private network namespace can be made."
command -v ip >/dev/null || skip "ip (iproute2) is not installed, so a private network namespace cannot be set up."
if [ "$(id -u)" = 0 ]; then flags=-n; else flags=-rn; fi
unshare $flags true 2>/dev/null || skip "this machine does not allow private network namespaces (unshare $flags failed)."

exec unshare $flags bash -c '
  # A fresh namespace has loopback and nothing else; refuse anything more.
  [ "$(ip -o link show | grep -cv " lo:")" = 0 ] || { echo "netns.sh: skipped: not in a fresh network namespace." >&2; exit 77; }
  ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo \
    || { echo "netns.sh: skipped: cannot bring up loopback multicast in the private network namespace." >&2; exit 77; }
  export CYCLONEDDS_URI="file://$0"
  exec "$@"
' "$here/cyclonedds.xml" "$@"
