#!/usr/bin/env bash
# Whether tracking's end-point misses belong to its path or to the last
# frame: the three thesis routes driven straight and with tracking in each
# layout, and tracking's mean error over straight driving's measured at the
# last frame and at the one and two frames before it (`lab/scripts/last-frame.py`).
# A miss that the frame before does not share is one frame's estimate, not
# what the path did. Prints JSON.
#
#   lab/scripts/last-frame.sh "303 202 101" 1000..1030 > out/last-frame-1000.json
set -euo pipefail
cd "$(dirname "$0")/../.."
. lab/scripts/layouts-and-seeds.sh
for route in route-1-2 route-2-1 feature-poor; do
    for technique in None Tracking; do
        sed -e "s/technique: None/technique: $technique/" -e "s/name: \"$route\"/name: \"$route~$technique\"/" \
            "lab/scenarios/thesis/$route.ron" > "$work/$route~$technique.ron"
        grep -q "name: \"$route~$technique\"" "$work/$route~$technique.ron" || { echo "$route.ron: the name did not match" >&2; exit 1; }
    done
done
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --trajectories --out "$work/runs" >&2
python3 lab/scripts/last-frame.py "$work/runs"
