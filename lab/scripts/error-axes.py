#!/usr/bin/env python3
"""Splits each run's end-point error into its parts along the route and
across it, from a sweep of `ROUTE~VARIANT~AID` scenarios over layouts
(`NAME@LAYOUT/seed-N/trajectory.csv` and `report.json`, as
`lab/scripts/error-axes.sh` runs them).

The error is egomotion's at the last frame (the report's
`endpoint_error_m`); along is its part on the line from the robot's true
position at the first frame to the one at the last (positive: egomotion
ahead of the truth), across the rest (positive: left of the way driven).

    lab/scripts/error-axes.py /tmp/runs

Prints JSON: per route, variant and aid, the runs, the mean end-point
error and its ratio to driving straight (aid `none`) on the same layouts
and seeds (null where straight driving's runs end within a micrometre on
average), the RMS of the parts along and across, the RMS error of the
wheel scale egomotion measured (the wheels are exact: 1 is right; null
unless every run measured one), the failed frames per run and the mean
time.
"""
import glob
import json
import math
import os
import sys
from statistics import mean

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trajectory_log  # noqa: E402  (lab/scripts/trajectory_log.py)


def axes(path):
    """The end-point error's parts (along, across) from one trajectory.csv."""
    frames = trajectory_log.frames(path)
    start, end = frames[min(frames)], frames[max(frames)]
    dx, dy = float(end['true_x']) - float(start['true_x']), float(end['true_y']) - float(start['true_y'])
    length = math.hypot(dx, dy) or 1.0
    ex, ey = float(end['ego_x']) - float(end['true_x']), float(end['ego_y']) - float(end['true_y'])
    return (ex * dx + ey * dy) / length, (ey * dx - ex * dy) / length


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values))


def main(root):
    cells = {}
    for path in glob.glob(os.path.join(root, '*', '*', 'report.json')):
        directory = os.path.dirname(path)
        name, _, layout = directory.split(os.sep)[-2].partition('@')
        route, variant, aid = name.split('~')
        report = json.load(open(path))
        along, across = axes(os.path.join(directory, 'trajectory.csv'))
        # The split must add up to the report's own end-point error.
        if abs(math.hypot(along, across) - report['endpoint_error_m']) > 2e-5:
            sys.exit(f'{directory}: the parts do not add up to the end-point error')
        run = (report['endpoint_error_m'], along, across, report['wheel_scale'], report['egomotion_failures'],
               report['sim_time_s'])
        cells.setdefault((route, variant), {}).setdefault(aid, {})[(layout, report['seed'])] = run
    out = {}
    for (route, variant), by_aid in sorted(cells.items()):
        straight = by_aid.get('none', {})
        for aid, runs in sorted(by_aid.items()):
            keys = sorted(set(runs) & set(straight))
            # Without noise straight driving ends exactly where egomotion
            # says, and no ratio to it means anything.
            straight_m = sum(straight[k][0] for k in keys)
            errors = [r[0] for r in runs.values()]
            scales = [r[3] - 1.0 for r in runs.values() if r[3] is not None]
            if len(scales) < len(runs):
                scales = []
            out.setdefault(route, {}).setdefault(variant, {})[aid] = {
                'runs': len(runs),
                'error_m': round(mean(errors), 4),
                'vs_straight': round(sum(runs[k][0] for k in keys) / straight_m, 3)
                if straight_m > 1e-6 * len(keys) > 0 else None,
                'rms_along_m': round(rms([r[1] for r in runs.values()]), 4),
                'rms_across_m': round(rms([r[2] for r in runs.values()]), 4),
                'rms_wheel_scale_error': round(rms(scales), 5) if scales else None,
                'failed_frames': round(mean(r[4] for r in runs.values()), 2),
                'time_s': round(mean(r[5] for r in runs.values()), 1),
            }
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == '__main__':
    if len(sys.argv) != 2:
        sys.exit(f'usage: {sys.argv[0]} RUNS')
    main(sys.argv[1])
