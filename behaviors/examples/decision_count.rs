//! The decision benchmark's case (73 headings over 1 000 landmarks 0.3 to
//! 2 m high, end-point objective), run `N` times, for counting
//! instructions where timings are too noisy:
//!
//! ```sh
//! cargo build --release -p ubf-behaviors --example decision_count
//! valgrind --tool=callgrind target/release/examples/decision_count 20 geometric
//! valgrind --tool=callgrind target/release/examples/decision_count 40 geometric
//! ```
//!
//! The difference of the two totals over 20 is one decision's count. The
//! model is `geometric`, `geometric-3d` or `exponential-3d`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use ubf_behaviors::decision::{best_heading, DecisionCosts, DecisionRules, Objective};
use ubf_perception::error_model::{CvTable, ErrorModelKind, MODEL_STEP_M};
use ubf_perception::StereoCamera;

fn main() {
    let mut args = std::env::args().skip(1);
    let usage = "usage: decision_count N geometric|geometric-3d|exponential-3d";
    let Some(n) = args.next().and_then(|n| n.parse::<usize>().ok()) else { return eprintln!("{usage}") };
    let kind = match args.next().as_deref() {
        Some("geometric") => ErrorModelKind::Geometric,
        Some("geometric-3d") => ErrorModelKind::Geometric3d,
        Some("exponential-3d") => ErrorModelKind::FittedExponential3d,
        _ => return eprintln!("{usage}"),
    };
    let camera = StereoCamera::default();
    let table = CvTable::for_camera(kind, &camera, MODEL_STEP_M, 80.0);
    let [up_fov, down_fov] = camera.vertical_reach();
    let rules = DecisionRules {
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
    };
    // The same landmarks as `benches/decision.rs`.
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let landmarks: Vec<[f64; 3]> = (0..1000)
        .map(|_| {
            let height = rng.random_range(0.3..2.0);
            match rng.random_range(0..3) {
                0 => [rng.random_range(0.0..60.0), 3.0, height],
                1 => [rng.random_range(0.0..60.0), -3.0, height],
                _ => [60.0, rng.random_range(-3.0..3.0), height],
            }
        })
        .collect();
    let objective = Objective::EndPoint {
        heading: 0.1,
        goal_bearing: 0.0,
        remaining_m: 30.0,
        turn_tolerance: 2f64.to_radians(),
        costs: DecisionCosts::default(),
    };
    let candidates: Vec<f64> = (-36..=36).map(|k| f64::from(k) * 2.5f64.to_radians()).collect();
    for _ in 0..n {
        black_box(best_heading(
            &table,
            &rules,
            black_box(&landmarks),
            (10.0, 0.0),
            candidates.iter().copied(),
            &objective,
        ));
    }
}
