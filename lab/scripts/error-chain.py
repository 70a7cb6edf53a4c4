#!/usr/bin/env python3
"""Where a run's end-point error comes from, link by link.

Each egomotion pose rests on a chain of estimates: the frame was matched
to a keyframe (`ego_anchor` in trajectory.csv), which was matched to an
earlier one, and so on back to the start; a bridged frame rests on the
frame before it and odometry. This splits the error at the last frame
into what each link of that chain added, to first order: the link's own
position error, plus its own heading error carried over the distance from
the link's end to the last frame. The parts add up to the end-point error
(the script prints how closely), so removing a class of links from the sum
says how much of the error it carries.

Links are classed as `short` (the keyframe less than 2 m back), `long`
(2 m or more: matched mostly to far landmarks, which fix bearings well and
sideways motion poorly) and `bridge` (odometry). Runs are grouped by
scenario name (a sweep's `NAME@LAYOUT` directories under one NAME).

    ubf sweep route.ron --seeds 100..110 --trajectories --out /tmp/runs
    lab/scripts/error-chain.py /tmp/runs

Prints JSON: per scenario, the runs, the RMS end-point error, how closely
the chain's sum matches it, and per class the links per run, the RMS of
what they add and the RMS end-point error without them.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trajectory_log  # noqa: E402  (lab/scripts/trajectory_log.py)

LONG_M = 2.0


def wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi


def chain_parts(path):
    """The end-point error (x, y) at the last frame and each link's part of
    it, as (class, (dx, dy)), from one trajectory.csv."""
    first = trajectory_log.frames(path)
    if not first:
        return None

    def true(r):
        return float(r['true_x']), float(r['true_y']), float(r['true_theta'])

    def error(r):
        t = true(r)
        return float(r['ego_x']) - t[0], float(r['ego_y']) - t[1], wrap(float(r['ego_theta']) - t[2])

    frames = sorted(first)
    last = first[frames[-1]]
    end = true(last)
    parts = []
    frame = frames[-1]
    previous = dict(zip(frames[1:], frames))
    while frame in previous:
        row = first[frame]
        anchor = int(row['ego_anchor']) if row['ego_anchor'] else previous[frame]
        if anchor not in first:
            break
        (tf, ta), (ef, ea) = (true(row), true(first[anchor])), (error(row), error(first[anchor]))
        # What the anchor's error alone puts on this frame: its position
        # error, and its heading error swung over the link.
        inherited = (ea[0] - ea[2] * (tf[1] - ta[1]), ea[1] + ea[2] * (tf[0] - ta[0]), ea[2])
        own = (ef[0] - inherited[0], ef[1] - inherited[1], wrap(ef[2] - inherited[2]))
        part = (own[0] - own[2] * (end[1] - tf[1]), own[1] + own[2] * (end[0] - tf[0]))
        if not row['ego_anchor']:
            kind = 'bridge'
        else:
            kind = 'long' if math.hypot(tf[0] - ta[0], tf[1] - ta[1]) >= LONG_M else 'short'
        parts.append((kind, part))
        frame = anchor
    return error(last)[:2], parts


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else 0.0


def main(roots):
    groups = {}
    for root in roots:
        for directory, _, files in os.walk(root):
            if 'trajectory.csv' not in files:
                continue
            result = chain_parts(os.path.join(directory, 'trajectory.csv'))
            if result is None:
                continue
            relative = os.path.relpath(directory, root).split(os.sep)
            name = relative[0].split('@')[0] if len(relative) > 1 else os.path.basename(os.path.abspath(directory))
            groups.setdefault(name, []).append(result)
    out = {}
    for name, runs in sorted(groups.items()):
        summed = [tuple(sum(p[k] for _, p in parts) for k in (0, 1)) for _, parts in runs]
        classes = {}
        for kind in ('short', 'long', 'bridge'):
            without = []
            alone = []
            count = 0
            for (end, parts), total in zip(runs, summed):
                mine = [p for k, p in parts if k == kind]
                count += len(mine)
                x, y = sum(p[0] for p in mine), sum(p[1] for p in mine)
                alone.append(math.hypot(x, y))
                without.append(math.hypot(total[0] - x, total[1] - y))
            classes[kind] = {
                'links_per_run': round(count / len(runs), 2),
                'rms_part_m': round(rms(alone), 4),
                'rms_error_without_m': round(rms(without), 4),
            }
        out[name] = {
            'runs': len(runs),
            'rms_error_m': round(rms([math.hypot(*end) for end, _ in runs]), 4),
            'rms_chain_sum_m': round(rms([math.hypot(*s) for s in summed]), 4),
            'links': classes,
        }
    json.dump(out, sys.stdout, indent=2)
    print()


if __name__ == '__main__':
    if len(sys.argv) < 2:
        sys.exit(f'usage: {sys.argv[0]} DIR_OR_TRAJECTORY_DIR...')
    main(sys.argv[1:])
