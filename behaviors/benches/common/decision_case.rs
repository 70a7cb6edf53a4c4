//! The decision benchmark's case, shared by `benches/decision.rs` and
//! `examples/decision_count.rs` so that timings and instruction counts
//! measure the same work.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use ubf_behaviors::decision::{DecisionCosts, DecisionRules, Objective};
use ubf_perception::StereoCamera;

/// Where the robot stands, m.
pub const AT: (f64, f64) = (10.0, 0.0);

/// The engine's rules for `camera`, one-metre steps.
pub fn rules(camera: &StereoCamera) -> DecisionRules {
    let [up_fov, down_fov] = camera.vertical_reach();
    DecisionRules {
        half_fov: camera.horizontal_fov() / 2.0,
        step_m: 1.0,
        min_slant_m: 0.5,
        max_range_m: 80.0,
        baseline_m: camera.baseline_m,
        min_stereo_range_m: 1.12,
        min_landmarks: 4,
        camera_height_m: 1.0,
        up_fov,
        down_fov,
    }
}

/// 1 000 landmarks on the walls and far end of a 6 m × 60 m corridor,
/// 0.3 to 2 m above the floor (as the route scenarios place them).
pub fn landmarks() -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..1000)
        .map(|_| {
            let height = rng.random_range(0.3..2.0);
            match rng.random_range(0..3) {
                0 => [rng.random_range(0.0..60.0), 3.0, height],
                1 => [rng.random_range(0.0..60.0), -3.0, height],
                _ => [60.0, rng.random_range(-3.0..3.0), height],
            }
        })
        .collect()
}

/// The end-point objective with 30 m to go, facing 0.1 rad off the goal.
pub fn objective() -> Objective {
    Objective::EndPoint {
        heading: 0.1,
        goal_bearing: 0.0,
        remaining_m: 30.0,
        turn_tolerance: 2f64.to_radians(),
        costs: DecisionCosts::default(),
    }
}

/// 73 headings: ±90° every 2.5°.
pub fn candidates() -> Vec<f64> {
    (-36..=36).map(|k| f64::from(k) * 2.5f64.to_radians()).collect()
}
