#!/usr/bin/env python3
"""Writes docs/aiding-families.md from out/aiding-families.json (the
summary lab/scripts/aiding-families.sh prints), applying lab/protocol.md's
rules for a claim, so that no number or verdict on that page is written by
hand.

    python3 lab/scripts/aiding-families-page.py [SUMMARY.json [PAGE.md [RUNS-DIR]]]

RUNS-DIR (lab/runs by default) holds the summaries of the protocol's
earlier runs, on earlier code, as aiding-families-{first,second,third,
fourth,fifth,sixth,seventh,eighth,ninth,tenth,eleventh,twelfth,
thirteenth,fourteenth,fifteenth,sixteenth,seventeenth,eighteenth,
nineteenth}.json, and error-axes-feature-poor.json (what
lab/scripts/error-axes.sh prints for the feature-poor route on the
protocol's layouts and seeds), whose section is left out where it is
missing.
"""
import json
import math
import os
import sys

FAMILIES = ['ordinary-far', 'ordinary-near', 'feature-poor', 'featureless-20', 'featureless-30', 'range-20',
            'noise-1px', 'fov-32']
AIDS = ['scan', 'triggered-scan', 'camera']
PAYS, COSTS, WITHIN = 0.85, 1.1, 1.1


def interval(r):
    text = f"{r['ratio']:.2f} [{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}]"
    if 'ci95_layouts_and_seeds' in r:
        low, high = r['ci95_layouts_and_seeds']
        text += f" ({low:.2f}, {high:.2f})"
    return text


def verdict(r, bounds='ci95'):
    low, high = r.get(bounds, r['ci95'])
    if high < PAYS:
        return 'pays'
    if low > COSTS:
        return 'costs'
    return 'no different'


def beyond(r, bound):
    return sorted(l for l, x in r['per_layout'].items() if x > bound)


def beyond_noise(r, bound):
    """The layouts whose own interval (their seeds resampled) lies wholly
    above `bound`, or None for a summary without those intervals."""
    per = r.get('per_layout_ci95')
    return None if per is None else sorted(l for l, (low, _) in per.items() if low > bound)


def verdict_below(r):
    """Whether the second interval (layouts and seeds resampled apart)
    lies below 1; None where the summary lacks it."""
    bounds = r.get('ci95_layouts_and_seeds')
    return None if bounds is None else bounds[1] < 1


def first_limits(first):
    """The time-limit counts of the first run's range-20 family, when its
    summary is at hand."""
    if not first or 'range-20' not in first:
        return ''
    cells = [(a, w, c) for w, aids in first['range-20']['default'].items() for a, c in aids.items()]
    counts = [f"{c['time_limit_runs']} of {c['runs']} {'straight' if a == 'none' else a} runs ({w} wheels)" for a, w, c in cells if c['time_limit_runs']]
    return f" ({', '.join(counts)})" if counts else ''


def main():
    source = sys.argv[1] if len(sys.argv) > 1 else 'out/aiding-families.json'
    target = sys.argv[2] if len(sys.argv) > 2 else 'docs/aiding-families.md'
    data = json.load(open(source))
    # The protocol's earlier runs, on earlier code (kept in the repository,
    # as they cannot be run again without it), for the deviations they led to.
    runs_dir = sys.argv[3] if len(sys.argv) > 3 else 'lab/runs'

    def earlier(name):
        # Every earlier run is cited by the page: a missing summary is an
        # error, not an empty column.
        path = os.path.join(runs_dir, f'aiding-families-{name}.json')
        if not os.path.exists(path):
            sys.exit(f'{path}: the summary of the protocol\'s {name} run is missing')
        return json.load(open(path))

    (first, second, third, fourth, fifth, sixth, seventh, eighth, ninth, tenth, eleventh, twelfth, thirteenth,
     fourteenth, fifteenth, sixteenth, seventeenth, eighteenth, nineteenth) = (
        earlier(n) for n in ['first', 'second', 'third', 'fourth', 'fifth', 'sixth', 'seventh', 'eighth', 'ninth',
                             'tenth', 'eleventh', 'twelfth', 'thirteenth', 'fourteenth', 'fifteenth', 'sixteenth',
                             'seventeenth', 'eighteenth', 'nineteenth'])
    families = [f for f in FAMILIES if f in data]
    cell = lambda f, e, w, a: data[f][e][w][a]  # noqa: E731
    some = cell(families[0], 'default', 'exact', 'none')
    runs = sum(c['runs'] for f in data.values() for e in f.values() for w in e.values() for c in w.values())
    out = []
    say = out.append
    say('# Action aiding over families of layouts')
    say('')
    say('The experiment [lab/protocol.md](../lab/protocol.md) laid out before any of its runs: '
        f'{len(families)} families of layouts, {some["layouts"]} generated layouts in each (layout seeds '
        f'40001–40012) and {some["runs"] // some["layouts"]} run seeds a layout (50000–50029), {runs} runs. '
        'Every number and verdict below is written by `lab/scripts/aiding-families-page.py` from the summary '
        'the protocol\'s command prints, by the protocol\'s rules:')
    say('')
    say('```sh run-slow')
    say('lab/scripts/aiding-families.sh "40001 40002 40003 40004 40005 40006 40007 40008 40009 40010 40011 40012" \\')
    say('    50000..50030 > out/aiding-families.json   # about 30 minutes on two cores')
    say('python3 lab/scripts/aiding-families-page.py')
    say('```')
    say('')
    say('Ratios are of mean end-point errors (egomotion\'s pose against the truth at the last frame) over '
        'all of a cell\'s runs, with a 95 % interval from a bootstrap over the layouts. *Default* is the '
        'estimate behaviours now steer by (odometry\'s sideways motion fused into egomotion, and its '
        'distance, put in the wheels\' scale as the steps measure it, `odometry_fusion: Sideways`; steering by '
        'it, `navigate: true`); *visual* is the thesis\'s setting '
        'and the default before (purely visual egomotion, steering by odometry). Beyond the protocol, '
        '*compass* is the default with odometry\'s heading held by the walls (`wall_compass: ()`, off by '
        'default: see its own section).')
    say('')

    say('## Deviation from the protocol')
    say('')
    say('The protocol\'s command was first run on the code it was committed with (commit 7e29dfa; that run\'s '
        'page is `git show a072b46:docs/aiding-families.md`). It showed the default estimate ending runs on '
        f'the time limit in the range-20 family{first_limits(first)}, where egomotion fails a third of its frames: '
        'the robot steered by egomotion\'s pose wholesale, '
        'and where that pose had drifted metres off it circled the goal it placed there. The pose steered by '
        'was then changed to combine egomotion\'s pose and odometry\'s by their covariances '
        '(`Tracker::navigation_pose`), developed on training layouts 2121–2828 (seeds 100–109), and the same '
        'command was run again on the same layouts and seeds: this page is that second run. Its layouts had '
        'been seen once, so for that one change they are not blind. A second interval was added to the '
        'summary for the second run (in round brackets beside the '
        'protocol\'s): every layout is run with the same seeds, so a seed\'s share of the error is common to '
        'all layouts and the protocol\'s interval, resampling layouts only, is conditional on those seeds; the '
        'second resamples layouts and seeds apart. Verdicts follow the protocol\'s interval; where the second '
        'would change one, the last section says so.')
    say('')
    say('The second run (its page: `git show 28e35d9:docs/aiding-families.md`) showed the default estimate '
        'worse than purely visual egomotion with 1 px of pixel noise. On training layouts 2121–2828 the cause '
        'was found in the along-track error: the sideways correction moved a visual distance metres uncertain '
        'through a correlation the linearised covariance gets wrong at that noise (zeroing that part of the '
        'correction took the along-track error from 1.52 to 1.03 m RMS). `Sideways` fusion was changed to take '
        'odometry\'s distance as well, corrected by the wheels\' scale the visual steps measure while driving, '
        'chosen on those training layouts, and the command was run a third time on the same layouts and '
        'seeds (its page: `git show 78860a7:docs/aiding-families.md`).')
    say('')
    say('The wheels\' scale measured that way was still left out of two places: frames bridged on odometry '
        '(nothing matched) took odometry\'s distance as counted, and so did odometry\'s own pose in the blend '
        'the robot steers by. Both were put in the measured scale, chosen on the training layouts 2121–2828 '
        '(seeds 100–109, driving straight with the default) by egomotion\'s end-point error alone: the range-20 '
        'family with wheels 1 % off went from 0.928 to 0.875 m and the other families\' cells moved by at most '
        '±2.5 %. The command was run a fourth time on the same layouts and seeds (its summary: '
        '`lab/runs/aiding-families-fourth.json`). Its end-point errors moved as little, but an independent review '
        'of it found the runs that missed the goal\'s tolerance multiplied (table below): odometry\'s own pose, '
        'scaled by what vision measured, carried vision\'s distance error instead of checking it, and the pose '
        'steered by followed. On the training layouts that part alone accounted for it (missed goals, driving '
        'straight with exact wheels: fov-32 0 → 23 of 80, featureless-20 1 → 22; back to 0 and 1 without it). '
        'It was taken out, the bridged frames kept the measured scale with its error added to their covariance, '
        'and the command was run a fifth time on the same layouts and seeds (its summary: '
        '`lab/runs/aiding-families-fifth.json`; its page: `git show 2c8709b:docs/aiding-families.md`).')
    say('')
    say('The fifth run left the range-20 family where it was, default and visual alike. Two causes were found '
        'there on the training layouts 2121–2828 (seeds 100–109, where egomotion failed 115 of a run\'s 136 '
        'frames), each tested by removing it. First, a defect: with two or three landmarks in view, a blind '
        'stretch longer than a keyframe\'s reach (10 m) retired every keyframe, and the next frame was taken as '
        'a fresh start, dropping the motion since the frame before (0.3 m of driving, or 10° of a scan\'s turn, '
        'each time). Fixed, straight driving\'s error there went from 0.631 to 0.364 m with the default estimate '
        '(the scan\'s from 0.983 to 0.304 m), and no other family\'s figures moved; the defect was egomotion\'s, '
        'so the fix serves the visual estimate too (0.598 to 0.354 m), and the two estimates\' ratio there stays '
        'near 1. Second, a step needed three consistent landmarks; with odometry fused in, two now do (the gate '
        'checks their motion against the wheels\', the fusion takes the sideways motion from the wheels, leaving '
        'the pair the turn, and the pair must agree on its distance apart): range-20 went from 0.364 to 0.352 m '
        '(with wheels 1 % off from 0.499 to 0.403, veering from 0.660 to 0.468), the other families\' cells '
        'within a few per cent. Missed goals rose in one cell on those seeds (fov-32 with the triggered scan, '
        '13 to 22 of 80) and not on seeds 110–129 (10 to 9). The report\'s estimated end pose was also changed '
        'to the pose the robot steered by (it was odometry\'s own), which the protocol\'s measures do not use; '
        'the table of that pose below is an addition to the protocol. The command was run a sixth time on the '
        'same layouts and seeds (a run started before an independent review of the two-landmark step was '
        'stopped unfinished; the review added the pair\'s agreement; its summary: '
        '`lab/runs/aiding-families-sixth.json`; its page: `git show a264fc3:docs/aiding-families.md`).')
    say('')
    say('The sixth run left 12 range-20 runs with the veer on the time limit, one seed on every layout: the '
        'robot pinned against the wall at the goal\'s x, the pose it steered by about 2 m off sideways, as '
        'odometry\'s pose, which the blend leans on where egomotion has few landmarks, carried the veer its noise '
        'model (a random slip) does not describe. The visual steps now measure the veer (the visual turn less '
        'odometry\'s, against the distance, fitted like the wheels\' scale and weighed against a prior of '
        '0.1°/m σ, the noise model\'s new `veer_deg_per_m`), and odometry\'s pose in the blend is turned by it '
        'along its whole path, with the veer\'s own error added to its covariance; bridged frames keep '
        'odometry\'s count of the turn. Chosen on the training layouts 2121–2828 (seeds 100–109; prior 0.1 '
        'against 0.02 and 0.05; turning bridged frames too was tried and dropped, as it cost egomotion\'s end '
        'point in range-20 scan runs, 0.276 → 0.321 m, and 0.234 → 0.307 m on seeds 110–129): range-20 with '
        'the veer went from 10 runs of 80 on the time limit to 0, and from 80 to 47 missing the goal; its '
        'cost, in range-20 with exact wheels, 28 → 39 of 80 missing the goal (73 → 79 of 160 on seeds '
        '110–129, and scanning there 70 → 97). The command was run a seventh time on the same layouts and '
        'seeds (its summary: `lab/runs/aiding-families-seventh.json`; its page: '
        '`git show 2caf6d0:docs/aiding-families.md`).')
    say('')
    say('The seventh run took the range-20 runs with the veer on the time limit from 12 to 2, and ended two '
        'others there that had not been: range-20 on exact wheels, scanning and steering the camera. Both were '
        'replayed (held-out runs: layout 40009 seed 50020, layout 40002 seed 50016): in the scanning one '
        'egomotion ended 0.07 m off and the pose steered by 1.9 m, as the veer measured had run to '
        '−0.15 ± 0.04°/m while the robot turned back and forth by the goal, and odometry\'s pose turned by it '
        'led the blend. A reading of the veer is now as uncertain as its stretch turned (2 % of the turn: a '
        'wheel base a little off, a visual turn through a sweep), and its distance is odometry\'s forward travel '
        'since the keyframe. The share was chosen on the training layouts (against none and 0.05): scanning '
        'in range-20, the pose steered by went from 0.370 to 0.295 m off and the runs missing the goal from 45 '
        'to 39 of 80 (seeds 110–129: 0.409 to 0.259 m, 96 to 65 of 160); its cost there, one straight run with '
        'the veer on the time limit that had ended 1.7 m off after bumping the wall. The cause was found on '
        'held-out runs, so this change is not blind either. The command was run an eighth time on the same '
        'layouts and seeds (its summary: `lab/runs/aiding-families-eighth.json`; its page: '
        '`git show bd71574:docs/aiding-families.md`).')
    say('')
    say('The eighth run left the steered camera no different from straight driving in every family (0.90–1.04×): '
        'a look turns nothing, so only the step term of the costs could tell looks apart, and the shipped '
        'costs, fitted to what the robot\'s own paths changed, put it at zero, so every look that kept enough '
        'landmarks in view tied and the camera looked ahead wherever it could. On the training layouts '
        '2121–2828 (seeds 100–129, default estimate, this command\'s camera aid with `objective: Cv` added) the '
        'view of least step CV ended 0.73–0.90× straight driving\'s error in seven families of eight '
        '(feature-poor 0.97), where looking ahead ended 0.91–1.03×; with the visual estimate the same looks '
        'ended 0.91–1.30×, worse than looking ahead in four families and better in two. Which half of the estimate decides was '
        'tested by crossing them on four families (ordinary-near, featureless-20, noise-1px, fov-32): purely '
        'visual egomotion steering by its own pose, 0.88–1.22×; odometry fused, steering by odometry, '
        '0.67–0.76×. So where egomotion fuses odometry the camera now looks for the view of least step CV, '
        'whatever the costs, and elsewhere the objective decides as before (the visual estimate\'s cells do '
        'not move). The robot\'s own tracking given the same step term (σ_cv 0.614, the costs fitted to end '
        'points as they are) did not pay with the default estimate on those layouts (0.91–1.12× straight '
        'driving, and fov-32 missed the goal in 51 runs of 240 instead of 6), so the robot\'s costs stay. The '
        'change was prompted by the eighth run\'s held-out result, so it is not blind either. The command was '
        'run a ninth time on the same layouts and seeds (its summary: `lab/runs/aiding-families-ninth.json`; '
        'its page: `git show 578f0f3:docs/aiding-families.md`).')
    say('')
    say('An independent review of the ninth run found a defect in it: where no look within half the field of '
        'view of the last kept enough landmarks in view, the camera jumped straight back to the course (the '
        'end-point objective had priced every such look as the odometry bridge, all alike, and took the one '
        'nearest the course; the CV has no such price), so the next frame shared little with the last. It now '
        'turns back by at most half its view, as before. That moved the camera\'s ratios by at most 0.01 on the '
        'training layouts (2121–2828, seeds 100–129) and over the held-out layouts against the ninth run. The '
        'command was run a tenth time on the same layouts and seeds (its summary: '
        '`lab/runs/aiding-families-tenth.json`; its page: `git show 360310e:docs/aiding-families.md`). After it '
        'the rule was narrowed to `Sideways` fusion, the default: with `Full` fusion (odometry\'s turn taken too; '
        'none of this page\'s cells) the view of least step CV ended 0.91–1.30× straight driving on the training '
        'layouts, against 0.93–1.17× looking ahead (worse in three families, better in three), so there the '
        'objective decides. No cell here moves with it.')
    say('')
    say('The tenth run left two straight runs of the default estimate with the veer on the time limit in the '
        'range-20 family, pinned against the wall beside the goal, and the range-20 family\'s error where it was. '
        'Both point to odometry\'s heading: driving the training layouts 2121–2828 (seeds 100–129) with odometry that slips '
        'no heading at all (its noise model unchanged) took straight driving\'s error in range-20 from 0.321 to '
        '0.036 m, where egomotion bridges most frames on odometry and the few landmarks cannot measure the '
        'turns (on three of those layouts and ten seeds, egomotion\'s heading error at the end went from '
        '1.11° to 0.11° RMS). No wheel is that good, but corridor walls are straight: the side sonars\' echoes, '
        'traced while driving straight, give each wall\'s direction, and a Kalman filter takes the first two '
        'walls that agree as the building\'s axes and later ones as the heading\'s drift (`wall_compass`; see '
        '[scenario-format.md](scenario-format.md#wall_compass)). It assumes the building\'s long walls are '
        'square to one another, which a robot in an unknown building cannot know, so it is off by default and '
        'the protocol\'s two estimates do not move; the command now also runs a third, *compass*, beyond the '
        'protocol. On the training layouts and seeds, straight driving with it ended lower than the default in '
        '21 of the 24 family and wheel cells (0.55–0.99×; range-20 with the veer 0.487 → 0.266 m, its runs on '
        'the time limit 1 → 0, missing the goal 175 → 81 of 240) and higher in noise-1px (1.01–1.05×), on '
        'the code before an independent review found the first two walls weighed the wrong way round (fixed '
        'before this run). Its '
        'settings are judgement, not tuned: a line spans 2 m of driving, a wall is taken as straight to 0.3° '
        '(σ) whatever its echoes\' scatter says. Every family here is one straight corridor with straight, '
        'parallel, unbroken walls (the layouts redraw the landmarks only), so these are the compass\'s best '
        'case: its assumption holds exactly. The summary also gives each layout\'s ratio its own interval '
        'now (its seeds resampled in pairs, from a generator of its own, so the protocol\'s intervals are drawn '
        'as before), to tell a layout beyond 1.1× by chance from one beyond it by more than its 30 seeds '
        'explain. The command was run an eleventh time on the same layouts and seeds (its summary: '
        '`lab/runs/aiding-families-eleventh.json`; its page: `git show d23fa88:docs/aiding-families.md`). The '
        'compass was prompted by the tenth run\'s held-out runs on the time limit, so its cells are not blind '
        'either.')
    say('')
    say('The eleventh run left the compass well short of odometry without heading slip in range-20 (0.84× '
        'the default against 0.11×). On the training layouts (2121–2828, seeds 100–109, straight, exact wheels) '
        'the compass held odometry\'s heading to 0.55° RMS at the end (steering by odometry), but egomotion\'s '
        'ended 0.96° off: a wall\'s correction reached egomotion only on frames it bridged on odometry, and '
        'the next match to a keyframe laid before the correction undid it. Each correction is now also a '
        'heading fix for egomotion (`State::heading_fix`): a Kalman update of the heading error egomotion\'s '
        'odometry bridges laid down, which turns its pose, and each keyframe by the share of that error laid '
        'down before it (a keyframe laid by vision alone keeps its heading); a bridged frame no longer takes '
        'the correction whole from the odometry it is carried on. Egomotion\'s heading then ended 0.52° off '
        'and its end point 0.166 m (0.285 before, 0.352 without the compass). Weighing the fix against the '
        'pose\'s whole heading variance (or the estimator\'s own with the bridges\') instead was tried and '
        'dropped: those are far above what vision errs by, and the fix pulled good visual headings to the '
        'wall\'s half degree (straight driving 1.8–2.9× the default in feature-poor and ordinary-near, seeds '
        '100–109); so was taking the corrections out of the odometry the gate and the veer\'s fit compare '
        'vision with (range-20 with the veer 0.42 → 0.45×, feature-poor 0.93 → 1.01×). Over seeds 100–129 of '
        'the training layouts the compass then ended range-20 at 0.41×, 0.53× and 0.36× the default (exact, '
        'scale, veer; 0.82×, 0.89×, 0.55× before), and every other family and wheels cell within ±0.03 of '
        'before but noise-1px with the veer (1.05 → 0.98×; noise-1px\'s runs missing the goal rose, 88, 46, '
        '83 → 96, 60, 102 of 240 on exact, scale and veer wheels). The compass\'s outside test, on the robot maker\'s simulator with its own sonar and odometry, '
        'is in [deploy.md](deploy.md#the-wall-compass-on-amrisim). The default and visual cells cannot move '
        'with the change (the compass is off in them), and the command was run a twelfth time on the same '
        'layouts and seeds (its summary: `lab/runs/aiding-families-twelfth.json`; its page: '
        '`git show da5e460:docs/aiding-families.md`). The change was prompted by the eleventh run\'s '
        'held-out compass cells, so they are not blind. Scanning in range-20 with the compass ends as without '
        'it (0.255 against 0.254 m), so against straight driving with it, which gained, the scan now costs: on training '
        'layout 2121 (seeds 100–109) its runs with and without the compass are identical, as a wall\'s line '
        'needs 2 m of straight driving and the scan stops to turn before that; with lines of 0.8 m '
        '(`span_m: 0.8`) the compass corrects there and the scan\'s error fell from 0.347 to 0.171 m. The '
        'span stays 2 m, untried on the other families and on straight driving.')
    say('')
    short = [f for f in families if twelfth[f]['default']['exact']['none']['error_vs_visual']['ratio'] > 0.6]
    say('The twelfth run left the default\'s straight driving above 0.6× the visual estimate in '
        + ', '.join(f"{f} ({twelfth[f]['default']['exact']['none']['error_vs_visual']['ratio']:.2f}×)" for f in short)
        + '. On the training layouts (2121–2828, seeds 100–109, straight) its error sat mostly in the wheels\' '
        'scale: given the true scale from the start, it fell to 0.35–0.7× in every family but range-20, with '
        'wheels 1 % off and with a random distance slip too. The scale is measured from the same visual steps '
        'and errs most in the first keyframes, yet the distance taken in it stayed in every pose chained on '
        'after, and before it settled (five keyframes) no distance was taken at all. Egomotion now keeps, '
        'along each pose\'s chain, odometry\'s distance as counted and as taken (`DistanceLedger`), and reports '
        'the pose with all of it put in the scale measured last; and it takes the distance as counted until '
        'the scale is measured. Chosen on seeds 100–109 by the geometric mean, over the eight families and '
        'four kinds of wheels (exact, 1 % scale, the veer, and a random distance slip of 1 cm/√m, '
        '`distance_slip_m_per_sqrt_m`, new to the simulator, whose wheels had erred in distance only by a '
        'fixed scale), of the ratio to before: the ledger alone 0.82, with the distance from the start 0.77; '
        'on seeds 110–129, 0.77, with no cell worse than the visual estimate. A prior on the scale towards 1 '
        'instead gained more with exact wheels and cost up to 1.8× the visual estimate with wheels 1 % off, and '
        'was dropped. The random distance slip raises the default\'s error on the training layouts by up to '
        'two fifths (seeds 110–129, before and after the change alike), where the visual estimate\'s hardly '
        'moves: the default leans on the wheels\' distance. The visual cells cannot move with the change; the '
        'default and compass cells do. The command was run a thirteenth time on the same layouts and seeds '
        '(its summary: `lab/runs/aiding-families-thirteenth.json`; its page: '
        '`git show 45ea777:docs/aiding-families.md`). The change was prompted by the twelfth run\'s held-out '
        'figures for the default, so its cells are not blind. Straight runs missing the goal rose with it in '
        'fov-32 (exact 7 → 17, veer 5 → 28 of 360) while the pose steered by ended nearer on average; on the '
        'training layouts every such run stopped with that pose 0.25–0.28 m from the goal, at the edge of '
        'its tolerance, so a few centimetres of that pose ahead of the truth turn a run out.')
    say('')
    ratio = lambda run, f: run[f]['default']['exact']['none']['error_vs_visual']['ratio']  # noqa: E731
    on_time_limit = lambda run, e: sum(c['time_limit_runs'] for f in families  # noqa: E731
                                       for w in run[f][e].values() for c in w.values())
    say('The rigid estimator scaled a step\'s covariance by how much its residuals exceed what its assumed '
        'pixel noise (0.3 px) explains, but never down. The simulator\'s cameras have 0.047 px, and on the '
        'training layouts the default\'s pose covariance was 3–5× wider than its error, so fusion leaned on '
        'odometry more than the visual steps deserved. The covariance now follows the residuals down as well, '
        'to no less than 0.3 of the assumed variance (chosen from 0, 0.03, 0.1, 0.3 and 1 on seeds 100–109 by '
        'the same rule as the ledger: straight driving\'s end point 0.93× before, geometric mean over eight '
        'families and four kinds of wheels, no cell worse than the visual estimate; on seeds 110–129 0.94×). '
        'Real KITTI frames, noisier than 0.3 px, are unchanged. The visual estimate\'s cells move a little with '
        'it (it picks keyframes by their covariance). The change was found on the training layouts, looking '
        'at the pose steered by with wheels 1 % off, not at this page; but these layouts have now been seen '
        'fourteen times. The command was run a fourteenth time on the same layouts and seeds (its summary: '
        '`lab/runs/aiding-families-fourteenth.json`; its page: `git show 1412f4e:docs/aiding-families.md`). '
        'Default ÷ visual, straight, exact wheels, thirteenth run → fourteenth: '
        + ', '.join(f'{f} {ratio(thirteenth, f):.2f} → {ratio(fourteenth, f):.2f}' for f in families) + '. '
        'The default\'s runs on the time limit, every aid and wheels: '
        f'{on_time_limit(thirteenth, "default")} → {on_time_limit(fourteenth, "default")}; the change was not '
        'aimed at them, and a run or two pinned by the wall can come and go with any small shift.')
    say('')
    steered = lambda run, f, w: run[f]['default'][w]['none']['steered_error_m']  # noqa: E731
    nearer = [f for f in families if steered(fifteenth, f, 'scale') < 0.95 * steered(fourteenth, f, 'scale')]
    missed = lambda run, w: sum(run[f]['default'][w]['none']['missed_goal_runs'] for f in families)  # noqa: E731
    say('The protocol\'s wheels off in scale are 1 % larger than the encoders think, which leaves the pose '
        'steered by behind the truth, and the robot drives on past where it stops believing itself. Wheels 1 % '
        'smaller do the opposite: on the training layouts (seeds 110–129, straight, with the fourteenth run\'s '
        'code; `WHEELS=short` in `lab/scripts/aiding-families.sh`) the default stopped outside the goal\'s '
        'tolerance in 1030 of 1280 runs, against 208 with exact wheels, though egomotion\'s end point was as '
        'good as with exact wheels: the pose steered by kept odometry\'s distance as counted. Put whole in the '
        'scale vision measures, it ended 0.44–0.51 m off against 0.17–0.42 with 1 px of pixel noise, where '
        'vision\'s own scale errs by a percent. It is now put in that scale as far as the measure outweighs a '
        'prior on the '
        'wheels\' scale, calibrated to within half a percent (the noise model\'s new `scale_sigma`; chosen on '
        'seeds 100–109 against 0.01 and 0.02, over exact wheels, wheels 1 % long and 1 % short, the veer and the '
        'distance slip: the pose steered by 0.85× as far off as before, geometric mean; on seeds 110–129 0.85× '
        'too, 0.56× with wheels short, 1.14× with exact wheels, and runs outside the tolerance with wheels short '
        '1030 → 594, with exact wheels 208 → 257; [perception.md](perception.md#public-datasets)). Egomotion\'s '
        'own end point, the protocol\'s measure, moves only where the path steered does. The command was run a '
        'fifteenth time on the same layouts and seeds (its summary: `lab/runs/aiding-families-fifteenth.json`; '
        'its page: `git show 3908af6:docs/aiding-families.md`). The pose steered by, '
        'straight, default, fourteenth run → fifteenth, with the protocol\'s wheels 1 % off in scale: '
        + ', '.join(f'{f} {steered(fourteenth, f, "scale"):.3f} → {steered(fifteenth, f, "scale"):.3f} m'
                    for f in families)
        + '; with exact wheels: '
        + ', '.join(f'{f} {steered(fourteenth, f, "exact"):.3f} → {steered(fifteenth, f, "exact"):.3f} m'
                    for f in families)
        + f'. Runs outside the tolerance, all families: exact wheels {missed(fourteenth, "exact")} → '
        f'{missed(fifteenth, "exact")}, wheels off in scale {missed(fourteenth, "scale")} → {missed(fifteenth, "scale")}, '
        f'the veer {missed(fourteenth, "veer")} → {missed(fifteenth, "veer")}. Default ÷ visual, straight, exact '
        'wheels, fourteenth run → fifteenth: '
        + ', '.join(f'{f} {ratio(fourteenth, f):.2f} → {ratio(fifteenth, f):.2f}' for f in families) + '. '
        f'The default\'s runs on the time limit: {on_time_limit(fourteenth, "default")} → '
        f'{on_time_limit(fifteenth, "default")}. Beyond the protocol, with wheels 1 % short on these layouts and seeds '
        '(`WHEELS=short ESTIMATES=default AIDS=none lab/scripts/aiding-families.sh` with this page\'s layouts and '
        'seeds, the fourteenth run\'s code against the fifteenth\'s), the pose steered by ended 0.43–0.52× as far off '
        'in six families (ordinary-near 0.127 → 0.054 m) and 0.90–0.91× in noise-1px and range-20, and the runs '
        'outside the goal\'s tolerance went from 2355 to 1441 of 2880. With exact wheels and the protocol\'s, '
        'more runs end outside it (listed below), though with the protocol\'s wheels the pose steered by ended '
        'nearer in ' + (', '.join(nearer) or 'no family') + ' (by 5 % or more) and level or further in '
        + (', '.join(f for f in families if f not in nearer) or 'none') + ': it had lagged the truth with '
        'wheels 1 % long, so the robot drove on past where it stopped believing itself, and with exact wheels it '
        'leans a little less on odometry\'s distance, exact in the simulator, and more on egomotion\'s.')
    rose = [(f, w, fourteenth[f]['default'][w]['none'], fifteenth[f]['default'][w]['none']) for f in families
            for w in ('exact', 'scale', 'veer')]
    rose = [(f, w, b, n) for f, w, b, n in rose if n['missed_goal_runs'] > b['missed_goal_runs'] + 5]
    if rose:
        say('')
        say('Straight runs whose true position missed the goal\'s tolerance rose with the fifteenth run\'s change in '
            + '; '.join(f"{f}, {w} wheels ({b['missed_goal_runs']} → {n['missed_goal_runs']} of {n['runs']}; the "
                        f"pose steered by {b['steered_error_m']:.3f} → {n['steered_error_m']:.3f} m off on average)"
                        for f, w, b, n in rose)
            + '. The robot stops where the pose it steers by first comes within the tolerance, at its edge, so a '
            'few centimetres of that pose ahead of the truth turn a run out.')
    error = lambda run, f, w, a: run[f]['default'][w][a]['error_m']  # noqa: E731
    straight_error = lambda run, f: error(run, f, 'exact', 'none')  # noqa: E731
    vs_straight = lambda run, f, a: run[f]['default']['exact'][a]['error_vs_straight']['ratio']  # noqa: E731
    aid_error = lambda run, f, a: error(run, f, 'exact', a)  # noqa: E731
    say('')
    say('`Sideways` fusion took no heading from odometry, but it took odometry\'s sideways position over each '
        'stretch as it was, and that carries odometry\'s heading drift: a drift growing over a straight stretch '
        'moves its end aside by half the distance times the drift, and through the coupling of slide and turn in '
        'the visual motion the fusion pulled the turn towards odometry\'s. It was found on the training layouts '
        '(2121–2828, seeds 100–129, feature-poor, straight), by removing the simulated wheels\' random heading '
        'slip with the noise model unchanged: egomotion\'s heading error at the end went from 0.58° to 0.35° RMS '
        'with the default and did not move with the visual estimate (1.15° against 1.16°). Each step now takes '
        'odometry\'s position less the stretch\'s drift lever times its turn, which such a drift leaves as '
        'counted (no setting; [perception.md](perception.md#public-datasets)). On the training layouts, driving '
        'straight over five kinds of wheels, egomotion\'s end point went to 0.82× of before (seeds 100–109) and '
        '0.85× (seeds 110–129), its worst cell against the visual estimate no worse than before (1.10×, range-20 '
        'with the distance slip). The run was on the code of commit 1e316dd; a review then left a stretch that '
        'backed up on the way without a lever (commit aa3c2b6), which changed none of the training runs. The '
        'change was not looked '
        'for on this page, but these layouts have now been seen sixteen times. The command was run a sixteenth '
        'time on the same layouts and seeds (its summary: `lab/runs/aiding-families-sixteenth.json`; its page: '
        '`git show b9b4150:docs/aiding-families.md`). Default ÷ visual, straight, exact '
        'wheels, fifteenth run → sixteenth: '
        + ', '.join(f'{f} {ratio(fifteenth, f):.2f} → {ratio(sixteenth, f):.2f}' for f in families)
        + '; the default\'s end point, same cells: '
        + ', '.join(f'{f} {straight_error(fifteenth, f):.3f} → {straight_error(sixteenth, f):.3f} m' for f in families)
        + '. In the feature-poor family, against straight driving with the default, fifteenth run → sixteenth: '
        + ', '.join(f'{a} {vs_straight(fifteenth, "feature-poor", a):.2f} → {vs_straight(sixteenth, "feature-poor", a):.2f}'
                    for a in AIDS)
        + ': straight driving gained most, the aids\' own end points moved less ('
        + ', '.join(f'{a} {aid_error(fifteenth, "feature-poor", a):.4f} → {aid_error(sixteenth, "feature-poor", a):.4f} m'
                    for a in AIDS) + ')'
        + f'. Runs outside the goal\'s tolerance, straight, all families: exact wheels {missed(fifteenth, "exact")} '
        f'→ {missed(sixteenth, "exact")}, wheels off in scale {missed(fifteenth, "scale")} → {missed(sixteenth, "scale")}, '
        f'the veer {missed(fifteenth, "veer")} → {missed(sixteenth, "veer")}. The default\'s runs on the time limit: '
        f'{on_time_limit(fifteenth, "default")} → {on_time_limit(sixteenth, "default")}'
        + (': a straight range-20 run with the veer (layout 40001, seed 50011, replayed: egomotion 1.5 m off at the '
           'end, the pose steered by 1.7 m, the robot pinned by the wall beside the goal), the kind the tenth run '
           'left, which the compass\'s runs here avoid.' if on_time_limit(sixteenth, 'default') == 1 else '.'))
    failed = lambda run, f, w, a: run[f]['default'][w][a]['failed_frames']  # noqa: E731
    say('')
    say('With a 20 m detection range the walls\' landmarks are seen only between where they enter the field of '
        'view and where they turn too oblique, so one or two are in view at a time: on a training run (layout '
        '2121, seed 100, straight, default) egomotion bridged 85 of its 136 frames on odometry, turn and all, 36 '
        'of them with one landmark matched to a keyframe. With `Sideways` fusion one landmark now makes a step: '
        'odometry\'s position over the stretch, as that fusion takes it, fixes the translation and the '
        'landmark\'s line of sight the turn, its range checked against odometry\'s distance and its turn against '
        'odometry\'s heading error; and a frame with one landmark in view becomes a keyframe (no setting; '
        '[perception.md](perception.md#public-datasets)). On the training layouts, driving straight over five '
        'kinds of wheels, range-20\'s end point went to 0.60–0.82× of before (seeds 100–109) and 0.55–0.79× '
        '(seeds 110–129, where nothing was chosen), and on seeds 100–109 no other family moved by more than 1 %. '
        'The run is on the code of commit 3c8eea3; a review then gave the simplified estimator back its own '
        'steps on one landmark, which that commit had cut off, and the rigid estimator\'s training runs stayed '
        'byte-identical. The change was not looked for on this page, but these layouts '
        'have now been seen seventeen times. The command was run a seventeenth time on the same layouts and '
        'seeds (its summary: `lab/runs/aiding-families-seventeenth.json`; its page: '
        '`git show a76de95:docs/aiding-families.md`). Default ÷ visual, straight, exact wheels, sixteenth run → '
        'seventeenth: '
        + ', '.join(f'{f} {ratio(sixteenth, f):.2f} → {ratio(seventeenth, f):.2f}' for f in families)
        + '. In range-20, the default\'s end point, straight, by wheels: '
        + ', '.join(f'{w} {error(sixteenth, "range-20", w, "none"):.3f} → {error(seventeenth, "range-20", w, "none"):.3f} m'
                    for w in ('exact', 'scale', 'veer'))
        + '; with the aids, exact wheels: '
        + ', '.join(f'{a} {error(sixteenth, "range-20", "exact", a):.3f} → {error(seventeenth, "range-20", "exact", a):.3f} m'
                    for a in AIDS)
        + '; failed frames a straight run (exact wheels) '
        f'{failed(sixteenth, "range-20", "exact", "none"):.1f} → {failed(seventeenth, "range-20", "exact", "none"):.1f}. '
        'Runs outside the goal\'s tolerance, straight, range-20: '
        + ', '.join(f'{w} wheels {sixteenth["range-20"]["default"][w]["none"]["missed_goal_runs"]} → '
                    f'{seventeenth["range-20"]["default"][w]["none"]["missed_goal_runs"]}' for w in ('exact', 'scale', 'veer'))
        + f' of 360. The default\'s runs on the time limit: {on_time_limit(sixteenth, "default")} → '
        f'{on_time_limit(seventeenth, "default")}.')
    # Every run the progress check or the time limit ended in `run`, all cells.
    ended = lambda run, key: sum(c.get(key, 0) for f in families for e in run[f].values()  # noqa: E731
                                 for w in e.values() for c in w.values())
    # The visual estimate's straight runs with the veer, by family: `what` of each.
    visual_veer = lambda run, what: [run[f]['visual']['veer']['none'].get(what, 0) for f in families]  # noqa: E731
    pinned = lambda run, key: ', '.join(str(n) for n in visual_veer(run, key))  # noqa: E731
    say('')
    say('A robot pinned beside a wall its goal lies behind bumped the wall until the time limit: the visual '
        'estimate\'s straight runs with the veer, which steer by odometry as the thesis did, did so in seven '
        'families (12 runs of 360 in each, in the seventeenth run). A scenario\'s progress check, which ends the run with the robot stopped '
        'once it has stayed within 0.5 m of one spot for 30 s short of the goal (`end: no_progress`), is now on '
        'by default wherever there is a goal (`progress: None` turns it off; '
        '[scenario-format.md](scenario-format.md#scenario)). No estimate changed. On the training layouts '
        '(2121–2828, seeds 110–129, every estimate, aid and kind of wheels, 23 040 runs) it ended none; on the '
        'visual estimate\'s straight runs with the veer, seeds 100–129, it ended the 16 pinned ones after '
        '115–131 s, their error unchanged. The run is on the code of commit 5ff626c. The command was run an '
        'eighteenth time on the same layouts and seeds (its summary: `lab/runs/aiding-families-eighteenth.json`; '
        'its page: `git show d565a7b:docs/aiding-families.md`). Runs on the time limit, every cell, seventeenth '
        'run → eighteenth: '
        f'{ended(seventeenth, "time_limit_runs")} → {ended(eighteenth, "time_limit_runs")}; runs the progress check '
        f'ended: {ended(eighteenth, "no_progress_runs")}. The visual estimate\'s straight runs with the veer, by family '
        f'({", ".join(families)}): on the time limit ({pinned(seventeenth, "time_limit_runs")}) → '
        f'({pinned(eighteenth, "time_limit_runs")}), ended by the progress check ({pinned(eighteenth, "no_progress_runs")}); '
        f'their end point {", ".join(f"{a:.3f} → {b:.3f}" for a, b in zip(visual_veer(seventeenth, "error_m"), visual_veer(eighteenth, "error_m")))} m; '
        f'their time {", ".join(f"{a:.0f} → {b:.0f}" for a, b in zip(visual_veer(seventeenth, "time_s"), visual_veer(eighteenth, "time_s")))} s a run.')
    # Every cell of the estimates that fit the wheels (the visual one does
    # not): its end point in `run` over its end point in `before`.
    fitted = lambda run, before: sorted(  # noqa: E731
        (run[f][e][w][a]['error_m'] / before[f][e][w][a]['error_m'], f, e, w, a)
        for f in families for e in ('default', 'compass') if e in run[f]
        for w in run[f][e] for a in run[f][e][w])
    moved = fitted(nineteenth, eighteenth)
    visual_same = all(nineteenth[f]['visual'][w][a] == eighteenth[f]['visual'][w][a]
                      for f in families for w in nineteenth[f]['visual'] for a in nineteenth[f]['visual'][w])
    geo = lambda xs: math.exp(sum(math.log(x) for x in xs) / len(xs))  # noqa: E731
    geometric = geo([r for r, *_ in moved])
    say('')
    say('The wheels\' scale and veer, which `Sideways` fusion measures from the visual steps, were fitted over '
        'the readings alike, and the readings from one keyframe share its landmarks\' errors: a robot turning on '
        'the spot for 40 minutes beside its goal (a training run with the progress check off) read one keyframe '
        '982 times and took the scale from 0.996 to 0.959 on exact wheels, egomotion 0.96 m off. They are now '
        'fitted keyframe by keyframe, each keyframe weighed by one over its variance plus the spread between '
        'keyframes that the variances do not explain ([perception.md](perception.md#public-datasets)): that run '
        'ends 0.058 m off. On the training layouts (2121–2828, seeds 110–129, the default estimate) the cells '
        'moved by −9 % to +7 % with 1 px of pixel noise, whose runs scatter most, and −3 % to +5 % elsewhere '
        '(two builds differing only in how one sum rounds differed by up to 2.4 %), and scanning lost at most '
        '3.5 %. The run is on the code of commit 3d3ab16; nothing was chosen on this page. The '
        'command was run a nineteenth time on the same layouts and seeds (its summary: '
        '`lab/runs/aiding-families-nineteenth.json`; its page: `git show 75bc0bf:docs/aiding-families.md`). '
        'Every cell of the default and compass estimates, eighteenth run → nineteenth (the visual estimate fits no '
        'wheels' + (', and its cells are unchanged to the last bit' if visual_same else ', yet its cells moved')
        + f'): end point {geometric:.3f}× (geometric mean of {len(moved)} cells), from '
        f'{moved[0][0]:.2f}× ({" ".join(moved[0][1:])}) to {moved[-1][0]:.2f}× ({" ".join(moved[-1][1:])}); '
        f'{sum(1 for r, *_ in moved if r == 1.0)} cells unchanged to the last bit. Default ÷ visual, straight, exact '
        'wheels: ' + ', '.join(f'{f} {ratio(eighteenth, f):.2f} → {ratio(nineteenth, f):.2f}' for f in families)
        + '. The aids against straight driving in feature-poor layouts, default estimate: '
        + ', '.join(f'{a} {vs_straight(eighteenth, "feature-poor", a):.2f} → {vs_straight(nineteenth, "feature-poor", a):.2f}'
                    for a in AIDS)
        + f'. Runs outside the goal\'s tolerance, every cell: {ended(eighteenth, "missed_goal_runs")} → '
        f'{ended(nineteenth, "missed_goal_runs")}; on the time '
        f'limit: {ended(eighteenth, "time_limit_runs")} → {ended(nineteenth, "time_limit_runs")}; ended by the progress '
        f'check: {ended(eighteenth, "no_progress_runs")} → {ended(nineteenth, "no_progress_runs")}.')
    # Only the steered camera's runs read the head: every other cell must be
    # the nineteenth run's to the bit.
    others_same = all(data[f][e][w][a] == nineteenth[f][e][w][a] for f in families for e in data[f]
                      for w in data[f][e] for a in data[f][e][w] if a != 'camera')
    camera = lambda run, e: [run[f][e]['exact']['camera']['error_vs_straight']['ratio'] for f in families]  # noqa: E731
    say('')
    say('Egomotion places its first keyframe\'s view by the robot\'s start heading and the pan the head reads '
        'then, and chains later headings to that view, so an error in that one reading turns the whole map; over '
        'visual steps later readings\' errors cancel. The robot now reads the head 64 times for the first frame '
        'and takes the mean, the simulated head\'s extra readings drawing from a stream of their own so that '
        'every later reading is as it was ([perception.md](perception.md#a-camera-on-a-pan-tilt-unit)). It was '
        'found on the training layouts (2121–2828), where the steered camera ended 1.10× straight driving\'s '
        'error in feature-poor layouts with one reading and 1.00× with the first reading alone exact (seeds '
        '110–129); with the mean of 64, 1.01× (seeds 100–129), and the camera\'s geometric mean over the eight '
        'families went from 0.883× to 0.858×. The run is on the code of commit 7085966; the cause was '
        'looked for because this page\'s camera was worse than straight driving in feature-poor layouts, so the '
        'change is not blind. The command was run a twentieth time on the same layouts and seeds: this page is '
        'that twentieth run. Every cell without the steered camera is '
        + ('the nineteenth run\'s to the last bit' if others_same else 'NOT the nineteenth run\'s: a defect')
        + '. The steered camera against straight driving, exact wheels, nineteenth run → this, default estimate: '
        + ', '.join(f'{f} {a:.2f} → {b:.2f}' for f, a, b in zip(families, camera(nineteenth, 'default'), camera(data, 'default')))
        + f' (geometric mean {geo(camera(nineteenth, "default")):.3f} → {geo(camera(data, "default")):.3f}); with '
        'the wall compass: '
        + ', '.join(f'{f} {a:.2f} → {b:.2f}' for f, a, b in zip(families, camera(nineteenth, 'compass'), camera(data, 'compass')))
        + f' (geometric mean {geo(camera(nineteenth, "compass")):.3f} → {geo(camera(data, "compass")):.3f}); purely '
        'visual: ' + ', '.join(f'{f} {a:.2f} → {b:.2f}' for f, a, b in zip(families, camera(nineteenth, 'visual'), camera(data, 'visual')))
        + f' (geometric mean {geo(camera(nineteenth, "visual")):.3f} → {geo(camera(data, "visual")):.3f}). Runs '
        f'outside the goal\'s tolerance, every cell: {ended(nineteenth, "missed_goal_runs")} → '
        f'{ended(data, "missed_goal_runs")}; on the time limit: {ended(nineteenth, "time_limit_runs")} → '
        f'{ended(data, "time_limit_runs")}; ended by the progress check: {ended(nineteenth, "no_progress_runs")} → '
        f'{ended(data, "no_progress_runs")}.')
    if second:
        earlier_runs = [('second', second), ('third', third), ('fourth', fourth), ('fifth', fifth),
                        ('sixth', sixth), ('seventh', seventh), ('eighth', eighth), ('ninth', ninth),
                        ('tenth', tenth), ('eleventh', eleventh), ('twelfth', twelfth), ('thirteenth', thirteenth),
                        ('fourteenth', fourteenth), ('fifteenth', fifteenth), ('sixteenth', sixteenth),
                        ('seventeenth', seventeenth), ('eighteenth', eighteenth), ('nineteenth', nineteenth)]
        say('')
        say('Driving straight with the default estimate, by run: the ratio to the visual estimate on the same '
            'wheels, then the runs (of 360) whose true position missed the goal\'s tolerance.')
        say('')
        say('| family | wheels | ' + ' | '.join(f'{n} run' for n, _ in earlier_runs) + ' | this run | missed: '
            + ', '.join(n for n, _ in earlier_runs) + ', this |')
        say('| --- | --- | ' + ' | '.join('---' for _ in earlier_runs) + ' | --- | --- |')
        for f in families:
            for w in ['exact', 'scale', 'veer']:
                cells = [r[f]['default'][w]['none'] if r and f in r else None for _, r in earlier_runs]
                now = cell(f, 'default', w, 'none')
                missed = [str(c['missed_goal_runs']) if c else '' for c in cells] + [str(now['missed_goal_runs'])]
                say(f"| {f} | {w} | " + ' | '.join(interval(c['error_vs_visual']) if c else '' for c in cells)
                    + f" | {interval(now['error_vs_visual'])} | {', '.join(missed)} |")
    say('')
    say('The steered camera against straight driving, default estimate, in the eighth run (looking ahead), '
        'the tenth (the view of least step CV) and this one (the same view, on the estimate of now): the error ratio, '
        'the layouts where it ends beyond '
        '1.1× straight driving and the worst layout now, the error of the pose the robot steered by (straight '
        'driving\'s in brackets), and the runs (of 360) whose true position missed the goal\'s tolerance '
        '(straight driving\'s in brackets). The protocol\'s measure is egomotion\'s pose; the pose steered by '
        'blends it with odometry\'s and can move the other way.')
    say('')
    say('| family | eighth run | tenth run | this run | layouts beyond 1.1×: eighth, tenth, this (worst now) | '
        'steered m: eighth, this (straight) | missed: eighth, tenth, this (straight) |')
    say('| --- | --- | --- | --- | --- | --- | --- |')
    for f in families:
        runs_ = [r[f]['default']['exact']['camera'] for r in (eighth, tenth)] + [cell(f, 'default', 'exact', 'camera')]
        straight = cell(f, 'default', 'exact', 'none')
        ratios = [c['error_vs_straight'] for c in runs_]
        worst = max(ratios[-1]['per_layout'].values())
        say(f"| {f} | " + ' | '.join(interval(r) for r in ratios) + ' | '
            + ', '.join(str(len(beyond(r, WITHIN))) for r in ratios) + f" of {len(ratios[-1]['per_layout'])} "
            f"({worst:.2f}) | {runs_[0]['steered_error_m']:.3f}, {runs_[-1]['steered_error_m']:.3f} "
            f"({straight['steered_error_m']:.3f}) | " + ', '.join(str(c['missed_goal_runs']) for c in runs_)
            + f" ({straight['missed_goal_runs']}) |")
    say('')
    say('## The default estimate against purely visual egomotion')
    say('')
    say('Driving straight, per family: the mean end-point error with each estimate, the ratio default ÷ '
        'visual, the layouts on which the default ends further off, the verdict (better: the interval\'s '
        'upper end below 1; the issue\'s figure: a ratio of 0.6 or less), and the runs whose true position '
        'ended outside the goal\'s tolerance with each (the robot stops where the pose it steers by puts the '
        'goal: odometry\'s with the visual estimate, the fused one with the default).')
    say('')
    say('| family | visual m | default m | default ÷ visual | layouts where the default is worse | better | ≤ 0.6× | '
        'missed the goal: visual, default |')
    say('| --- | --- | --- | --- | --- | --- | --- | --- |')
    pooled = {'visual': [], 'default': []}
    for f in families:
        v, d = cell(f, 'visual', 'exact', 'none'), cell(f, 'default', 'exact', 'none')
        r = d['error_vs_visual']
        pooled['visual'].append(v['error_m'])
        pooled['default'].append(d['error_m'])
        worse = beyond(r, 1.0)
        say(f"| {f} | {v['error_m']:.3f} | {d['error_m']:.3f} | {interval(r)} | "
            f"{len(worse)} of {len(r['per_layout'])}{': ' + ', '.join(worse) if worse else ''} | "
            f"{'yes' if r['ci95'][1] < 1 else 'no'} | {'yes' if r['ratio'] <= 0.6 else 'no'} | "
            f"{v['missed_goal_runs']}, {d['missed_goal_runs']} of {d['runs']} |")
    mean = lambda xs: sum(xs) / len(xs)  # noqa: E731
    say('')
    say(f"Over the families (the mean of the families' means): {mean(pooled['visual']):.3f} m visual, "
        f"{mean(pooled['default']):.3f} m default, "
        f"{mean(pooled['default']) / mean(pooled['visual']):.2f}×.")
    # The visual estimate is egomotion too: a fix to egomotion moves it, and
    # the figure the issue set (0.6× the estimate of before) is then to be
    # read against the visual estimate as the earlier run measured it.
    moved = [f for f in families if f in fifth
             and abs(cell(f, 'visual', 'exact', 'none')['error_m'] / fifth[f]['visual']['exact']['none']['error_m'] - 1)
             > 0.01]
    if moved:
        say('')
        say('The visual estimate itself moved since the fifth run (egomotion\'s fix above serves it too) in '
            + '; '.join(f"{f} (from {fifth[f]['visual']['exact']['none']['error_m']:.3f} to "
                        f"{cell(f, 'visual', 'exact', 'none')['error_m']:.3f} m)" for f in moved)
            + '. Against the visual estimate as the fifth run measured it, the estimate of before, the default '
            'now ends at ' + '; '.join(
                f"{cell(f, 'default', 'exact', 'none')['error_m'] / fifth[f]['visual']['exact']['none']['error_m']:.2f}× "
                f"in {f}" for f in moved) + '.')
    say('')

    if all('steered_vs_visual' in cell(f, 'default', 'exact', 'none') for f in families):
        say('**The pose the robot steered by** (not in the protocol: added after it, with intervals drawn apart '
            'from the protocol\'s): the report\'s estimate error, the distance from where the robot ended to '
            'where the pose it steered by put it, driving straight on exact wheels. With the visual estimate '
            'that pose is odometry\'s; with the default, egomotion\'s combined with odometry\'s. It is the pose '
            'the robot stops by, so it decides whether the goal is reached.')
        say('')
        say('| family | visual m | default m | default ÷ visual | layouts where the default is worse |')
        say('| --- | --- | --- | --- | --- |')
        for f in families:
            v, d = cell(f, 'visual', 'exact', 'none'), cell(f, 'default', 'exact', 'none')
            r = d['steered_vs_visual']
            worse = beyond(r, 1.0)
            say(f"| {f} | {v['steered_error_m']:.3f} | {d['steered_error_m']:.3f} | {interval(r)} | "
                f"{len(worse)} of {len(r['per_layout'])}{': ' + ', '.join(worse) if worse else ''} |")
        say('')
        say('The same pose with the default estimate on each wheels, driving straight and scanning, in the '
            'sixth run (before the measured veer, above, turned odometry\'s pose in it), the seventh, the eighth '
            'and this one, and the runs (of 360) whose true position missed the goal\'s tolerance.')
        say('')
        say('| family | wheels | aid | sixth run m | seventh run m | eighth run m | this run m | '
            'missed: sixth, seventh, eighth, this |')
        say('| --- | --- | --- | --- | --- | --- | --- | --- |')
        for f in families:
            for w, a in (('exact', 'none'), ('scale', 'none'), ('veer', 'none'), ('exact', 'scan')):
                runs_ = [r[f]['default'][w][a] for r in (sixth, seventh, eighth)] + [cell(f, 'default', w, a)]
                say(f"| {f} | {w} | {'straight' if a == 'none' else a} | "
                    + ' | '.join(f"{c['steered_error_m']:.3f}" for c in runs_) + ' | '
                    + ', '.join(str(c['missed_goal_runs']) for c in runs_) + ' |')
        say('')

    say('**With wheels that err beyond odometry\'s noise model** (1 % scale: the wheels 1 % larger than the '
        'encoders think; veer: 0.05° per metre odometry does not see), straight driving: the default against '
        'the visual estimate on the same wheels (no worse: the interval\'s upper end below 1), and each against '
        'the visual estimate on exact wheels.')
    say('')
    say('| family | wheels | visual m | default m | default ÷ visual | no worse | visual ÷ visual, exact wheels | '
        'default ÷ visual, exact wheels |')
    say('| --- | --- | --- | --- | --- | --- | --- | --- |')
    for f in families:
        for w in ('scale', 'veer'):
            v, d = cell(f, 'visual', w, 'none'), cell(f, 'default', w, 'none')
            r = d['error_vs_visual']
            say(f"| {f} | {w} | {v['error_m']:.3f} | {d['error_m']:.3f} | {interval(r)} | "
                f"{'yes' if r['ci95'][1] < 1 else 'no'} | {interval(v['error_vs_visual_exact_wheels'])} | "
                f"{interval(d['error_vs_visual_exact_wheels'])} |")
    say('')

    def aid_rows(e):
        """The aids against straight driving with estimate `e`, a row per
        family and aid."""
        for f in families:
            straight = cell(f, e, 'exact', 'none')
            for a in AIDS:
                c = cell(f, e, 'exact', a)
                r, t = c['error_vs_straight'], c['time_vs_straight']
                over, real = beyond(r, WITHIN), beyond_noise(r, WITHIN)
                say(f"| {f} | {a} | {interval(r)} | {verdict(r)} | {len(over)} of {len(r['per_layout'])}"
                    f"{'' if real is None else f' ({len(real)})'} | "
                    f"{t['ratio']:.2f} | {c['failed_frames']:.1f} ({straight['failed_frames']:.1f}) |")

    # Each layout's own interval, added after the tenth run: older summaries lack it.
    noise = all(beyond_noise(cell(f, e, 'exact', a)['error_vs_straight'], WITHIN) is not None
                for e in ('default', 'visual') for f in families for a in AIDS)
    for e in ('default', 'visual'):
        say(f'## Aids against straight driving, {e} estimate')
        say('')
        say('Per family and aid: the error ratio to straight driving with its interval and the verdict (pays: '
            'upper end below 0.85; costs: lower end above 1.1), the layouts where the aid ends beyond 1.1× '
            'straight driving'
            + (' (in brackets, beyond the protocol: those whose own interval, their 30 seeds resampled in pairs, '
               'lies wholly above 1.1: per layout, and not corrected for the hundreds of such intervals)' if noise else '')
            + ', the time ratio, and failed frames per run (straight driving\'s in brackets).')
        say('')
        say('| family | aid | error ÷ straight | verdict | layouts beyond 1.1×'
            + (' (beyond the seeds\' noise)' if noise else '') + ' | time ÷ straight | failed frames / run |')
        say('| --- | --- | --- | --- | --- | --- | --- |')
        aid_rows(e)
        say('')

    compass = all('compass' in data[f] for f in families)
    if compass:
        say('## The wall compass (beyond the protocol)')
        say('')
        say('Driving straight, per family and wheels: the mean error with the default estimate and with the '
            'wall compass, the compass\'s ratio to the default and to the visual estimate on the same wheels '
            '(with the protocol\'s intervals, drawn from generators of their own), the runs that ended on the '
            'time limit and those (of 360) whose true position missed the goal\'s tolerance, default then compass.')
        say('')
        say('| family | wheels | default m | compass m | compass ÷ default | eleventh run (before the heading '
            'fix) | compass ÷ visual | time limit | missed |')
        say('| --- | --- | --- | --- | --- | --- | --- | --- | --- |')
        for f in families:
            for w in ('exact', 'scale', 'veer'):
                d, c = cell(f, 'default', w, 'none'), cell(f, 'compass', w, 'none')
                before = eleventh[f]['compass'][w]['none'] if eleventh and f in eleventh else None
                say(f"| {f} | {w} | {d['error_m']:.3f} | {c['error_m']:.3f} | {interval(c['error_vs_default'])} | "
                    f"{interval(before['error_vs_default']) if before else ''} | "
                    f"{interval(c['error_vs_visual'])} | {d['time_limit_runs']}, {c['time_limit_runs']} | "
                    f"{d['missed_goal_runs']}, {c['missed_goal_runs']} |")
        say('')
        say('The aids with the wall compass against straight driving with it, as the tables above.')
        say('')
        say('| family | aid | error ÷ straight | verdict | layouts beyond 1.1× (beyond the seeds\' noise) | '
            'time ÷ straight | failed frames / run |')
        say('| --- | --- | --- | --- | --- | --- | --- |')
        aid_rows('compass')
        say('')

    axes_path = os.path.join(runs_dir, 'error-axes-feature-poor.json')
    if os.path.exists(axes_path):
        error_axes(json.load(open(axes_path))['feature-poor'], say)
    say('## What holds and what does not')
    say('')
    claims = []
    for e in ('default', 'visual'):
        for f in families:
            for a in AIDS:
                r = cell(f, e, 'exact', a)['error_vs_straight']
                claims.append((verdict(r), f'{a} with the {e} estimate in {f} ({interval(r)})'))
    for kind in ('pays', 'costs'):
        held = [text for v, text in claims if v == kind]
        say(f"- **An aid {kind}** in: {'; '.join(held) if held else 'no family'}.")
    within = [(f, e, a) for e in ('default', 'visual') for f in families for a in AIDS
              if cell(f, e, 'exact', a)['error_vs_straight']['ratio'] <= WITHIN
              and not beyond(cell(f, e, 'exact', a)['error_vs_straight'], WITHIN)]
    total = len(families) * len(AIDS) * 2
    say(f'- **Within 1.1× straight driving** on every layout: {len(within)} of {total} family, aid and '
        'estimate combinations; the rest are in the tables above with the layouts beyond.')
    losses = [(f, e, a, real) for e in ('default', 'visual') for f in families for a in AIDS
              for real in [beyond_noise(cell(f, e, 'exact', a)['error_vs_straight'], WITHIN)] if real]
    if noise:
        say(f"- **Beyond 1.1× on a layout by more than its seeds' noise** (an addition to the protocol: the "
            f"layout's own 95 % interval, its seeds resampled in pairs, wholly above 1.1; per layout, and not "
            f"corrected for the many intervals): {len(losses)} of {total} "
            "combinations"
            + (': ' + '; '.join(f"{a} with the {e} estimate in {f} (layout{'s' if len(real) > 1 else ''} "
                                f"{', '.join(real)})" for f, e, a, real in losses) if losses else '')
            + f". In the other {total - len(losses)}, every layout beyond 1.1× is within what 30 seeds can tell "
            "apart from 1.1.")
    fp = [f for f in families if f == 'feature-poor']
    for f in fp:
        for a, name in (('triggered-scan', 'triggered scan'), ('camera', 'steered camera')):
            c = cell(f, 'default', 'exact', a)
            r, t = c['error_vs_straight'], c['time_vs_straight']
            met = r['ratio'] <= PAYS and t['ratio'] <= 1.5
            added = '' if a == 'triggered-scan' else ' (an addition to the protocol, which names the triggered scan here)'
            why = ' Where the error lies, and what a look would have to do: the section above.' if (
                a == 'camera' and not met and os.path.exists(axes_path)) else ''
            say(f"- **The {name} in the feature-poor family** (default estimate){added}: {interval(r)} straight "
                f"driving's error at {t['ratio']:.2f}× its time: the issue's figure (0.85× at 1.5× the time) is "
                f"{'met' if met else 'not met'}.{why}")
    better = [f for f in families if cell(f, 'default', 'exact', 'none')['error_vs_visual']['ci95'][1] < 1]
    say(f"- **The default estimate is better than purely visual egomotion** driving straight in "
        f"{len(better)} of {len(families)} families"
        f"{'' if len(better) == len(families) else ' (not in: ' + ', '.join(f for f in families if f not in better) + ')'}"
        f"; at 0.6× or less in {sum(cell(f, 'default', 'exact', 'none')['error_vs_visual']['ratio'] <= 0.6 for f in families)}.")
    no_worse = [f for f in families
                if all(cell(f, 'default', w, 'none')['error_vs_visual']['ci95'][1] < 1 for w in ('scale', 'veer'))]
    say(f"- **With miscalibrated wheels** the default is better than the visual estimate on the same wheels, with "
        f"both the scale error and the veer, in {len(no_worse)} of {len(families)} families"
        f"{'' if len(no_worse) == len(families) else ' (not in: ' + ', '.join(f for f in families if f not in no_worse) + ')'}.")
    changed = [text for e in ('default', 'visual') for f in families for a in AIDS
               for r in [cell(f, e, 'exact', a)['error_vs_straight']]
               if 'ci95_layouts_and_seeds' in r and verdict(r) != verdict(r, 'ci95_layouts_and_seeds')
               for text in [f"{a} with the {e} estimate in {f}: {verdict(r)} by the protocol's interval, "
                            f"{verdict(r, 'ci95_layouts_and_seeds')} with seeds resampled too"]]
    say(f"- **Verdicts the second interval would change:** {'; '.join(changed) if changed else 'none'}.")
    limits = [f'{f}, {e}, {a}, {w}: {c["time_limit_runs"]}' for f in families for e, ws in data[f].items()
              for w, aids in ws.items() for a, c in aids.items() if c['time_limit_runs']]
    say(f"- **Runs that ended on the time limit:** {'; '.join(limits) if limits else 'none'}.")
    others = [f'{f}, {e}, {a}, {w}: {", ".join(c["other_ends"])}'
              + (f' ({c["no_progress_runs"]} by the progress check)' if c.get('no_progress_runs') else '')
              for f in families for e, ws in data[f].items()
              for w, aids in ws.items() for a, c in aids.items() if c.get('other_ends')]
    say(f"- **Runs that ended otherwise** (neither at the goal nor on the time limit): "
        f"{'; '.join(others) if others else 'none'}.")
    if compass:
        limits = sum(c['time_limit_runs'] for f in families for c in data[f]['compass']['exact'].values()) + sum(
            data[f]['compass'][w]['none']['time_limit_runs'] for f in families for w in ('scale', 'veer'))
        better = [f for f in families if cell(f, 'compass', 'exact', 'none')['error_vs_visual']['ci95'][1] < 1]
        at_most = sum(cell(f, 'compass', 'exact', 'none')['error_vs_visual']['ratio'] <= 0.6 for f in families)
        gains = [f for f in families if cell(f, 'compass', 'exact', 'none')['error_vs_default']['ci95'][1] < 1]
        losses = [f for f in families if cell(f, 'compass', 'exact', 'none')['error_vs_default']['ci95'][0] > 1]
        # The summary rounds bounds to three places: a bound of exactly 1 is at the edge, not clear of it.
        edges = [f for f in families if cell(f, 'compass', 'exact', 'none')['error_vs_default']['ci95'][0] == 1]
        lost = [f for f in gains if verdict_below(cell(f, 'compass', 'exact', 'none')['error_vs_default']) is False]
        within = [(f, a) for f in families for a in AIDS
                  if cell(f, 'compass', 'exact', a)['error_vs_straight']['ratio'] <= WITHIN
                  and not beyond(cell(f, 'compass', 'exact', a)['error_vs_straight'], WITHIN)]
        say(f"- **With the wall compass** (beyond the protocol): runs on the time limit, every aid and wheels, "
            f"{limits}; driving straight with exact wheels, better than the default (interval below 1) in "
            f"{len(gains)} of {len(families)} families{': ' + ', '.join(gains) if gains else ''}, worse (interval "
            f"above 1) in {len(losses)}{': ' + ', '.join(losses) if losses else ''}"
            f"{'; at the edge (lower end 1.00): ' + ', '.join(edges) if edges else ''}"
            f"{'; with seeds resampled too, no longer better in: ' + ', '.join(lost) if lost else ''}; better than the visual "
            f"estimate in {len(better)} of {len(families)}, at 0.6× or less in {at_most}; within 1.1× straight "
            f"driving on every layout, {len(within)} of {len(families) * len(AIDS)} family and aid combinations.")
        for a, name in (('triggered-scan', 'triggered scan'), ('camera', 'steered camera')):
            c = cell('feature-poor', 'compass', 'exact', a) if 'feature-poor' in families else None
            if c:
                r, t = c['error_vs_straight'], c['time_vs_straight']
                met = r['ratio'] <= PAYS and t['ratio'] <= 1.5
                say(f"- **The {name} in the feature-poor family with the wall compass**: {interval(r)} straight "
                    f"driving's error at {t['ratio']:.2f}× its time: the issue's figure is "
                    f"{'met' if met else 'not met'}.")
    say('')
    open(target, 'w').write('\n'.join(out))


def error_axes(split, say):
    """The section on where the error lies in feature-poor layouts, from
    lab/scripts/error-axes.sh's summary (lab/runs/error-axes-feature-poor.json)."""
    mm = lambda m: f'{1000 * m:.1f}'  # noqa: E731
    say('## Where the error lies in feature-poor layouts (beyond the protocol)')
    say('')
    say('`ROUTES=feature-poor lab/scripts/error-axes.sh` on this page\'s layouts and seeds (the default estimate, '
        'exact wheels; its summary: `lab/runs/error-axes-feature-poor.json`, the same byte for byte on the code of '
        'commits 0c480b3 and 1c0d799): each aid\'s end-point error split '
        'into its parts along the route and across it, with the route\'s noise, without stereo noise (pixel '
        'noise and outliers), without wheel slip and without either. `head-ahead` drives straight with the camera '
        'on the steered camera\'s pan-tilt head, never turned: what the head\'s readings alone cost. The wheel '
        'scale\'s error is that of the scale egomotion measured by the end (the wheels are exact).')
    say('')
    say('| noise | aid | error m | ÷ straight | RMS along mm | RMS across mm | wheel scale RMS error | failed frames / run '
        '| time s |')
    say('| --- | --- | --- | --- | --- | --- | --- | --- | --- |')
    variants = ['base', 'no-stereo-noise', 'no-slip', 'no-noise']
    aids = ['none', 'head-ahead', 'camera', 'scan', 'triggered-scan']
    for v in variants:
        for a in aids:
            c = split[v][a]
            ratio = '—' if c['vs_straight'] is None else f"{c['vs_straight']:.2f}"
            say(f"| {v} | {a} | {c['error_m']:.4f} | {ratio} | {mm(c['rms_along_m'])} | "
                f"{mm(c['rms_across_m'])} | {c['rms_wheel_scale_error']:.5f} | {c['failed_frames']:.1f} | "
                f"{c['time_s']:.1f} |")
    say('')
    base, no_stereo, no_slip, no_noise = (split[v] for v in variants)
    along, across = base['none']['rms_along_m'], base['none']['rms_across_m']
    scales = ', '.join(f"{a} {base[a]['rms_wheel_scale_error']:.5f}" for a in aids)
    improved = [a for a in aids[1:]
                if base[a]['rms_wheel_scale_error'] <= 0.95 * base['none']['rms_wheel_scale_error']]
    # The across part that, with straight driving's along part, makes 0.85×
    # straight driving's RMS error.
    target = (PAYS * math.hypot(along, across)) ** 2 - along ** 2
    need = (f"its across part would have to fall to {mm(math.sqrt(target))} mm, "
            f"{math.sqrt(target) / across:.2f} of straight driving's" if target > 0 else "no across part would do")
    say(f"With the default estimate the distance driven is odometry's times the wheel scale egomotion measures "
        f"from the camera, the heading is the camera's, and odometry's sideways motion is taken as counted. "
        f"Driving straight, {mm(along)} mm RMS of the error lies along the route and {mm(across)} mm across it. "
        f"Without stereo noise the along part falls to {mm(no_stereo['none']['rms_along_m'])} mm and the scale's "
        f"error from {base['none']['rms_wheel_scale_error']:.5f} to {no_stereo['none']['rms_wheel_scale_error']:.5f}. "
        f"The scale's error by aid: {scales}; {', '.join(improved) if improved else 'no aid'} "
        f"improve{'s' if len(improved) <= 1 else ''} it by 5 % or more. Across the route straight driving ends "
        f"{mm(across)} mm off, with the head held ahead {mm(base['head-ahead']['rms_across_m'])} mm and with the "
        f"steered camera's looks {mm(base['camera']['rms_across_m'])} mm; without stereo noise "
        f"{mm(no_stereo['none']['rms_across_m'])} mm stays across, without slip {mm(no_slip['none']['rms_across_m'])} mm "
        f"and without either {mm(no_noise['none']['rms_across_m'])} mm, so most of it comes from the two together. "
        f"For a look to end at 0.85× straight driving's RMS error with the along part as straight driving's, "
        f"{need}; the looks tried leave it about as it was.")
    say('')
    say(f"**Other looks.** Other rules for the look were tried in scratch "
        f"builds on the training layouts (2121–2828, seeds 100–159, the steered camera against straight driving "
        f"in this family; the figures are typed in here, the builds are not in the repository): the shipped view "
        f"of least step CV 1.11×, the view with the most landmarks 1.04×, the head held ahead by the same "
        f"behaviour 1.02×, either view chosen among every landmark of the simulated world, not only those "
        f"the robot had seen, 1.08× and 1.03×, and the view of least CV taken only where its CV is below 0.85, "
        f"0.7 or 0.5 of looking ahead's (else ahead), 1.14×, 1.15× and 1.09×. None came near 0.85×; over the "
        f"eight families the most landmarks and least CV both came to 0.89× (geometric mean). Nor did the head "
        f"swept blind from side to side while the robot drives straight (`SweepCamera`, no scratch build: "
        f"`FAMILIES=feature-poor AIDS=\"none sweep\" ESTIMATES=default WHEELS=\"\" SWEEP_AMPLITUDE=60 "
        f"SWEEP_PERIOD=12 lab/scripts/aiding-families.sh \"2121 … 2828\" 130..160`): of twelve settings (±30°, "
        f"45°, 60° or 90°, every 8, 12 or 16 s; ±90° every 8 s asks more than the head's 60°/s) the best on "
        f"seeds 100–129, ±60° every 12 s, ended 0.82× there, where it was picked, and 1.17× on seeds 130–159 "
        f"(0.97× over both).")
    say('')
    say(f"**What of the scan helps.** What reaches further is measuring the scale and the heading better than "
        f"driving straight does: the scan, which turns on the spot, does both, at "
        f"{base['scan']['time_s'] / base['none']['time_s']:.1f}× the time. What of it helps was tested "
        f"in scratch builds on the same training layouts and seeds, where the scan ends 0.93× straight driving's "
        f"error in this family (0.77× on this page's layouts, above): turning back to the goal's bearing after "
        f"every scan instead of to the heading it picks, it ended 0.93× too, and standing still for as long as "
        f"a scan's turns take instead of turning, 1.14×. So what helps is the views taken as the robot turns on "
        f"the spot, not the heading it picks nor the stop; scanning only every few metres, within the triggered "
        f"scan's budget, ended 1.14×.")
    say('')
    say(f"**Stopping costs here.** Stopping for as long as a scan takes at every step, instead of scanning, "
        f"ended 0.80× without stereo noise and 1.03× without slip (`lab/scripts/error-axes.sh` on the same "
        f"build): it costs only where the two noises meet, as the error across the route does. In the ordinary "
        f"families, with more landmarks, it cost nothing measurable, 0.97× and 0.91× on seeds 100–129. What "
        f"the camera sees while the robot stands is not the cause: egomotion ignoring every frame taken "
        f"standing still ended 1.17×, as did leaving those frames out of the wheels' fits (1.17×) and holding "
        f"egomotion's anchor keyframe through the stand (1.17×). Nor is it the time: stopping for 1 s at every "
        f"step (1.37× straight driving's time) ended 1.11×, about as stopping for 10 s. So the cost comes with "
        f"slowing to a stop and starting again, by a way not found. It matters to a robot that stops often where few landmarks are in view.")
    say('')


if __name__ == '__main__':
    main()
