#!/usr/bin/env bash
# How much the end-point error depends on the line driven through a layout,
# and whether the predictions can tell the lines apart: route 1->2 driven
# straight (no aiding, no turn) along three parallel lines, the centre line
# and 0.6 m either side of it, on the given layouts. Prints JSON: per layout
# and line, the RMS end-point error over the seeds and the RMS of two
# predictions of it (the decision's error model, and egomotion's own
# covariance); then, over the side lines against the centre line of the same
# layout, the spread of the error ratios, and for each prediction how often
# it gets the direction of the change right and the correlation of its log
# ratio with the actual one. Beside them, two lines crossing the same
# offsets diagonally (from 0.6 m one side to 0.6 m the other, 1.69° off the
# axis) over the centre line, and tracking on the centre line over straight
# driving on it, the same layouts and seeds.
#
#   lab/scripts/path-lottery.sh "2121 2222 2323 2424 2525 2626 2727 2828 2929 3030" 100..130 > out/path-lottery.json
set -euo pipefail
cd "$(dirname "$0")/../.."
. lab/scripts/layouts-and-seeds.sh
. lab/scripts/route-line.sh
# NAME:FROM:TO:HEADING: the three parallel lines, then the same lateral
# offsets crossed diagonally, 1.69° off the axis, both ways.
for line in -0.6:-0.6:-0.6:0 0.0:0.0:0.0:0 0.6:0.6:0.6:0 diagonal-up:-0.6:0.6:1.69 diagonal-down:0.6:-0.6:-1.69; do
    IFS=: read -r name from to heading <<< "$line"
    route_line "$from" "$to" "$heading" > "$work/$name.ron"
done
sed -e "s/technique: None/technique: Tracking/" lab/scenarios/thesis/route-1-2.ron > "$work/tracking.ron"
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --out "$work/runs" >&2
python3 - "$work/runs" <<'EOF'
import glob, json, math, os, sys
from statistics import mean

def rms(values):
    return math.sqrt(mean(v * v for v in values))

def correlation(pairs):
    (ma, mb) = (mean(a for a, _ in pairs), mean(b for _, b in pairs))
    ab = sum((a - ma) * (b - mb) for a, b in pairs)
    aa = sum((a - ma) ** 2 for a, _ in pairs)
    bb = sum((b - mb) ** 2 for _, b in pairs)
    return ab / math.sqrt(aa * bb)

runs = {}
for path in glob.glob(os.path.join(sys.argv[1], '*', '*', 'report.json')):
    scenario = path.split(os.sep)[-3]
    line, layout = scenario.split('@')
    runs.setdefault(layout, {}).setdefault(line, []).append(json.load(open(path)))
predictions = {'decision_model': 'predicted_endpoint_sigma_m', 'egomotion_covariance': 'egomotion_sigma_m'}
layouts = {}
for layout, lines in sorted(runs.items()):
    layouts[layout] = {
        line: {
            'runs': len(reports),
            'error_rms_m': rms([r['endpoint_error_m'] for r in reports]),
            **{name + '_sigma_rms_m': rms([r[field] for r in reports]) for name, field in predictions.items()},
        }
        for line, reports in sorted(lines.items())
    }
ratios, agreement, tracking, diagonal = [], {}, [], []
for lines in layouts.values():
    tracking.append(lines.pop('tracking')['error_rms_m'] / lines['0.0']['error_rms_m'])
    diagonal.append([lines.pop(d)['error_rms_m'] / lines['0.0']['error_rms_m'] for d in ('diagonal-up', 'diagonal-down')])
    centre = lines['0.0']
    for line in ('-0.6', '0.6'):
        actual = math.log(lines[line]['error_rms_m'] / centre['error_rms_m'])
        ratios.append(actual)
        for name in predictions:
            key = name + '_sigma_rms_m'
            agreement.setdefault(name, []).append((actual, math.log(lines[line][key] / centre[key])))
ratios = sorted(math.exp(r) for r in ratios)
print(json.dumps({
    'layouts': layouts,
    'side_over_centre': {
        'ratios': ratios,
        'beyond_1_1': sum(r > 1.1 for r in ratios),
        'below_0_9': sum(r < 0.9 for r in ratios),
    },
    'diagonal_over_centre': diagonal,
    'tracking_over_centre': sorted(tracking),
    'predictions': {
        name: {
            'right_direction': sum(a * p > 0 for a, p in pairs),
            'of': len(pairs),
            'log_ratio_correlation': correlation(pairs),
        }
        for name, pairs in agreement.items()
    },
}, indent=1))
EOF
