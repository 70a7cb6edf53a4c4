# Sourced by the scripts that drive the thesis routes with each estimate
# and aid. Both are filters from a route file to its variant.
#
# `estimate NAME`: `default` (odometry's sideways motion fused, steering by
# the fused pose), `visual` (purely visual egomotion, steering by odometry,
# as the thesis did) or `compass` (the default with odometry's heading held
# by the walls, `wall_compass: ()`).
estimate() {
    case $1 in
        default) sed -e "s/, odometry_fusion: Off, navigate: false//" ;;
        visual) cat ;;
        compass) sed -e "s/, odometry_fusion: Off, navigate: false),/),\n        wall_compass: (),/" ;;
        *) echo "unknown estimate $1" >&2; return 2 ;;
    esac
}
# `check_estimate NAME FILE`: fails, naming FILE, unless `estimate NAME`
# took.
check_estimate() {
    if [ "$1" != visual ] && grep -q "odometry_fusion: Off, navigate: false" "$2"; then
        echo "$2: the estimate's edit did not match" >&2
        return 1
    fi
    if [ "$1" = compass ] && ! grep -q "wall_compass: ()" "$2"; then
        echo "$2: the compass did not go in" >&2
        return 1
    fi
}
# The camera put on a pan-tilt head, as the aids that turn it need.
on_head='s/camera: (/camera: (pan_tilt: (), /'
# `aid NAME`: `none` (straight at the goal), `scan`, `triggered-scan` (the
# scan within a budget of SCAN_BUDGET, default 0.5, of the time driven),
# `camera` (straight, the camera steered on a pan-tilt head),
# `head-ahead` (straight, the camera on the same head, never turned: what
# the head's readings alone cost the steered camera) or `sweep` (straight,
# the head swept blind from side to side by `SweepCamera`, SWEEP_AMPLITUDE
# degrees either way, default 45, every SWEEP_PERIOD seconds, default 8).
aid() {
    case $1 in
        none) cat ;;
        scan) sed -e "s/technique: None/technique: Scan/" ;;
        triggered-scan) sed -e "s/technique: None/technique: Scan, scan_budget: ${SCAN_BUDGET:-0.5}/" ;;
        camera) sed -e "s/technique: None/technique: Tracking, steer: Camera/" -e "$on_head" ;;
        head-ahead) sed -e "$on_head" ;;
        sweep) sed -e "$on_head" \
            -e "s/\(ActionAiding(technique: None[^)]*)),\)/\1\n            (behavior: SweepCamera(amplitude_deg: ${SWEEP_AMPLITUDE:-45.0}, period_s: ${SWEEP_PERIOD:-8.0})),/" ;;
        *) echo "unknown aid $1" >&2; return 2 ;;
    esac
}
# `check_aid NAME FILE`: fails, naming FILE, unless `aid NAME` took: a sed
# that matched nothing would run straight driving under the aid's name.
check_aid() {
    case $1 in
        none) ;;
        head-ahead) grep -q "pan_tilt: ()" "$2" || { echo "$2: the head did not go in" >&2; return 1; } ;;
        sweep) grep -q "SweepCamera(" "$2" && grep -q "pan_tilt: ()" "$2" \
            || { echo "$2: the sweep's edit did not match" >&2; return 1; } ;;
        camera) grep -q "steer: Camera" "$2" && grep -q "pan_tilt: ()" "$2" \
            || { echo "$2: the camera's edit did not match" >&2; return 1; } ;;
        scan) grep -q "technique: Scan" "$2" || { echo "$2: the scan's edit did not match" >&2; return 1; } ;;
        triggered-scan) grep -q "technique: Scan, scan_budget:" "$2" \
            || { echo "$2: the triggered scan's edit did not match" >&2; return 1; } ;;
    esac
}
