#!/usr/bin/env python3
"""Summarises a sweep of lab/scripts/aiding-families.sh, as lab/protocol.md
says: per family, estimate and aid, the mean end-point error, time and
failed frames, and each one's ratio to straight driving (the same family,
estimate and wheels) with a 95 % interval from a bootstrap over layouts
(seeds kept with their layout: layouts are what the claims generalise
over), and the same per layout. Prints JSON.

    python3 lab/scripts/aiding-families.py RUNS
"""
import glob
import json
import os
import random
import sys
from statistics import mean

RESAMPLES = 2000


def load(root):
    """(family, estimate, aid, wheels) -> layout -> [report, ...]."""
    runs = {}
    for path in glob.glob(os.path.join(root, '*', '*', 'report.json')):
        name, _, layout = path.split(os.sep)[-3].partition('@')
        key = tuple(name.split('~'))
        runs.setdefault(key, {}).setdefault(layout, []).append(json.load(open(path)))
    return runs


def measure(report, what):
    if what == 'error':
        return report['endpoint_error_m']
    if what == 'time':
        return report['sim_time_s']
    return report['egomotion_failures']


def ratio(cell, base, what, rng):
    """Ratio of means over every run, its bootstrap interval over layouts,
    and each layout's ratio."""
    layouts = sorted(set(cell) & set(base))

    def pooled(chosen):
        top = [measure(r, what) for l in chosen for r in cell[l]]
        bottom = [measure(r, what) for l in chosen for r in base[l]]
        return mean(top) / mean(bottom) if mean(bottom) > 0 else float('nan')

    point = pooled(layouts)
    draws = sorted(pooled([rng.choice(layouts) for _ in layouts]) for _ in range(RESAMPLES))
    low, high = draws[int(0.025 * RESAMPLES)], draws[int(0.975 * RESAMPLES) - 1]
    per_layout = {l: round(pooled([l]), 3) for l in layouts}
    return {'ratio': round(point, 3), 'ci95': [round(low, 3), round(high, 3)], 'per_layout': per_layout}


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    runs = load(sys.argv[1])
    # One generator for the whole summary, seeded: the same runs give the
    # same intervals.
    rng = random.Random(20261204)
    out = {}
    for key in sorted(runs):
        family, estimate, aid, wheels = key
        cell = runs[key]
        reports = [r for rs in cell.values() for r in rs]
        entry = {
            'layouts': len(cell),
            'runs': len(reports),
            'error_m': round(mean(measure(r, 'error') for r in reports), 4),
            # The pose the behaviours steered by, at the end, against the
            # truth: what the robot believed when it stopped.
            'steered_pose_error_m': round(mean(r['estimate_error_m'] for r in reports), 4),
            'time_s': round(mean(measure(r, 'time') for r in reports), 1),
            'failed_frames': round(mean(measure(r, 'failures') for r in reports), 2),
            'time_limit_runs': sum(r['end'] == 'time_limit' for r in reports),
            'missed_goal_runs': sum(not r['reached_goal'] for r in reports),
            'collisions': sum(r['collisions'] for r in reports),
        }
        straight = runs.get((family, estimate, 'none', wheels))
        if aid != 'none' and straight:
            entry['error_vs_straight'] = ratio(cell, straight, 'error', rng)
            entry['time_vs_straight'] = ratio(cell, straight, 'time', rng)
        visual = runs.get((family, 'visual', aid, wheels))
        if estimate == 'default' and visual:
            entry['error_vs_visual'] = ratio(cell, visual, 'error', rng)
        exact = runs.get((family, 'visual', 'none', 'exact'))
        if wheels != 'exact' and exact:
            entry['error_vs_visual_exact_wheels'] = ratio(cell, exact, 'error', rng)
        out.setdefault(family, {}).setdefault(estimate, {}).setdefault(wheels, {})[aid] = entry
    json.dump(out, sys.stdout, indent=1, sort_keys=True)
    print()


if __name__ == '__main__':
    main()
