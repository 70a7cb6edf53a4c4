//! One evaluative decision: 73 candidate headings over 1 000 tracked
//! landmarks, with the end-point objective (30 m to go) and with the
//! thesis's CV objective, the same for 73 directions of a steerable camera,
//! the same with the 3D error models (landmark height counted), and the
//! share of it spent indexing the landmarks (no candidates). Run with
//! `cargo bench -p ubf-behaviors --bench decision`.

use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use ubf_behaviors::decision::{best_heading, best_look, DecisionCosts, DecisionRules, Objective};
use ubf_perception::error_model::{CvTable, ErrorModelKind, MODEL_STEP_M};
use ubf_perception::StereoCamera;

fn decision(c: &mut Criterion) {
    let camera = StereoCamera::default();
    let table = CvTable::for_camera(ErrorModelKind::Geometric, &camera, MODEL_STEP_M, 80.0);
    let rules = DecisionRules {
        half_fov: camera.horizontal_fov() / 2.0,
        step_m: 1.0,
        min_slant_m: 0.5,
        max_range_m: 80.0,
        baseline_m: camera.baseline_m,
        min_stereo_range_m: 1.12,
        min_landmarks: 4,
        camera_height_m: 1.0,
        up_fov: camera.vertical_reach()[0],
        down_fov: camera.vertical_reach()[1],
    };
    // 1 000 landmarks on the walls and far end of a 6 m × 60 m corridor,
    // 0.3 to 2 m above the floor (as the route scenarios place them).
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let at = (10.0, 0.0);
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
    // 73 headings: ±90° every 2.5°.
    let candidates: Vec<f64> = (-36..=36).map(|k| f64::from(k) * 2.5f64.to_radians()).collect();
    c.bench_function("decision/73_headings_1000_landmarks", |b| {
        b.iter(|| black_box(best_heading(&table, &rules, &landmarks, at, candidates.iter().copied(), &objective)))
    });
    // The thesis's objective: no heading can be skipped for its turns.
    c.bench_function("decision/73_headings_1000_landmarks_cv_objective", |b| {
        b.iter(|| black_box(best_heading(&table, &rules, &landmarks, at, candidates.iter().copied(), &Objective::Cv)))
    });
    // A steerable camera: 73 looks while the robot keeps its course (no
    // look can be skipped for its turns either).
    c.bench_function("decision/73_looks_1000_landmarks", |b| {
        b.iter(|| black_box(best_look(&table, &rules, &landmarks, at, 0.0, candidates.iter().copied(), &objective)))
    });
    // The 3D models: the height's part of each landmark's information is
    // worked out once per decision, not per heading.
    for (name, kind) in
        [("geometric_3d", ErrorModelKind::Geometric3d), ("exponential_3d", ErrorModelKind::FittedExponential3d)]
    {
        let table = CvTable::for_camera(kind, &camera, MODEL_STEP_M, 80.0);
        c.bench_function(&format!("decision/73_headings_1000_landmarks_{name}"), |b| {
            b.iter(|| black_box(best_heading(&table, &rules, &landmarks, at, candidates.iter().copied(), &objective)))
        });
    }
    c.bench_function("decision/indexing_only", |b| {
        b.iter(|| black_box(best_heading(&table, &rules, &landmarks, at, std::iter::empty(), &objective)))
    });
}

criterion_group!(benches, decision);
criterion_main!(benches);
