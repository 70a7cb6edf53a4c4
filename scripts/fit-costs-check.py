#!/usr/bin/env python3
"""Which form of the end-point model predicts what stays, on seeds kept apart.

Reads the trajectory.csv logs `scripts/fit-costs.sh` leaves (OUT=DIR), splits
the runs by seed (the first two thirds fit, the rest test), fits each model
form by non-negative least squares as `ubf model fit-costs` does, either at
the end points alone or at every tenth matched frame and the end, and prints
the mean negative log-likelihood of the test runs' end-point errors under
each fitted σ (2D Gaussian: lower is better).

    SEEDS=100..130 OUT=out/fit-costs-130 scripts/fit-costs.sh
    python3 scripts/fit-costs-check.py out/fit-costs-130
"""
import csv
import glob
import math
import os
import re
import sys

HALF_DEGREE = math.radians(0.5)
NAMES = ['σ_cv² per (CV·d)²', 'heading per turn', 'heading per radian', 'position per turn', 'per metre²']
MODELS = {
    'in use: steps, heading per turn and per radian': [0, 1, 2],
    '+ position per turn': [0, 1, 2, 3],
    '+ variance per metre² driven': [0, 1, 2, 4],
    'all five': [0, 1, 2, 3, 4],
}


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def checkpoints(path):
    """(features, e², is the end) at every tenth matched frame and the last, as ubf model fit-costs reads a log."""
    frames, last, last_failures = [], None, 0.0
    for row in csv.DictReader(open(path)):
        if row['frame'] == last or not row['ego_x']:
            continue
        last = row['frame']
        failures = float(row['ego_failures'])
        frames.append({
            'truth': (float(row['true_x']), float(row['true_y']), float(row['true_theta'])),
            'ego': (float(row['ego_x']), float(row['ego_y'])),
            'matched': failures == last_failures,
            'cv': float(row['ego_step_cv']) if row['ego_step_cv'] else None,
        })
        last_failures = failures
    turns, cv2, d2, out = [], 0.0, 0.0, []

    def checkpoint(f, end):
        at = f['truth'][:2]
        lever2 = [(at[0] - p[0]) ** 2 + (at[1] - p[1]) ** 2 for p, _ in turns]
        features = [cv2, sum(lever2), sum(t * l for (_, t), l in zip(turns, lever2)), len(turns), d2]
        out.append((features, (f['ego'][0] - at[0]) ** 2 + (f['ego'][1] - at[1]) ** 2, end))

    k = 0
    while k + 1 < len(frames):
        if k % 10 == 9 and frames[k]['matched']:
            checkpoint(frames[k], False)
        a, b = frames[k], frames[k + 1]
        if abs(wrap(b['truth'][2] - a['truth'][2])) > HALF_DEGREE:
            end = k + 1
            while end + 1 < len(frames) and abs(wrap(frames[end + 1]['truth'][2] - frames[end]['truth'][2])) > HALF_DEGREE:
                end += 1
            turns.append((frames[end]['truth'][:2], abs(wrap(frames[end]['truth'][2] - a['truth'][2]))))
            k = end
            continue
        d = math.hypot(b['truth'][0] - a['truth'][0], b['truth'][1] - a['truth'][1])
        if a['matched'] and b['matched'] and d >= 0.05 and b['cv'] is not None:
            cv2 += (b['cv'] * d) ** 2
            d2 += d * d
        k += 1
    checkpoint(frames[-1], True)
    return out


def solve(a, b):
    """Gaussian elimination with partial pivoting; None if singular."""
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        if abs(m[p][c]) < 1e-300:
            return None
        m[c], m[p] = m[p], m[c]
        for r in range(n):
            if r != c:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[i][n] / m[i][i] for i in range(n)]


def nnls(rows, columns):
    """Least squares with every coefficient ≥ 0, dropping the most negative until none is."""
    active = list(columns)
    while active:
        a = [[sum(x[p] * x[q] for x, _ in rows) for q in active] for p in active]
        b = [sum(x[p] * y for x, y in rows) for p in active]
        c = solve(a, b) or [0.0] * len(active)
        worst = min(range(len(active)), key=lambda i: c[i])
        if c[worst] >= 0:
            return dict(zip(active, c))
        del active[worst]
    return {}


if len(sys.argv) != 2:
    sys.exit(f"usage: {sys.argv[0]} LOGDIR   (the OUT directory of scripts/fit-costs.sh)")
runs = []
for path in glob.glob(os.path.join(sys.argv[1], '**', 'trajectory.csv'), recursive=True):
    seed = re.search(r'seed-(\d+)', path)
    if seed:  # a sweep's layout: DIR/SCENARIO/seed-N/trajectory.csv
        runs.append((int(seed.group(1)), checkpoints(path)))
seeds = sorted({s for s, _ in runs})
if len(seeds) < 3:
    sys.exit(f"{sys.argv[1]}: need logs of at least three seeds (seed-N directories with trajectory.csv), found {len(seeds)}")
cut = seeds[len(seeds) * 2 // 3]
train = [c for s, cs in runs if s < cut for c in cs]
test = [c for s, cs in runs if s >= cut for c in cs if c[2]]
print(f"{len(runs)} logs; fitted on seeds {seeds[0]}..{cut - 1}, tested on the end points of seeds {cut}..{seeds[-1]} ({len(test)})")
for where, rows in [('end points', [c for c in train if c[2]]), ('every tenth frame', train)]:
    print(f"fitted at {where}:")
    for name, columns in MODELS.items():
        coefficients = nnls([(x, y) for x, y, _ in rows], columns)
        nll = 0.0
        for x, y, _ in test:
            variance = max(sum(coefficients.get(k, 0.0) * x[k] for k in columns), 1e-6)
            nll += math.log(variance / 2) + y / variance
        fitted = ', '.join(f"{NAMES[k]} {v:.3g}" for k, v in coefficients.items())
        print(f"  {name:48s} NLL {nll / len(test):+.3f}   {fitted}")
