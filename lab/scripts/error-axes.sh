#!/usr/bin/env bash
# Whether an aid's end-point error lies along the route or across it, with
# one error source removed at a time: each route (default estimate, exact
# wheels) driven with each aid, as it is, without stereo noise (pixel noise
# and outliers), without wheel slip and without either, split by
# `lab/scripts/error-axes.py`.
# With the default estimate the distance is odometry's times the wheel
# scale egomotion measures and the heading is the camera's, so the error
# along the route goes with the scale's error and the error across it with
# the heading's. Prints JSON.
#
#   lab/scripts/error-axes.sh "2121 2222 2323 2424" 100..130 > out/error-axes.json
#
# ROUTES and AIDS (space-separated; aids as lab/scripts/aids.sh names them)
# narrow the run.
set -euo pipefail
cd "$(dirname "$0")/../.."
. lab/scripts/layouts-and-seeds.sh
. lab/scripts/aids.sh
routes=${ROUTES:-feature-poor route-1-2 route-2-1}
aids=${AIDS:-none head-ahead camera scan triggered-scan}
stereo=(-e "s/pixel_noise_px: 0.047, outlier_share: 0.08/pixel_noise_px: 0.0, outlier_share: 0.0/")
slip=(-e "s/slip_deg_per_sqrt_m: 0.2/slip_deg_per_sqrt_m: 0.0/")
for route in $routes; do
    for variant in base no-stereo-noise no-slip no-noise; do
        case $variant in
            base) edit=(-e "") ;;
            no-stereo-noise) edit=("${stereo[@]}") ;;
            no-slip) edit=("${slip[@]}") ;;
            no-noise) edit=("${stereo[@]}" "${slip[@]}") ;;
        esac
        for a in $aids; do
            file="$work/$route~$variant~$a.ron"
            sed "${edit[@]}" "lab/scenarios/thesis/$route.ron" | estimate default | aid "$a" > "$file"
            # A sed that matched nothing would run another file under this name.
            check_estimate default "$file" || exit 1
            check_aid "$a" "$file" || exit 1
            case $variant in no-stereo-noise | no-noise)
                grep -q "pixel_noise_px: 0.0, outlier_share: 0.0" "$file" \
                    || { echo "$file: the stereo noise's edit did not match" >&2; exit 1; } ;;
            esac
            case $variant in no-slip | no-noise)
                grep -q "slip_deg_per_sqrt_m: 0.0" "$file" \
                    || { echo "$file: the slip's edit did not match" >&2; exit 1; } ;;
            esac
        done
    done
done
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --trajectories --out "$work/runs" >&2
python3 lab/scripts/error-axes.py "$work/runs"
