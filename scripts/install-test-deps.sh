#!/bin/sh
# What the test suite needs besides Rust, on a Debian or Ubuntu machine:
# a C compiler (a few crates build C), Python 3 with venv (the checks against outside implementations install
# their own PyPI packages, Cyclone DDS, the MCAP and rosbag2 readers and
# jsonschema, into .venv-* on first use), and `unshare` and `ip`, with which
# the ROS 2 tests put their DDS traffic in a private network namespace, and
# `systemd-analyze`, which checks the service unit in deploy/, and Node.js
# with npm, with which the live view is watched by Foxglove's own client
# (installed into .npm-foxglove on first use).
# Installs only what is missing; root or sudo needed for that.
set -eu
missing=""
command -v cc >/dev/null || missing="$missing gcc libc6-dev"
command -v python3 >/dev/null || missing="$missing python3"
python3 -c "import venv, ensurepip" 2>/dev/null || missing="$missing python3-venv"
command -v unshare >/dev/null || missing="$missing util-linux"
command -v ip >/dev/null || missing="$missing iproute2"
command -v systemd-analyze >/dev/null || missing="$missing systemd"
command -v node >/dev/null || missing="$missing nodejs"
command -v npm >/dev/null || missing="$missing npm"
[ -z "$missing" ] && { echo "nothing to install"; exit 0; }
sudo=""; [ "$(id -u)" = 0 ] || sudo=sudo
$sudo apt-get update
$sudo apt-get install -y $missing
