#!/usr/bin/env bash
# Where an aided technique's error comes from, one source removed at a time:
# the thesis routes on the given layouts, driven straight (camera fixed)
# and aided, with the routes' noise, then without stereo outliers, without
# pixel noise, without wheel slip, without all three, and without all three
# and with exact pan encoders (camera steering only); and, for robot
# steering, with the decision's turn costs tripled (a test of whether turns
# are priced right). Prints JSON: per route and variant, the mean of the
# per-seed differences (aided − straight) in end-point error with a 95 %
# interval, and the failures per run of each.
#
#   lab/scripts/error-sources.sh camera "404 505 606" 2000..2030 > out/camera-sources.json
#   lab/scripts/error-sources.sh tracking "1212 1313" 6000..6030 route-1-2 > out/tracking-sources.json
set -euo pipefail
cd "$(dirname "$0")/../.."
aid=$1 layouts=$2 seeds=$3 routes=${4:-route-1-2 route-2-1 feature-poor}
case $aid in
    camera) tree='technique: Tracking, steer: Camera' unit='pan_tilt: (), ' variants='exact-encoders' ;;
    tracking) tree='technique: Tracking' unit='' variants='dear-turns' ;;
    *) echo "usage: $0 camera|tracking LAYOUTS SEEDS [ROUTES]" >&2; exit 2 ;;
esac
cargo build --release --quiet
ubf=target/release/ubf
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for route in $routes; do
    for variant in base no-outliers no-pixel-noise no-slip no-noise $variants; do
        slip=0.2 outliers=0.08 pixels=0.047 aided_unit=$unit aided_tree=$tree
        case $variant in
            no-outliers) outliers=0.0 ;;
            no-pixel-noise) pixels=0.0 ;;
            no-slip) slip=0.0 ;;
            no-noise) slip=0.0 outliers=0.0 pixels=0.0 ;;
            exact-encoders) slip=0.0 outliers=0.0 pixels=0.0 aided_unit='pan_tilt: (noise_deg: 0.0, resolution_deg: 0.0), ' ;;
            dear-turns) aided_tree="$tree, costs: (heading_var_per_turn: 3.6e-5, heading_var_per_rad: 2.79e-5)" ;;
        esac
        edits=(-E -e "s/slip_deg_per_sqrt_m: 0.2/slip_deg_per_sqrt_m: $slip/"
            -e "s/pixel_noise_px: 0.047, outlier_share: 0.08/pixel_noise_px: $pixels, outlier_share: $outliers/")
        sed "${edits[@]}" "lab/scenarios/thesis/$route.ron" > "$work/$route~$variant~straight.ron"
        sed "${edits[@]}" -e "s/technique: None/$aided_tree/" \
            -e "s/camera: \(/camera: ($aided_unit/" "lab/scenarios/thesis/$route.ron" > "$work/$route~$variant~aided.ron"
    done
done
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --out "$work/runs" >&2
python3 - "$work/runs" <<'EOF'
import glob, json, math, os, sys
from statistics import mean, stdev

runs = {}
for path in glob.glob(os.path.join(sys.argv[1], '*', '*', 'report.json')):
    scenario, seed = path.split(os.sep)[-3:-1]
    kind, layout = scenario.split('@')
    route, variant, steer = kind.split('~')
    runs.setdefault((route, variant), {}).setdefault((layout, seed), {})[steer] = json.load(open(path))
out = {}
for (route, variant), pairs in sorted(runs.items()):
    diffs = [p['aided']['endpoint_error_m'] - p['straight']['endpoint_error_m'] for p in pairs.values()]
    half = 1.96 * stdev(diffs) / math.sqrt(len(diffs))
    out.setdefault(route, {})[variant] = {
        'runs': len(diffs),
        'straight_m': mean(p['straight']['endpoint_error_m'] for p in pairs.values()),
        'aided_m': mean(p['aided']['endpoint_error_m'] for p in pairs.values()),
        'difference_m': mean(diffs),
        'difference_ci95_m': [mean(diffs) - half, mean(diffs) + half],
        'straight_failures': mean(p['straight']['egomotion_failures'] for p in pairs.values()),
        'aided_failures': mean(p['aided']['egomotion_failures'] for p in pairs.values()),
    }
print(json.dumps(out, indent=1))
EOF
