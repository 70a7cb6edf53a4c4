# Sourced by the scripts that drive the thesis routes on wheels that err
# beyond odometry's noise model. `wheel_errors NAME` prints the route
# files' odometry line for NAME: `exact` (the routes' own: random slip as
# the noise model says), `scale` (wheels 1 % larger than the encoders
# think: distance and turns come out 1 % short), `veer` (a steady 0.05°
# per metre odometry does not see), `distance` (beyond the protocol: a
# random distance slip of 1 cm per √m, both wheels together, within the
# noise model's distance σ) or `short` (beyond the protocol: wheels 1 %
# smaller than the encoders think, so distance comes out 1 % long).
wheel_errors() {
    case $1 in
        exact) echo 'slip_deg_per_sqrt_m: 0.2' ;;
        scale) echo 'slip_deg_per_sqrt_m: 0.2, left_scale: 1.01, right_scale: 1.01' ;;
        veer) echo 'slip_deg_per_sqrt_m: 0.2, veer_deg_per_m: -0.05' ;;
        short) echo 'slip_deg_per_sqrt_m: 0.2, left_scale: 0.99, right_scale: 0.99' ;;
        distance) echo 'slip_deg_per_sqrt_m: 0.2, distance_slip_m_per_sqrt_m: 0.01' ;;
        *) echo "unknown wheels $1" >&2; return 2 ;;
    esac
}
