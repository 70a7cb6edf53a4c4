//! One evaluative decision: 73 candidate headings over 1 000 tracked
//! landmarks, with the end-point objective (30 m to go) and with the
//! thesis's CV objective, the same for 73 directions of a steerable camera,
//! the same with the 3D error models (landmark height counted), and the
//! share of it spent indexing the landmarks (no candidates). Run with
//! `cargo bench -p ubf-behaviors --bench decision`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use ubf_behaviors::decision::{best_heading, best_look, Objective};
use ubf_perception::error_model::{CvTable, ErrorModelKind, MODEL_STEP_M};
use ubf_perception::StereoCamera;

#[path = "common/decision_case.rs"]
mod case;

fn decision(c: &mut Criterion) {
    let camera = StereoCamera::default();
    let table = CvTable::for_camera(ErrorModelKind::Geometric, &camera, MODEL_STEP_M, 80.0);
    let (rules, landmarks, objective, candidates, at) =
        (case::rules(&camera), case::landmarks(), case::objective(), case::candidates(), case::AT);
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
