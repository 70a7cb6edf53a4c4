#!/usr/bin/env bash
# Measures the egomotion error coefficients the end-point decision weighs:
# runs the thesis routes straight and with the techniques that turn
# (tracking and the scan with the thesis's CV-only objective, and the
# zig-zag) on training seeds, keeps every run's trajectory.csv, and fits the
# coefficients to each run's difference from the straight run of the same
# route and seed: what choosing a path changes, which is what the decision
# weighs. (`ubf model fit-costs DIR` without `--against` fits the end points
# as they are: the coefficients of the predicted σ runs report.)
#
#   lab/scripts/fit-costs.sh                 # seeds 100..110, logs in out/fit-costs
#   SEEDS=200..230 OUT=/tmp/logs lab/scripts/fit-costs.sh
#   SEEDS=100..130 lab/scripts/fit-costs.sh --write behaviors/src/decision_costs.ron
#                                            # the decision's coefficients, as built in
set -euo pipefail
cd "$(dirname "$0")/../.."
seeds=${SEEDS:-100..110}
out=${OUT:-out/fit-costs}
cargo build --release --quiet
ubf=target/release/ubf
scenarios=$(mktemp -d)
trap 'rm -rf "$scenarios"' EXIT
for route in route-1-2 route-2-1 feature-poor; do
    for technique in None Tracking Scan ZigZag; do
        sed "s/technique: None/technique: $technique, objective: Cv/" \
            "lab/scenarios/thesis/$route.ron" > "$scenarios/$route-$technique.ron"
    done
    sed "s/technique: None/technique: Tracking/" "lab/scenarios/thesis/$route.ron" > "$scenarios/$route-Tracking-EndPoint.ron"
done
rm -rf "$out"
"$ubf" sweep "$scenarios"/*.ron --seeds "$seeds" --out "$out" --trajectories >&2
"$ubf" model fit-costs "$out" --against "$out"/*-None "$@"
