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

use std::hint::black_box;
use ubf_behaviors::decision::best_heading;
use ubf_perception::error_model::{CvTable, ErrorModelKind, MODEL_STEP_M};
use ubf_perception::StereoCamera;

#[path = "../benches/common/decision_case.rs"]
mod case;

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
    let (rules, landmarks, objective, candidates) =
        (case::rules(&camera), case::landmarks(), case::objective(), case::candidates());
    for _ in 0..n {
        black_box(best_heading(
            &table,
            &rules,
            black_box(&landmarks),
            case::AT,
            candidates.iter().copied(),
            &objective,
        ));
    }
}
