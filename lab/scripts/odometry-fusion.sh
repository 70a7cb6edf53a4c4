#!/usr/bin/env bash
# What combining egomotion with odometry buys, and what it costs when the
# odometry is worse than its noise model says: the thesis routes driven
# straight and with tracking, egomotion purely visual (`odometry_fusion:
# Off`), with odometry's sideways motion (`Sideways`) and with all of it
# (`Full`), and with the sideways fusion steering the robot (`navigate:
# true`; otherwise it steers by odometry, as the thesis's robot did), on
# the routes' odometry (random slip only), on wheels 1 % larger
# than the encoders think (the robot goes 1 % further and turns 1 % more
# than odometry says), and with a steady
# veer of 0.05° per metre that odometry does not see. Prints JSON: per
# route, odometry and fusion, each technique's mean end-point error with a
# 95 % interval, its failures per run and the runs that hit the time limit.
#
#   lab/scripts/odometry-fusion.sh "2121 2222 2323" 100..120 > out/odometry-fusion.json
set -euo pipefail
cd "$(dirname "$0")/../.."
. lab/scripts/layouts-and-seeds.sh
. lab/scripts/wheels.sh
for route in route-1-2 route-2-1 feature-poor; do
    for odometry in exact scale veer; do
        errors=$(wheel_errors "$odometry")
        for fusion in Off Sideways Full SidewaysNavigating; do
            settings="odometry_fusion: $fusion, navigate: false"
            [ "$fusion" = SidewaysNavigating ] && settings='odometry_fusion: Sideways, navigate: true'
            for technique in None Tracking; do
                sed -e "s/slip_deg_per_sqrt_m: 0.2/$errors/" \
                    -e "s/odometry_fusion: Off, navigate: false/$settings/" \
                    -e "s/technique: None/technique: $technique/" \
                    "lab/scenarios/thesis/$route.ron" > "$work/$route~$odometry~$fusion~$technique.ron"
            done
        done
    done
done
# Every file must have taken every edit.
for file in "$work"/*~Off~*.ron; do
    grep -q "odometry_fusion: Off, navigate: false" "$file" || { echo "$file: the egomotion line did not match" >&2; exit 1; }
done
for file in "$work"/*~Sideways*~*.ron "$work"/*~Full~*.ron; do
    ! grep -q "odometry_fusion: Off" "$file" || { echo "$file: the egomotion line did not match" >&2; exit 1; }
done
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --out "$work/runs" >&2
python3 - "$work/runs" <<'EOF'
import glob, json, math, os, sys
from statistics import mean, stdev

runs = {}
for path in glob.glob(os.path.join(sys.argv[1], '*', '*', 'report.json')):
    route, odometry, fusion, technique = path.split(os.sep)[-3].split('@')[0].split('~')
    runs.setdefault((route, odometry, fusion, technique), []).append(json.load(open(path)))
out = {}
for (route, odometry, fusion, technique), reports in sorted(runs.items()):
    errors = [r['endpoint_error_m'] for r in reports]
    half = 1.96 * stdev(errors) / math.sqrt(len(errors))
    cell = out.setdefault(route, {}).setdefault(odometry, {}).setdefault(fusion, {})
    cell[technique.lower()] = {
        'runs': len(errors),
        'mean_m': round(mean(errors), 4),
        'ci95_m': [round(mean(errors) - half, 4), round(mean(errors) + half, 4)],
        'failures_per_run': round(mean(r['egomotion_failures'] for r in reports), 2),
        'time_limit_runs': sum(r['end'] == 'time_limit' for r in reports),
        'no_progress_runs': sum(r['end'] == 'no_progress' for r in reports),
    }
json.dump(out, sys.stdout, indent=1)
print()
EOF
