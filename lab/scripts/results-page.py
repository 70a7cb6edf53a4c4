#!/usr/bin/env python3
# Writes docs/results.md from the JSON and text the commands below leave in
# out/, so that no number on that page is copied by hand. Run
# lab/scripts/results-data.sh first (it runs every command, a few minutes on two
# cores), then this script.
import json
import os


def load(name):
    return json.load(open(os.path.join('out', name)))


T = ['none', 'zigzag', 'scan', 'tracking']
ROUTES = ['1->2 (far landmarks ahead)', '2->1 (near landmarks ahead)', 'feature-poor']
SHORT = {ROUTES[0]: '1→2', ROUTES[1]: '2→1', ROUTES[2]: 'feature-poor'}
fit = open('out/fit.txt').read().strip()
table2 = load('table2.json')
costs = load('fit-costs.json')
t4 = load('table4.json')
dev = load('endpoint.json')
dev_cv = load('endpoint-cv.json')
rtt = load('endpoint-rtt.json')
held = {seed: load(f'endpoint-held-{seed}.json') for seed in (101, 202, 303)}
held2 = {seed: load(f'endpoint-held-{seed}.json') for seed in (707, 808, 909)}
held3 = {seed: load(f'endpoint-held-{seed}.json') for seed in (1111, 1212, 1313)}
held4 = {seed: load(f'endpoint-held-{seed}.json') for seed in (1414, 1515, 1616)}
held5 = {seed: load(f'endpoint-held-{seed}.json') for seed in (1717, 1818, 1919)}
all_held = {**held, **held2, **held3, **held4, **held5}
# Tracking over straight driving at the last frame and the two before (lab/scripts/last-frame.sh).
FILE_ROUTE = {ROUTES[0]: 'route-1-2', ROUTES[1]: 'route-2-1', ROUTES[2]: 'feature-poor'}
last_frame = {}
for first_seed in (1000, 3000, 6000, 7000, 8000):
    for route, layouts in load(f'last-frame-{first_seed}.json').items():
        last_frame.setdefault(route, {}).update(layouts)


def misses_at(frame):
    """The held-out (layout, route) cases where tracking ends beyond 1.1× straight driving, measured at `frame`."""
    return {(seed, rt) for seed in all_held for rt in ROUTES if last_frame[FILE_ROUTE[rt]][str(seed)][frame] > 1.1}


LAYOUTS = [101, 202, 303, 707, 808, 909, 1111, 1212, 1313, 1414, 1515, 1616, 1717, 1818, 1919]
held3d = {seed: load(f'endpoint-held-{seed}-3d.json') for seed in LAYOUTS}
fused_held = {f: {seed: load(f'endpoint-held-{seed}-{f}.json') for seed in LAYOUTS} for f in ('sideways', 'full')}
steps = {model: load(f'steps-{model}.json') for model in ('Geometric', 'Geometric3d')}
costs130 = load('fit-costs-130.json')
levels = load('fit-costs-levels.json')
levels130 = load('fit-costs-levels-130.json')
# The coefficients in use: ActionAiding's `costs` default, as it describes it.
described = next(line for line in open('out/action-aiding.md') if line.startswith('| `costs` |'))
in_use = {k.strip(): float(v) for k, v in (kv.split(':') for kv in described.split('`')[3].strip('()').split(','))}
held_cv = load('endpoint-held-101-cv.json')
env = load('where-aiding-pays.json')
banks = load('keyframes.json')['scenarios']
ablation = [(label, load(f'ablation-{k}.json')) for k, label in [
    ('0', 'before: reference given up after 3 s'),
    ('1', '+ keyframe bank, odometry bridge, outages'),
    ('2', '+ feasible, end-point decision (uncalibrated)'),
    ('3', '+ truth at the sensed instant, turn gate'),
    ('4', '+ 8 % outliers (Table 2), odometry gate, fitted costs'),
    ('5', '+ anchor by predicted error, refitted costs'),
    ('6', '+ straight on the odometry bridge, odometry χ² gate'),
    ('7', '+ end game: turns keep their way round, the last stretch steers at the goal'),
    ('8', "+ each landmark's later depth error along its own line of sight"),
]] + [("+ costs fitted against straight runs: today", dev)]

out = []
w = out.append


def time_limit_sentence():
    """Which runs of the end-point tables ran out of time, counted, not assumed."""
    tables = {'seeds 0..30': dev, 'the CV objective': dev_cv, 'rotate-then-translate': rtt, 'layout 101 with the CV objective': held_cv}
    tables.update({f'layout {seed}': d for seed, d in all_held.items()})
    def ended(key):
        return [f"{name}, {SHORT[route]}, {est}, {t} ({c[key]})"
                for name, data in tables.items() for route in ROUTES
                for est, techniques in data['routes'][route].items() for t, c in techniques.items() if c.get(key)]
    hits, gave_up = ended('runs_time_limit'), ended('runs_no_progress')
    said = (f"No run of the {len(tables)} end-point experiments on this page ended on the time limit." if not hits
            else "Runs that ended on the time limit: " + "; ".join(hits) + ".")
    if gave_up:
        said += (" Runs the progress check ended (the robot held on one spot short of the goal, `end: no_progress`): "
                 + "; ".join(gave_up) + ". Most are one seed of a set whose odometry drift pins the robot beside a wall near the goal, where before the check it dithered until its pose crept into the goal's tolerance (replayed: layout 707, route 1→2, the scan, seed 3025, held within 0.5 m for 135 s, then at the goal by its pose and 0.299 m off; with the check it stops at 387 s, 0.306 m off).")
    return said


def cell(c):
    e = c['endpoint_error_m']
    return f"{e['mean']:.3f} [{e['ci95'][0]:.3f}, {e['ci95'][1]:.3f}]"


def ratio(a, b):
    return a['endpoint_error_m']['mean'] / b['endpoint_error_m']['mean']


def geometric_ci(xs):
    """Geometric mean of ratios over layouts, with a t interval on the logs."""
    import math
    logs = [math.log(x) for x in xs]
    m = sum(logs) / len(logs)
    sd = (sum((x - m) ** 2 for x in logs) / (len(logs) - 1)) ** 0.5
    half = {10: 2.262, 12: 2.201, 15: 2.145, 20: 2.093}.get(len(logs), 2.0) * sd / len(logs) ** 0.5
    return math.exp(m), math.exp(m - half), math.exp(m + half)


w("# Results: action aiding on the simulator, beside the thesis\n")
w("Every table on this page comes from the commands shown, on the committed code, and the page is written by `lab/scripts/results-page.py` from their output (`lab/scripts/results-data.sh` runs them), so no table is copied by hand; the prose's diagnoses quote single development runs (named by layout and seed, reproducible with `ubf run`) that the page does not regenerate. The thesis's numbers stand beside ours. Nothing was tuned towards the thesis's outcome tables (4–11): the simulator is calibrated to its input measurements only (Table 1's pixel noise, Table 2's share of gross mismatches, its frame rate, speeds and geometry), and the decision's coefficients are measured from our own run logs on seeds kept apart from every figure below.\n")
def fusion_row(route, data):
    """Over the held-out layouts: straight driving's mean error, and tracking's and the scan's ratios to it."""
    import math
    cells = [d['routes'][route]['rigid'] for d in data.values()]
    straight = sum(c['none']['endpoint_error_m']['mean'] for c in cells) / len(cells)
    tr = [ratio(c['tracking'], c['none']) for c in cells]
    sc = [ratio(c['scan'], c['none']) for c in cells]
    gm = lambda xs: math.exp(sum(math.log(x) for x in xs) / len(xs))
    fails = max(c['tracking']['egomotion_failures']['mean'] for c in cells)
    return straight, gm(tr), sum(x <= 1.1 for x in tr), gm(sc), sum(x <= 1.5 for x in sc), fails


w("## In short\n")
w("- **Over families of layouts, as set out before the runs.** The experiment of [lab/protocol.md](../lab/protocol.md) (eight layout families, twelve fresh layouts each, 30 seeds, both estimates, every aid and miscalibrated wheels) is written up on its own page, [aiding-families.md](aiding-families.md), by the protocol's rules. Where its verdicts and the single-layout and held-out figures below differ, its verdicts are the ones that generalise; the sections below stay as the reproductions and diagnoses they are. Every table below is regenerated on today's code; where its prose quotes development runs, it says they are of the code of their time.")
pays_early = [c for c in env['cells'] if c['ratio_ci95'][1] < 1.0]
losses_early = [c for c in env['cells'] if c['ratio_ci95'][0] > 1.0]


def tracking_over(data):
    """The routes of one held-out layout where tracking ends beyond 1.1× straight driving."""
    return sum(ratio(data['routes'][rt]['rigid']['tracking'], data['routes'][rt]['rigid']['none']) > 1.1 for rt in ROUTES)


held_ratios = {t: [ratio(d['routes'][rt]['rigid'][t], d['routes'][rt]['rigid']['none']) for d in all_held.values() for rt in ROUTES] for t in T}
w("- **Aiding no longer multiplies the error.** Before this work, switching ActionAiding on multiplied the end-point error by up to 40 (the first table below). The cause was defects, not physics: egomotion threw its motion away after 3 s without a usable frame, the decision accepted headings egomotion could not use and charged nothing for turning, and the end-point error compared poses taken at different instants. With those fixed, every technique ends within a few tenths of a metre of straight driving over 40 m. The estimator itself had a defect too, found by driving straight lines off the corridor's axis: it laid a landmark's later depth error along the earlier line of sight; corrected, every technique ends 16–30 % nearer on route 1→2 of ten training layouts, and real KITTI frames 1.11 % of the path off instead of 1.53 %.")
w(f"- **Where aiding pays, the physical scan pays most.** On the {len(held_ratios['scan'])} held-out route-and-layout cases the scan ends at {min(held_ratios['scan']):.2f}–{max(held_ratios['scan']):.2f}× straight driving's error, " + f"and on the environment map (held-out seeds and layout) the best aided technique gains in {len(pays_early)} of {len(env['cells'])} environments with its whole interval below 1 (" + "; ".join(f"{c['factor']} {c['level']}: {c['best']} ×{c['ratio']:.2f}" for c in pays_early) + ") and loses in " + (f"{len(losses_early)} (" + "; ".join(f"{c['factor']} {c['level']}: {c['best']} ×{c['ratio']:.2f}" for c in losses_early) + ")" if losses_early else "none") + f". Tracking misses its 1.1× target on {sum(tracking_over(d) for d in all_held.values())} of {3 * len(all_held)} held-out route-and-layout cases (it missed on 11 before its costs were fitted against straight runs; measured one frame before the last, on {len(misses_at('one_before'))}, {len(misses_at('one_before') & misses_at('last'))} of them the same: the misses are the last frame's, see *Against the targets*): fitted to what a path changes against driving straight, the decision's step term, the thesis's CV, comes out zero, as the runs whose views it rated better did not end nearer; so tracking drives at the goal and turns only where too few landmarks would be in view there (section *The decision's coefficients*).")
side_held = {rt: (fusion_row(rt, all_held)[0], fusion_row(rt, fused_held['sideways'])[0]) for rt in ROUTES}
w("- **Far landmarks carry egomotion's error; odometry's sideways motion removes most of it.** Split along the chain of estimates each pose rests on, straight driving's error on route 1→2 sits almost wholly in the few matches to keyframes metres back, which rest on far landmarks that cannot tell a sideways slide from a slight turn. Taking odometry's sideways motion into those matches (`odometry_fusion: Sideways`, now the default; this page's other runs, as the thesis, use purely visual egomotion) takes straight driving's mean error on the held-out layouts from " + ", ".join(f"{a:.3f} to {b:.3f} m on {SHORT[rt]}" for rt, (a, b) in side_held.items()) + ", and survives wheels 1 % off in scale, which the fusion of all of odometry's motion does not. Steering by that pose instead of odometry (`navigate: true`) keeps a veering robot off the walls where steering by odometry left some runs bumping a wall until the time limit (section *Odometry fusion*). Why a heading off the corridor's axis costs is measured too: the estimator reads part of a far landmark's depth noise as a turn (an errors-in-variables bias; taking its expected value off removes the penalty but cost straight driving more than it won, as the estimator's precision on far landmarks leans on odometry's turn).")
w("- **The thesis's large gains are not reproduced.** With the noise its own Tables 1 and 2 report, straight driving already ends within 2 % of the distance with either estimator, where the thesis's robot ended 21–45 % off (Tables 5–7); there is little left for aiding to win. Why the thesis's straight runs were so much worse is not known here (section *Why the thesis's gains do not appear*).\n")

w("## What each fix did\n")
w("Route 1→2, rigid estimator, seeds 0..30, mean end-point error in metres (the evaluative techniques use the end-point objective from the second fix on). Each row is `ubf experiment thesis-endpoint --json` at the commit named in `lab/scripts/results-data.sh`.\n")
w("| code | none | zig-zag | scan | tracking | scan failures / run | tracking failures / run |")
w("| --- | --- | --- | --- | --- | --- | --- |")
for label, data in ablation:
    r = data['routes'][ROUTES[0]]['rigid']
    w(f"| {label} | " + " | ".join(f"{r[t]['endpoint_error_m']['mean']:.2f}" for t in T)
      + f" | {r['scan']['egomotion_failures']['mean']:.0f} | {r['tracking']['egomotion_failures']['mean']:.1f} |")
w("")
w("The first fix carries almost all of the change: the old tracker gave its reference frame up after 3 s without a match, and the motion since with it; with a bank of keyframes and an odometry bridge nothing is dropped, and the scan's sweep costs one rotation estimate (the frame at the chosen heading is matched against the keyframe taken before the sweep). The scan still reports many failed frames: those are frames at the ends of its sweep that share no landmarks with any keyframe; the robot stands still while they are bridged (outage distance in the tables below). The fifth row carries 8 % gross stereo mismatches instead of 2 %, which raises straight driving's error (see Table 2 below), and an odometry gate without which those mismatches occasionally slid a motion metres along the line of sight (seed 1018 of layout 303: 6.2 m of false forward motion in one frame).\n")
before, today = ablation[4][1]['routes'][ROUTES[0]]['rigid'], ablation[5][1]['routes'][ROUTES[0]]['rigid']
change = lambda t: f"{before[t]['endpoint_error_m']['mean']:.2f} to {today[t]['endpoint_error_m']['mean']:.2f} m"
w(f"The sixth row changes how a frame's anchor is chosen. The keyframe with the most certain pose, metres back, used to anchor a frame whenever it matched on six landmarks; now the newest keyframe is matched too, and the match predicting the smaller error wins (each keyframe carries its pose covariance, each match the estimator's inverse information; see [perception.md](perception.md#public-datasets), where the same change stopped real KITTI frames landing metres off). The coefficients were refitted for it (next section). On this route straight driving's error went from {change('none')}, the scan's from {change('scan')}, tracking's from {change('tracking')}, and the zig-zag's from {change('zigzag')}.\n")
before, today = ablation[5][1]['routes'][ROUTES[0]]['rigid'], ablation[6][1]['routes'][ROUTES[0]]['rigid']
w(f"The seventh row makes two changes, found by replaying the runs where tracking ended worst on development layouts 404, 505 and 606 (seeds 2000..2030, kept apart from every table here). First, a heading needs four landmarks predicted in view, and where driving at the goal had fewer, the decision turned away to one that had them, often in the last metre before the goal; the frames after such a turn matched keyframes 9 m back on three or four landmarks and landed decimetres off. Driving at the goal now stays a candidate there, costed as a step on the odometry bridge (its heading drift per metre, measured by `ubf model fit-costs` on the bridged steps of the training logs). On the development layouts that alone took tracking's worst route from 1.27× to 1.00× straight driving. Second, the odometry gate now also weighs a rigid motion's disagreement with odometry by both covariances (the estimate's, and odometry's own error model), rejecting what a χ² test at 99.9 % cannot explain: far landmarks with a mismatch among them agreed on motions 0.9 m longer than the wheels drove, with a claimed σ of 0.14 m. That lowered straight driving's error on the development layouts' route 2→1 from 0.09–0.13 m to 0.07 m. On route 1→2 here straight driving's error went from {change('none')}, the scan's from {change('scan')}, tracking's from {change('tracking')}, and the zig-zag's from {change('zigzag')}.\n")
before, today = ablation[6][1]['routes'][ROUTES[0]]['rigid'], ablation[7][1]['routes'][ROUTES[0]]['rigid']
fails = lambda t: f"{before[t]['egomotion_failures']['mean']:.1f} to {today[t]['egomotion_failures']['mean']:.1f}"
w(f"The eighth row fixes the end game, found by replaying runs that failed many frames near the goal. Three defects, each in how ActionAiding turns: (1) a turn sent the long way round (after the short way was blocked, by AvoidCollision turning away from a wall, say) recomputed its direction from the heading error every tick, so where the error wrapped past 180° the direction flipped and the robot rocked on the spot until the turn was declared stuck again, then drove a circle; it now keeps the direction it was given. (2) The last stretch turned on the spot to a bearing fixed at the last decision and drove a step along it, passing a goal that odometry or a nudge from AvoidCollision had put off the line and turning back beside a wall; it now steers at the goal every tick, slowing in proportion to the distance so that it cannot orbit it, and goes the long way round when blocked. (3) A turn blocked a few degrees short went the long way, a full revolution failing every frame; less than a quarter turn short it now steers while driving. On this route tracking's failures per run went from {fails('tracking')} and its error from {change('tracking')}; the scan's from {change('scan')}.\n")
before, today = ablation[7][1]['routes'][ROUTES[0]]['rigid'], ablation[8][1]['routes'][ROUTES[0]]['rigid']
w(f"The ninth row changes how the rigid estimator weighs a matched landmark: by the inverse covariance of its residual, the sum of two ellipses stretched along the lines of sight, the keyframe's from where the robot was and the frame's from where it is. Both used to be laid along the keyframe's line, which ignores the parallax between viewpoints metres apart, so a far landmark's depth error, tilted by a few degrees, passed for a precise bearing. The frame's ellipse now lies along its own line, turned by the turn odometry measured (see [perception.md](perception.md#public-datasets): on real KITTI frames it took the end point from 1.53 % to 1.11 % of the path). It was found by driving route 1→2 straight along a line 1.7° off the corridor's axis, with no turn (`ubf sweep` of the route file with `start: (x: 1.0, y: -0.6, heading_deg: 1.69)` and the goal at `y: 0.6`, beside the file as it is, on ten training layouts 2121..3030, seeds 100..130; error RMS over seeds at the last frame before 36 m, geometric mean over layouts): that ended 24 % further off than the centre line did, the penalty vanished with frame-to-frame matching and grew with the keyframes' reach (12 % with a 3 m reach, 36 % with 30 m), and with the fix it is 16 %. On those layouts the fix took straight driving's error on route 1→2 down by 18 %, tracking's by 20 %, the scan's by 16 % and the zig-zag's by 30 % (geometric means over layouts of the mean error, each run `ubf run` of the route file with the layout's seed and the technique, before and after the change). On this route straight driving's error went from {change('none')}, the scan's from {change('scan')}, tracking's from {change('tracking')}, and the zig-zag's from {change('zigzag')}.\n")
before, today = ablation[8][1]['routes'][ROUTES[0]]['rigid'], dev['routes'][ROUTES[0]]['rigid']
fails = lambda t: f"{before[t]['egomotion_failures']['mean']:.1f} to {today[t]['egomotion_failures']['mean']:.1f}"
w(f"The last row fits the decision's coefficients to what a path changes against driving straight instead of to end points as they are (section *The decision's coefficients, measured*): the step term, the thesis's CV, comes out zero, so tracking drives at the goal unless too few landmarks would be in view there. On this route straight driving's error went from {change('none')}, the scan's from {change('scan')}, tracking's from {change('tracking')} (its failures per run from {fails('tracking')}), and the zig-zag's from {change('zigzag')}.\n")

w("## Noise from the thesis's inputs: Table 2\n")
w("```sh run\nubf experiment thesis-table2\n```\n")
th = table2['thesis']
best = table2['best_outlier_share']
row = next(r for r in table2['rows'] if r['outlier_share'] == best)['stats']
zero = table2['rows'][0]['stats']
w(f"The thesis's Table 2 lists the egomotion each of 13 landmarks gives for one frame step; less the 0.15 m step, the errors have a median of {th['median_abs_m']:.2f} m, and {100*th['beyond_0_1_m']:.0f} %, {100*th['beyond_1_m']:.0f} % and {100*th['beyond_2_m']:.0f} % of them exceed 0.1, 1 and 2 m. The command rebuilds §3.1's scene from Table 1 (its five located landmarks, 34–50 m away), takes {table2['trials']} frame pairs a step apart with the Table-1 pixel noise ({table2['pixel_noise_px']} px), and computes the same statistics for gross-mismatch shares from 0 to 20 %.\n")
w("| | median error m | > 0.1 m | > 1 m | > 2 m |")
w("| --- | --- | --- | --- | --- |")
w(f"| thesis, Table 2 | {th['median_abs_m']:.2f} | {100*th['beyond_0_1_m']:.0f} % | {100*th['beyond_1_m']:.0f} % | {100*th['beyond_2_m']:.0f} % |")
w(f"| simulator, no mismatches | {zero['median_abs_m']:.2f} | {100*zero['beyond_0_1_m']:.0f} % | {100*zero['beyond_1_m']:.0f} % | {100*zero['beyond_2_m']:.0f} % |")
w(f"| simulator, {100*best:.0f} % mismatches (nearest beyond 1 and 2 m) | {row['median_abs_m']:.2f} | {100*row['beyond_0_1_m']:.0f} % | {100*row['beyond_1_m']:.0f} % | {100*row['beyond_2_m']:.0f} % |")
w("")
w(f"Pixel noise alone gives no error beyond 2 m; the tail needs gross mismatches, and {100*best:.0f} % reproduces it. The route scenarios therefore use `outlier_share: {best:.2f}`. The median is higher than the thesis's; the scene cannot be rebuilt exactly, since Table 1 locates only five landmarks, all 34–50 m away, and Table 2's other eight (some with errors of 2–7 cm) are not located in the text. Raising the mismatches from 2 % to 8 % raised straight driving's error on route 1→2 from 0.55 to 0.71 m (first table), and even 1 px of pixel noise, twenty times Table 1's, leaves it near a metre (environment map below): noise is not what separates the thesis's 14 m from our fractions of a metre.\n")

w("## The decision's coefficients, measured\n")
w("```sh run-slow\nlab/scripts/fit-costs.sh      # runs the routes on seeds 100..110 and calls: ubf model fit-costs out/fit-costs --against out/fit-costs/*-None\nSEEDS=100..130 lab/scripts/fit-costs.sh\nubf model fit-costs out/fit-costs      # the same runs' end points as they are\n```\n")
w(f"The end-point objective weighs a step's translation variance against the heading variance a turn leaves, carried over the distance still to go. The coefficients are measured on {costs['logs']} runs of the three routes (straight, zig-zag, scan and tracking with the CV objective, so that there are plenty of turns, and tracking with the end-point objective), by non-negative least squares on `e² ≈ σ_cv²·Σ(CV·d)² + Σ_turns (per_turn + per_rad·|turn|)·lever²`, a turn being any frame interval whose heading changed by more than half a degree. They are fitted two ways. The decision chooses between paths through the same place, so its coefficients are fitted to what a path changes: each run's squared end-point error less that of the straight run of the same route and seed, against the same difference of the terms (`--against`). Fitted instead to the end points as they are, across the routes, the step term is also credited with what separates one route from another: where the landmarks are far, the steps' CVs and the errors are both larger. Those coefficients, the *levels*, are what a run's predicted σ (the tables below) is computed with:\n")
w("| coefficient | in use (decision) | against straight runs, seeds 100..110 | against straight runs, seeds 100..130 | levels, seeds 100..110 | levels, seeds 100..130 |")
w("| --- | --- | --- | --- | --- | --- |")
for key, name, unit in [
    ('step_sigma_per_cv', 'translation σ per unit step CV per metre', ''),
    ('heading_var_per_turn', 'heading variance per turn', ' rad²'),
    ('heading_var_per_rad', 'heading variance per radian turned', ' rad²'),
    ('bridge_heading_var_per_m', 'heading variance per metre on the odometry bridge (measured directly)', ' rad²'),
]:
    w(f"| {name} | {in_use[key]:.3g}{unit} | {costs[key] or 0:.3g}{unit} | {costs130[key] or 0:.3g}{unit} | {levels[key] or 0:.3g}{unit} | {levels130[key] or 0:.3g}{unit} |")
w("")
free = costs130['unconstrained']
w(f"Against straight runs the step term comes out zero: free in sign, the least squares put σ_cv² at {free[0]:.2f} (and the heading variance per turn at {free[1]:.1e} rad², per radian at {free[2]:.1e} rad²), so the runs whose steps had the smaller CVs did not end nearer than driving straight; they ended further off. A camera steered to the views the CV rates best (below) says the same: fitted on its runs on the three routes against straight driving (seeds 100..130, the step term alone, with the levels' σ_cv in its decision so that it looks aside), σ_cv² comes out −0.10 [−0.38, +0.13] (95 % bootstrap interval; `ubf sweep --trajectories` of the three route files steered and straight, then the same least squares with the step term alone in a scratch Python replica, since `ubf model fit-costs` needs turns and refuses runs without them; a development measurement, not regenerated here). Fitted to the end points as they are, the same runs give σ_cv {levels130['step_sigma_per_cv']:.2f}: the CV does go with the error across routes, but within one route it does not tell which path ends nearer. That is the finding of the sections below (*The line driven matters as much as any turn*) put as a measurement of the decision's own term. So the decision in use puts nothing on a step's view, charges a turn {in_use['heading_var_per_rad']:.3g} rad² per radian (now and back to the goal bearing, over the distance still to go), and drives at the goal unless too few landmarks are predicted there for egomotion, where it weighs the odometry bridge's heading drift (measured directly on the {costs130['bridged_steps']} bridged steps: {(costs130['bridge_heading_var_per_m'] ** 0.5) * 57.2958:.2f}° per √m, where the routes' odometry slips 0.2° per √m; fitted at the end point beside the other terms, against straight runs, it comes out {costs130['bridge_heading_var_per_m_at_end']:.2e} rad² per metre, so the bridge is priced at what of it stays) against the smallest turn to a heading that has them. The coefficients in use are those of seeds 100..130 (the sweep ran with them in use; the turns it fits are the CV objective's, about {costs130['turn_mean_deg']:.0f}° on average). Until this change the decision took the coefficients fitted to end points as they are (σ_cv 0.90, 9.3·10⁻⁶ rad² per radian, 1.2·10⁻⁵ rad² per turn, fitted with older code); on the ten training layouts (2121..3030, seeds 100..130, `ubf sweep --layout-seeds` of the route files with tracking beside them driven straight) tracking then ended 1.13×, 0.99× and 1.04× straight driving's error on routes 1→2, 2→1 and feature-poor (geometric means over the layouts; 8 of the 30 route-layouts beyond 1.1×), and with the coefficients in use 1.00×, 0.99× and 1.00× (2 of 30: ×1.24 on layout 2626 feature-poor and 2323 route 2→1, both the last frame's, as below). On three layouts first run after the change (3131, 3232, 3333, seeds 9000..9030, the same commands) tracking ends 1.00×, 0.98× and 1.01× (feature-poor ×1.22 on layout 3232, the last frame's too), where the old coefficients gave 0.97×, 0.98× and 1.00×; the scan there ends 0.77×, 0.64× and 1.16×.\n")
w("Whether another form of the model would predict better was measured on seeds kept apart (`ubf model fit-costs out/fit-costs-130 --check`: fitted on seeds 100..120, the mean negative log-likelihood of the end-point errors of seeds 120..130 under each fitted σ; lower is better). At the end points the extra terms add nothing: a position variance per turn and a variance per metre driven whatever the CV are each fitted to zero, with the same likelihood; fitting at every tenth frame instead of the end points predicts worse (the forms are fitted to end points as they are; the check does not pair runs):\n")
w("```text output\n" + open('out/fit-costs-check.txt').read().rstrip() + "\n```\n")
w(f"Frame by frame the errors are far larger: across a turn the heading differs from the truth by {costs['turn_rms_error_deg']:.2f}° RMS (turns of {costs['turn_mean_deg']:.0f}° on average), and a single straight step by {costs['step_rms_error_m']:.2f} m. Most of that does not stay: 80 such steps would end about {costs['step_rms_error_m'] * 80 ** 0.5:.1f} m off if their errors added up, and the straight runs end {dev['routes'][ROUTES[0]]['rigid']['none']['endpoint_error_m']['mean']:.2f} m off; in the logs the pose swings from frame to frame as different keyframes anchor it, and swings back. An earlier fit to the per-frame errors put a turn's heading variance at 5.8·10⁻⁴ rad², about 40 times what stays in the coefficients of that time. The coefficients in use are the defaults of `ActionAiding(costs: ...)` (`DecisionCosts::levels` holds the levels); the thesis-faithful CV objective is `objective: Cv`.\n")

w("## End-point error: Tables 5–7 and 10\n")
w("```sh run\nubf experiment thesis-endpoint                           # seeds 0..30, each route's own layout\nubf experiment thesis-endpoint --objective cv            # the thesis's CV-only decision\nubf experiment thesis-endpoint --seeds 1000..1030 --layout-seed 101   # held out (also 202, 303)\n```\n")
w("Three routes mirror §4.4.2: 40.7 m towards far landmarks (the corridor opens into a lobby, doors 20 m past the goal), the same distance towards near ones, and 20.4 m past a long featureless wall. Error is |true position − egomotion position| at the last frame, m: mean and 95 % CI over 30 seeds. *Pred. σ* is the end-point σ the decision's model predicts for the path driven (from odometry and the step CVs, no ground truth); *act/pred* is the RMS of the actual errors over the RMS of the predicted σ (1 = calibrated). *Outage m* is metres driven on the odometry bridge. " + time_limit_sentence() + "\n")
span = {t: [dev['routes'][rt]['rigid'][t]['actual_over_predicted'] for rt in ROUTES] for t in T}
w("The model's prediction of the end-point error (act/pred) ranges, over the three routes, " + "; ".join(f"{t} {min(span[t]):.2f}–{max(span[t]):.2f}" for t in T) + ": right to within a factor of about two for straight driving and tracking; above 1 the model is optimistic, below 1 pessimistic.\n")
thesis_ep = {
    ROUTES[0]: {'none': '14.04', 'zigzag': '10.03', 'scan': '3.94', 'tracking': '3.94', 'camera': '—'},
    ROUTES[1]: {'none': '8.64', 'zigzag': '5.70', 'scan': '2.24', 'tracking': '2.24', 'camera': '—'},
    ROUTES[2]: {'none': '9.19', 'zigzag': 'failed', 'scan': '2.24', 'tracking': '2.24', 'camera': '—'},
}
for route in ROUTES:
    w(f"### {route}, seeds 0..30\n")
    w("| technique | rigid: error m [95 % CI] | × straight | pred. σ m | act/pred | failures | outage m | time + % | simple 2D: error m | × straight | thesis m (eval.) |")
    w("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    r, s2 = dev['routes'][route]['rigid'], dev['routes'][route]['simple2d']
    for t in T + ['camera']:
        c = r[t]
        w(f"| {t} | {cell(c)} | {ratio(c, r['none']):.2f} | {c['predicted_sigma_m']['mean']:.2f} | {c['actual_over_predicted']:.2f} | {c['egomotion_failures']['mean']:.1f} | {c['outage_m']['mean']:.2f} | {c['time_overhead_pct']['mean']:.0f} | {s2[t]['endpoint_error_m']['mean']:.2f} | {ratio(s2[t], s2['none']):.2f} | {thesis_ep[route][t]} |")
    w("")

w("### Held out: layouts and seeds nobody tuned on\n")
w("Rigid estimator, end-point objective: mean error (m) of each aided technique over straight driving's in the same layout and seeds. Every set shows the committed code. The first three layouts (seeds 1000..1030) have been reported since the keyframe bank. The odometry bridge and χ² gate were developed on other layouts (404, 505, 606, seeds 2000..2030), and layouts 707, 808 and 909 (seeds 3000..3030) were first run after them. Layouts 1111, 1212 and 1313 (seeds 6000..6030) were first run to check a later idea (ending the last step beside the goal instead of a full step on), which was dropped (on layout 1111 route 1→2 it multiplied tracking's failures and its time many times over). The end-game fixes were developed on the development layouts and on three single runs replayed from the second and third sets (808 seed 3010, 1111 seed 6001, 909 seed 3025), so those sets are no longer clean; layouts 1414, 1515 and 1616 (seeds 7000..7030) were first run after the fixes. Layouts 1717, 1818 and 1919 (seeds 8000..8030) were first run after the estimator's line-of-sight fix (the ninth row of the first table) and the trial of an information-based step term (below), which was dropped; nothing was developed or tried on them. A tracking ratio beyond 1.1 is in bold, and so is a failure count beyond 5.\n")
w("| layout | route | none m | zig-zag × | scan × | tracking × [95 % CI of tracking m] | tracking failures / run | camera × |")
w("| --- | --- | --- | --- | --- | --- | --- | --- |")
bold = lambda text, over: f"**{text}**" if over else text
for seed, data in all_held.items():
    for route in ROUTES:
        r = data['routes'][route]['rigid']
        tr, fails = ratio(r['tracking'], r['none']), r['tracking']['egomotion_failures']['mean']
        ci = r['tracking']['endpoint_error_m']['ci95']
        w(f"| {seed} | {SHORT[route]} | {r['none']['endpoint_error_m']['mean']:.3f} | {ratio(r['zigzag'], r['none']):.2f} | {ratio(r['scan'], r['none']):.2f} | {bold(f'{tr:.2f}', tr > 1.1)} [{ci[0]:.3f}, {ci[1]:.3f}] | {bold(f'{fails:.1f}', fails > 5)} | {ratio(r['camera'], r['none']):.2f} |")
w("")
cases = [(seed, rt, d['routes'][rt]['rigid']) for seed, d in all_held.items() for rt in ROUTES]
worst_scan = max(ratio(r['scan'], r['none']) for _, _, r in cases)
missed = [(seed, rt, ratio(r['tracking'], r['none'])) for seed, rt, r in cases if ratio(r['tracking'], r['none']) > 1.1]
failing = [(seed, rt, r['tracking']['egomotion_failures']['mean']) for seed, rt, r in cases if r['tracking']['egomotion_failures']['mean'] > 5]
scan_over = [(seed, rt, r) for seed, rt, r in cases if ratio(r['scan'], r['none']) > 1.5]
scan_sentence = (f"The scan stays within {worst_scan:.2f}× straight driving on every held-out route (target 1.5×)." if not scan_over else
                 f"The scan stays within 1.5× straight driving (the target) on {len(cases) - len(scan_over)} of {len(cases)} held-out cases and **misses** on " +
                 "; ".join(f"layout {seed} route {SHORT[rt]} ({ratio(r['scan'], r['none']):.2f}×: {r['scan']['endpoint_error_m']['mean']:.3f} m against {r['none']['endpoint_error_m']['mean']:.3f} m)" for seed, rt, r in scan_over) + ".")
back = {k: [last_frame[FILE_ROUTE[rt]][str(seed)][k] for seed, rt, _ in cases] for k in ('last', 'one_before', 'two_before')}
missed_keys = {(seed, rt) for seed, rt, _ in missed}
persisting = [(seed, rt) for seed, rt, _ in cases if (seed, rt) in missed_keys and last_frame[FILE_ROUTE[rt]][str(seed)]['one_before'] > 1.1]
others = [(seed, rt, last_frame[FILE_ROUTE[rt]][str(seed)]['one_before']) for seed, rt, _ in cases if (seed, rt) not in missed_keys and last_frame[FILE_ROUTE[rt]][str(seed)]['one_before'] > 1.1]
last_frame_sentence = (
    f" Measured one frame before the last (`lab/scripts/last-frame.sh` over the same layouts and seeds), "
    + (f"{len(persisting)} of these misses persist" if persisting else "none of these misses persists")
    + f", and tracking is within 1.1× on {sum(r <= 1.1 for r in back['one_before'])} of {len(cases)} cases"
    + (" (the ones beyond are others: " + "; ".join(f"layout {seed} route {SHORT[rt]}, {x:.2f}×" for seed, rt, x in others) + ")" if others else "")
    + f"; two frames before the last, on {sum(r <= 1.1 for r in back['two_before'])} (at most {max(back['two_before']):.2f}×). "
    "A miss at one instant is one frame of one run, and which cases draw such a frame is chance. Looked into on layouts 2323 and 2626 (training) and 3232 (first run after the coefficients' change; "
    "development runs, not regenerated here), each miss is one or two of the 30 runs: the robot held its heading within 3° "
    "of the corridor's axis until the last metre, and its last frame was matched to a keyframe 4.7–8.0 m back on 4 landmarks, "
    "with a heading 3.6–12.5° off odometry's that the odometry gate let through (its bound grows 1° per metre, and the "
    "match claimed a heading σ of 2.4–4°); on layout 2626 feature-poor, seed 118, that last frame took egomotion from 0.02 m off "
    "(the frame before) to 0.60 m, where straight driving ended 0.015 m off. On the training layouts too, one "
    "frame earlier, 2626 is within 1.1× and 3030 is not (1.19×). Where no keyframe matches on 6 landmarks, choosing the anchor by the error its match "
    "predicts instead of by the most landmarks removed the 2626 miss but left straight driving's feature-poor "
    "error 8 % larger on average over the training layouts (6 % larger, and 2626 still beyond 1.1×, counting only matches "
    "of 4 landmarks or more, which can outvote one outlier); neither was kept."
)
pooled = {t: {rt: sum(r[t]['endpoint_error_m']['mean'] for _, r2, r in cases if r2 == rt) / sum(r['none']['endpoint_error_m']['mean'] for _, r2, r in cases if r2 == rt) for rt in ROUTES} for t in ('tracking', 'scan')}
w(f"**Against the targets.** Per route, over the {len(all_held)} held-out layouts (the mean error over all their runs, over straight driving's): tracking " + ", ".join(f"×{pooled['tracking'][rt]:.2f} on {SHORT[rt]}" for rt in ROUTES) + " (target 1.1×), the scan " + ", ".join(f"×{pooled['scan'][rt]:.2f}" for rt in ROUTES) + f" (target 1.5×). {scan_sentence} Tracking is within 1.1× on {len(cases) - len(missed)} of {len(cases)} held-out cases and **misses** on " + "; ".join(f"layout {seed} route {SHORT[rt]} ({x:.2f}×)" for seed, rt, x in missed) + (f". Its egomotion failures stay at or below 5 per run in every case (at most {max(r['tracking']['egomotion_failures']['mean'] for _, _, r in cases):.1f})" if not failing else f". Its egomotion failures stay at or below 5 per run on {len(cases) - len(failing)} of {len(cases)} and **exceed** it on " + "; ".join(f"layout {seed} route {SHORT[rt]} ({x:.1f})" for seed, rt, x in failing)) + "." + last_frame_sentence + f" Before the decision's costs were fitted against straight runs, tracking missed 1.1× on 11 of these 45 cases, 8 of them on route 1→2, where it turned towards views that did not pay (the paragraphs below), and its failures exceeded 5 per run on layout 1111 route 1→2 (7.3). On layout 1111 they came mostly from the end game (185 of the 220 failed frames of its 30 runs came within 2 m of the goal): in its run with most (seed 6001, 36 failures) odometry, which the routes steer by, had drifted 1.3 m sideways by the goal, so the robot turned 50° towards where odometry put the goal, passed it 1 m to the side and turned back round, failing frame after frame. Steering by egomotion instead (`navigate: true`, fusion off) takes that layout's tracking failures from 7.3 to 3.1 per run (`ubf sweep` of the route file with tracking and the layout's seed, seeds 6000..6030; development runs, not regenerated here), but on the ten training layouts it does not bring tracking nearer straight driving on route 1→2 (×1.16 against ×1.13, seeds 100..130). The end-game fixes (eighth row of the first table) took tracking's failures on layout 808 route 1→2 from 15.2 per run to {held2[808]['routes'][ROUTES[0]]['rigid']['tracking']['egomotion_failures']['mean']:.1f}, and on layout 707 from 5.2 to {held2[707]['routes'][ROUTES[0]]['rigid']['tracking']['egomotion_failures']['mean']:.1f}; before them, in that layout's four runs with most failures (207, 128, 38 and 25), 385 of the 398 came within 2 m of the goal, where the robot, having passed the goal just outside the tolerance, turned back and circled it. With the estimator before the ninth row of the first table, on layout 101 route 2→1 (seed 1001), after a 7.7° turn 6 m out, the egomotion pose swung by up to 0.6 m from frame to frame as keyframes metres apart took turns anchoring it, and kept 0.45 m of along-track error to the end, where straight driving ended 0.03 m off. But matching frame to frame, where no anchors alternate, leaves tracking as far behind on that layout (0.237 against 0.147 m, 1.61×, against 1.52× with the bank): the swings were not the cause of that miss, and its cause is not known. Combining each visual motion with odometry's helps every technique, and the fusion that survives a wheel scale error takes only odometry's sideways motion (section *Odometry fusion*, below). Wherever the goal bearing keeps enough landmarks in view, tracking drives the same line as straight driving. We did not tune toward the target: the coefficients are a least-squares fit on seeds 100..130 of the routes' own layouts, the change was developed on the ten training layouts, and these rows were run after.\n")
tsrc = load('tracking-sources.json')['route-1-2']


def diff_mm(variant):
    c = tsrc[variant]
    return f"{1000 * c['difference_m']:+.0f} mm [{1000 * c['difference_ci95_m'][0]:+.0f}, {1000 * c['difference_ci95_m'][1]:+.0f}]"


w(f"**Why tracking missed on route 1→2**, measured on the two layouts where it missed most (`lab/scripts/error-sources.sh tracking \"1212 1313\" 6000..6030 route-1-2`, one error source removed at a time, the same seeds driven straight and with tracking). With the coefficients fitted to end points as they are, then in use (development figures, not regenerated here), tracking ended +109 mm [+37, +182] further off than straight driving with the routes' noise; without stereo outliers the difference stayed (+112 mm [+51, +173]), and without wheel slip (+105 mm [+42, +169]); without pixel noise it went (−4 mm [−31, +23]). So the turns brought in no new error; they made the pixel noise cost more, as the headings they led to were estimated less well than driving straight, and tripling the turn costs cut the difference to +13 mm [−17, +44]. With the coefficients in use now the same command gives {diff_mm('base')} with the routes' noise and {diff_mm('no-pixel-noise')} without pixel noise. Why the old decision could not tell which turns pay is the next paragraph.\n")
lottery = load('path-lottery.json')
side, lot_tracking, told = lottery['side_over_centre'], lottery['tracking_over_centre'], lottery['predictions']
# Per layout, both diagonals (up and down) and both side lines, each pair's geometric mean.
diagonal = [(up * down) ** 0.5 for up, down in lottery['diagonal_over_centre']]
sides_per_layout = [(lines['-0.6']['error_rms_m'] * lines['0.6']['error_rms_m']) ** 0.5 / lines['0.0']['error_rms_m'] for lines in lottery['layouts'].values()]
held_tracking = [ratio(d['routes'][ROUTES[0]]['rigid']['tracking'], d['routes'][ROUTES[0]]['rigid']['none']) for d in all_held.values()]
gm_lot = geometric_ci(lot_tracking)
w(f"**The line driven matters as much as any turn.** Driving route 1→2 straight along a line 0.6 m to either side of the centre line, with no aiding and no turn, changes the end-point error (RMS over seeds 100..130) by ×{min(side['ratios']):.2f}–×{max(side['ratios']):.2f} depending on the layout: {side['beyond_1_1']} of the {len(side['ratios'])} side lines end more than 1.1× the centre line's error and {side['below_0_9']} less than 0.9× (ten training layouts, `lab/scripts/path-lottery.sh`); on average over the layouts the side lines end where the centre line does (geometric mean of both sides over the centre line " + "×{:.2f} [{:.2f}, {:.2f}]".format(*geometric_ci(sides_per_layout)) + "). Crossing the same offsets diagonally, from 0.6 m on one side to 0.6 m on the other (1.69° off the axis, both ways, no turn), does cost: " + "×{:.2f} [{:.2f}, {:.2f}]".format(*geometric_ci(diagonal)) + f" the centre line's error (ranges ×{min(min(p) for p in lottery['diagonal_over_centre']):.2f}–×{max(max(p) for p in lottery['diagonal_over_centre']):.2f}). So a lateral offset costs nothing on average and a heading off the corridor's axis does: something in the estimator or the simulator still depends on the heading relative to the walls (the line-of-sight fix of the first table's last row removed part of it). Where it sits is measured (section *Odometry fusion*: the links of egomotion's chain that match keyframes metres back through far landmarks carry it, and giving those links odometry's sideways motion removes it); why they fare worse on a diagonal is an errors-in-variables bias of the estimator, measured there too. It comes with the pixel noise: with the route file's pixel noise set to 0 (in the centre and diagonal files alike, same layouts and seeds, `ubf sweep --layout-seeds`), the diagonals end at ×0.92 and ×1.00 the centre line's error, while without wheel slip they end at ×1.34 and ×1.32 and without stereo outliers at ×1.11 and ×1.28 (up and down; development runs, not regenerated here). With the coefficients fitted to end points as they are, tracking drove such headings; with those in use it drives at the goal. On the same layouts tracking ends at ×{min(lot_tracking):.2f}–×{max(lot_tracking):.2f} the centre line's error, geometric mean ×{gm_lot[0]:.2f} [{gm_lot[1]:.2f}, {gm_lot[2]:.2f}]. The decision's error model cannot tell such lines apart: for the side lines against the centre line it predicts the direction of the change {told['decision_model']['right_direction']} times in {told['decision_model']['of']} (correlation of the log ratios {told['decision_model']['log_ratio_correlation']:+.2f}), where egomotion's own covariance, chained through the keyframes, gets it {told['egomotion_covariance']['right_direction']} times ({told['egomotion_covariance']['log_ratio_correlation']:+.2f}). So the price of a turn is not the whole story: the step term, built on the thesis's CV, does not predict which views leave less error in the pose, and a decision built on it chooses among lines through a layout no better than chance, paying for its turns besides. With the coefficients in use tracking's route-1→2 ratio on the held-out sets is ×{min(held_tracking):.2f}–×{max(held_tracking):.2f}, geometric mean " + "×{:.2f} [{:.2f}, {:.2f}]".format(*geometric_ci(held_tracking)) + " (*Against the targets* says where it misses 1.1×). A step term from the estimator's own information instead was tried next (scratch code, not part of the product): each candidate's predicted landmarks summed into the 3×3 information the rigid estimator would have about the step (forward, left, yaw) at 1 px of pixel noise, which agrees with the estimator's own normal equations to 1e-4, and the same covariance logged for every matched frame from the landmarks it matched, so that `ubf model fit-costs` could fit its scale to the end points beside the turn costs. Fitted as one coefficient on the variance the step leaves at the goal (translation, yaw over the lever and their coupling), the scale came out 0.022 px² per metre (0.023 once refitted with it in use). With it, on the ten training layouts (2121..3030, seeds 100..130, `ubf sweep --layout-seeds`), tracking's geometric-mean ratio to straight driving went from 1.13 to 1.02 on route 1→2 (2 layouts of 10 beyond 1.1×, against 7), but from 0.99 to 0.94 on route 2→1 with 5 of 10 beyond 1.1× (against none) and from 1.04 to 1.06 on the feature-poor route (3 against 1), and it turned more (extra time 16, 13 and 7 % against 7, 1 and 2 %): 10 of 30 route-layouts beyond the target against 8, so it was not adopted. Fitted with translation and yaw as separate coefficients (what stays of them could differ), the least squares put nothing on either: across the 150 training runs the predicted step covariances do not explain the end-point errors, and within one route and technique their correlation with the squared error ranges from −0.78 to +0.60 over ten seeds. An earlier trial of the same term, scaled by the share of egomotion's chained covariance that stays (actual ÷ covariance σ, squared: 0.023 of the covariance at the routes' 0.047 px), made the step term about a hundred times smaller than this fit does; its better figures (1.03×, 2.2 % extra time) came from turning less, towards straight driving. So no step model measured here, the thesis's CV or the estimator's information, predicts which views leave less error at the end of these routes, and the measured part of the decision is the price of a turn. Fitting the decision's coefficients to what a path changes against driving straight puts that finding into the decision: the step term comes out zero (section *The decision's coefficients*).\n")
r = held_cv['routes']
w(f"**The thesis's CV objective on the same held-out runs** (layout 101) turns far more (tracking {r[ROUTES[0]]['rigid']['tracking']['time_overhead_pct']['mean']:.0f} % longer than straight on route 1→2, against {held[101]['routes'][ROUTES[0]]['rigid']['tracking']['time_overhead_pct']['mean']:.0f} % with the end-point objective) and ends at " + ", ".join(f"{ratio(r[rt]['rigid']['tracking'], r[rt]['rigid']['none']):.2f}×" for rt in ROUTES) + " straight driving's error with tracking and " + ", ".join(f"{ratio(r[rt]['rigid']['scan'], r[rt]['rigid']['none']):.2f}×" for rt in ROUTES) + " with the scan.\n")

chain = load('error-chain.json')
robust = load('odometry-fusion.json')
FUSIONS = [('off', all_held), ('sideways', fused_held['sideways']), ('full', fused_held['full'])]
LINES = [('centre', 'centre line'), ('diagonal-up', 'diagonal up'), ('diagonal-down', 'diagonal down')]
w("### Odometry fusion\n")
w("```sh run-slow\nlab/scripts/error-chain.sh \"2121 2222 2323 2424 2525 2626 2727 2828 2929 3030\" 100..130   # the error split along egomotion's chain\nubf experiment thesis-endpoint --seeds 1000..1030 --layout-seed 101 --odometry-fusion sideways   # every held-out layout; also full\nlab/scripts/odometry-fusion.sh \"2121 2222 2323\" 100..120   # with wheels that err more than the noise model says\n```\n")
c0 = chain['centre~Off']
w(f"**Where purely visual egomotion loses its accuracy.** Each egomotion pose rests on a chain of estimates: the frame was matched to a keyframe (`trajectory.csv` names it, `ego_anchor`), that keyframe to an earlier one, and so on back to the start. `lab/scripts/error-chain.py` splits the error at the last frame along that chain, each link adding its own position error and its own heading error carried over the distance still to go; the parts add up to the error (RMS {c0['rms_chain_sum_m']:.3f} m against {c0['rms_error_m']:.3f} m on the centre line, to first order). Driving route 1→2 straight, on the lines of `lab/scripts/path-lottery.sh` (ten training layouts, seeds 100..130), with purely visual egomotion (the `Off` rows) the few links per run whose keyframe lies 2 m or more back carry almost all of the error and the many short ones add little; with `Sideways` fusion the long links carry less, and about half the error is left without them:\n")
w("| line | fusion | RMS error m | long links / run | their part m | RMS error without them m | short links / run | their part m |")
w("| --- | --- | --- | --- | --- | --- | --- | --- |")
for key, name in LINES:
    for fusion in ('Off', 'Sideways'):
        c = chain[f'{key}~{fusion}']
        lo, sh = c['links']['long'], c['links']['short']
        w(f"| {name} | {fusion} | {c['rms_error_m']:.3f} | {lo['links_per_run']:.1f} | {lo['rms_part_m']:.3f} | {lo['rms_error_without_m']:.3f} | {sh['links_per_run']:.1f} | {sh['rms_part_m']:.3f} |")
w("")
w("The `Sideways` diagonal-down row rose from 0.064 to 0.083 m with steps on one landmark (commit 3c8eea3, perception.md), all of it in one run of its 300 (layout 2525, seed 104), a run that fails with or without them: steering by odometry (`navigate: false`, as in the thesis), the robot ends pinned against the wall beside the goal, turning back and forth on the spot until the time limit, 40 minutes, and egomotion drifted from 0.035 to 0.96 m off where it had held: not through the steps on one landmark, which followed odometry to within a millimetre, but through the wheels' scale, read 982 times from one keyframe's landmarks as the robot turned there and taken from 1.00 to 0.96 on exact wheels (perception.md says more, and what was tried). Over the other 299 runs the row went from 0.064 to 0.061 m (`ubf sweep` of that line, before and after the change, 1.69° down, seeds 100..130 on the ten layouts). With the progress check on by default (since the aiding protocol's eighteenth run) that run and the nine others of seed 104 on this line, all pinned the same way, end after 127 s (`end: no_progress`), that one 0.015 m off, and the row was 0.061 m in the same sweep. Since then the wheels' scale is fitted keyframe by keyframe, a keyframe read many times weighing no more than the keyframes' spread allows (perception.md): with the check off, that run ends 0.058 m off instead of 0.96. The table gives the row as now run.\n")
cu, cd = chain['diagonal-up~Off'], chain['diagonal-down~Off']
w(f"A long link is a frame matched to a keyframe metres back through the landmarks both still see, mostly far ones, since the near ones have left the view. Far landmarks fix their bearings well and the robot's sideways motion poorly: a slide sideways and a slight turn move a far bearing alike, so such a match can be decimetres off sideways with a matching error in heading (in development runs of the centre and diagonal lines on layouts 2121..2424, seeds 100..109, read from the tracker's debug log, `RUST_LOG=ubf_perception=debug`: σ of 1–3 m sideways by the estimator's own covariance, 0.27 m RMS in fact, against 0.03 m for odometry over the same stretches). Where landmarks are sparse, as on these routes, the chain cannot avoid them: when a near landmark leaves the view, only far ones tie the frame to any keyframe. The diagonals' penalty (section *Held out*) is carried by the same links: {cu['links']['long']['rms_part_m']:.3f} and {cd['links']['long']['rms_part_m']:.3f} m on the diagonals against {c0['links']['long']['rms_part_m']:.3f} m on the centre line, with {cu['links']['long']['links_per_run']:.1f} and {cd['links']['long']['links_per_run']:.1f} long links per run against {c0['links']['long']['links_per_run']:.1f}. With odometry's sideways motion in those links, the diagonals end no worse than the centre line ({chain['diagonal-up~Sideways']['rms_error_m']:.3f} and {chain['diagonal-down~Sideways']['rms_error_m']:.3f} m against {chain['centre~Sideways']['rms_error_m']:.3f} m): the heading penalty was the long links' sideways weakness.\n")




w("**Why a diagonal fares worse: the estimator reads a heading off the far landmarks' direction as a turn.** The rigid estimator fits `a ≈ R b + t` to each landmark seen as `a` in the keyframe and `b` in the frame, so the noisy `b` stands in the yaw's Jacobian while `b`'s own depth noise stands in the residual. Where a landmark's two lines of sight differ (the parallax of a landmark off the line driven, which on a diagonal has one sign for the whole far cluster), the two correlate, and the least squares reads part of the depth noise as a turn: an errors-in-variables bias. Measured on the estimator alone (`cargo test -p ubf-perception far_wall`: ten landmarks on a wall 37–47 m ahead, links of 5 m, Table 1's 0.047 px), the mean yaw error of a link is −0.10° heading 1.69° one way and +0.11° the other, with an RMS of 0.31°; it stays the same at 0.01 and 0.094 px, as such a bias does (it is a ratio of noises), and vanishes only with no noise at all. Taking the pull's expected value (`Σ tr(Jᵀ Rᵀ Λ R Σ_b)`, scaled to the noise the residuals show) off the yaw gradient removes it (+0.03° and −0.01°), which confirms the mechanism. It was tried in the product too (a scratch build taking the pull off every rigid estimate; `lab/scripts/path-lottery.sh` and `lab/scripts/error-chain.sh` on the ten training layouts, seeds 100..130): the diagonals' penalty went from ×1.19 to ×1.02 and tracking's ratio to the centre line from ×1.14 to ×1.04 (4 layouts of 10 beyond 1.1× against 6), but straight driving on the centre line ended 11 % further off (0.362 to 0.403 m RMS) and the side lines 4–11 %, so it is not adopted. The reason is the second finding: on far landmarks alone the estimator's precision is largely borrowed from odometry. Each landmark's later line of sight is laid by odometry's turn, and told a turn 0.5° off the estimate follows it by about a third (the same test); with those lines laid by the estimate's own turn instead, the yaw's RMS error on the far wall grows from 0.3° to 1.3°, and a two-view bundle adjustment in pixels (scratch code; the maximum-likelihood estimate) has 1.7°: that is all the far wall itself says about the turn. In the simulator the lean shows too (scratch builds on the code of that time, before `Sideways` took odometry's distance, when its centre line ended 0.163 m off against the table's figure today; `lab/scripts/error-chain.sh`, same layouts and seeds): with every landmark's later line laid by the estimate's own turn, straight driving ends 31 % further off on the centre line (0.477 against 0.364 m RMS) and 36–44 % on the diagonals, while with `Sideways` fusion the lines make little difference (0.164 against 0.163 m on the centre line, 0.147–0.149 against 0.137–0.147 m on the diagonals); and fusing odometry's turn alone instead of its sideways motion leaves 0.31–0.34 m (0.34–0.35 m with the lines laid by the estimate's own turn) against `Sideways`' 0.14–0.16 m, so what pins far matches is odometry's sideways motion, not its turn. With the pull taken off, the estimate follows odometry's turn wholly (0.55° for 0.5°), and odometry's turn over a 5 m link carries the wheel slip. Taking odometry's sideways motion in (`Sideways`, below) settles the same ambiguity from the other side, and with it the correction changed nothing (on the code of that time: 0.163 to 0.158 m on the centre line, 0.137 to 0.139 and 0.147 to 0.145 m on the diagonals). So purely visual egomotion, `odometry_fusion: Off`, is visual in what it combines but not in how it weighs: odometry gates every match and lays its uncertainty, and on far landmarks that is much of what fixes the turn.\n")
w(f"So `egomotion: (odometry_fusion: ...)` combines each visual motion that passes the odometry gate with odometry's over the same stretch, weighed by the estimator's covariance and the gate's noise model: `Sideways` takes odometry's sideways motion and its distance, reported in the wheels' scale as the steps measure it (see [aiding-families.md](aiding-families.md)), and the landmarks' bearings then fix the heading; `Full` takes its distance and heading too. It is the default now (with `navigate: true`), chosen on these held-out layouts and on the miscalibrated wheels below; the thesis measured image-only navigation, and the other tables on this page do too, through the route files' `odometry_fusion: Off, navigate: false`. Holding odometry's heading by the walls the side sonars trace (`wall_compass`) is off unless a file asks for it, and the route files do not, as the thesis's robot had none, so no run on this page has it (its figures are on [aiding-families.md](aiding-families.md)). On the {len(LAYOUTS)} held-out layouts (the same runs as the table above, each layout with its own 30 seeds), per route: straight driving's mean error, and the geometric mean over layouts of tracking's and the scan's ratio to it, with the number of layouts within the targets:\n")
w("| route | fusion | straight m | tracking × | tracking within 1.1× | most tracking failures / run | scan × | scan within 1.5× |")
w("| --- | --- | --- | --- | --- | --- | --- | --- |")
for route in ROUTES:
    for name, data in FUSIONS:
        s, t, tn, sc, sn, f = fusion_row(route, data)
        w(f"| {SHORT[route]} | {name} | {s:.3f} | {t:.2f} | {tn} of {len(data)} | {f:.1f} | {sc:.2f} | {sn} of {len(data)} |")
w("")
w("With the routes' odometry, whose only error is the random slip its noise model describes, both cut straight driving's error and, over the held-out layouts, tracking's and the scan's, `Full` most. What each costs when the wheels err otherwise, on three training layouts (seeds 100..120; wheels 1 % larger than the encoders think, so that distance and turns come out 1 % short; or a steady veer of 0.05° per metre that odometry does not see), mean end-point error, m. The routes steer by odometry, as the thesis's robot did (§4.4.1); *navigating* is `Sideways` with the robot steering by the pose egomotion and odometry combine instead (`navigate: true`):\n")
ODOMETRY = [('exact', "routes' odometry"), ('scale', 'wheels 1 % off'), ('veer', 'veer 0.05°/m')]
w("| route | odometry | straight: off | sideways | full | sideways, navigating | tracking: off | sideways | full | sideways, navigating |")
w("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
MODES = ('Off', 'Sideways', 'Full', 'SidewaysNavigating')
for route, label in [('route-1-2', '1→2'), ('route-2-1', '2→1'), ('feature-poor', 'feature-poor')]:
    for key, name in ODOMETRY:
        r = robust[route][key]
        w(f"| {label} | {name} | " + " | ".join(f"{r[f][t]['mean_m']:.3f}" for t in ('none', 'tracking') for f in MODES) + " |")
w("")
worst_full = max(robust[rt]['scale']['Full']['none']['mean_m'] / robust[rt]['scale']['Off']['none']['mean_m'] for rt in robust)
side_ok = all(robust[rt][o]['Sideways'][t]['mean_m'] < robust[rt][o]['Off'][t]['mean_m'] for rt in robust for o in ('exact', 'scale', 'veer') for t in ('none', 'tracking'))
w(f"`Full` carries a wheel scale error into the pose frame after frame: with wheels 1 % off, straight driving ends up to {worst_full:.1f}× further off than with no fusion at all. `Sideways` " + ("ends nearer than purely visual egomotion in every case of the table: a scale error leaves odometry's sideways motion alone, and a veer, which turns odometry's path without bending it, is read against its turn (a veer of 0.05° per metre would otherwise add a centimetre over a 5 m link)" if side_ok else "ends nearer than purely visual egomotion in every case of the table but " + "; ".join(f"{rt} {o} {t} ({robust[rt][o]['Sideways'][t]['mean_m']:.3f} against {robust[rt][o]['Off'][t]['mean_m']:.3f} m)" for rt in robust for o in ('exact', 'scale', 'veer') for t in ('none', 'tracking') if not robust[rt][o]['Sideways'][t]['mean_m'] < robust[rt][o]['Off'][t]['mean_m'])) + f". A robot's own odometry decides between them (see [deploy.md](deploy.md)); the decision's turn costs were fitted to purely visual egomotion and were not refitted for either.\n")
def veer_ends(key):
    """The odometry-fusion table's runs that ended by `key`'s count, by cell."""
    return {(rt, o, f, t): robust[rt][o][f][t].get(key, 0) for rt in robust for o in robust[rt] for f in robust[rt][o] for t in robust[rt][o][f]}


timed_out, gave_up = veer_ends('time_limit_runs'), veer_ends('no_progress_runs')
cases = lambda ends: [f"{rt} {o} {f} {t} ({n} of {robust[rt][o][f][t]['runs']})" for (rt, o, f, t), n in ends.items() if n]  # noqa: E731
navigating_ended = sum(n for ends in (timed_out, gave_up) for (rt, o, f, t), n in ends.items() if f == 'SidewaysNavigating')
navigating_runs = sum(robust[rt][o]['SidewaysNavigating'][t]['runs'] for rt in robust for o in robust[rt] for t in robust[rt][o]['SidewaysNavigating'])
w(("The veer also shows a defect that fusion does not touch. The routes steer by odometry, as the thesis's robot did (§4.4.1), so a veer odometry does not see walks the robot off the goal line; where the wheel slip adds to it, the robot ends beside a wall, odometry puts the goal a few decimetres away towards the wall, and every turn towards it sweeps the robot's corner into the wall: without a check on its progress the run goes on to the time limit, colliding thousands of ticks and failing hundreds to thousands of frames (replayed: seed 104 on routes 1→2 and 2→1 in all three layouts, the robot 0.63 m from the wall with the goal 0.4–0.6 m away towards it by odometry). A scenario's progress check ends such a run with the robot stopped (`end: no_progress`), and since the aiding protocol's eighteenth run it is on by default wherever there is a goal (0.5 m in 30 s; `progress: None` turns it off; the same check ends a drive on the robot). Runs of this table it ended: " + ("; ".join(cases(gave_up)) or "none") + ". Runs that hit the time limit: " + ("; ".join(cases(timed_out)) or "none") + ". Steering by the pose egomotion and odometry combine removes the cause: " + (f"no run of the navigating columns ended either way ({navigating_runs} runs), and a veering robot keeps to its line (`tests/simulation.rs` replays seed 104)." if not navigating_ended else f"{navigating_ended} runs of the navigating columns still ended either way.")) if any(timed_out.values()) or any(gave_up.values()) else "No run of this table hit the time limit or was ended by the progress check.")
w("")
w("### Steering a camera instead of the robot\n")
w("The *camera* column is ActionAiding with `steer: Camera`: the robot drives straight at the goal, as straight driving does, while a camera on a simulated pan-tilt unit (`pan_tilt: ()`: ±150°, 60°/s, encoders to 0.05° with 0.02° noise) looks, frame by frame, where the evaluative decision over the tracking list says, within half the field of view of its last look (see [perception.md](perception.md#a-camera-on-a-pan-tilt-unit)). Every other column has the camera fixed, looking ahead. It was built on the development layouts 404, 505 and 606 (seeds 2000..2030). Its look is chosen by the step term alone (the robot does not turn), and with the coefficients in use that term is zero, so the camera looks straight ahead unless too few landmarks would be in view there, and the column ends near straight driving; the camera's own runs, fitted against straight driving, put the term at zero too (section *The decision's coefficients*). That holds for this page's runs, purely visual as the thesis's were: with odometry's sideways motion fused into egomotion (`Sideways`, the default) a steered camera looks for the view of least step CV whatever the coefficients, which on training layouts measured better than looking ahead with that estimate in seven layout families of eight and, purely visual, worse in four of them and better in two; where that pays over held-out layouts is in [aiding-families.md](aiding-families.md). The tables below are regenerated with the coefficients in use; the prose after them describes what was found with the step term fitted to end points as they are (σ_cv 0.90, `ActionAiding(technique: Tracking, steer: Camera, costs: (step_sigma_per_cv: 0.9))`), when the camera looked aside all the time, and where its reasoning no longer matches the tables, the tables are today's.\n")
cam = {rt: [ratio(d['routes'][rt]['rigid']['camera'], d['routes'][rt]['rigid']['none']) for d in all_held.values()] for rt in ROUTES}


w(f"| route | camera × straight, geometric mean over the {len(all_held)} held-out layouts [95 % CI] | layouts where it gains (< 0.9×) | where it loses (> 1.1×) | range |")
w("| --- | --- | --- | --- | --- |")
for rt in ROUTES:
    xs = cam[rt]
    w(f"| {SHORT[rt]} | " + "{:.2f} [{:.2f}, {:.2f}]".format(*geometric_ci(xs)) + f" | {sum(x < 0.9 for x in xs)} | {sum(x > 1.1 for x in xs)} | {min(xs):.2f}–{max(xs):.2f} |")
w("")
clear = [SHORT[rt] for rt in ROUTES if geometric_ci(cam[rt])[2] < 1 or geometric_ci(cam[rt])[1] > 1]
w("Over layouts, " + ("no route's interval lies clear of 1" if not clear else "only " + ", ".join(clear) + " lies clear of 1") + ". With the step term fitted to end points as they are, where the landmarks ahead were far (route 1→2) looking at the side walls tended to pay, and where they were near (route 2→1) or the side was a long featureless wall it tended to cost, but single layouts swung both ways by more than those averages.\n")
src = load('camera-sources.json')


def share_sentence():
    """Which single source's removal shrinks the steered camera's excess on route 2→1 most, from the data."""
    b21 = src['route-2-1']
    base = b21['base']['difference_m']
    names = {'no-outliers': 'the stereo outliers', 'no-pixel-noise': 'the pixel noise', 'no-slip': 'the wheel slip'}
    best = min(names, key=lambda v: b21[v]['difference_m'])
    return (f" With the routes' noise the steered camera ends {1000 * base:+.1f} mm from straight driving on route 2→1; removing {names[best]} "
            f"shrinks that most, to {1000 * b21[best]['difference_m']:+.1f} mm, more than removing any other single source.\n")
VARIANTS = [('base', "the routes' noise"), ('no-outliers', 'no stereo outliers'), ('no-pixel-noise', 'no pixel noise'), ('no-slip', 'no wheel slip'),
            ('no-noise', 'none of the three'), ('exact-encoders', 'none, and exact pan encoders')]
w("**Where its error comes from**, one source removed at a time (`lab/scripts/error-sources.sh camera`: development layouts 404, 505 and 606, seeds 2000..2030, the same runs straight and steered; the difference steered − straight in mean end-point error, mm, [95 % CI], and failures per run, straight → steered):\n")
w("| removed | " + " | ".join(SHORT[rt] for rt in ROUTES) + " |")
w("| --- | --- | --- | --- |")
ROUTE_FILES = {ROUTES[0]: 'route-1-2', ROUTES[1]: 'route-2-1', ROUTES[2]: 'feature-poor'}
for v, label in VARIANTS:
    cells = []
    for rt in ROUTES:
        c = src[ROUTE_FILES[rt]][v]
        cells.append(f"{1000 * c['difference_m']:+.1f} [{1000 * c['difference_ci95_m'][0]:+.1f}, {1000 * c['difference_ci95_m'][1]:+.1f}]; {c['straight_failures']:.1f} → {c['aided_failures']:.1f}")
    w(f"| {label} | " + " | ".join(cells) + " |")
w("")
b21 = src['route-2-1']
w((f"With every noise source removed, a steered camera still fails {b21['no-noise']['aided_failures']:.1f} frame(s) a run on route 2→1 where the fixed camera fails {b21['no-noise']['straight_failures']:.1f}: " if b21['no-noise']['aided_failures'] > b21['no-noise']['straight_failures'] else f"With every noise source removed, a steered camera fails no more frames a run on route 2→1 than the fixed camera ({b21['no-noise']['aided_failures']:.1f} against {b21['no-noise']['straight_failures']:.1f}) with the coefficients in use; with σ_cv 0.90 it failed more: ") + f"looking at a near side wall, the landmarks stream through the view and a frame can share fewer than three with every keyframe (a replay on layout 505 matched only a few landmarks to keyframes metres back while looking far to the right, and failed a frame between). A look that keeps the last frame's landmarks in view (tried: candidates filtered to those predicted to keep at least four) left the failures on the development layouts where they were, and was dropped. With no noise, steering also leaves a small error straight driving does not ({1000 * b21['no-noise']['difference_m']:.1f} mm on route 2→1): the pan encoders. A reading one 0.05° step off when a keyframe is taken becomes a heading bias for every frame anchored on it (one step is 35 mm after 40 m; the replays show exactly that in the runs whose first reading rounded the wrong way); with exact encoders it is {1000 * b21['exact-encoders']['difference_m']:.1f} mm.")
w(share_sentence())
cam_cells = [c for c in env['cells'] if c['best'] == 'camera']
cam_gains = [c for c in cam_cells if c['ratio_ci95'][1] < 1.0]
cam_losses = [c for c in cam_cells if c['ratio_ci95'][0] > 1.0]
cam_rest = [c for c in cam_cells if c not in cam_gains and c not in cam_losses]
listed = lambda cells: "; ".join(f"{c['factor']} {c['level']}: {c['ratio']:.2f} [{c['ratio_ci95'][0]:.2f}, {c['ratio_ci95'][1]:.2f}]" for c in cells) or "none"
w(f"On the environment map (below) camera steering was the best aided technique on the development seeds in {len(cam_cells)} of {len(env['cells'])} environments; on the held-out seeds and layout it gained with its whole 95 % interval below 1 in {len(cam_gains)} of them ({listed(cam_gains)}), lost with its whole interval above 1 in {len(cam_losses)} ({listed(cam_losses)}), and elsewhere ended at {min(c['ratio'] for c in cam_rest):.2f}–{max(c['ratio'] for c in cam_rest):.2f}× straight driving with intervals that include 1.\n")

w("### The thesis's simplified estimator\n")
w("```sh run\nubf experiment thesis-endpoint --rotate-then-translate   # the thesis's decoupled motion (§4.4.5)\n```\n")
w("The simplified estimator (§4.4.7) reads each step as a translation or a rotation. It now takes the motion type from the commanded phase, scales its translation threshold to each landmark's depth noise, and uses weighted medians and a range-consistency gate (`Simple2d(robust: false)` is the thesis's form). Mean end-point error, m, seeds 0..30, end-point objective:\n")
w("| route | profile | none | zig-zag | scan | tracking |")
w("| --- | --- | --- | --- | --- | --- |")
for route in ROUTES:
    for label, data in [('continuous', dev), ('rotate-then-translate', rtt)]:
        r = data['routes'][route]['simple2d']
        w(f"| {SHORT[route]} | {label} | " + " | ".join(f"{r[t]['endpoint_error_m']['mean']:.2f}" for t in T) + " |")
w("")
rtt_timed_out = sum(c['runs_time_limit'] for rt in ROUTES for est in rtt['routes'][rt].values() for c in est.values())
rtt_gave_up = sum(c.get('runs_no_progress', 0) for rt in ROUTES for est in rtt['routes'][rt].values() for c in est.values())
rtt_gave_up_said = (f" The progress check ended {rtt_gave_up} run(s) of this table (listed under the end-point tables above): the robot held within 0.5 m of one spot for 30 s short of the goal." if rtt_gave_up else "")
if rtt_timed_out:
    w(f"With the decoupled motion, {rtt_timed_out} run(s) of this table ran out of time (listed under the end-point tables above). In the one replayed (route 2→1, scan, seed 1), the robot stood 0.8 m from a wall 1.3 m short of where it believed the goal was; AvoidCollision, voting little, and ActionAiding fused into a turn request that changed sign every tick and never fell under the 0.5°/s below which the decoupled robot translates, so it turned back and forth on the spot until the time limit. This is not fixed: the continuous profile, which all the other tables use, drives on through such requests." + rtt_gave_up_said + "\n")
else:
    w("With the decoupled motion no run of this table ran out of time. Two did before (route 2→1, the scan, seed 1, with either estimator): 1.8 m from the goal and 0.8 m from a wall, AvoidCollision's turn away from the wall and the step's correction back towards its heading fused into a turn request that changed sign every tick and never fell under the 0.5°/s below which the decoupled robot translates, so the robot turned to and fro on the spot and the step never ended. A step that gains less than a 57th of its length in 5 s now ends, and the next decision starts from where the robot is (`a_step_a_rotate_then_translate_robot_cannot_take_is_decided_again` in tests/simulation.rs); the continuous profile's results did not move." + rtt_gave_up_said + "\n")

w("## Where aiding pays\n")
w("```sh run-slow\nubf experiment where-aiding-pays --plot docs/where-aiding-pays.png\n```\n")
w(f"One factor of route 1→2 varied at a time; for each environment the best aided technique is chosen on seeds {env['development_seeds'][0]}..{env['development_seeds'][1]} and its error measured, beside straight driving's, on seeds {env['held_out_seeds'][0]}..{env['held_out_seeds'][1]} in held-out layout {env['held_out_layout_seed']} (so choosing the best of four, the zig-zag, the scan, tracking and camera steering, does not flatter it). Rigid estimator, end-point objective. Below 1 aiding pays.\n")
w("![Where aiding pays](where-aiding-pays.png)\n")
w("| factor | level | best aided | straight m | aided m | ratio [95 % CI] |")
w("| --- | --- | --- | --- | --- | --- |")
for c in env['cells']:
    base = ' (base)' if c['base'] else ''
    w(f"| {c['factor']} | {c['level']}{base} | {c['best']} | {c['straight_m']:.3f} | {c['aided_m']:.3f} | {c['ratio']:.2f} [{c['ratio_ci95'][0]:.2f}, {c['ratio_ci95'][1]:.2f}] |")
pays = [c for c in env['cells'] if c['ratio_ci95'][1] < 1.0]
costs_ = [c for c in env['cells'] if c['ratio_ci95'][0] > 1.0]
w("")
w("In the 2.4 m corridor AvoidCollision acts on most runs; since it holds on until the way to the goal is clear (it used to fall silent as soon as the way ahead was, and GoTo turned back into the obstacle), that row changed from the zig-zag, ×1.10 [0.77, 1.57] (straight 0.376 m), to the one above; no other row changed then (that change's two binaries, the same command; rows have moved with later code).\n")
w(f"Held-out gains whose whole interval lies below 1: {len(pays)} of {len(env['cells'])} environments" + (" (" + "; ".join(f"{c['factor']} {c['level']}: {c['best']} ×{c['ratio']:.2f}" for c in pays) + ")" if pays else "") + f". Losses whose whole interval lies above 1: {len(costs_)}" + (" (" + "; ".join(f"{c['factor']} {c['level']}: {c['best']} ×{c['ratio']:.2f}" for c in costs_) + ")" if costs_ else "") + ".\n")

w("## Table 4: journey CV in simulation\n")
w("```sh run\nubf experiment thesis-table4            # the thesis's CV objective; --objective end-point for ours\n```\n")
w("Ten 6 m × 60 m corridors with 16 random landmarks (a quarter on the side walls), 40 m of travel, one run per technique per corridor, rigid estimator, the thesis's CV-only decision.\n")
w("| | none | zig-zag | scan | tracking |")
w("| --- | --- | --- | --- | --- |")
w("| mean journey CV (failures) | " + " | ".join(f"{t4['mean'][t]:.3f} ({t4['mean_failures'][t]:.0f})" for t in T) + " |")
w("| reduction vs none | " + " | ".join(f"{t4['improvement_pct'][t]:.0f} %" for t in T) + " |")
w("| thesis reduction | 0 % | 44 % | 65 % | 59 % |")
w("")
w("Aiding cuts the journey CV sharply, as in the thesis, and by more. These reductions do not become end-point gains of the same size (the end-point tables).\n")

w("## Why the thesis's gains do not appear\n")
w("Each reason below is a measurement on this page, not an inference:\n")
def bank(technique, kind):
    f = banks[f'{technique}-{kind}']['fields']
    return f['endpoint_error_m']['mean'], f['endpoint_error_m']['ci95']
w("1. **Straight driving is accurate here, with or without keyframes.** One explanation we reached for was that keyframes stop a far landmark's depth error from accumulating step by step. It was tested by taking them away: with a one-frame bank the rigid estimator matches frame to frame. Route 1→2, seeds 0..30, CV objective (`lab/scripts/results-data.sh`, the sweep into `out/keyframes`), mean end-point error, m:\n")
w("| technique | keyframe bank | frame to frame |")
w("| --- | --- | --- |")
for t, name in zip(['None', 'ZigZag', 'Scan', 'Tracking'], T):
    (a, ca), (b, cb) = bank(t, 'bank'), bank(t, 'frame-to-frame')
    w(f"| {name} | {a:.2f} [{ca[0]:.2f}, {ca[1]:.2f}] | {b:.2f} [{cb[0]:.2f}, {cb[1]:.2f}] |")
w("")
(straight_bank, sb), (straight_f2f, sf) = bank('None', 'bank'), bank('None', 'frame-to-frame')
helps = sb[1] < sf[0]
w(f"   Frame to frame, straight driving ends {straight_f2f:.2f} m off against {straight_bank:.2f} m with the bank" + (": the bank does keep depth error from piling up (the intervals do not overlap)" if helps else ", within the intervals: the hypothesis is refuted") + f". But {straight_f2f:.2f} m is {100 * straight_f2f / 40.7:.1f} % of the 40.7 m route, where the thesis's robot ended 21–45 % off: the bank is not what makes straight driving accurate here. Without it, the scan and tracking end worse; the bank is what lets turning techniques keep their accuracy. Straight driving is accurate with either estimator: the simplified one, also frame to frame, ends within 2 % too (the tables' *simple 2D* column). What made the thesis's robot 20 times less accurate driving straight is not in its published noise measurements, and we have not found it.")
r101 = held[101]['routes'][ROUTES[0]]['rigid']['tracking']
c101 = held_cv['routes'][ROUTES[0]]['rigid']['tracking']
w(f"2. **Turning costs about what it gains.** Every turn leaves heading error that grows with the distance still to go. With the measured coefficients the end-point decision turns far less than the thesis's CV decision (tracking {r101['time_overhead_pct']['mean']:.0f} % against {c101['time_overhead_pct']['mean']:.0f} % longer than straight driving, held-out layout 101, route 1→2), and neither decision turns tracking into a clear gain over straight driving (section *Held out*).")
t4_cuts = [t4['improvement_pct'][t] for t in T if t != 'none']
w("3. **Table 4's CV reductions do not become end-point reductions.** The journey CV falls by " + "–".join(f"{x:.0f}" for x in (min(t4_cuts), max(t4_cuts))) + " % with aiding (Table 4); the end-point error does not fall by anything like it (the end-point tables).")
w(f"4. **The CV does not say which path ends nearer.** Of two straight lines 0.6 m apart through the same layout, the decision's model (the thesis's CV, summed over the steps) predicts which ends with the smaller error {told['decision_model']['right_direction']} times in {told['decision_model']['of']}, no better than a coin (section *Held out*). Action aiding rests on that prediction; where it fails, steering by it moves the robot onto lines no better than the one it left.\n")
w("The simplified estimator, even with its fixes and the thesis's rotate-then-translate motion, loses with the zig-zag and the scan; we have not measured why.\n")

w("## The error model\n")
w("```sh run\nubf model fit\n```\n")
w("```text output\n" + fit + "\n```\n")
w("The exponential form of eq. 24 fits the geometric model (eq. 16–23) only moderately: the geometric CV is `y(y−s)/(f·s·max(T, 2|x|))`, quadratic in depth and hyperbolic across. It ranks most landmark pairs as the geometric model does, which is what the decision engine needs. `ubf model heatmap --out model.png` draws figure 16.\n")
w("![The geometric error model over the field of view](figures/error-model.png)\n")

w("### Landmark height (§5.3.1)\n")
w("The thesis leaves landmark height out of its evaluation and expects it to help. The 3D form applies eq. 16–23 in both image axes: a step also moves a landmark's row, by `f·|z|·s/(y(y−s))` in each image, so `CV = y(y−s)/(f·s·(max(T, 2|x|) + 2|z|))`, the planar CV at the cameras' level and smaller above or below it. Its exponential fit gains a factor `e^{−δ|z|}` (the right-hand column above). A scenario selects either: `ActionAiding(model: Geometric3d)` or `FittedExponential3d`, and `ubf experiment thesis-endpoint --model geometric-3d` runs the end-point experiment with it.\n")


def model_gain(technique, route):
    """Geometric mean over the held-out layouts of (3D ÷ planar) end-point error, with a t interval on the logs."""
    return geometric_ci([held3d[l]['routes'][route]['rigid'][technique]['endpoint_error_m']['mean']
                         / all_held[l]['routes'][route]['rigid'][technique]['endpoint_error_m']['mean'] for l in LAYOUTS])


w(f"Measured on the {len(LAYOUTS)} held-out layouts (each with its own 30 seeds; the same runs with either model), the end-point error with the 3D model over that with the planar one, geometric mean over layouts [95 % CI]:\n")
w("| technique | " + " | ".join(SHORT[rt] for rt in ROUTES) + " |")
w("| --- | --- | --- | --- |")
for t, name in [('scan', 'physical scan'), ('tracking', 'landmark tracking'), ('camera', 'camera steering')]:
    w(f"| {name} | " + " | ".join("{:.2f} [{:.2f}, {:.2f}]".format(*model_gain(t, rt)) for rt in ROUTES) + " |")
w("")
g, p = steps['Geometric'], steps['Geometric3d']
clear = [f"{name} on {SHORT[rt]} ({model_gain(t, rt)[0]:.2f}×)" for t, name in [('scan', 'the scan'), ('tracking', 'tracking'), ('camera', 'camera steering')]
         for rt in ROUTES if model_gain(t, rt)[2] < 1 or model_gain(t, rt)[1] > 1]
lead = ("No interval lies clear of 1" if not clear else "Only " + ", ".join(clear) + (" has" if len(clear) == 1 else " have") + " an interval clear of 1")
w(f"{lead}: on these routes the 3D model moves the end point by a few per cent at most (with the step term in use at zero, the runs are identical: neither model enters the decision). That it would not help with a step term either is measured, not assumed: it does not predict our estimator's errors better. Over the straight frame-to-frame steps of the same runs ({g['steps']:,} with the planar model, {p['steps']:,} with the 3D one; the routes driven straight and with tracking, seeds 100..120, `lab/scripts/results-data.sh`), the rank correlation of a step's actual translation error with its predicted `CV·d` is {g['step_error_rank_correlation']:.3f} with the planar model and {p['step_error_rank_correlation']:.3f} with the 3D one. The rigid estimator aligns the landmarks' triangulated floor positions, whose errors do not depend on height (each landmark's information in `egomotion/rigid.rs` has no height term), so a row's motion, which the 3D model counts, is information this estimator never uses. An estimator that minimised reprojection error in both image axes would use it; we have not built one.\n")

w("## Choices and where they come from\n")
w("| parameter | value | source |")
w("| --- | --- | --- |")
w("| corridor, landmarks, travel (Table 4) | 6 m × 60 m, 16 landmarks, ¼ on side walls, 40 m | thesis §4.2.1 |")
w("| camera baseline | 0.6 m | thesis §4.4.10.1, figure 39 |")
w("| focal length, image | 554.3 px, 640 × 480 (60° field of view) | a common stereo camera; the thesis does not give its own |")
w("| pixel noise | 0.047 px | Table 1: depth σ 0.5 m at 50 m for this camera |")
w(f"| gross stereo mismatches (routes) | {100*best:.0f} % | Table 2, by `ubf experiment thesis-table2` |")
w("| frame rate | 2 Hz | thesis §3.3.2 |")
w("| top speed | 0.6 m/s | thesis §4.4.6 |")
w("| routes | 40.7 m, 40.7 m, 20.4 m in a 4 m corridor | thesis §4.4.2; 4 m rather than 2.4 m so that a 0.68 m Powerbot can zig-zag |")
w("| decision coefficients | fitted | `SEEDS=100..130 lab/scripts/fit-costs.sh`, seeds 100..130 |")
w("| keyframes | 10, 1 m or 15° apart, retired 10 m away | chosen once; not tuned on these results |")
w("")
open('docs/results.md', 'w').write("\n".join(out) + "\n")
print("wrote docs/results.md")
