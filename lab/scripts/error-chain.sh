#!/usr/bin/env bash
# Which links of egomotion's chain carry the end-point error: route 1->2
# driven straight along the centre line and along the two diagonals of
# `lab/scripts/path-lottery.sh` (from 0.6 m one side to 0.6 m the other, 1.69°
# off the corridor's axis), egomotion purely visual and with odometry's
# sideways motion (`odometry_fusion: Sideways`), split by
# `lab/scripts/error-chain.py`. Prints its JSON, one entry per line and fusion.
#
#   lab/scripts/error-chain.sh "2121 2222 2323 2424 2525 2626 2727 2828 2929 3030" 100..130 > out/error-chain.json
set -euo pipefail
cd "$(dirname "$0")/../.."
. lab/scripts/layouts-and-seeds.sh
. lab/scripts/route-line.sh
# NAME:FROM:TO:HEADING, as in lab/scripts/path-lottery.sh.
for line in centre:0.0:0.0:0 diagonal-up:-0.6:0.6:1.69 diagonal-down:0.6:-0.6:-1.69; do
    IFS=: read -r name from to heading <<< "$line"
    for fusion in Off Sideways; do
        route_line "$from" "$to" "$heading" \
            | sed -e "s/odometry_fusion: Off,/odometry_fusion: $fusion,/" > "$work/$name~$fusion.ron"
        grep -q "odometry_fusion: $fusion," "$work/$name~$fusion.ron" || { echo "route-1-2.ron: the egomotion line did not match" >&2; exit 1; }
    done
done
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --trajectories --out "$work/runs" >&2
python3 lab/scripts/error-chain.py "$work/runs"
