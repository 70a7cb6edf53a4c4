#!/bin/sh
# Runs foxglove-live-check.mjs with the official Foxglove client library,
# installed on first use into .npm-foxglove/ beside scripts/ (Node.js and
# npm needed: scripts/install-test-deps.sh). Arguments: those of the .mjs.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
dir="$root/.npm-foxglove"
packages="@foxglove/ws-protocol@0.8.0 ws@8.18.3"
# Tests run it in parallel: one installs, the others wait; an interrupted
# install (no marker naming the packages) is done again.
exec 9>"$dir.lock"
flock 9
if [ "$(cat "$dir/.installed" 2>/dev/null)" != "$packages" ]; then
    rm -rf "$dir"
    mkdir -p "$dir"
    # shellcheck disable=SC2086
    npm install --silent --no-audit --no-fund --prefix "$dir" $packages >&2
    echo "$packages" > "$dir/.installed"
fi
flock -u 9
FOXGLOVE_CLIENT_DIR="$dir" exec node "$root/scripts/foxglove-live-check.mjs" "$@"
