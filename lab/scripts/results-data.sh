#!/usr/bin/env bash
# Runs every command docs/results.md reports, leaving their output in out/
# for lab/scripts/results-page.py. About 30 minutes on two cores.
#
#   lab/scripts/results-data.sh && python3 lab/scripts/results-page.py
#
# With ABLATION=1 it also builds the commits the "What each fix did" table
# compares, in a scratch worktree, and runs the end-point experiment there.
set -euo pipefail
cd "$(dirname "$0")/../.."
mkdir -p out
cargo build --release --quiet
ubf=target/release/ubf
"$ubf" model fit > out/fit.txt
"$ubf" behaviors --describe ActionAiding > out/action-aiding.md
"$ubf" experiment thesis-table2 --json > out/table2.json
OUT=out/fit-costs lab/scripts/fit-costs.sh --json > out/fit-costs.json
SEEDS=100..130 OUT=out/fit-costs-130 lab/scripts/fit-costs.sh --json > out/fit-costs-130.json
"$ubf" model fit-costs out/fit-costs --json > out/fit-costs-levels.json
"$ubf" model fit-costs out/fit-costs-130 --json > out/fit-costs-levels-130.json
"$ubf" model fit-costs out/fit-costs-130 --check > out/fit-costs-check.txt
"$ubf" experiment thesis-table4 --json > out/table4.json
"$ubf" experiment thesis-endpoint --json > out/endpoint.json
"$ubf" experiment thesis-endpoint --objective cv --json > out/endpoint-cv.json
"$ubf" experiment thesis-endpoint --rotate-then-translate --json > out/endpoint-rtt.json
# The end-point experiment on held-out layouts, with the planar error model
# and with the 3D one, and tracking against straight driving at the last
# frame and the two before (out/last-frame-FIRSTSEED.json): held_out SEEDS
# LAYOUT...
held_out() {
    local seeds=$1 layout
    shift
    for layout in "$@"; do
        "$ubf" experiment thesis-endpoint --seeds "$seeds" --layout-seed "$layout" --json > "out/endpoint-held-$layout.json"
        "$ubf" experiment thesis-endpoint --seeds "$seeds" --layout-seed "$layout" --model geometric-3d --json \
            > "out/endpoint-held-$layout-3d.json"
        for fusion in sideways full; do
            "$ubf" experiment thesis-endpoint --seeds "$seeds" --layout-seed "$layout" --odometry-fusion "$fusion" \
                --json > "out/endpoint-held-$layout-$fusion.json"
        done
    done
    lab/scripts/last-frame.sh "$*" "$seeds" > "out/last-frame-${seeds%%..*}.json"
}
held_out 1000..1030 101 202 303
# A second held-out set, first run after the change it checks (straight on
# the odometry bridge, the odometry χ² gate) was developed on layouts
# 404, 505 and 606 with seeds 2000..2030.
held_out 3000..3030 707 808 909
# A third, run once a later idea (shorter last steps) had been tried on it
# and dropped: it is reported with the code as committed.
held_out 6000..6030 1111 1212 1313
# A fourth, first run after the end-game fixes (a turn keeps its way round,
# the last stretch steers at the goal, a turn stuck a few degrees short
# steers on), which were found on the development layouts and on single
# runs of the second and third sets (808 seed 3010, 1111 seed 6001, 909
# seed 3025).
held_out 7000..7030 1414 1515 1616
# A fifth, first run on the committed code after the line-of-sight fix, and
# after an information-based step term had been tried on the training
# layouts and dropped: nothing was developed or tried on it.
held_out 8000..8030 1717 1818 1919
"$ubf" experiment thesis-endpoint --seeds 1000..1030 --layout-seed 101 --objective cv --json > out/endpoint-held-101-cv.json
# Whether the 3D error model predicts egomotion's step errors better: the
# routes driven straight and with tracking, the step CVs from each model,
# ranked against the steps' actual errors by `ubf model fit-costs`.
for model in Geometric Geometric3d; do
    variants=$(mktemp -d)
    for route in route-1-2 route-2-1 feature-poor; do
        for technique in None Tracking; do
            sed -e "s/technique: None/technique: $technique/" \
                -e "s/egomotion: (estimator: Rigid(),/egomotion: (estimator: Rigid(), model: $model,/" \
                "lab/scenarios/thesis/$route.ron" > "$variants/$route-$technique.ron"
        done
    done
    "$ubf" sweep "$variants"/*.ron --seeds 100..120 --out "out/steps-$model" --trajectories --overwrite >&2
    "$ubf" model fit-costs "out/steps-$model" --json > "out/steps-$model.json"
    rm -rf "$variants"
done
"$ubf" experiment where-aiding-pays --plot docs/where-aiding-pays.png --json > out/where-aiding-pays.json
# Route 1->2 with a one-frame keyframe bank (frame-to-frame matching)
# beside the default bank, every technique, the thesis's CV objective.
variants=$(mktemp -d)
for technique in None ZigZag Scan Tracking; do
    for bank in bank frame-to-frame; do
        egomotion='egomotion: (estimator: Rigid(),'
        [ "$bank" = frame-to-frame ] && \
            egomotion='egomotion: (estimator: Rigid(), keyframes: 1, keyframe_spacing_m: 0.01, keyframe_spacing_deg: 0.01,'
        sed -e "s/technique: None/technique: $technique, objective: Cv/" \
            -e "s/        egomotion: (estimator: Rigid(),/        $egomotion/" \
            lab/scenarios/thesis/route-1-2.ron > "$variants/$technique-$bank.ron"
    done
done
"$ubf" sweep "$variants"/*.ron --seeds 0..30 --out out/keyframes --overwrite >&2
cp out/keyframes/summary.json out/keyframes.json
rm -rf "$variants"
# Where camera steering's error comes from (development layouts), and
# tracking's on the two held-out layouts where it misses most on route 1->2.
lab/scripts/error-sources.sh camera "404 505 606" 2000..2030 > out/camera-sources.json
lab/scripts/error-sources.sh tracking "1212 1313" 6000..6030 route-1-2 > out/tracking-sources.json
# How much the end point depends on the line driven: ten training layouts,
# kept apart from every held-out table, on the cost fit's seeds.
lab/scripts/path-lottery.sh "2121 2222 2323 2424 2525 2626 2727 2828 2929 3030" 100..130 > out/path-lottery.json
# Which links of egomotion's chain carry that error, on the same lines.
lab/scripts/error-chain.sh "2121 2222 2323 2424 2525 2626 2727 2828 2929 3030" 100..130 > out/error-chain.json
# What odometry fusion buys, and what it costs when the wheels err more
# than odometry's noise model says (training layouts).
lab/scripts/odometry-fusion.sh "2121 2222 2323" 100..120 > out/odometry-fusion.json
if [ "${ABLATION:-0}" = 1 ]; then
    # The code before the keyframe bank, then after each fix in turn.
    commits=(a7c19a4 383fdec 9bf8784 f752499 9a0a8ec 281d3ac 7b52484 8c2df86 195009d)
    scratch=$(mktemp -d)
    trap 'git worktree remove --force "$scratch/tree" 2>/dev/null || true; rm -rf "$scratch"' EXIT
    for k in "${!commits[@]}"; do
        git worktree add --force --detach "$scratch/tree" "${commits[$k]}" > /dev/null
        (cd "$scratch/tree" && CARGO_TARGET_DIR="$PWD/../target" cargo build --release --quiet \
            && "../target/release/ubf" experiment thesis-endpoint --json) > "out/ablation-$k.json"
        git worktree remove --force "$scratch/tree"
    done
fi
