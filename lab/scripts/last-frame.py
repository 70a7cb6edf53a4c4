#!/usr/bin/env python3
"""Tracking's mean end-point error over straight driving's, per route and
layout, measured at the last frame and at the one and two frames before
it, from a sweep of `ROUTE~None` and `ROUTE~Tracking` scenarios over
layouts (`NAME@LAYOUT/seed-N/trajectory.csv`, as `lab/scripts/last-frame.sh`
runs them).

    lab/scripts/last-frame.py /tmp/runs

Prints JSON: {"route": {"layout": {"last": r, "one_before": r,
"two_before": r}}}, each `r` tracking's mean error over straight's.
"""
import glob
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trajectory_log  # noqa: E402  (lab/scripts/trajectory_log.py)

FRAMES_BACK = {"last": 1, "one_before": 2, "two_before": 3}


def frame_errors(path):
    """The position error at each frame, in order."""
    first = trajectory_log.frames(path)
    return [math.hypot(float(r['ego_x']) - float(r['true_x']), float(r['ego_y']) - float(r['true_y']))
            for r in (first[k] for k in sorted(first))]


def mean_errors(directory):
    """Per frame back, the mean error over the runs in `directory`."""
    runs = [frame_errors(p) for p in sorted(glob.glob(os.path.join(directory, 'seed-*', 'trajectory.csv')))]
    runs = [r for r in runs if len(r) >= 3]
    if not runs:
        sys.exit(f"{directory}: no runs with three frames")
    return {k: sum(r[-back] for r in runs) / len(runs) for k, back in FRAMES_BACK.items()}


def main(root):
    out = {}
    for tracking in sorted(glob.glob(os.path.join(root, '*~Tracking@*'))):
        name = os.path.basename(tracking)
        route, layout = name.split('~Tracking@')
        aided, straight = mean_errors(tracking), mean_errors(os.path.join(root, f'{route}~None@{layout}'))
        out.setdefault(route, {})[layout] = {k: aided[k] / straight[k] for k in FRAMES_BACK}
    json.dump(out, sys.stdout, indent=1, sort_keys=True)
    print()


if __name__ == '__main__':
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
