//! Writes a perturbed copy of a KITTI odometry sequence, for `ubf
//! pipeline` and `scripts/opencv-compare.py` to read the same frames:
//!
//! ```text
//! cargo run --release -p ubf-perception --example perturb -- FROM TO shift-1|blur-2|contrast-0.5 [FRAMES]
//! ```

use std::path::Path;
use ubf_perception::perturb::{perturb_sequence, Perturbation};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: perturb FROM TO shift-ROWS|blur-SIGMA|contrast-FACTOR [FRAMES]";
    let [from, to, kind, rest @ ..] = args.as_slice() else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let parsed = kind.split_once('-').and_then(|(name, value)| match name {
        "shift" => value.parse().ok().map(Perturbation::ShiftRight),
        "blur" => value.parse().ok().map(Perturbation::Blur),
        "contrast" => value.parse().ok().map(Perturbation::Contrast),
        _ => None,
    });
    let Some(perturbation) = parsed else {
        eprintln!("{kind}: not a perturbation; {usage}");
        std::process::exit(2);
    };
    let frames = rest.first().and_then(|f| f.parse().ok());
    if let Err(e) = perturb_sequence(Path::new(from), Path::new(to), perturbation, frames) {
        eprintln!("{e}");
        std::process::exit(1);
    }
}
