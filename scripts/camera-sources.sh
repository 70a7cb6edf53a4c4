#!/usr/bin/env bash
# Where camera steering's error comes from, one source removed at a time:
# the thesis routes on the development layouts (404, 505, 606; seeds
# 2000..2030), driven straight with a fixed camera and with the camera
# steered (ActionAiding(technique: Tracking, steer: Camera) on a simulated
# pan-tilt unit), with the routes' noise, then without stereo outliers,
# without pixel noise, without wheel slip, without all three, and without
# all three and with exact pan encoders. Prints JSON: per route and variant,
# the mean of the per-seed differences (steered − straight) in end-point
# error with a 95 % interval, and the failures per run of each.
#
#   scripts/camera-sources.sh > out/camera-sources.json
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
ubf=target/release/ubf
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for layout in 404 505 606; do
    for route in route-1-2 route-2-1 feature-poor; do
        for variant in base no-outliers no-pixel-noise no-slip no-noise exact-encoders; do
            slip=0.2 outliers=0.08 pixels=0.047 unit='pan_tilt: ()'
            case $variant in
                no-outliers) outliers=0.0 ;;
                no-pixel-noise) pixels=0.0 ;;
                no-slip) slip=0.0 ;;
                no-noise) slip=0.0 outliers=0.0 pixels=0.0 ;;
                exact-encoders) slip=0.0 outliers=0.0 pixels=0.0 unit='pan_tilt: (noise_deg: 0.0, resolution_deg: 0.0)' ;;
            esac
            edits=(-E -e "s/(random_landmarks: \(.*seed: )[0-9]+\)/\1$layout)/"
                -e "s/slip_deg_per_sqrt_m: 0.2/slip_deg_per_sqrt_m: $slip/"
                -e "s/pixel_noise_px: 0.047, outlier_share: 0.08/pixel_noise_px: $pixels, outlier_share: $outliers/")
            sed "${edits[@]}" "scenarios/thesis/$route.ron" > "$work/$layout~$route~$variant~straight.ron"
            sed "${edits[@]}" -e "s/technique: None/technique: Tracking, steer: Camera/" \
                -e "s/camera: \(/camera: ($unit, /" "scenarios/thesis/$route.ron" > "$work/$layout~$route~$variant~camera.ron"
        done
    done
done
"$ubf" sweep "$work"/*.ron --seeds 2000..2030 --out "$work/runs" >&2
python3 - "$work/runs" <<'EOF'
import glob, json, math, os, sys
from statistics import mean, stdev

runs = {}
for path in glob.glob(os.path.join(sys.argv[1], '*', '*', 'report.json')):
    scenario, seed = path.split(os.sep)[-3:-1]
    layout, route, variant, steer = scenario.split('~')
    runs.setdefault((route, variant), {}).setdefault((layout, seed), {})[steer] = json.load(open(path))
out = {}
for (route, variant), pairs in sorted(runs.items()):
    diffs = [p['camera']['endpoint_error_m'] - p['straight']['endpoint_error_m'] for p in pairs.values()]
    half = 1.96 * stdev(diffs) / math.sqrt(len(diffs))
    out.setdefault(route, {})[variant] = {
        'runs': len(diffs),
        'straight_m': mean(p['straight']['endpoint_error_m'] for p in pairs.values()),
        'camera_m': mean(p['camera']['endpoint_error_m'] for p in pairs.values()),
        'difference_m': mean(diffs),
        'difference_ci95_m': [mean(diffs) - half, mean(diffs) + half],
        'straight_failures': mean(p['straight']['egomotion_failures'] for p in pairs.values()),
        'camera_failures': mean(p['camera']['egomotion_failures'] for p in pairs.values()),
    }
print(json.dumps(out, indent=1))
EOF
