#!/usr/bin/env bash
# Action aiding and the pose estimate over families of generated layouts,
# as lab/protocol.md lays out: every family's route file (below) with each
# estimate (`default`: odometry's sideways motion fused, steering by the
# fused pose; `visual`: purely visual egomotion, steering by odometry, as
# the thesis did; beyond the protocol, `compass`: the default with
# odometry's heading held by the walls, `wall_compass: ()`) and each aid,
# swept over the layouts and seeds given, then
# summarised by lab/scripts/aiding-families.py. Prints its JSON.
#
#   lab/scripts/aiding-families.sh "40001 40002" 50000..50030 > out/aiding-families.json
#
# FAMILIES, AIDS, ESTIMATES and WHEELS (space-separated) narrow the run;
# SCAN_BUDGET is the triggered scan's budget.
set -euo pipefail
cd "$(dirname "$0")/../.."
. lab/scripts/layouts-and-seeds.sh
. lab/scripts/wheels.sh
. lab/scripts/aids.sh
families=${FAMILIES:-ordinary-far ordinary-near feature-poor featureless-20 featureless-30 range-20 noise-1px fov-32}
aids=${AIDS:-none scan triggered-scan camera}
estimates=${ESTIMATES:-default visual compass}
# Wheels that err beyond odometry's noise model, driven straight only.
wheels=${WHEELS:-scale veer}
thesis=lab/scenarios/thesis
# The family's route file, on stdout.
family() {
    case $1 in
        ordinary-far) cat $thesis/route-1-2.ron ;;
        ordinary-near) cat $thesis/route-2-1.ron ;;
        feature-poor) cat $thesis/feature-poor.ron ;;
        featureless-20 | featureless-30)
            local to=30.0
            [ "$1" = featureless-30 ] && to=40.0
            sed -e "s/corridor: (width: 4.0, length: 62.0),/&\n        featureless: [(side: Left, from: 10.0, to: $to), (side: Right, from: 10.0, to: $to)],/" \
                $thesis/route-1-2.ron ;;
        range-20) sed -e "s/outlier_share: 0.08)/outlier_share: 0.08, max_range_m: 20.0)/" $thesis/route-1-2.ron ;;
        noise-1px) sed -e "s/pixel_noise_px: 0.047/pixel_noise_px: 1.0/" $thesis/route-1-2.ron ;;
        # 32° across 640 px: f = 320 / tan 16°.
        fov-32) sed -e "s/camera: (pixel_noise_px/camera: (stereo: (focal_px: 1116.0), pixel_noise_px/" $thesis/route-1-2.ron ;;
        *) echo "unknown family $1" >&2; exit 2 ;;
    esac
}
odometry() {
    sed -e "s/slip_deg_per_sqrt_m: 0.2/$(wheel_errors "$1")/"
}
for f in $families; do
    for e in $estimates; do
        for a in $aids; do
            family "$f" | estimate "$e" | aid "$a" > "$work/$f~$e~$a~exact.ron"
        done
        for w in $wheels; do
            family "$f" | estimate "$e" | odometry "$w" > "$work/$f~$e~none~$w.ron"
        done
    done
done
# Every file must have taken every edit: a sed that matched nothing would
# quietly run the base file under another name.
for file in "$work"/*.ron; do
    IFS='~' read -r f e a w <<< "$(basename "$file" .ron)"
    base=$(family "$f")
    [ "$f" = ordinary-far ] || [ "$f" = ordinary-near ] || [ "$f" = feature-poor ] \
        || ! diff -q <(echo "$base") <(family ordinary-far) > /dev/null \
        || { echo "$file: the family's edit did not match" >&2; exit 1; }
    check_estimate "$e" "$file" || exit 1
    check_aid "$a" "$file" || exit 1
    [ "$w" = exact ] || grep -qF "$(wheel_errors "$w")" "$file" || { echo "$file: the wheels' edit did not match" >&2; exit 1; }
done
"$ubf" sweep "$work"/*.ron --seeds "$seeds" --layout-seeds "${layouts// /,}" --out "$work/runs" >&2
python3 lab/scripts/aiding-families.py "$work/runs"
