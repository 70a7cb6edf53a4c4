#!/usr/bin/env python3
"""Summarises a sweep of lab/scripts/aiding-families.sh, as lab/protocol.md
says: per family, estimate and aid, the mean end-point error, time and
failed frames (and, beyond the protocol, the error of the pose the
robot steered by), and each one's ratio to straight driving (the same family,
estimate and wheels) with a 95 % interval from a bootstrap over layouts
(seeds kept with their layout: layouts are what the claims generalise
over; and, as a second interval, layouts and seeds resampled apart), and
the same per layout. Prints JSON.

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
    if what == 'steered':
        return report['estimate_error_m']
    if what == 'time':
        return report['sim_time_s']
    return report['egomotion_failures']


def ratio(cell, base, what, rng, layout_rng=None):
    """Ratio of means over every run and each layout's ratio, with two 95 %
    intervals: the protocol's, from resampling layouts (each with its
    seeds), and one from resampling layouts and run seeds independently,
    since every layout is run with the same seeds and a seed's share of
    the error is then common to all of them. Given `layout_rng`, each
    layout's ratio gets an interval of its own too, from resampling its
    seeds (paired): whether a layout beyond a bound is beyond what its
    seeds' noise explains."""
    layouts = sorted(set(cell) & set(base))
    by_seed = lambda runs: {r['seed']: measure(r, what) for r in runs}  # noqa: E731
    top = {l: by_seed(cell[l]) for l in layouts}
    bottom = {l: by_seed(base[l]) for l in layouts}
    seeds = sorted(set.intersection(*(set(top[l]) & set(bottom[l]) for l in layouts)))

    def pooled(chosen_layouts, chosen_seeds):
        a = sum(top[l][s] for l in chosen_layouts for s in chosen_seeds)
        b = sum(bottom[l][s] for l in chosen_layouts for s in chosen_seeds)
        return a / b if b > 0 else float('inf')

    def interval(draw):
        draws = sorted(draw() for _ in range(RESAMPLES))
        return [round(draws[int(0.025 * RESAMPLES)], 3), round(draws[int(0.975 * RESAMPLES) - 1], 3)]

    resample = lambda xs, r=rng: [r.choice(xs) for _ in xs]  # noqa: E731
    out = {
        'ratio': round(pooled(layouts, seeds), 3),
        'ci95': interval(lambda: pooled(resample(layouts), seeds)),
        'ci95_layouts_and_seeds': interval(lambda: pooled(resample(layouts), resample(seeds))),
        # Unrounded, so that a bound is tested on the ratio itself.
        'per_layout': {l: pooled([l], seeds) for l in layouts},
    }
    if layout_rng is not None:
        out['per_layout_ci95'] = {l: interval(lambda: pooled([l], resample(seeds, layout_rng))) for l in layouts}
    return out


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    runs = load(sys.argv[1])
    # One generator for the whole summary, seeded: the same runs give the
    # same intervals.
    rng = random.Random(20261204)
    # The measure added after the protocol draws from a generator of its
    # own, so the protocol's intervals stay as they were drawn.
    added_rng = random.Random(20261205)
    layout_rng = random.Random(20261206)
    # The estimate added after the protocol (the wall compass) draws from
    # generators of its own too.
    compass_rng, compass_layout_rng = random.Random(20261207), random.Random(20261208)
    out = {}
    for key in sorted(runs):
        family, estimate, aid, wheels = key
        cell = runs[key]
        reports = [r for rs in cell.values() for r in rs]
        entry = {
            'layouts': len(cell),
            'runs': len(reports),
            'error_m': round(mean(measure(r, 'error') for r in reports), 4),
            # Not in the protocol: the pose the robot steered by against the
            # truth where it ended (the report's estimate error; in reports
            # written before it gave the pose steered by, odometry's own).
            'steered_error_m': round(mean(measure(r, 'steered') for r in reports), 4),
            'time_s': round(mean(measure(r, 'time') for r in reports), 1),
            'failed_frames': round(mean(measure(r, 'failures') for r in reports), 2),
            'time_limit_runs': sum(r['end'] == 'time_limit' for r in reports),
            # The progress check's ends: the robot held on one spot short of
            # the goal (on by default since the eighteenth run).
            'no_progress_runs': sum(r['end'] == 'no_progress' for r in reports),
            # Any other end than the goal or the time limit (no progress, a
            # behaviour's failure), by its name.
            'other_ends': sorted({r['end'] for r in reports} - {'goal_reached', 'time_limit'}),
            'missed_goal_runs': sum(not r['reached_goal'] for r in reports),
            'collisions': sum(r['collisions'] for r in reports),
        }
        protocol = estimate in ('default', 'visual')
        straight = runs.get((family, estimate, 'none', wheels))
        if aid != 'none' and straight:
            entry['error_vs_straight'] = ratio(cell, straight, 'error', *((rng, layout_rng) if protocol
                                                                          else (compass_rng, compass_layout_rng)))
            entry['time_vs_straight'] = ratio(cell, straight, 'time', rng if protocol else compass_rng)
        default = runs.get((family, 'default', aid, wheels))
        if estimate == 'compass' and default:
            entry['error_vs_default'] = ratio(cell, default, 'error', compass_rng)
            entry['steered_vs_default'] = ratio(cell, default, 'steered', compass_rng)
        visual = runs.get((family, 'visual', aid, wheels))
        if estimate != 'visual' and visual:
            entry['error_vs_visual'] = ratio(cell, visual, 'error', rng if protocol else compass_rng)
            entry['steered_vs_visual'] = ratio(cell, visual, 'steered', added_rng if protocol else compass_rng)
        exact = runs.get((family, 'visual', 'none', 'exact'))
        if wheels != 'exact' and exact:
            entry['error_vs_visual_exact_wheels'] = ratio(cell, exact, 'error', rng if protocol else compass_rng)
        out.setdefault(family, {}).setdefault(estimate, {}).setdefault(wheels, {})[aid] = entry
    json.dump(out, sys.stdout, indent=1, sort_keys=True)
    print()


if __name__ == '__main__':
    main()
